"""The paper's friction models (Dahl, eq. 4; LuGre, eq. 5) as vectorised functions.

Units: slip ``u`` in inch, slip velocity ``v`` in in/s, forces in lbf, the internal
(bristle) state ``z`` in inch. Every function broadcasts over its arguments, so a
batch of parameter sets is an array axis.

LuGre convention
----------------
The paper prints eq. 5a as ``dz/dt = v - sigma0 |v| z / g(v)`` with
``g(v) = alpha0 + alpha1 exp(-(v/v0)^2)`` and calls ``alpha0`` the Coulomb *force*
and ``alpha0 + alpha1`` the stiction *force*. Read literally, ``sigma0 z`` is a force and
``g`` is a force, so ``sigma0 |v| z / g`` has units of velocity: eq. 5a is consistent
with ``g`` in force units, and its steady sliding state is ``sigma0 z = g(v)`` (the
friction force then equals the Stribeck curve, as in Olsson et al. 1998). That is the
convention implemented here. The paper's remark that Dahl follows from
``g(v) = Fc / sigma0`` belongs to Olsson's other way of writing the model
(``dz/dt = v - |v| z / g(v)``, where ``g`` is a length); in the form printed as eq. 5a
Dahl follows from ``g(v) = Fc`` (``alpha1 = 0``, ``alpha0 = Fc``), ``sigma1 = alpha2 = 0``,
``sigma0 = sigma``. The test suite checks that reduction.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "dahl_z_rate",
    "dahl_force",
    "dahl_branch_z",
    "dahl_dissipation_per_cycle",
    "lugre_g",
    "lugre_sigma1",
    "lugre_z_rate",
    "lugre_force",
    "hysteresis_loop",
    "loop_dissipation",
    "MODELS",
]

MODELS = ("dahl", "lugre")
"""Names of the friction models implemented here."""

LUGRE_PARAMS = ("sigma0", "sigma1", "alpha0", "alpha1", "alpha2", "v0", "vd")


# --------------------------------------------------------------------------- Dahl
def dahl_z_rate(z_in: ArrayLike, v_in_s: ArrayLike, sigma_lbf_in: ArrayLike, fc_lbf: ArrayLike) -> np.ndarray:
    """Dahl state equation (paper eq. 4a): ``dz/dt = v - sigma |v| z / Fc``.

    Parameters
    ----------
    z_in : array_like
        Bristle state, inch (the friction force is ``sigma * z``).
    v_in_s : array_like
        Slip velocity, in/s.
    sigma_lbf_in : array_like
        Rest stiffness sigma, lbf/in.
    fc_lbf : array_like
        Coulomb (limiting) friction force, lbf.

    Returns
    -------
    numpy.ndarray
        dz/dt in in/s, broadcast over the inputs.
    """
    v = np.asarray(v_in_s, dtype=float)
    return v - np.asarray(sigma_lbf_in) * np.abs(v) * np.asarray(z_in) / np.asarray(fc_lbf)


def dahl_force(z_in: ArrayLike, sigma_lbf_in: ArrayLike) -> np.ndarray:
    """Dahl friction force (paper eq. 4b) ``F = sigma z`` in lbf."""
    return np.asarray(sigma_lbf_in, dtype=float) * np.asarray(z_in, dtype=float)


def dahl_branch_z(
    u_in: ArrayLike,
    direction: ArrayLike,
    u_rev_in: ArrayLike,
    z_rev_in: ArrayLike,
    sigma_lbf_in: ArrayLike,
    fc_lbf: ArrayLike,
) -> np.ndarray:
    """Exact Dahl state on a branch of monotonic slip.

    Dahl is rate independent: with ``s = sign(v)`` fixed, eq. 4a becomes
    ``dz/du = 1 - s sigma z / Fc``, whose solution from the last reversal
    ``(u_rev, z_rev)`` is ``z = s Fc/sigma + (z_rev - s Fc/sigma) exp(-sigma s (u - u_rev) / Fc)``.

    Parameters
    ----------
    u_in : array_like
        Slip, inch.
    direction : array_like
        ``s``, +1 or -1: sign of the slip velocity on this branch.
    u_rev_in, z_rev_in : array_like
        Slip and state at the start of the branch (last reversal), inch.
    sigma_lbf_in, fc_lbf : array_like
        Dahl parameters, lbf/in and lbf.

    Returns
    -------
    numpy.ndarray
        z in inch.
    """
    s = np.asarray(direction, dtype=float)
    z_sat = s * np.asarray(fc_lbf) / np.asarray(sigma_lbf_in)
    decay = np.asarray(sigma_lbf_in) / np.asarray(fc_lbf) * s * (np.asarray(u_in) - np.asarray(u_rev_in))
    # min(): a stage of a time step may look a little past a reversal; keep exp finite.
    return z_sat + (np.asarray(z_rev_in) - z_sat) * np.exp(-np.minimum(decay, 50.0))


def dahl_dissipation_per_cycle(
    amplitude_in: ArrayLike, sigma_lbf_in: ArrayLike, fc_lbf: ArrayLike
) -> np.ndarray:
    """Energy dissipated per steady, symmetric slip cycle ``u = A sin(wt)`` by Dahl.

    Derivation (rate independence, ``lam = sigma / Fc``): on the rising half-cycle
    ``z(u) = Fc/sigma - (z_A + Fc/sigma) exp(-lam (u + A))`` starting from ``-z_A`` at
    ``u = -A``. Symmetry of the steady cycle requires ``z(A) = z_A``, which gives
    ``z_A = (Fc/sigma) tanh(lam A)``. The loop integral is twice the rising branch:
    ``E = 2 sigma int_{-A}^{A} z du = 4 Fc A - 4 (Fc^2/sigma) tanh(sigma A / Fc)``.
    Limits: ``(4/3) sigma^2 A^3 / Fc`` for small A (cubic, so equivalent damping grows
    linearly with amplitude), ``4 Fc A`` for large A (Coulomb).

    Parameters
    ----------
    amplitude_in : array_like
        Slip amplitude A, inch.
    sigma_lbf_in, fc_lbf : array_like
        Dahl parameters, lbf/in and lbf.

    Returns
    -------
    numpy.ndarray
        Dissipated energy per cycle, lbf*in.

    Examples
    --------
    Large slip approaches Coulomb's ``4 Fc A``; small slip the cubic ``(4/3) sigma^2 A^3 / Fc``:

    >>> sigma, fc = 2133.4, 38.0
    >>> round(float(dahl_dissipation_per_cycle(10.0, sigma, fc) / (4 * fc * 10.0)), 4)
    0.9982
    >>> round(float(dahl_dissipation_per_cycle(1e-7, sigma, fc) / (4 / 3 * sigma**2 * 1e-21 / fc)), 9)
    1.0
    """
    a = np.asarray(amplitude_in, dtype=float)
    sigma = np.asarray(sigma_lbf_in, dtype=float)
    fc = np.asarray(fc_lbf, dtype=float)
    x = sigma * a / fc
    # Series for small x: the difference x - tanh(x) cancels catastrophically.
    small = np.abs(x) < 1e-3
    xs = np.where(small, x, 0.0)
    series = 4.0 * fc**2 / sigma * (xs**3 / 3.0 - 2.0 * xs**5 / 15.0)
    exact = 4.0 * fc * a - 4.0 * fc**2 / sigma * np.tanh(x)
    return np.where(small, series, exact)


# --------------------------------------------------------------------------- LuGre
def lugre_g(
    v_in_s: ArrayLike, alpha0_lbf: ArrayLike, alpha1_lbf: ArrayLike, v0_in_s: ArrayLike
) -> np.ndarray:
    """Stribeck curve (paper eq. 5c) ``g(v) = alpha0 + alpha1 exp(-(v/v0)^2)`` in lbf."""
    v = np.asarray(v_in_s, dtype=float)
    return np.asarray(alpha0_lbf) + np.asarray(alpha1_lbf) * np.exp(-((v / np.asarray(v0_in_s)) ** 2))


def lugre_sigma1(v_in_s: ArrayLike, sigma1_lbf_s_in: ArrayLike, vd_in_s: ArrayLike) -> np.ndarray:
    """Velocity-dependent micro-damping (paper eq. 5d) ``sigma1 exp(-(v/vd)^2)``, lbf*s/in."""
    v = np.asarray(v_in_s, dtype=float)
    return np.asarray(sigma1_lbf_s_in) * np.exp(-((v / np.asarray(vd_in_s)) ** 2))


def lugre_z_rate(
    z_in: ArrayLike,
    v_in_s: ArrayLike,
    sigma0_lbf_in: ArrayLike,
    alpha0_lbf: ArrayLike,
    alpha1_lbf: ArrayLike,
    v0_in_s: ArrayLike,
) -> np.ndarray:
    """LuGre state equation (paper eq. 5a, ``g`` in force units): ``v - sigma0 |v| z / g(v)``.

    Returns dz/dt in in/s. With ``alpha1 = 0`` and ``alpha0 = Fc`` this is
    :func:`dahl_z_rate` with ``sigma = sigma0``.
    """
    v = np.asarray(v_in_s, dtype=float)
    g = lugre_g(v, alpha0_lbf, alpha1_lbf, v0_in_s)
    return v - np.asarray(sigma0_lbf_in) * np.abs(v) * np.asarray(z_in) / g


def lugre_force(
    z_in: ArrayLike,
    v_in_s: ArrayLike,
    sigma0_lbf_in: ArrayLike,
    sigma1_lbf_s_in: ArrayLike,
    alpha0_lbf: ArrayLike,
    alpha1_lbf: ArrayLike,
    alpha2_lbf_s_in: ArrayLike,
    v0_in_s: ArrayLike,
    vd_in_s: ArrayLike,
) -> np.ndarray:
    """LuGre friction force (paper eq. 5b, 5d): ``sigma0 z + sigma1(v) dz/dt + alpha2 v`` in lbf."""
    v = np.asarray(v_in_s, dtype=float)
    z_dot = lugre_z_rate(z_in, v, sigma0_lbf_in, alpha0_lbf, alpha1_lbf, v0_in_s)
    return (
        np.asarray(sigma0_lbf_in) * np.asarray(z_in)
        + lugre_sigma1(v, sigma1_lbf_s_in, vd_in_s) * z_dot
        + np.asarray(alpha2_lbf_s_in) * v
    )


# --------------------------------------------------------------------------- loops
def _z_rate_and_force(model: str, params: Mapping[str, ArrayLike]):
    """(rate(z, v), force(z, v)) closures for a model name and its parameters."""
    if model == "dahl":
        sigma, fc = params["sigma"], params["fc"]
        return (lambda z, v: dahl_z_rate(z, v, sigma, fc), lambda z, v: dahl_force(z, sigma))
    if model == "lugre":
        p = {k: params[k] for k in LUGRE_PARAMS}
        return (
            lambda z, v: lugre_z_rate(z, v, p["sigma0"], p["alpha0"], p["alpha1"], p["v0"]),
            lambda z, v: lugre_force(
                z,
                v,
                **{
                    "sigma0_lbf_in": p["sigma0"],
                    "sigma1_lbf_s_in": p["sigma1"],
                    "alpha0_lbf": p["alpha0"],
                    "alpha1_lbf": p["alpha1"],
                    "alpha2_lbf_s_in": p["alpha2"],
                    "v0_in_s": p["v0"],
                    "vd_in_s": p["vd"],
                },
            ),
        )
    raise ValueError(f"unknown friction model {model!r}; expected one of {MODELS}")


def _relaxation_per_length(model: str, params: Mapping[str, ArrayLike]) -> np.ndarray:
    """Largest ``|dz_rate/dz| / |v|`` (1/in): how many e-folds z makes per inch of slip."""
    if model == "dahl":
        return np.asarray(params["sigma"], float) / np.asarray(params["fc"], float)
    a0 = np.asarray(params["alpha0"], float)
    gmin = np.minimum(a0, a0 + np.asarray(params["alpha1"], float))
    return np.asarray(params["sigma0"], float) / gmin


def hysteresis_loop(
    model: str,
    params: Mapping[str, ArrayLike],
    amplitude_in: ArrayLike,
    *,
    frequency_hz: float = 1.0,
    cycles: int = 3,
    points_per_cycle: int = 2000,
    steady_start: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Friction force along a displacement-driven cycle ``x = A sin(2 pi f t)``.

    The drive starts at ``x = 0`` moving up. With ``steady_start`` the state starts on
    the steady Dahl loop, ``z(0) = Fc/sigma - (z_A + Fc/sigma) exp(-sigma A/Fc)`` with
    ``z_A = (Fc/sigma) tanh(sigma A/Fc)`` (for LuGre the same with ``Fc = alpha0``,
    ``sigma = sigma0``: exact when ``alpha1 = 0``, otherwise only a good first guess);
    otherwise it starts virgin, ``z = 0``. This matters for small loops: a start off the
    steady loop decays only as ``exp(-2 sigma A / Fc)`` per half cycle. ``cycles`` full
    cycles are integrated by classical RK4 on the exact drive. The step is refined automatically so that the
    state's relaxation rate ``sigma |v| / Fc`` (or ``sigma0 |v| / g``) times the step
    stays below 0.5, well inside RK4's stability limit (2.78), so stiff parameter sets
    (large ``sigma A / Fc``) are still integrated accurately.

    Parameters
    ----------
    model : {"dahl", "lugre"}
        Friction model.
    params : mapping of array_like
        Model parameters (Dahl: ``sigma`` lbf/in, ``fc`` lbf; LuGre: ``sigma0`` lbf/in,
        ``sigma1`` lbf*s/in, ``alpha0`` lbf, ``alpha1`` lbf, ``alpha2`` lbf*s/in,
        ``v0`` in/s, ``vd`` in/s), broadcast together into a batch.
    amplitude_in : array_like
        Displacement amplitude A, inch, broadcast with the parameters: several
        amplitudes are one batch, each loop integrated as alone (every operation is
        elementwise) but with the step the largest amplitude needs.
    frequency_hz : float
        Drive frequency (only matters for the rate-dependent LuGre model), Hz.
    cycles : int
        Number of cycles driven; the last one is taken as the steady loop.
    points_per_cycle : int
        Output samples per cycle (the integration step may be finer).
    steady_start : bool
        Start on the steady Dahl loop (True) or from the virgin state ``z = 0``.

    Returns
    -------
    x_in : numpy.ndarray, shape (*amplitude.shape, cycles * points_per_cycle + 1)
        Displacement, inch.
    force_lbf : numpy.ndarray, shape (*batch, cycles * points_per_cycle + 1)
        Friction force, lbf.
    """
    rate, force = _z_rate_and_force(model, params)
    omega = 2.0 * np.pi * frequency_hz
    lam = np.max(_relaxation_per_length(model, params))
    n_out = cycles * points_per_cycle
    dt_out = 1.0 / (frequency_hz * points_per_cycle)
    # |v| <= A omega, so rate * h <= lam A omega h; keep that <= 0.5.
    sub = max(1, int(np.ceil(lam * np.max(amplitude_in) * omega * dt_out / 0.5)))
    h = dt_out / sub
    batch = np.broadcast(*[np.asarray(v) for v in params.values()], np.asarray(amplitude_in)).shape
    z = np.zeros(batch)
    if steady_start:
        stiff = np.asarray(params["sigma"] if model == "dahl" else params["sigma0"], float)
        fc = np.asarray(params["fc"] if model == "dahl" else params["alpha0"], float)
        z_sat = fc / stiff
        z_peak = z_sat * np.tanh(stiff * amplitude_in / fc)
        z = z + z_sat - (z_peak + z_sat) * np.exp(-stiff * amplitude_in / fc)
    t_out = np.arange(n_out + 1) * dt_out
    x = np.multiply.outer(amplitude_in, np.sin(omega * t_out))
    f_out = np.empty(batch + (n_out + 1,))
    vel = lambda t: amplitude_in * omega * np.cos(omega * t)  # noqa: E731
    f_out[..., 0] = force(z, vel(0.0))
    t = 0.0
    for i in range(n_out):
        for _ in range(sub):
            v1, v2, v3 = vel(t), vel(t + 0.5 * h), vel(t + h)
            k1 = rate(z, v1)
            k2 = rate(z + 0.5 * h * k1, v2)
            k3 = rate(z + 0.5 * h * k2, v2)
            k4 = rate(z + h * k3, v3)
            z = z + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            t += h
        t = t_out[i + 1]  # no drift of the clock from repeated additions
        f_out[..., i + 1] = force(z, vel(t))
    return x, f_out


def loop_dissipation(x_in: ArrayLike, force_lbf: ArrayLike, points_per_cycle: int) -> np.ndarray:
    """Energy dissipated in the last full cycle, ``closed integral F dx``, lbf*in.

    The integral is taken as ``sum F dx/dn`` over the periodic samples of the last cycle,
    with ``dx/dn`` the spectral derivative of the (periodic) drive: the trapezoid rule
    on a periodic integrand is far more accurate than ``sum F_mid * diff(x)``, which
    matters because a small loop's area is a tiny difference of two large integrals.
    Positive for a dissipative loop.

    Parameters
    ----------
    x_in : array_like, shape (n,)
        Displacement, inch, sampled uniformly in time; its last ``points_per_cycle + 1``
        samples span exactly one period.
    force_lbf : array_like, shape (..., n)
        Force at the same samples, lbf.
    points_per_cycle : int
        Samples per period.
    """
    n = points_per_cycle
    x = np.asarray(x_in, float)[-(n + 1) : -1]
    f = np.asarray(force_lbf, float)[..., -(n + 1) : -1]
    k = np.fft.rfftfreq(n) * 2.0 * np.pi  # radians per sample
    dx_dn = np.fft.irfft(1j * k * np.fft.rfft(x), n)
    return np.sum(f * dx_dn, axis=-1)
