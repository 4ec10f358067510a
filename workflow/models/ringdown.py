"""Ring-down of one mode with a friction joint (paper eq. 9), batched over parameter sets.

Equation of motion (modal coordinate ``xi``, mass-normalised mode)::

    xi'' + 2 zeta0 omega xi' + omega^2 xi = -phi_s F_joint(u, v)
    u = phi_s xi  (joint slip, in),  v = phi_s xi'  (slip velocity, in/s)

``phi_s`` (``slip_per_modal``) is the joint slip per unit modal coordinate. With
``phi_s = 1`` the friction parameters absorb the scaling. The ring-down starts at
``xi = 0`` with modal velocity ``initial_velocity`` and a virgin joint (``z = 0``).

Integrator (why it is fast and what it does about stiffness)
-----------------------------------------------------------
* **Exponential (Lawson) RK4.** The joint's small-amplitude linearisation
  (stiffness ``k_lin``, damping ``c_lin``; Dahl: ``sigma``; LuGre: ``sigma0`` and
  ``sigma1 + alpha2``) is added to the linear oscillator, whose flow over a step is
  applied *exactly* (2x2 matrix exponential per parameter set, computed once). RK4 only
  integrates the remainder ``-phi_s (F - k_lin u - c_lin v)``, which is small for a
  lightly damped joint. The error constant therefore scales with the size of the
  nonlinearity rather than with ``(omega h)^4`` alone, so ~20 steps per period give
  envelope errors far below 1e-3 (``bench/bench_integrator.py``).
* **Dahl without stiffness.** Dahl is rate independent; between velocity reversals its
  state is an exact function of slip (:func:`workflow.models.friction.dahl_branch_z`). The
  integrator keeps the last reversal and the direction as per-set memory, and evaluates
  the joint force algebraically at every stage. The stiff rate ``sigma |v| / Fc`` (which
  may exceed omega by orders of magnitude in deep sliding) never enters a stability
  limit, and the kink of ``|v|`` at reversals is removed: a reversal inside a step is
  located by cubic Hermite interpolation of the slip, so only an O(h^4) local error
  remains per reversal (4th-order convergence is kept).
* **LuGre's internal state.** ``z`` is integrated by the same Lawson RK4 with the
  relaxation rate ``a = sigma0 |v| / g(v)`` frozen at the start of the step and applied
  exactly (``exp(-a h)``). What is left explicit is the change of ``a`` within a step,
  ``~ a_max * omega * h``; each set's step is refined so that
  ``a_max * omega * h^2 <= 0.05`` (``a_max`` from its starting slip velocity), which
  keeps it well inside RK4's stability region.
* **Output grid.** Each set's step is ``1 / (fs_out * m)`` with an integer ``m`` chosen
  so that there are at least ``steps_per_period`` steps per period of its stuck-joint
  frequency, so output samples fall on steps and need no interpolation.
* **Compiled.** The step loop runs per parameter set in scalar code compiled by Numba
  (``cache=True``: compiled once per checkout, a few seconds). The NumPy formulation of the same scheme,
  vectorised across the batch, was bound by per-operation overhead: 1.8 s for 1000 Dahl
  ring-downs, and 130 s for one configuration's LuGre fit, whose deep-sliding sets need
  many substeps (``bench/bench_integrator.py`` prints the figures).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numba
import numpy as np
from numpy.typing import ArrayLike

from workflow.models import friction

__all__ = [
    "JOINT_PARAMETERS",
    "simulate_ringdown",
    "reference_ringdown",
    "oscillator_propagator",
    "envelope_relative_error",
]

#: Parameters of each joint model, in the order the compiled kernel takes them.
JOINT_PARAMETERS: dict[str, tuple[str, ...]] = {
    "none": (),
    "dahl": ("sigma", "fc"),
    "lugre": ("sigma0", "sigma1", "alpha0", "alpha1", "alpha2", "v0", "vd"),
}
_KIND = {"none": 0, "dahl": 1, "lugre": 2}
# LuGre: keep (rate variation within a step) * h = a_max * omega * h^2 below this
# (1 is stable; 0.05 keeps deep-sliding LuGre within ~1e-3 of Dahl, measured).
_LUGRE_RATE_STEP = 0.05
# A Runge-Kutta stage can look slightly past a reversal; keep exp() finite.
_EXP_CAP = 50.0
# error_model="numpy": IEEE results instead of Python's ZeroDivisionError checks, which
# halve the kernel's speed (measured).
_jit = numba.njit(cache=True, error_model="numpy")


# --------------------------------------------------------------------------- propagator
@_jit
def _propagator(k: float, c: float, t: float) -> tuple[float, float, float, float]:
    """Exact flow exp(L t) of x'' + c x' + k x = 0 (one set, any regime)."""
    mu = 0.5 * c
    disc = k - mu * mu
    if disc > 0.0:
        om = math.sqrt(disc)
        cos = math.cos(om * t)
        sinc = math.sin(om * t) / om if om * t > 1e-8 else t
    elif disc < 0.0:
        om = math.sqrt(-disc)
        cos = math.cosh(om * t)
        sinc = math.sinh(om * t) / om if om * t > 1e-8 else t
    else:
        cos, sinc = 1.0, t
    decay = math.exp(-mu * t)
    return (decay * (cos + mu * sinc), decay * sinc, -k * decay * sinc, decay * (cos - mu * sinc))


@_jit
def _propagator_batch(k, c, t):
    n = k.size
    out = np.empty((4, n))
    for i in range(n):
        out[0, i], out[1, i], out[2, i], out[3, i] = _propagator(k[i], c[i], t)
    return out


def oscillator_propagator(
    stiffness_per_s2: ArrayLike, damping_per_s: ArrayLike, t_s: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Exact flow ``exp(L t)`` of ``x'' + C x' + K x = 0`` for state ``(x, x')``.

    Parameters
    ----------
    stiffness_per_s2 : array_like
        K, 1/s^2 (any sign).
    damping_per_s : array_like
        C, 1/s (any sign).
    t_s : float
        Time step, s.

    Returns
    -------
    e00, e01, e10, e11 : numpy.ndarray
        Matrix entries; ``e01`` in s, ``e10`` in 1/s.
    """
    k, c = np.broadcast_arrays(np.asarray(stiffness_per_s2, float), np.asarray(damping_per_s, float))
    out = _propagator_batch(np.ascontiguousarray(k).ravel(), np.ascontiguousarray(c).ravel(), float(t_s))
    return tuple(row.reshape(k.shape) for row in out)


# ------------------------------------------------------------------------------ kernel
@_jit
def _lugre_rate_coeff(v, sigma0, alpha0, alpha1, v0):
    return sigma0 / (alpha0 + alpha1 * math.exp(-((v / v0) ** 2)))


@_jit
def _remainder(kind, p, phi, k_joint, c_joint, a0, a1, b, b0, xi, eta, z):
    """Nonlinear modal force ``-phi (F - k_joint u - c_joint v)`` and ``dz/dt``."""
    if kind == 1:  # Dahl on the current branch: z = a0 + a1 exp(b xi + b0)
        zb = a0 + a1 * math.exp(min(b * xi + b0, _EXP_CAP))
        return phi * p[0] * (phi * xi - zb), 0.0
    if kind == 2:
        v = phi * eta
        z_dot = v - _lugre_rate_coeff(v, p[0], p[2], p[3], p[5]) * abs(v) * z
        f = p[0] * z + p[1] * math.exp(-((v / p[6]) ** 2)) * z_dot + p[4] * v
        return -phi * (f - k_joint * phi * xi - c_joint * v), z_dot
    return 0.0, 0.0


@_jit
def _ringdown_kernel(
    kind,
    params,
    phi_all,
    k_lin_all,
    c_lin_all,
    k_joint_all,
    c_joint_all,
    v_init_all,
    substeps,
    dt_out,
    disp,
    vel,
    acc,
):
    """Lawson RK4 ring-down of every set; writes rows of disp, vel, acc (modal units)."""
    n_out = disp.shape[1]
    for i in range(disp.shape[0]):
        p = params[i]
        phi, k_lin, c_lin = phi_all[i], k_lin_all[i], c_lin_all[i]
        k_joint, c_joint = k_joint_all[i], c_joint_all[i]
        m = substeps[i]
        h = dt_out / m
        hh = 0.5 * h
        e00, e01, e10, e11 = _propagator(k_lin, c_lin, hh)
        p00, p01, p10, p11 = _propagator(k_lin, c_lin, h)
        xi, eta, z = 0.0, v_init_all[i], 0.0
        # Dahl branch memory (virgin start at xi = 0): z = a0 + a1 exp(b xi + b0).
        a0 = a1 = b = b0 = 0.0
        if kind == 1:
            s = -1.0 if eta < 0.0 else 1.0
            z_sat = p[1] / p[0]
            a0, a1, b = s * z_sat, -s * z_sat, -p[0] / p[1] * s * phi
        for j in range(n_out):
            for sub in range(m):
                n1, d1 = _remainder(kind, p, phi, k_joint, c_joint, a0, a1, b, b0, xi, eta, z)
                if sub == 0:  # the output sample is the start of this step
                    disp[i, j], vel[i, j] = xi, eta
                    acc[i, j] = n1 - k_lin * xi - c_lin * eta
                exi = e00 * xi + e01 * eta
                eeta = e10 * xi + e11 * eta
                pxi = p00 * xi + p01 * eta
                peta = p10 * xi + p11 * eta
                a = ez = 0.0
                if kind == 2:
                    v = phi * eta
                    a = _lugre_rate_coeff(v, p[0], p[2], p[3], p[5]) * abs(v)
                    ez = math.exp(-a * hh)
                    d1 += a * z
                w2 = ez * (z + hh * d1)
                n2, d2 = _remainder(
                    kind,
                    p,
                    phi,
                    k_joint,
                    c_joint,
                    a0,
                    a1,
                    b,
                    b0,
                    exi + hh * e01 * n1,
                    eeta + hh * e11 * n1,
                    w2,
                )
                d2 += a * w2
                w3 = ez * z + hh * d2
                n3, d3 = _remainder(kind, p, phi, k_joint, c_joint, a0, a1, b, b0, exi, eeta + hh * n2, w3)
                d3 += a * w3
                w4 = ez * ez * z + h * ez * d3
                n4, d4 = _remainder(
                    kind, p, phi, k_joint, c_joint, a0, a1, b, b0, pxi + h * e01 * n3, peta + h * e11 * n3, w4
                )
                d4 += a * w4
                n23 = n2 + n3
                xi_new = pxi + h / 6.0 * p01 * n1 + h / 3.0 * e01 * n23
                eta_new = peta + h / 6.0 * p11 * n1 + h / 3.0 * e11 * n23 + h / 6.0 * n4
                if kind == 2:
                    z = ez * ez * z + h / 6.0 * (ez * ez * d1 + 2.0 * ez * (d2 + d3) + d4)
                elif kind == 1 and eta_new * b > 0.0:
                    # Velocity reversal inside the step. Its time from linear velocity;
                    # the Hermite displacement there is O(h^4) accurate because xi is
                    # stationary at the reversal (error ~ theta error squared).
                    theta = eta / (eta - eta_new)
                    d = xi_new - xi
                    hv0, hv1 = h * eta, h * eta_new
                    c2 = 3.0 * d - 2.0 * hv0 - hv1
                    c3 = hv0 + hv1 - 2.0 * d
                    x_r = xi + theta * (hv0 + theta * (c2 + theta * c3))
                    z_r = a0 + a1 * math.exp(b * x_r + b0)
                    # The stages after the reversal used the old branch; add the missing
                    # impulse of the (new - old) branch force over the rest of the step,
                    # else a one-signed O(h^3) error per reversal accumulates. With
                    # xi - xi_r = alpha tau^2 / 2 the difference grows as tau^2; one node
                    # at tau_e / sqrt(3) integrates tau^2 exactly, and
                    # int (tau_e - tau) tau^2 = (tau_e / 4) int tau^2.
                    alpha = (eta_new - eta) / h
                    tau_e = (1.0 - theta) * h
                    e = math.exp(min(-b * alpha * tau_e * tau_e / 6.0, _EXP_CAP))
                    dz = (z_r + a0) * e - (z_r - a0) / e - 2.0 * a0
                    d_eta = -phi * p[0] * tau_e * dz
                    xi_new += 0.25 * tau_e * d_eta
                    eta_new += d_eta
                    a0, a1, b, b0 = -a0, z_r + a0, -b, b * x_r
                xi, eta = xi_new, eta_new


def _broadcast_batch(*arrays) -> int:
    shape = np.broadcast(*[np.asarray(a) for a in arrays]).shape
    if len(shape) > 1:
        raise ValueError(f"parameters must broadcast to a 1-D batch, got shape {shape}")
    return shape[0] if shape else 1


def _joint_linearisation(model: str, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Small-amplitude stiffness (lbf/in), damping (lbf s/in) and max relaxation per in/s."""
    zero = np.zeros(p.shape[0])
    if model == "dahl":
        sigma, fc = p.T
        if np.any(sigma <= 0) or np.any(fc <= 0):
            raise ValueError("Dahl parameters sigma and fc must be positive")
        return sigma, zero, zero
    if model == "lugre":
        sigma0, sigma1, alpha0, alpha1, alpha2, v0, vd = p.T
        g_min = np.minimum(alpha0, alpha0 + alpha1)
        if np.any(g_min <= 0) or np.any(sigma0 <= 0):
            raise ValueError("LuGre needs sigma0 > 0 and g(v) = alpha0 + alpha1 exp(.) > 0")
        if np.any(v0 <= 0) or np.any(vd <= 0):
            raise ValueError("LuGre velocities v0 and vd must be positive")
        return sigma0, sigma1 + alpha2, sigma0 / g_min
    return zero, zero, zero


def simulate_ringdown(
    model: str,
    params: Mapping[str, ArrayLike],
    *,
    omega_rad_s: ArrayLike,
    zeta0: ArrayLike,
    slip_per_modal: ArrayLike = 1.0,
    initial_velocity: ArrayLike,
    fs_out_hz: float,
    duration_s: float,
    steps_per_period: int = 64,
) -> dict[str, np.ndarray | float]:
    """Batched ring-down of eq. 9 by exponential (Lawson) RK4 with a fixed step per set.

    Parameters
    ----------
    model : {"dahl", "lugre", "none"}
        Joint force model (``none``: the linear damped oscillator).
    params : mapping of array_like
        Joint parameters (:data:`JOINT_PARAMETERS`; units in :mod:`workflow.models.friction`),
        each broadcastable to the batch.
    omega_rad_s : array_like
        Natural frequency of the linear mode without the joint, rad/s.
    zeta0 : array_like
        Linear viscous modal damping ratio.
    slip_per_modal : array_like
        ``phi_s``, joint slip per unit modal coordinate.
    initial_velocity : array_like
        Modal velocity at t = 0 (modal displacement per second).
    fs_out_hz : float
        Output sample rate, Hz; samples at ``t = j / fs_out``.
    duration_s : float
        Output duration, s (``round(duration * fs)`` samples).
    steps_per_period : int
        Minimum number of steps per period of each set's stuck-joint frequency.

    Returns
    -------
    dict
        ``t_s`` (n,), ``displacement``, ``velocity``, ``acceleration`` (batch, n) in modal
        units, ``substeps`` (batch,) (steps per output sample) and ``steps_per_period``
        (the fewest actual steps per stuck-joint period in the batch).
    """
    if model not in JOINT_PARAMETERS:
        raise ValueError(f"unknown joint model {model!r}; expected one of {sorted(JOINT_PARAMETERS)}")
    names = JOINT_PARAMETERS[model]
    missing = set(names) - set(params)
    if missing:
        raise ValueError(f"{model} needs parameters {sorted(missing)}")
    batch = _broadcast_batch(
        omega_rad_s, zeta0, slip_per_modal, initial_velocity, *[params[k] for k in names]
    )
    col = lambda a: np.ascontiguousarray(np.broadcast_to(np.asarray(a, float), (batch,)))  # noqa: E731
    p = np.stack([col(params[k]) for k in names], axis=1) if names else np.zeros((batch, 0))
    omega, zeta, phi, v_init = col(omega_rad_s), col(zeta0), col(slip_per_modal), col(initial_velocity)
    k_joint, c_joint, relax_per_velocity = _joint_linearisation(model, p)

    k_lin = omega**2 + phi**2 * k_joint
    c_lin = 2.0 * zeta * omega + phi**2 * c_joint
    omega_stuck = np.sqrt(np.abs(k_lin))
    n_out = int(round(duration_s * fs_out_hz))
    dt_out = 1.0 / fs_out_hz
    m = np.maximum(1, np.ceil(steps_per_period * omega_stuck / (2.0 * np.pi) * dt_out))
    a_max = relax_per_velocity * np.abs(phi * v_init)
    m = np.maximum(m, np.ceil(dt_out * np.sqrt(a_max * omega_stuck / _LUGRE_RATE_STEP)))
    m = m.astype(np.int64)

    disp = np.empty((batch, n_out))
    vel = np.empty((batch, n_out))
    acc = np.empty((batch, n_out))
    _ringdown_kernel(_KIND[model], p, phi, k_lin, c_lin, k_joint, c_joint, v_init, m, dt_out, disp, vel, acc)
    return {
        "t_s": np.arange(n_out) * dt_out,
        "displacement": disp,
        "velocity": vel,
        "acceleration": acc,
        "substeps": m,
        "steps_per_period": float(np.min(2.0 * np.pi * m / (omega_stuck * dt_out))),
    }


# ---------------------------------------------------------------------------- reference
def reference_ringdown(
    model: str,
    params: Mapping[str, float],
    *,
    omega_rad_s: float,
    zeta0: float,
    slip_per_modal: float = 1.0,
    initial_velocity: float,
    fs_out_hz: float,
    duration_s: float,
    method: str = "LSODA",
    rtol: float = 1e-10,
) -> dict[str, np.ndarray]:
    """One ring-down by ``scipy.integrate.solve_ivp`` on the paper's ODE form.

    The state is ``(xi, xi', z)`` with ``z`` obeying eq. 4a (Dahl) or 5a (LuGre)
    directly — an independent formulation from the fast simulator's exact slip branches.

    Parameters
    ----------
    model : {"dahl", "lugre", "none"}
        Joint model.
    params : mapping of float
        Joint parameters (one set).
    omega_rad_s, zeta0, slip_per_modal, initial_velocity, fs_out_hz, duration_s
        As :func:`simulate_ringdown` (scalars).
    method : str
        ``solve_ivp`` method (``LSODA``, ``Radau``, ``DOP853`` ...).
    rtol : float
        Relative tolerance; the absolute tolerances are ``rtol`` times the state scales.

    Returns
    -------
    dict
        ``t_s``, ``displacement``, ``velocity``, ``acceleration`` (n,), ``nfev``.
    """
    # here, not at the top: the fits import this module and never need SciPy's integrators
    from scipy.integrate import solve_ivp

    phi = float(slip_per_modal)
    p = {k: float(v) for k, v in params.items()}
    if model == "dahl":
        rate = lambda z, v: friction.dahl_z_rate(z, v, p["sigma"], p["fc"])  # noqa: E731
        force = lambda z, v: p["sigma"] * z  # noqa: E731
        z_scale = p["fc"] / p["sigma"]
    elif model == "lugre":
        rate = lambda z, v: friction.lugre_z_rate(  # noqa: E731
            z, v, p["sigma0"], p["alpha0"], p["alpha1"], p["v0"]
        )
        force = lambda z, v: friction.lugre_force(  # noqa: E731
            z, v, p["sigma0"], p["sigma1"], p["alpha0"], p["alpha1"], p["alpha2"], p["v0"], p["vd"]
        )
        z_scale = min(p["alpha0"], p["alpha0"] + p["alpha1"]) / p["sigma0"]
    elif model == "none":
        rate = lambda z, v: 0.0 * z  # noqa: E731
        force = lambda z, v: 0.0 * z  # noqa: E731
        z_scale = 1.0
    else:
        raise ValueError(f"reference_ringdown supports dahl, lugre, none; got {model!r}")

    def accel(xi, eta, z):
        return -2.0 * zeta0 * omega_rad_s * eta - omega_rad_s**2 * xi - phi * force(z, phi * eta)

    def rhs(_t, y):
        xi, eta, z = y
        return [eta, accel(xi, eta, z), rate(z, phi * eta)]

    n_out = int(round(duration_s * fs_out_hz))
    t = np.arange(n_out) / fs_out_hz
    x_scale = abs(initial_velocity) / omega_rad_s
    atol = rtol * np.array([x_scale, abs(initial_velocity), min(z_scale, abs(phi) * x_scale)])
    sol = solve_ivp(
        rhs, (0.0, t[-1]), [0.0, float(initial_velocity), 0.0], method=method, t_eval=t, rtol=rtol, atol=atol
    )
    if not sol.success:
        raise RuntimeError(f"reference integration failed: {sol.message}")
    xi, eta, z = sol.y
    return {
        "t_s": t,
        "displacement": xi,
        "velocity": eta,
        "acceleration": np.array([accel(a, b, c) for a, b, c in zip(xi, eta, z)]),
        "nfev": sol.nfev,
    }


def envelope_relative_error(
    signal: ArrayLike, reference: ArrayLike, *, trim_fraction: float = 0.05, floor_fraction: float = 1e-3
) -> np.ndarray:
    """Largest relative difference of Hilbert envelopes, ``max |e_s - e_r| / e_r``.

    The first and last ``trim_fraction`` of the record are skipped (the discrete
    Hilbert transform's end effects), as are samples where the reference envelope is
    below ``floor_fraction`` of its peak.

    Parameters
    ----------
    signal : array_like, shape (..., n)
        Simulated signal(s).
    reference : array_like, shape (n,) or (..., n)
        Reference signal.

    Returns
    -------
    numpy.ndarray
        Relative error per signal (dimensionless).
    """
    from scipy.signal import hilbert  # only the integrator's checks need it (tests, bench)

    es = np.abs(hilbert(np.asarray(signal, float), axis=-1))
    er = np.abs(hilbert(np.asarray(reference, float), axis=-1))
    n = es.shape[-1]
    lo, hi = int(trim_fraction * n), int((1 - trim_fraction) * n)
    es, er = es[..., lo:hi], er[..., lo:hi]
    keep = er > floor_fraction * er.max(axis=-1, keepdims=True)
    return np.max(np.where(keep, np.abs(es - er) / np.where(keep, er, 1.0), 0.0), axis=-1)
