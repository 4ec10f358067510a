"""Fit the paper's friction models (Dahl, LuGre) to measured damping and frequency curves.

A configuration's measured segments (all runs) give damping ratio and frequency versus
velocity amplitude. A candidate parameter set is judged by simulating a ring-down
(:mod:`workflow.models.ringdown`) and passing the simulated response through the *same* chain
as the measurements (band-pass, envelope of the analytic signal, segmented log
decrement; :mod:`workflow.measured.decay`), so any bias of that chain affects both alike.

One simulated ring-down per parameter set
-----------------------------------------
The system is autonomous and, once the virgin start of the friction state has been
forgotten, a ring-down passes through every smaller amplitude in the same state whatever
amplitude it started from. So one simulation started *above* the largest run's starting
amplitude (by ``start_margin``) covers all runs; its own start-up (virgin friction state
and filter transient) then lies at amplitudes above the measured ones. It is run longer
than a record by the time the slowest measured decay needs to go from the largest to the
smallest starting amplitude, so it also reaches the smallest measured amplitudes.

Objective
---------
Residuals per measured segment: ``(ln zeta_meas - ln zeta_model) / s_zeta`` and
``(f_meas - f_model) / f_meas / s_f``, the model curves interpolated (in log amplitude)
at the measured amplitudes. ``s_zeta`` and ``s_f`` are the local scatter of the
measurements about a smooth curve (cubic in log amplitude, all runs pooled, RMS in
amplitude bins; :func:`measurement_scatter`): run-to-run scatter plus noise, larger
near the noise floor. Cost = half the sum of squares.

Search
------
Parameters are mapped to a box in which they are roughly independent: stuck-joint
frequency ``f0``, friction share of the stuck stiffness ``r = phi^2 sigma / omega0^2``,
knee velocity ``v_knee = omega0 Fc / (sigma phi)`` (response units: where slip saturates),
``zeta0``; all but ``f0`` log-scaled. A scrambled Sobol batch over the box is simulated
in one batched call; the best ``local_starts`` are refined together by a batched
Levenberg-Marquardt: each iteration simulates, for every start, two trial steps (a
smaller and a larger damping) in one call, then the forward-difference Jacobian of each
accepted trial in a second. The compiled simulator costs the same per ring-down whatever
the batch, so the Jacobians of rejected trials, which an earlier one-call iteration also
simulated, are not worth simulating (a third fewer ring-downs per fit, the same result
to the bit: every ring-down is simulated and analysed on its own).

Uncertainty
-----------
Linearised: ``cov = s^2 (J^T J)^-1`` in the search coordinates at the optimum, with
``s^2 = 2 cost / (N - p)``, inflated by ``1 / (1 - segment_overlap)`` because overlapping
segments are not independent, and propagated to the physical parameters by the
delta method. It does not include model error beyond what ``s^2`` absorbs.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from workflow.measured import filters, segment_fits
from workflow.measured.settings import AnalysisSettings
from workflow.models.ringdown import simulate_ringdown
from workflow.models.sampling import scrambled_sobol_points
from workflow.models.settings import ModelSettings

__all__ = [
    "RingdownFitContext",
    "RingdownFitResult",
    "simulation_rate_hz",
    "ModelSpace",
    "model_space",
    "analyse_batch",
    "simulated_curves",
    "fit_friction_model",
    "measurement_scatter",
]


@dataclass(frozen=True)
class RingdownFitContext:
    """Modal and analysis context shared by measurements and simulations.

    Attributes
    ----------
    fs_hz : float
        Sample rate of the simulated records, Hz (:func:`simulation_rate_hz` of the
        measured records' rate).
    band_hz : (float, float)
        Band-pass edges, Hz.
    record_duration_s : float
        Length of a measured record, s.
    slip_per_modal : float
        ``phi_s``, joint slip per unit modal coordinate (1: parameters absorb scale).
    response_per_modal : float
        Sensor displacement per unit modal coordinate, in (1: same absorption).
    response : {"acceleration", "velocity", "displacement"}
        Measured quantity, so the simulated one is analysed in the same form.
    analysis : AnalysisSettings
        The decay analysis the measurements went through (filter order, segment length
        and overlap, edge time constants); the simulations go through the same.
    steps_per_period : int
        Simulator steps per period (minimum; see :func:`simulate_ringdown`).
    """

    fs_hz: float
    band_hz: tuple[float, float]
    record_duration_s: float
    slip_per_modal: float = 1.0
    response_per_modal: float = 1.0
    response: str = "acceleration"
    analysis: AnalysisSettings = field(default_factory=AnalysisSettings)
    steps_per_period: int = ModelSettings.steps_per_period


SIMULATED_SAMPLES_PER_BAND_PERIOD = 16
"""Samples per period of the band-pass's upper edge in a simulated record (at least)."""


def simulation_rate_hz(sample_rate_hz: float, band_hz: tuple[float, float]) -> float:
    """Sample rate of the simulated ring-downs, Hz: the record's, divided by the largest
    integer that keeps :data:`SIMULATED_SAMPLES_PER_BAND_PERIOD` samples per period of
    the band's upper edge.

    A simulated ring-down is a noise-free single mode inside the band, so the damping
    and frequency the decay analysis finds in it do not depend on the sample rate once
    the band is well resolved: the fit needs the mode's periods and the measured
    amplitudes, not the record's rate (a 12.8 kHz record of a 125 Hz mode is simulated
    at 2560 Hz, the demo's own rate, which is kept). Between 1.6 and 12.8 kHz the
    simulated curves of the demo's Dahl and LuGre fits differ by at most 1e-2 in
    ``ln zeta`` (median 1e-4) and 4e-6 in relative frequency, below the averaged models'
    accuracy (0.02, 1e-4) and the measured scatter (tests/test_models_fitting.py).
    """
    factor = max(1, int(sample_rate_hz // (SIMULATED_SAMPLES_PER_BAND_PERIOD * band_hz[1])))
    return sample_rate_hz / factor


@dataclass
class RingdownFitResult:
    """Outcome of :func:`fit_friction_model`.

    Attributes
    ----------
    model : str
    params : dict of float
        Physical parameters: friction parameters (lbf, in, s units), ``zeta0``,
        ``omega_rad_s`` (linear mode without joint), ``f_linear_hz``.
    uncertainties : dict of float
        One standard deviation of each entry of ``params`` (linearised).
    cost : float
        Half the sum of squared normalised residuals.
    rms_log_zeta : float
        RMS of ``ln zeta_meas - ln zeta_model`` (relative damping error).
    rms_rel_frequency : float
        RMS of ``(f_meas - f_model) / f_meas``.
    curves : dict of ndarray
        Simulated ``velocity_amplitude_in_s``, ``zeta``, ``frequency_hz`` at the optimum.
    predicted : dict of ndarray
        Model ``zeta`` and ``frequency_hz`` at the measured amplitudes.
    search_point : ndarray
        Optimum in the search coordinates; ``n_simulations``: ring-downs simulated.
    """

    model: str
    params: dict[str, float]
    uncertainties: dict[str, float]
    cost: float
    rms_log_zeta: float
    rms_rel_frequency: float
    curves: dict[str, np.ndarray]
    predicted: dict[str, np.ndarray]
    search_point: np.ndarray
    n_simulations: int
    scatter: dict[str, float] = field(default_factory=dict)


# ------------------------------------------------------------------ parameter space
@dataclass(frozen=True)
class ModelSpace:
    """Search box of a model and the map from search coordinates to parameters."""

    model: str
    names: tuple[str, ...]
    lower: np.ndarray
    upper: np.ndarray
    to_physical: Callable[[np.ndarray], dict[str, np.ndarray]]


def model_space(
    model: str,
    velocity_amplitude_in_s: np.ndarray,
    zeta: np.ndarray,
    frequency_hz: np.ndarray,
    ctx: RingdownFitContext,
) -> ModelSpace:
    """Search box derived from the measured ranges and the physical parameter map.

    Search coordinates (Dahl): ``f0_hz``, ``log10 r``, ``log10 v_knee_in_s``,
    ``log10 zeta0``. LuGre adds ``log10 alpha1/alpha0``, ``log10 v0``, ``log10 vd`` (in
    response velocity units) and the damping ratios ``zeta_sigma1`` (signed, the paper's
    fit has ``sigma1 < 0``) and ``zeta_alpha2`` of ``sigma1`` and ``alpha2``.
    """
    v = np.asarray(velocity_amplitude_in_s, float)
    z = np.asarray(zeta, float)
    f = np.asarray(frequency_hz, float)
    v_lo, v_hi = np.log10(v.min() / 10.0), np.log10(v.max() * 10.0)
    z_hi = float(np.max(z))
    lower = [f.min() * 0.995, -4.0, v_lo, np.log10(max(z_hi * 1e-3, 1e-6))]
    upper = [f.max() * 1.05, np.log10(0.5), v_hi, np.log10(max(z_hi, 1e-5))]
    phi, resp = ctx.slip_per_modal, ctx.response_per_modal

    def base(theta):
        theta = np.atleast_2d(theta)
        omega0 = 2.0 * np.pi * theta[:, 0]
        r = 10.0 ** theta[:, 1]
        v_knee_modal = 10.0 ** theta[:, 2] / resp
        stiff = r * omega0**2 / phi**2
        force = stiff * phi * v_knee_modal / omega0  # Fc / sigma = slip at the knee
        return omega0, r, stiff, force, 10.0 ** theta[:, 3]

    if model == "dahl":
        names = ("f0_hz", "log10_r", "log10_v_knee_in_s", "log10_zeta0")

        def to_physical(theta):
            omega0, r, stiff, force, zeta0 = base(theta)
            omega = omega0 * np.sqrt(1.0 - r)
            return {"sigma": stiff, "fc": force, "zeta0": zeta0 * omega0 / omega, "omega_rad_s": omega}
    elif model == "lugre":
        names = (
            "f0_hz",
            "log10_r",
            "log10_v_knee_in_s",
            "log10_zeta0",
            "log10_alpha1_over_alpha0",
            "log10_v0_in_s",
            "log10_vd_in_s",
            "zeta_sigma1",
            "zeta_alpha2",
        )
        lower += [-3.0, v_lo, v_lo, -z_hi, 0.0]
        upper += [1.0, v_hi, v_hi, z_hi, z_hi]

        def to_physical(theta):
            theta = np.atleast_2d(theta)
            omega0, r, stiff, force, zeta0 = base(theta)
            omega = omega0 * np.sqrt(1.0 - r)
            slip_vel = phi / resp  # response velocity -> slip velocity
            return {
                "sigma0": stiff,
                "alpha0": force,
                "alpha1": force * 10.0 ** theta[:, 4],
                "v0": 10.0 ** theta[:, 5] * slip_vel,
                "vd": 10.0 ** theta[:, 6] * slip_vel,
                "sigma1": 2.0 * omega0 * theta[:, 7] / phi**2,
                "alpha2": 2.0 * omega0 * theta[:, 8] / phi**2,
                "zeta0": zeta0 * omega0 / omega,
                "omega_rad_s": omega,
            }
    else:
        raise ValueError(f"unknown model {model!r}; expected 'dahl' or 'lugre'")
    return ModelSpace(model, names, np.array(lower), np.array(upper), to_physical)


# ------------------------------------------------------------------------- analysis
def analyse_batch(responses: np.ndarray, ctx: RingdownFitContext) -> list[dict[str, np.ndarray]]:
    """Segmented log decrement of simulated records, chain of :mod:`workflow.measured.decay`.

    Same band-pass (analytic signal first), envelope and segments as the measurements;
    the decay starts at the envelope maximum and segments within ``edge_time_constants``
    filter time constants of it or of the record end are dropped. There is no noise, so
    no noise-floor rule; non-finite records give empty curves.

    Returns
    -------
    list of dict
        Per record ``velocity_amplitude_in_s``, ``zeta``, ``frequency_hz``, sorted by
        amplitude.
    """
    out = []
    tau = filters.filter_time_constant_s(ctx.band_hz)
    edge = int(np.ceil(ctx.analysis.edge_time_constants * tau * ctx.fs_hz))
    for x in np.atleast_2d(responses):
        empty = {k: np.empty(0) for k in ("velocity_amplitude_in_s", "zeta", "frequency_hz")}
        if not np.all(np.isfinite(x)) or not np.any(x):
            out.append(empty)
            continue
        z = filters.analytic_bandpass(x, ctx.fs_hz, ctx.band_hz, ctx.analysis.filter_order)
        env = np.abs(z)
        phase = filters.unwrapped_phase_rad(z)
        start = int(np.argmax(env))
        n = x.size
        mode_hz = float(np.mean(np.diff(phase[start:])) * ctx.fs_hz / (2 * np.pi))
        if not np.isfinite(mode_hz) or mode_hz <= 0:
            out.append(empty)
            continue
        starts, stops = segment_fits.segment_bounds(
            start + edge,
            n - edge,
            ctx.fs_hz,
            mode_hz,
            ctx.analysis.segment_cycles,
            ctx.analysis.segment_overlap,
        )
        seg = segment_fits.log_decrement_segments(env, phase, ctx.fs_hz, starts, stops)
        amp, zeta, freq = seg["amplitude"], seg["zeta"], seg["frequency_hz"]
        ok = np.isfinite(zeta) & np.isfinite(freq) & (amp > 0) & (freq > 0)
        amp, zeta, freq = amp[ok], zeta[ok], freq[ok]
        scale = {
            "acceleration": 1.0 / (2 * np.pi * freq),
            "velocity": np.ones_like(freq),
            "displacement": 2 * np.pi * freq,
        }[ctx.response]
        vel = amp * scale
        order = np.argsort(vel)
        out.append({"velocity_amplitude_in_s": vel[order], "zeta": zeta[order], "frequency_hz": freq[order]})
    return out


def simulated_curves(
    model: str,
    phys: dict[str, np.ndarray],
    ctx: RingdownFitContext,
    *,
    start_velocity_in_s: float,
    duration_s: float,
) -> list[dict[str, np.ndarray]]:
    """Simulate a batch of ring-downs and analyse them like the measurements.

    Parameters
    ----------
    model : {"dahl", "lugre"}
    phys : dict of ndarray
        Physical parameters (batch,), including ``omega_rad_s`` and ``zeta0``.
    ctx : RingdownFitContext
    start_velocity_in_s : float
        Starting velocity amplitude at the sensor, in/s.
    duration_s : float
        Simulated duration, s.
    """
    joint = {k: v for k, v in phys.items() if k not in ("omega_rad_s", "zeta0")}
    with np.errstate(all="ignore"):
        sim = simulate_ringdown(
            model,
            joint,
            omega_rad_s=phys["omega_rad_s"],
            zeta0=phys["zeta0"],
            slip_per_modal=ctx.slip_per_modal,
            initial_velocity=start_velocity_in_s / ctx.response_per_modal,
            fs_out_hz=ctx.fs_hz,
            duration_s=duration_s,
            steps_per_period=ctx.steps_per_period,
        )
        response = ctx.response_per_modal * sim[ctx.response]
    return analyse_batch(response, ctx)


def measurement_scatter(
    velocity_amplitude_in_s, zeta, frequency_hz, degree: int = 3, bins: int = 8, min_per_bin: int = 8
) -> tuple[np.ndarray, np.ndarray]:
    """Local scatter of ``ln zeta`` and of relative frequency about smooth trends.

    The trends are polynomials of ``degree`` in ``ln v`` (all runs pooled). The scatter
    is the RMS of the trend residuals in ``bins`` equal-count bins of amplitude, so
    noisy low-amplitude segments weigh less than clean ones (the scatter grows as the
    noise floor is approached). Each value is at least 1e-6.

    Returns
    -------
    s_log_zeta, s_rel_frequency : ndarray, shape (N,)
        Per segment, dimensionless.
    """
    x = np.log(np.asarray(velocity_amplitude_in_s, float))
    f = np.asarray(frequency_hz, float)
    order = np.argsort(x)
    n_bins = max(1, min(bins, x.size // max(min_per_bin, 1)))
    groups = np.array_split(order, n_bins)
    out = []
    for y in (np.log(np.asarray(zeta, float)), f / np.mean(f)):
        deg = min(degree, max(0, x.size - 2))
        resid = y - np.polyval(np.polyfit(x, y, deg), x)
        dof = max(1.0, 1.0 - (deg + 1) / x.size)
        s = np.empty_like(y)
        for g in groups:
            s[g] = np.sqrt(np.mean(resid[g] ** 2) / dof)
        out.append(np.maximum(s, 1e-6))
    return out[0], out[1]


def _interp_log(v_meas, curve, key):
    v = curve["velocity_amplitude_in_s"]
    if v.size < 2:
        return np.full(v_meas.shape, np.nan)
    # np.interp clamps outside the simulated range: a model that does not reach an
    # amplitude is judged by its nearest value there.
    return np.interp(np.log(v_meas), np.log(v), curve[key])


def _residuals(curves, v, ln_zeta, freq, s_z, s_f):
    """Normalised residual vectors (batch, 2N); failed simulations give large values."""
    res = np.empty((len(curves), 2 * v.size))
    for i, c in enumerate(curves):
        zm = _interp_log(v, c, "zeta")
        fm = _interp_log(v, c, "frequency_hz")
        with np.errstate(invalid="ignore", divide="ignore"):
            rz = (ln_zeta - np.log(zm)) / s_z
        rf = (freq - fm) / freq / s_f
        r = np.concatenate([rz, rf])
        res[i] = np.where(np.isfinite(r), r, 1e3)
    return res


# ---------------------------------------------------------------------------- fit
def fit_friction_model(
    model: str,
    velocity_amplitude_in_s,
    zeta,
    frequency_hz,
    run,
    start_velocity_in_s,
    ctx: RingdownFitContext,
    *,
    global_samples: int = 256,
    local_starts: int = 4,
    max_iterations: int = 12,
    seed: int = ModelSettings.seed,
    start_margin: float = 1.3,
    initial_points=None,
) -> RingdownFitResult:
    """Fit Dahl or LuGre (plus zeta0 and the linear frequency) to measured curves.

    Parameters
    ----------
    model : {"dahl", "lugre"}
    velocity_amplitude_in_s, zeta, frequency_hz : array_like, shape (N,)
        Measured segments (kept ones), all runs of one configuration.
    run : array_like, shape (N,)
        Run label of each segment (used for the start amplitudes and reporting).
    start_velocity_in_s : array_like
        Starting velocity amplitude of each run, in/s.
    ctx : RingdownFitContext
    global_samples, local_starts, seed
        Sobol batch size, number of refined candidates, generator seed.
    max_iterations : int
        Levenberg-Marquardt iterations per start.
    start_margin : float
        The simulation starts at this times the largest run start amplitude.
    initial_points : array_like, shape (K, n_coordinates), optional
        Search coordinates evaluated beside the global sample (e.g. the optimum of
        the averaged model, which is much cheaper to fit); they compete with it for
        the local starts.

    Returns
    -------
    RingdownFitResult
    """
    v = np.asarray(velocity_amplitude_in_s, float)
    z = np.asarray(zeta, float)
    f = np.asarray(frequency_hz, float)
    keep = np.isfinite(v) & np.isfinite(z) & np.isfinite(f) & (v > 0) & (z > 0)
    v, z, f = v[keep], z[keep], f[keep]
    if v.size < 5:
        raise ValueError(f"need at least 5 measured segments with zeta > 0, got {v.size}")
    starts = np.asarray(start_velocity_in_s, float)
    space = model_space(model, v, z, f, ctx)
    s_z, s_f = measurement_scatter(v, z, f)
    ln_z = np.log(z)
    v_start = start_margin * float(np.max(starts))
    # Extra time for the slowest measured decay to go from the largest to the smallest
    # starting amplitude (at most one more record).
    slowest = max(float(np.min(z)) * 2 * np.pi * float(np.min(f)), 1e-6)
    extra = np.log(v_start / max(float(np.min(starts)), 1e-12)) / slowest
    duration = ctx.record_duration_s + min(extra, ctx.record_duration_s)
    span = space.upper - space.lower
    n_sim = 0

    def evaluate(theta):
        nonlocal n_sim
        theta = np.clip(np.atleast_2d(theta), space.lower, space.upper)
        curves = simulated_curves(
            model, space.to_physical(theta), ctx, start_velocity_in_s=v_start, duration_s=duration
        )
        n_sim += theta.shape[0]
        return _residuals(curves, v, ln_z, f, s_z, s_f), curves

    # Global stage: one batched call over a scrambled Sobol sample of the box.
    theta0 = space.lower + scrambled_sobol_points(global_samples, span.size, seed) * span
    if initial_points is not None:
        extra = np.clip(np.atleast_2d(np.asarray(initial_points, float)), space.lower, space.upper)
        theta0 = np.concatenate([extra, theta0])
    res0, _ = evaluate(theta0)
    cost0 = 0.5 * np.sum(res0**2, axis=1)
    best = np.argsort(cost0)[:local_starts]
    theta = theta0[best]
    res = res0[best]
    cost = cost0[best]

    # Local stage: batched Levenberg-Marquardt over all starts at once.
    p = span.size
    dstep = 1e-3 * span

    def jacobians(points, base_res):
        pts = np.repeat(points, p, axis=0) + np.tile(np.diag(dstep), (points.shape[0], 1))
        r_pts, _ = evaluate(pts)
        return (r_pts.reshape(points.shape[0], p, -1) - base_res[:, None, :]).transpose(0, 2, 1) / dstep

    jac = jacobians(theta, res)
    mu = np.full(theta.shape[0], 1e-2)
    for _ in range(max_iterations):
        trials = []
        for k in range(theta.shape[0]):
            a = jac[k].T @ jac[k]
            g = jac[k].T @ res[k]
            for factor in (0.2, 5.0):
                lam = mu[k] * factor
                step = -np.linalg.solve(a + lam * np.diag(np.diag(a) + 1e-12), g)
                trials.append(np.clip(theta[k] + step, space.lower, space.upper))
        trials = np.array(trials)
        r_trial, _ = evaluate(trials)
        c_trial = 0.5 * np.sum(r_trial**2, axis=1)
        improved = False
        accepted = []  # the starts whose trial was accepted
        for k in range(theta.shape[0]):
            pair = [2 * k, 2 * k + 1]
            i = pair[int(np.argmin(c_trial[pair]))]
            if c_trial[i] < cost[k]:
                improved |= (cost[k] - c_trial[i]) > 1e-5 * cost[k]
                theta[k], res[k], cost[k] = trials[i], r_trial[i], c_trial[i]
                accepted.append(k)
                mu[k] = mu[k] * (0.2 if i == pair[0] else 5.0) / 2.0
            else:
                mu[k] *= 10.0
        if accepted:
            # the Jacobians at the accepted trials, in one batched simulation
            jac[accepted] = jacobians(theta[accepted], res[accepted])
        if not improved:
            break

    k = int(np.argmin(cost))
    theta_best, r_best, j_best = theta[k], res[k], jac[k]
    n_res = r_best.size
    s2 = 2.0 * cost[k] / max(1, n_res - p) / (1.0 - ctx.analysis.segment_overlap)
    cov = s2 * np.linalg.pinv(j_best.T @ j_best)
    phys = {key: float(val[0]) for key, val in space.to_physical(theta_best).items()}
    phys["f_linear_hz"] = phys["omega_rad_s"] / (2 * np.pi)
    # Delta method: numerical derivative of the physical map.
    grad = {}
    for i in range(p):
        e = np.zeros(p)
        e[i] = 1e-6 * span[i]
        hi = space.to_physical(theta_best + e)
        lo = space.to_physical(theta_best - e)
        for key in hi:
            grad.setdefault(key, np.zeros(p))[i] = (hi[key][0] - lo[key][0]) / (2 * e[i])
    grad["f_linear_hz"] = grad["omega_rad_s"] / (2 * np.pi)
    unc = {key: float(np.sqrt(max(g @ cov @ g, 0.0))) for key, g in grad.items()}
    _, curves = evaluate(theta_best)
    curve = curves[0]
    zm, fm = _interp_log(v, curve, "zeta"), _interp_log(v, curve, "frequency_hz")
    return RingdownFitResult(
        model=model,
        params=phys,
        uncertainties=unc,
        cost=float(cost[k]),
        rms_log_zeta=float(np.sqrt(np.mean((ln_z - np.log(zm)) ** 2))),
        rms_rel_frequency=float(np.sqrt(np.mean(((f - fm) / f) ** 2))),
        curves=curve,
        predicted={"velocity_amplitude_in_s": v, "zeta": zm, "frequency_hz": fm},
        search_point=theta_best,
        n_simulations=n_sim,
        scatter={"log_zeta": float(np.median(s_z)), "rel_frequency": float(np.median(s_f))},
    )
