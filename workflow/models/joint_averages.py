"""Cycle averages of the joint laws: dimensionless dissipation, in-phase stiffness and
turning-point energy per :class:`JointAverages`, functions of the joint's normalised
amplitude ``y`` (the ring-down models of :mod:`workflow.models.averaged` scale them).

* Dahl (closed form): ``d = 4 (y - tanh y)``, ``g = (2 / y)(1 + tanh y) e^-y I1(y)``,
  ``e = tanh(y)^2 / 2``.
* LuGre (paper eq. 5, ``g(v)`` in force units, ``v_d = v_0``, ``alpha2`` folded into
  ``zeta0``): steady periodic cycle computed numerically (exact exponential stepping
  of the linear-in-``z`` state equation over a half cycle, trapezoid rule in phase,
  which is spectrally accurate for periodic integrands).
* Iwan / Segalman four-parameter micro-slip: Jenkins elements whose slip thresholds
  have density ``R t^chi`` on ``(0, 1)`` (``-1 < chi``) plus a macro-slip element of
  weight ``S`` at ``t = 1``: ``D ~ y^(3 + chi)`` and ``zeta ~ y^(1 + chi)`` below
  macro-slip.
* Iwan with the threshold density set by the data: the stiffness share of each
  quarter-decade cell of slip thresholds, below the top of the measured amplitudes.
* A non-dissipative power-law stiffness (:func:`power_stiffness_harmonic_factor`), an
  extension used by :mod:`workflow.discovery`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

# scipy.special (0.2 s of start-up) is imported where a model's curves are computed, not
# by the jobs that import the models to assemble or draw the diagnosis
__all__ = [
    "JointAverages",
    "dahl_averages",
    "jenkins_dissipation",
    "jenkins_inphase",
    "iwan_averages",
    "iwan_cells_averages",
    "THRESHOLD_CELL_DECADES",
    "threshold_cell_edges",
    "lugre_averages",
    "power_stiffness_harmonic_factor",
]


# ----------------------------------------------------------------------------- joints
@dataclass(frozen=True)
class JointAverages:
    """Dimensionless cycle averages of a joint at normalised slip amplitude ``y``.

    With ``kappa`` the joint's small-amplitude modal stiffness and ``a_s`` its slip
    scale in modal units (``a = a_s y``):

    Attributes
    ----------
    dissipation : ndarray
        ``d(y) = D / (kappa a_s^2)``, energy dissipated per cycle.
    inphase : ndarray
        ``g(y) = K1 / kappa``, first-harmonic in-phase stiffness (1 while stuck).
    tip_energy_slope : ndarray or None
        ``de/dy`` where ``e(y) = E_tip / (kappa a_s^2)`` is the energy the joint
        stores at a turning point; None when only ``tip_energy`` is known.
    tip_energy : ndarray or None
        ``e(y)`` itself (used to differentiate numerically when the slope is None).
    """

    dissipation: np.ndarray
    inphase: np.ndarray
    tip_energy_slope: np.ndarray | None = None
    tip_energy: np.ndarray | None = None


def dahl_averages(y: ArrayLike) -> JointAverages:
    """Cycle averages of the Dahl joint (paper eq. 4) under ``u = A cos(omega t)``.

    Derivation (``y = sigma A / Fc``, force normalised by ``Fc``): the descending
    branch from the tip is ``F/Fc = -1 + (1 + tanh y) exp(-y (1 - cos psi))``
    (tip force ``Fc tanh y`` from loop symmetry). Then

    * ``D = 4 Fc A - 4 Fc^2/sigma tanh(y)``  ->  ``d = 4 (y - tanh y)``;
    * ``K1 = (1/(pi A)) int F cos psi dpsi``; with ``int_0^pi e^{y cos psi} cos psi dpsi
      = pi I1(y)``: ``g = (2/y)(1 + tanh y) e^{-y} I1(y)`` (-> 1 - 3y^2/8 for small y,
      -> 0 like ``y^-3/2`` in macro-slip: Coulomb friction has no in-phase part);
    * tip energy ``sigma z_tip^2 / 2`` -> ``e = tanh(y)^2/2``, ``de/dy = tanh y sech^2 y``.

    Parameters
    ----------
    y : array_like
        Slip amplitude over the slip scale ``Fc / sigma`` (dimensionless, >= 0).

    Returns
    -------
    JointAverages
    """
    from scipy import special

    y = np.abs(np.asarray(y, dtype=float))
    small = y < 1e-3
    ys = np.where(small, 1.0, y)
    th = np.tanh(y)
    d = np.where(small, 4.0 * (y**3 / 3.0 - 2.0 * y**5 / 15.0), 4.0 * (y - th))
    g = np.where(small, 1.0 - 0.375 * y**2, (2.0 / ys) * (1.0 + th) * special.i1e(ys))
    slope = th * (1.0 - th**2)
    return JointAverages(d, g, tip_energy_slope=slope)


def jenkins_dissipation(x: ArrayLike, t: ArrayLike) -> np.ndarray:
    """Energy per cycle of a unit-stiffness Jenkins element, ``4 t (x - t)`` when ``x > t``.

    Parameters
    ----------
    x : array_like
        Slip amplitude (any length unit).
    t : array_like
        Slip onset (slider limit over stiffness), same unit.

    Returns
    -------
    ndarray
        Dissipation per unit element stiffness, unit^2.
    """
    x = np.asarray(x, dtype=float)
    t = np.asarray(t, dtype=float)
    return 4.0 * t * np.maximum(x - t, 0.0)


def jenkins_inphase(tau: ArrayLike) -> np.ndarray:
    """In-phase first-harmonic stiffness of a Jenkins element per unit stiffness.

    ``h = (theta - sin(theta) cos(theta)) / pi`` with ``cos(theta) = 1 - 2 tau`` where
    ``tau = onset / amplitude``; 1 while stuck (``tau >= 1``), ``~ (16 / 3 pi) tau^1.5``
    deep in slip.

    Parameters
    ----------
    tau : array_like
        Slip onset over slip amplitude (dimensionless, >= 0).
    """
    tau = np.asarray(tau, dtype=float)
    cos_t = np.clip(1.0 - 2.0 * tau, -1.0, 1.0)
    theta = np.arccos(cos_t)
    return (theta - np.sin(theta) * cos_t) / np.pi


_GL_CACHE: dict[int, tuple[np.ndarray, np.ndarray]] = {}


def _gauss_legendre01(n: int) -> tuple[np.ndarray, np.ndarray]:
    if n not in _GL_CACHE:
        nodes, weights = np.polynomial.legendre.leggauss(n)
        _GL_CACHE[n] = (0.5 * (nodes + 1.0), 0.5 * weights)
    return _GL_CACHE[n]


def iwan_averages(x: ArrayLike, chi: ArrayLike, macro_ratio: ArrayLike, n_nodes: int = 24) -> JointAverages:
    """Cycle averages of Segalman's four-parameter Iwan joint (unit total stiffness).

    Jenkins elements (unit stiffness density) with slip onsets ``t`` distributed as
    ``rho(t) = R t^chi`` on ``0 < t < 1`` plus a macro-slip element of stiffness ``S`` at
    ``t = 1``; ``R / (chi + 1) + S = 1`` and ``S / (R / (chi + 1)) = macro_ratio``.

    * ``d(x) = int rho(t) 4 t (x - t) dt`` = ``4 R x^(chi+3) / ((chi+2)(chi+3))`` below
      macro-slip (``x <= 1``), so ``zeta ~ x^(1 + chi)``;
    * ``g(x) = int rho(t) h(t/x) dt`` (Gauss-Legendre in ``w = (t/m)^(chi+1)``, which
      removes the ``t^chi`` singularity);
    * only stuck elements store more energy as ``x`` grows: ``de/dx = x * (stiffness of
      the elements with onset > x)``.

    Parameters
    ----------
    x : array_like
        Slip amplitude over the largest slip onset (macro-slip at ``x = 1``).
    chi : array_like
        Power-law exponent of the onset density, ``> -1``.
    macro_ratio : array_like
        Stiffness of the macro-slip element over that of the distributed elements, >= 0.
    n_nodes : int
        Quadrature nodes for ``g``.

    Returns
    -------
    JointAverages
    """
    x, chi, beta = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, chi, macro_ratio)))
    x = np.abs(x)
    cp1 = chi + 1.0
    r_density = cp1 / (1.0 + beta)
    s_macro = beta / (1.0 + beta)
    m = np.minimum(x, 1.0)
    below = x <= 1.0
    d_below = 4.0 * r_density * m ** (chi + 3.0) / ((chi + 2.0) * (chi + 3.0))
    d_above = 4.0 * r_density * (x / (chi + 2.0) - 1.0 / (chi + 3.0)) + 4.0 * s_macro * (x - 1.0)
    d = np.where(below, d_below, d_above)
    nodes, weights = _gauss_legendre01(n_nodes)
    safe_x = np.where(x > 0, x, 1.0)
    t_nodes = m[..., None] * nodes ** (1.0 / cp1[..., None])
    h = jenkins_inphase(t_nodes / safe_x[..., None])
    slipped = r_density * m**cp1 / cp1 * np.sum(weights * h, axis=-1)
    stuck_distributed = r_density * (1.0 - m**cp1) / cp1
    macro = s_macro * np.where(below, 1.0, jenkins_inphase(1.0 / safe_x))
    g = np.where(x > 0, slipped + stuck_distributed + macro, 1.0)
    slope = x * (stuck_distributed + np.where(below, s_macro, 0.0))
    return JointAverages(d, g, tip_energy_slope=slope)


def _jenkins_log_integral_table(n: int = 20001) -> tuple[np.ndarray, np.ndarray]:
    """``H(tau) = int_0^tau h(s) / s ds`` of :func:`jenkins_inphase` on ``0 <= tau <= 1``.

    ``h(s) ~ (16 / 3 pi) s^1.5`` near 0, so the integrand is bounded; the trapezoid rule
    on 20001 points is accurate to ~1e-9 (linear interpolation between them adds
    ~1e-10).
    """
    tau = np.linspace(0.0, 1.0, n)
    integrand = np.zeros(n)
    integrand[1:] = jenkins_inphase(tau[1:]) / tau[1:]
    table = np.concatenate([[0.0], np.cumsum(0.5 * (integrand[1:] + integrand[:-1]) * np.diff(tau))])
    return tau, table


_JENKINS_LOG_TAU, _JENKINS_LOG_H = _jenkins_log_integral_table()
_JENKINS_LOG_SLOPE = np.diff(_JENKINS_LOG_H) / np.diff(_JENKINS_LOG_TAU)


THRESHOLD_CELL_DECADES = 0.25
"""Width of a slip-threshold cell, in decades of threshold. A smooth density of thresholds
(the lab's contact patches: 12,000 slip onsets spread over three decades) leaves half-decade
cells 5-9 scatters off the noise-free curves of a sensor that sees the mode three times
better than the reference one (frequency scatter 9e-6): the staircase's kinks. Quarter-decade
cells follow them within 1.3."""


def threshold_cell_edges(n_cells: int) -> np.ndarray:
    """Edges of the slip-threshold cells, :data:`THRESHOLD_CELL_DECADES` wide, the top one at 1.

    In units of the joint's slip scale (the measured amplitude range's top, see
    :data:`workflow.models.averaged.MODELS` ``iwan_cells_<n>``): ``10^((k - n) / 4)`` for
    ``k = 0 .. n``.
    """
    return 10.0 ** ((np.arange(n_cells + 1) - n_cells) * THRESHOLD_CELL_DECADES)


def _cells_loop(x_all, shares, edges, tau_table, h_table, slope_table):
    """:func:`iwan_cells_averages` per amplitude (compiled by :func:`_cells_kernel`)."""
    n, k = shares.shape
    log_edges = np.log(edges)
    last = tau_table.size - 1
    dissipation, inphase, energy_slope = np.empty(n), np.empty(n), np.empty(n)
    h_edges = np.empty(k + 1)
    for i in range(n):
        x = abs(x_all[i])
        if np.isnan(x):  # a fit's trial point beyond the curves' range stays NaN
            dissipation[i] = inphase[i] = energy_slope[i] = np.nan
            continue
        log_x = np.log(x) if x > 0 else log_edges[0]
        if x > 0:
            # H(min(t_j / x, 1)) at every edge, with np.interp's arithmetic on the table
            for j in range(k + 1):
                tau = min(edges[j] / x, 1.0)
                at = min(max(int(tau * last), 0), last - 1)
                if tau_table[at] > tau:
                    at -= 1
                if at < last - 1 and tau_table[at + 1] <= tau:
                    at += 1
                if tau >= 1.0:
                    h_edges[j] = h_table[last]
                elif tau == tau_table[at]:
                    h_edges[j] = h_table[at]
                else:
                    h_edges[j] = slope_table[at] * (tau - tau_table[at]) + h_table[at]
        d = g = stuck_all = 0.0
        for c in range(k):
            low, high = edges[c], edges[c + 1]
            density = shares[i, c] / (log_edges[c + 1] - log_edges[c])
            stuck = density * (log_edges[c + 1] - min(max(log_x, log_edges[c]), log_edges[c + 1]))
            if x > 0:
                m = min(max(x, low), high)
                d += 4.0 * density * (x * (m - low) - 0.5 * (m * m - low * low))
                g += density * (h_edges[c + 1] - h_edges[c])
            g += stuck
            stuck_all += stuck
        dissipation[i], inphase[i], energy_slope[i] = d, g, x * stuck_all
    return dissipation, inphase, energy_slope


@functools.cache
def _cells_kernel():
    """:func:`_cells_loop` compiled by Numba (cached on disk), at the first call: the jobs
    that import the models only to draw do not import Numba."""
    import numba

    return numba.njit(cache=True, error_model="numpy")(_cells_loop)


def iwan_cells_averages(y: ArrayLike, shares: ArrayLike) -> JointAverages:
    """Cycle averages of a parallel Jenkins (Iwan) joint with a piecewise slip-threshold density.

    The slip thresholds ``t`` (unit stiffness density) fill cells a quarter of a decade
    wide (:func:`threshold_cell_edges`), uniformly in ``ln t`` within each: cell ``k`` holds
    the stiffness share ``shares[k]`` with density ``c_k / t``, ``c_k = shares[k] /
    ln(t_(k+1) / t_k)``. Any Masing joint made of Jenkins elements is such a joint for
    some density (Iwan 1966); the cells let the data set it where the amplitudes reach.
    With ``m = clip(x, t_k, t_(k+1))``, per cell:

    * ``d = int c/t 4 t (x - t) dt = 4 c (x (m - t_k) - (m^2 - t_k^2) / 2)``;
    * ``g = c (H(m/x) - H(t_k/x)) + c ln(t_(k+1) / m)`` with ``H(tau) = int_0^tau h(s)/s ds``
      (slipping elements' in-phase stiffness, then the stuck ones'; ``H(m/x) - H(t_k/x)``
      is ``H(min(t_(k+1)/x, 1)) - H(min(t_k/x, 1))``, so ``H`` is read once per edge);
    * ``de/dx = x c ln(t_(k+1) / m)`` (only stuck elements store more energy).

    ``H`` is interpolated linearly in its table (:func:`_jenkins_log_integral_table`).

    Parameters
    ----------
    y : array_like
        Slip amplitude over the top edge of the cells.
    shares : array_like, shape ``B + (K,)``
        Stiffness share of each cell (summing to 1); ``B`` broadcasts against ``y``'s shape.

    Returns
    -------
    JointAverages
    """
    shares = np.asarray(shares, dtype=float)
    n_cells = shares.shape[-1]
    y = np.asarray(y, dtype=float)
    shape = np.broadcast_shapes(y.shape, shares.shape[:-1])
    averages = _cells_kernel()(
        np.array(np.broadcast_to(y, shape)).reshape(-1),
        np.array(np.broadcast_to(shares, shape + (n_cells,))).reshape(-1, n_cells),
        threshold_cell_edges(n_cells),
        _JENKINS_LOG_TAU,
        _JENKINS_LOG_H,
        _JENKINS_LOG_SLOPE,
    )
    d, g, slope = (a.reshape(shape) for a in averages)
    return JointAverages(d, g, tip_energy_slope=slope)


def lugre_averages(
    y: ArrayLike,
    velocity_ratio: ArrayLike,
    stiction_ratio: ArrayLike,
    micro_damping: ArrayLike,
    n_steps: int = 32,
) -> JointAverages:
    """Cycle averages of the LuGre joint (paper eq. 5) on its steady periodic cycle.

    Normalised with ``z~ = sigma0 z / alpha0`` and ``u~ = sigma0 u / alpha0 = y cos psi``,
    the state equation is linear in ``z~``:
    ``dz~/dpsi = du~/dpsi (1 + z~ / g~(psi))`` on the descending half cycle, with
    ``g~ = 1 + stiction_ratio exp(-(velocity_ratio sin psi)^2)``. Freezing ``g~`` at each
    step's mid-phase, ``z~ + g~`` decays exactly by ``exp(du~ / g~)``, so the half-cycle
    map is affine, ``z~_N = P z~_0 + Q``; loop symmetry ``z~_N = -z~_0`` gives the
    periodic state without transient cycles. The force is
    ``F~ = z~ + micro_damping exp(-(velocity_ratio sin psi)^2) dz~/dpsi``
    (``micro_damping = sigma1 omega / sigma0``; ``v_d = v_0``). Then
    ``d = 2 int_0^pi F~ (-du~/dpsi) dpsi`` (positive for a dissipative loop),
    ``g = (2 / (pi y)) int_0^pi F~ cos psi dpsi`` and ``e = z~_tip^2 / 2``.
    The trapezoid rule over the phase is used: for these periodic integrands it
    converges spectrally (Dahl limit: 1e-7 relative at 160 steps; ~1e-3 in the in-phase
    part at 32 steps, far below the models' accuracy class).

    Parameters
    ----------
    y : array_like
        Slip amplitude over ``alpha0 / sigma0``.
    velocity_ratio : array_like
        Slip velocity amplitude over the Stribeck velocity ``v0`` (= measured velocity
        amplitude over the Stribeck velocity in measured units).
    stiction_ratio : array_like
        ``alpha1 / alpha0`` (>= 0 for stiction above the Coulomb level).
    micro_damping : array_like
        ``sigma1 omega / sigma0`` (dimensionless; may be negative as in the paper's fit).
    n_steps : int
        Phase steps over the half cycle.

    Returns
    -------
    JointAverages
        ``tip_energy`` is given (``tip_energy_slope`` is None).
    """
    y, w, s, tw = np.broadcast_arrays(
        *(np.asarray(v, dtype=float) for v in (y, velocity_ratio, stiction_ratio, micro_damping))
    )
    y = np.maximum(np.abs(y), 1e-12)
    psi = np.linspace(0.0, np.pi, n_steps + 1)
    cos_p, sin_p = np.cos(psi), np.sin(psi)
    sin_mid = np.sin(0.5 * (psi[1:] + psi[:-1]))
    shape = (n_steps,) + (1,) * y.ndim
    # all steps at once: mid-step Stribeck factor and exact decay of (z~ + g~)
    g_mid = 1.0 + s * np.exp(-((w * sin_mid.reshape(shape)) ** 2))
    decays = np.exp(-y * (cos_p[:-1] - cos_p[1:]).reshape(shape) / g_mid)
    offsets = g_mid * (decays - 1.0)
    p_map = np.prod(decays, axis=0)
    q_map = np.zeros(y.shape)
    for j in range(n_steps):  # affine half-cycle map z_N = P z_0 + Q
        q_map = decays[j] * q_map + offsets[j]
    z = np.empty((n_steps + 1,) + y.shape)
    z[0] = -q_map / (1.0 + p_map)
    for j in range(n_steps):
        z[j + 1] = decays[j] * z[j] + offsets[j]
    node_shape = (n_steps + 1,) + (1,) * y.ndim
    stribeck = np.exp(-((w * sin_p.reshape(node_shape)) ** 2))
    du = -y * sin_p.reshape(node_shape)
    force = z + tw * stribeck * du * (1.0 + z / (1.0 + s * stribeck))
    trap = np.full(n_steps + 1, np.pi / n_steps)
    trap[[0, -1]] *= 0.5
    trap = trap.reshape(node_shape)
    diss = np.sum(trap * force * du, axis=0)
    inph = np.sum(trap * force * cos_p.reshape(node_shape), axis=0)
    z_tip = z[0]
    return JointAverages(2.0 * diss, 2.0 * inph / (np.pi * y), tip_energy=0.5 * z_tip**2)


def power_stiffness_harmonic_factor(p: ArrayLike) -> np.ndarray:
    """``c_p = (1/pi) int_0^{2 pi} |cos psi|^(p+2) dpsi`` for a restoring force ``k_p |x|^p x``.

    Its in-phase first harmonic at amplitude ``a`` is ``c_p k_p a^p`` (cubic, ``p = 2``:
    3/4), its potential ``k_p a^(p+2) / (p + 2)``.
    """
    from scipy import special

    m = np.asarray(p, dtype=float) + 2.0
    return 2.0 / np.sqrt(np.pi) * np.exp(special.gammaln((m + 1.0) / 2.0) - special.gammaln(m / 2.0 + 1.0))
