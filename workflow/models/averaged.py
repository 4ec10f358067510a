"""Averaged (describing-function / energy-balance) ring-down models of one mode.

A mass-normalised mode with a joint, ``xi'' + c xi' + k_nj xi + phi F_joint(phi xi) +
f_extra = 0``, rings down slowly (damping ratio of a few percent at most). Over one
cycle its motion is nearly ``xi = a cos(omega t)``; averaging the force laws over that
cycle gives, as functions of the amplitude ``a``, everything a log-decrement analysis
measures:

* the **first-harmonic in-phase stiffness** ``K1(a)``, hence the oscillation frequency
  ``omega^2 = k_nj + K1(a)``;
* the **energy dissipated per cycle** ``D(a)``;
* the **energy at a turning point** ``E(a)`` (velocity zero: elastic energy of the
  structure plus what the joint stores at the loop tip).

Energy balance between successive turning points, ``dE/da * da = -D(a) / 2`` per half
cycle, gives the displacement-envelope decay rate ``s_a = -d ln a / dt =
D omega / (2 pi a dE/da)``. The turning-point energy (not the equivalent linear system
``k_eq a^2 / 2``) is what makes this exact to first order for hysteretic joints: it
agrees with a direct integration of the Dahl oscillator to ~0.1 % where the
equivalent-linear shortcut is off by up to 3 % (tests/test_models_averaged.py).

The pipeline measures the band-passed response, i.e. the fundamental harmonic of the
recorded quantity, whose amplitude is ``omega^n a`` (``n`` = 0, 1, 2 for displacement,
velocity, acceleration). Its envelope decays at ``s_a (1 + n dln(omega)/dln(a))``; the
pipeline reports ``zeta = s / sqrt(s^2 + omega_d^2)`` and ``f = omega_d / 2 pi``
(:mod:`workflow.measured.decay`), and so does this module.

Identifiable parametrisation
----------------------------
The sensor's mode-shape value ``psi`` and the joint's slip per modal coordinate
``phi`` are unknown, so every model is written in quantities of the measured curves:

``f_lin_hz``
    small-amplitude (stuck-joint) natural frequency, Hz: ``omega_lin^2 = k_nj + kappa``.
``zeta0``
    linear viscous modal damping, ``c = 2 zeta0 omega_lin``.
``joint_stiffness_fraction`` (``beta``)
    joint share of the small-amplitude modal stiffness, ``kappa = beta omega_lin^2``
    (``kappa = phi^2 sigma`` for Dahl). Full slip lowers ``omega^2`` by that fraction.
``slip_velocity_in_s`` (``V_s``)
    measured velocity amplitude at which the joint's slip amplitude reaches its slip
    scale (Dahl ``Fc / sigma``; LuGre ``alpha0 / sigma0``; Iwan: the largest slip
    threshold), evaluated at ``omega_lin``. The joint's normalised amplitude is
    ``y = (V / V_s) (omega_lin / omega)``.

Energies are then ``kappa a_s^2`` times dimensionless functions of ``y`` (``a_s`` the
slip scale in modal units), and ``phi``, ``psi`` drop out.

Joint laws
----------
The dimensionless cycle averages of the joint laws (Dahl, LuGre, Iwan, Iwan with
data-set threshold cells) are in :mod:`workflow.models.joint_averages`. Extensions used
by :mod:`workflow.discovery`: quadratic damping ``c2 xi'|xi'|``, a non-dissipative
power-law stiffness, and a run-order drift of the slip scale.

Units: velocity amplitudes in in/s, frequencies in Hz, angular frequencies in rad/s.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from workflow.models.joint_averages import (
    JointAverages,
    dahl_averages,
    iwan_averages,
    iwan_cells_averages,
    lugre_averages,
    power_stiffness_harmonic_factor,
)

__all__ = [
    "ParamSpec",
    "AveragedModel",
    "MODELS",
    "RESPONSE_ORDER",
    "iwan_cells_model",
    "ring_down_observables",
    "gradient_along_grid",
    "CurveGrid",
    "model_curves",
    "combined_model",
    "COMBINED_MODELS",
    "drift_factor",
    "model_curves_on_grid",
]


RESPONSE_ORDER = {"displacement": 0, "velocity": 1, "acceleration": 2}
"""Time-derivative order of each measurable response quantity."""


# ------------------------------------------------------------------- ring-down model
def ring_down_observables(
    *,
    omega_lin: ArrayLike,
    y: ArrayLike,
    joint: JointAverages,
    beta: ArrayLike,
    zeta0: ArrayLike,
    slip_velocity: ArrayLike = 1.0,
    quadratic: ArrayLike = 0.0,
    extra_inphase: ArrayLike = 0.0,
    extra_energy_slope: ArrayLike = 0.0,
) -> dict[str, np.ndarray]:
    """Displacement-envelope decay rate and frequency from the cycle averages.

    All energies are divided by ``a_s^2`` (``a = a_s y``).

    Parameters
    ----------
    omega_lin : array_like
        Small-amplitude natural frequency, rad/s.
    y : array_like
        Normalised slip amplitude.
    joint : JointAverages
        Joint averages at ``y`` (``tip_energy_slope`` required).
    beta : array_like
        Joint stiffness fraction.
    zeta0 : array_like
        Linear viscous damping ratio (w.r.t. ``omega_lin``).
    slip_velocity : array_like
        ``V_s``, in/s (enters only the quadratic-damping term ``2 pi q V_s omega^2 y^3``).
    quadratic : array_like
        ``q`` in s/in: quadratic damping adds ``~ q V`` to the damping ratio.
    extra_inphase : array_like
        Additional in-phase stiffness (rad/s)^2 from a non-dissipative term.
    extra_energy_slope : array_like
        ``dU/da / a_s`` of that term, (rad/s)^2.

    Returns
    -------
    dict
        ``omega2`` (undamped oscillation frequency squared), ``decay_rate`` (``s_a``,
        1/s, displacement envelope).
    """
    omega_lin = np.asarray(omega_lin, dtype=float)
    beta = np.asarray(beta, dtype=float)
    kappa = beta * omega_lin**2
    k_nj = omega_lin**2 - kappa
    omega2 = np.maximum(k_nj + kappa * joint.inphase + extra_inphase, 1e-6 * omega_lin**2)
    omega = np.sqrt(omega2)
    y = np.asarray(y, dtype=float)
    dissipation = (
        np.pi * 2.0 * np.asarray(zeta0) * omega_lin * omega * y**2
        + kappa * joint.dissipation
        + 2.0 * np.pi * np.asarray(quadratic) * np.asarray(slip_velocity) * omega2 * y**3
    )
    energy_slope = k_nj * y + kappa * joint.tip_energy_slope + extra_energy_slope
    energy_slope = np.maximum(energy_slope, 1e-9 * omega_lin**2 * y)
    decay_rate = dissipation * omega / (2.0 * np.pi * y * energy_slope)
    return {"omega2": omega2, "decay_rate": decay_rate}


@dataclass(frozen=True)
class ParamSpec:
    """One model parameter: name, unit, scale of its fit coordinate, meaning."""

    name: str
    unit: str
    scale: str  # "log" (fitted as ln value) or "linear"
    description: str


_BASE = (
    ParamSpec("f_lin_hz", "Hz", "log", "small-amplitude natural frequency (stuck joint)"),
    ParamSpec("zeta0", "1", "log", "linear viscous modal damping ratio"),
    ParamSpec(
        "joint_stiffness_fraction",
        "1",
        "log",
        "joint share of the small-amplitude modal stiffness (frequency^2 lost at full slip)",
    ),
    ParamSpec(
        "slip_velocity_in_s",
        "in/s",
        "log",
        "measured velocity amplitude at which the joint slip reaches its slip scale",
    ),
)


@dataclass(frozen=True)
class AveragedModel:
    """An averaged ring-down model: parameters and a joint law with extensions.

    Attributes
    ----------
    name : str
        Model id (``dahl``, ``lugre``, ``iwan``, ``iwan_cells_<n>``, ``dahl_quadratic``,
        ``dahl_stiffness``, ``dahl_drift``).
    joint : str
        ``dahl``, ``lugre``, ``iwan`` or ``iwan_cells``.
    params : tuple of ParamSpec
        Fitted parameters, in order.
    fixed : tuple of str
        Names of parameters that are supplied, not fitted (``reference_velocity_in_s``).
    description : str
        One line for reports.
    """

    name: str
    joint: str
    params: tuple[ParamSpec, ...]
    description: str
    fixed: tuple[str, ...] = field(default_factory=tuple)

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.params)

    @property
    def uses_runs(self) -> bool:
        return any(p.name == "drift" for p in self.params)

    @property
    def cell_names(self) -> tuple[str, ...]:
        """Names of the slip-threshold cell parameters (``iwan_cells`` joints), lowest first."""
        return tuple(p.name for p in self.params if p.name.startswith("stiffness_fraction_cell_"))


MODELS: dict[str, AveragedModel] = {
    "dahl": AveragedModel("dahl", "dahl", _BASE, "Dahl joint (paper eq. 4) + linear viscous modal damping"),
    "lugre": AveragedModel(
        "lugre",
        "lugre",
        _BASE
        + (
            ParamSpec("stiction_ratio", "1", "linear", "alpha1 / alpha0 (stiction over Coulomb level)"),
            ParamSpec(
                "stribeck_velocity_in_s",
                "in/s",
                "log",
                "Stribeck velocity v0 = vd in measured velocity units",
            ),
            ParamSpec(
                "micro_damping_ratio",
                "1",
                "linear",
                "sigma1 term as a damping ratio at small amplitude, over zeta0",
            ),
        ),
        "LuGre joint (paper eq. 5; alpha2 folded into zeta0, vd = v0) + linear viscous damping",
    ),
    "iwan": AveragedModel(
        "iwan",
        "iwan",
        _BASE[:3]
        + (
            ParamSpec(
                "slip_velocity_in_s",
                "in/s",
                "log",
                "measured velocity amplitude at which the largest slip threshold is reached (macro-slip)",
            ),
            ParamSpec("chi", "1", "linear", "power-law exponent of the slip-threshold density"),
            ParamSpec(
                "macro_ratio", "1", "log", "stiffness of the macro-slip element over the distributed elements"
            ),
        ),
        "Segalman four-parameter Iwan joint (micro-slip) + linear viscous damping",
    ),
    "dahl_quadratic": AveragedModel(
        "dahl_quadratic",
        "dahl",
        _BASE
        + (
            ParamSpec(
                "quadratic_zeta_per_in_s",
                "s/in",
                "log",
                "quadratic damping c2 v|v| as damping ratio per unit velocity amplitude",
            ),
        ),
        "Dahl joint + linear viscous + quadratic (velocity-squared) damping",
    ),
    "dahl_stiffness": AveragedModel(
        "dahl_stiffness",
        "dahl",
        _BASE
        + (
            ParamSpec(
                "stiffness_shift",
                "1",
                "linear",
                "relative change of omega^2 from a non-dissipative stiffness at the "
                "reference velocity amplitude (negative: softening)",
            ),
            ParamSpec(
                "stiffness_exponent",
                "1",
                "log",
                "power of amplitude of that stiffness change (2: cubic spring)",
            ),
        ),
        "Dahl joint + linear viscous damping + non-dissipative power-law stiffness",
        fixed=("reference_velocity_in_s",),
    ),
    "dahl_drift": AveragedModel(
        "dahl_drift",
        "dahl",
        _BASE
        + (
            ParamSpec(
                "drift",
                "1",
                "linear",
                "relative change of the friction limit Fc (slip scale) over the run "
                "sequence: Fc_r = Fc (1 + drift (r - r_mean) / n_runs)",
            ),
        ),
        "Dahl joint with a friction limit drifting linearly with run order + viscous damping",
    ),
}
"""The averaged models, by id."""


MAX_THRESHOLD_CELLS = 24
"""Most quarter-decade slip-threshold cells of an ``iwan_cells_<n>`` model (six decades)."""


def iwan_cells_model(n_cells: int) -> AveragedModel:
    """The Iwan joint whose slip-threshold density is set by the data, in ``n_cells`` cells.

    Cell ``k`` (1 = lowest) holds the slip thresholds between ``10^((k - 1 - n) / 4)``
    and ``10^((k - n) / 4)`` times ``anchor_velocity_in_s``, the top of the measured
    amplitude range (fixed, not fitted: thresholds above it never slip and are part of
    the linear stiffness); its parameter is the share of the small-amplitude modal
    stiffness those elements release at full slip. Their sum is the joint stiffness
    fraction.
    """
    if not 1 <= n_cells <= MAX_THRESHOLD_CELLS:
        raise ValueError(f"n_cells must be 1 .. {MAX_THRESHOLD_CELLS}, got {n_cells}")
    cells = tuple(
        ParamSpec(
            f"stiffness_fraction_cell_{k}",
            "1",
            "log",
            f"modal stiffness share released by slip thresholds between 10^{(k - 1 - n_cells) / 4:g} "
            f"and 10^{(k - n_cells) / 4:g} of the top measured amplitude",
        )
        for k in range(1, n_cells + 1)
    )
    return AveragedModel(
        f"iwan_cells_{n_cells}",
        "iwan_cells",
        _BASE[:2] + cells,
        "Iwan joint with the slip-threshold density recovered from the data (quarter-decade cells) "
        "+ linear viscous damping",
        fixed=("anchor_velocity_in_s",),
    )


MODELS.update({f"iwan_cells_{n}": iwan_cells_model(n) for n in range(1, MAX_THRESHOLD_CELLS + 1)})


def combined_model(joint_model: str, extension_model: str) -> AveragedModel:
    """The joint law of ``joint_model`` with the extension of ``extension_model`` added.

    Two mechanisms at once (a micro-slip joint with a velocity-squared loss, with a
    non-dissipative stiffness): the extension's own parameters (those ``dahl`` lacks) are
    appended to the joint model's, and the supplied parameters of both are kept. Its id is
    ``<joint_model>+<extension>`` with the extension named as in ``dahl_<extension>``.
    """
    joint, extension = MODELS[joint_model], MODELS[extension_model]
    own = set(joint.param_names) | set(MODELS["dahl"].param_names)
    added = tuple(p for p in extension.params if p.name not in own)
    suffix = extension_model.removeprefix("dahl_")
    return AveragedModel(
        f"{joint_model}_{suffix}",
        joint.joint,
        joint.params + added,
        f"{joint.description} + {suffix} term of {extension_model}",
        fixed=tuple(dict.fromkeys(joint.fixed + extension.fixed)),
    )


COMBINED_MODELS = {
    (f"iwan_cells_{n}", extension): f"iwan_cells_{n}_{extension.removeprefix('dahl_')}"
    for n in range(1, MAX_THRESHOLD_CELLS + 1)
    for extension in ("dahl_quadratic", "dahl_stiffness")
}
"""(joint model, extension model) -> the combined model's id (:func:`combined_model`): the
Iwan joint with the slip thresholds from the data and a velocity-squared loss or a
stiffness term (``iwan_cells_<n>_quadratic``, ``iwan_cells_<n>_stiffness``)."""

MODELS.update({name: combined_model(*parts) for parts, name in COMBINED_MODELS.items()})


def _joint_averages(model: AveragedModel, y, velocity, params) -> JointAverages:
    if model.joint == "dahl":
        return dahl_averages(y)
    if model.joint == "iwan":
        return iwan_averages(y, params["chi"], params["macro_ratio"])
    if model.joint == "iwan_cells":
        return iwan_cells_averages(y, params["threshold_shares"])
    if model.joint == "lugre":
        beta = np.asarray(params["joint_stiffness_fraction"], dtype=float)
        tau_omega = 2.0 * np.asarray(params["micro_damping_ratio"]) * np.asarray(params["zeta0"]) / beta
        return lugre_averages(
            y, velocity / np.asarray(params["stribeck_velocity_in_s"]), params["stiction_ratio"], tau_omega
        )
    raise ValueError(f"unknown joint law {model.joint!r}")


def drift_factor(drift: ArrayLike, run_position: ArrayLike) -> np.ndarray:
    """Slip-scale factor ``1 + drift * run_position``, kept >= 0.05.

    ``run_position = (r - r_mean) / n_runs`` for run ``r`` of ``n_runs`` (0-based, in
    run order).
    """
    return np.maximum(1.0 + np.asarray(drift, dtype=float) * np.asarray(run_position, dtype=float), 0.05)


def gradient_along_grid(values: np.ndarray, coordinate: np.ndarray) -> np.ndarray:
    """Derivative of ``values`` along its last axis at the points ``coordinate``.

    The arithmetic of ``np.gradient(values, coordinate, axis=-1)`` (second-order
    central differences inside, first-order at the ends), without its argument
    handling, which cost as much as the arithmetic in the fits' residuals.

    Parameters
    ----------
    values : ndarray, shape (..., G)
    coordinate : ndarray, shape (G,)
        Increasing, G >= 2.

    Returns
    -------
    ndarray, shape (..., G)
        ``d values / d coordinate``.
    """
    values = np.asarray(values, dtype=float)
    dx = np.diff(coordinate)
    out = np.empty(values.shape)
    if (dx == dx[0]).all():
        out[..., 1:-1] = (values[..., 2:] - values[..., :-2]) / (2.0 * dx[0])
    else:
        dx1, dx2 = dx[:-1], dx[1:]
        a = -(dx2) / (dx1 * (dx1 + dx2))
        b = (dx2 - dx1) / (dx1 * dx2)
        c = dx1 / (dx2 * (dx1 + dx2))
        out[..., 1:-1] = a * values[..., :-2] + b * values[..., 1:-1] + c * values[..., 2:]
    out[..., 0] = (values[..., 1] - values[..., 0]) / dx[0]
    out[..., -1] = (values[..., -1] - values[..., -2]) / dx[-1]
    return out


def model_curves_on_grid(
    model: AveragedModel,
    params: Mapping[str, ArrayLike],
    velocity_grid: ArrayLike,
    *,
    run_position: ArrayLike | None = None,
    response_order: int | tuple[int, ...] = 2,
    n_iter: int = 2,
) -> tuple[np.ndarray, np.ndarray]:
    """Damping ratio and damped frequency on a velocity-amplitude grid.

    Parameters
    ----------
    model : AveragedModel
    params : mapping of array_like
        Physical parameter values (names of ``model.params`` plus fixed ones), each
        broadcastable to a batch shape ``B`` (use shape ``(P, 1)`` for ``P`` sets).
    velocity_grid : array_like, shape (G,)
        Measured velocity amplitudes, in/s, increasing and log-spaced (derivatives
        along the grid are taken in ``ln V``).
    run_position : array_like, shape (R,), optional
        For ``dahl_drift``: ``(r - r_mean) / n_runs`` of the runs; the result then has
        shape ``B + (R, G)`` with batch parameters broadcast against ``(R, 1)``.
    response_order : int or tuple of int
        0, 1, 2 for a displacement, velocity or acceleration record; a tuple of ``K``
        orders gives ``zeta`` in each (records of several quantities).
    n_iter : int
        Fixed-point iterations for ``y = (V / V_s)(omega_lin / omega)``.

    Returns
    -------
    zeta, frequency_hz : ndarray
        Shape ``broadcast(B, (G,))`` (or with the run axis); with a tuple of orders
        ``zeta`` has an axis of the ``K`` orders before the run and grid axes.
    """
    v = np.asarray(velocity_grid, dtype=float)
    p = {k: np.asarray(val, dtype=float) for k, val in params.items()}
    if model.joint == "iwan_cells":
        cells = np.stack(np.broadcast_arrays(*(p[name] for name in model.cell_names)), axis=-1)
        p["joint_stiffness_fraction"] = cells.sum(axis=-1)
        p["threshold_shares"] = cells / p["joint_stiffness_fraction"][..., None]
        p["slip_velocity_in_s"] = p["anchor_velocity_in_s"]
    if model.uses_runs:
        if run_position is None:
            raise ValueError(f"model {model.name} needs run_position")
        pos = np.asarray(run_position, dtype=float)[:, None]
        p = {k: val[..., None, :] if val.ndim >= 1 else val for k, val in p.items()}
        v_s = p["slip_velocity_in_s"] * drift_factor(p["drift"], pos)
    else:
        v_s = p["slip_velocity_in_s"]
    omega_lin = 2.0 * np.pi * p["f_lin_hz"]
    beta = p["joint_stiffness_fraction"]
    ratio = np.ones(np.broadcast_shapes(np.shape(v_s), np.shape(omega_lin), v.shape))
    quadratic = p.get("quadratic_zeta_per_in_s", 0.0)
    for _ in range(n_iter):
        y = v / (v_s * ratio)
        joint = _joint_averages(model, y, v, p)
        extra_k, extra_e = _extra_stiffness(model, p, v, ratio, omega_lin, v_s)
        omega2 = (1.0 - beta + beta * joint.inphase) * omega_lin**2 + extra_k
        ratio = np.sqrt(np.maximum(omega2, 1e-6 * omega_lin**2)) / omega_lin
    y = v / (v_s * ratio)
    log_v = np.log(v)
    if joint.tip_energy_slope is None:
        # de/dy = (de/dlnV) / (dln y/dlnV) / y, along the grid
        dlny = gradient_along_grid(np.log(y), log_v)
        slope = gradient_along_grid(joint.tip_energy, log_v) / (dlny * y)
        joint = JointAverages(joint.dissipation, joint.inphase, tip_energy_slope=slope)
    out = ring_down_observables(
        omega_lin=omega_lin,
        y=y,
        joint=joint,
        beta=beta,
        zeta0=p["zeta0"],
        slip_velocity=v_s,
        quadratic=quadratic,
        extra_inphase=extra_k,
        extra_energy_slope=extra_e,
    )
    omega2 = out["omega2"]
    s_a = out["decay_rate"]
    omega_d2 = np.maximum(omega2 - s_a**2, 1e-6 * omega2)
    orders = (response_order,) if np.ndim(response_order) == 0 else tuple(response_order)
    # d ln(omega) / d ln(a), with ln a = ln V - ln omega + const
    m = gradient_along_grid(0.5 * np.log(omega2), log_v) if any(orders) else None
    zetas = []
    for order in orders:
        s_meas = s_a * (1.0 + order * m / (1.0 - m)) if order else s_a
        zetas.append(s_meas / np.sqrt(s_meas**2 + omega_d2))
    zeta = zetas[0] if np.ndim(response_order) == 0 else np.stack(zetas, axis=-3 if model.uses_runs else -2)
    return zeta, np.sqrt(omega_d2) / (2.0 * np.pi)


def _extra_stiffness(model, p, v, ratio, omega_lin, v_s):
    """In-phase stiffness and energy slope (per a_s) of the non-dissipative term."""
    if "stiffness_shift" not in p:
        return 0.0, 0.0
    delta = p["stiffness_shift"]
    expo = p["stiffness_exponent"]
    x_ref = v / (p["reference_velocity_in_s"] * ratio)
    k1 = delta * omega_lin**2 * x_ref**expo
    y = v / (v_s * ratio)
    return k1, k1 * y / power_stiffness_harmonic_factor(expo)


@dataclass
class CurveGrid:
    """Fast evaluation of model curves at fixed measured amplitudes.

    The curves are computed on a log-spaced grid covering the amplitudes and
    interpolated linearly in ``ln V`` (weights computed once).

    Parameters
    ----------
    velocity_in_s : array_like, shape (n,)
        Measured velocity amplitudes of the segments, in/s.
    run_index : array_like of int, shape (n,), optional
        Run of each segment, 0-based in run order (needed by ``dahl_drift``).
    n_runs : int, optional
        Number of runs of the configuration (defaults to ``max(run_index) + 1``).
    response_order : int or array_like of int, shape (n,)
        0, 1, 2: displacement, velocity, acceleration record; per segment where the
        segments come from records of different quantities.
    grid_range : (float, float), optional
        Velocity range of the grid (defaults to the data's, padded by 5 %).
    n_grid : int
        Grid points.
    """

    velocity_in_s: np.ndarray
    run_index: np.ndarray | None = None
    n_runs: int | None = None
    response_order: int | np.ndarray = 2
    grid_range: tuple[float, float] | None = None
    n_grid: int = 48
    grid: np.ndarray = field(init=False)
    _lo: np.ndarray = field(init=False)
    _w: np.ndarray = field(init=False)
    _orders: int | tuple[int, ...] = field(init=False)
    _order_slot: np.ndarray | None = field(init=False)

    def __post_init__(self) -> None:
        v = np.asarray(self.velocity_in_s, dtype=float)
        if np.any(~np.isfinite(v)) or np.any(v <= 0):
            raise ValueError("velocity amplitudes must be finite and > 0")
        self.velocity_in_s = v
        lo, hi = self.grid_range or (float(v.min()), float(v.max()))
        lo, hi = lo / 1.05, hi * 1.05
        self.grid = np.geomspace(lo, hi, self.n_grid)
        pos = (np.log(v) - np.log(lo)) / (np.log(hi) - np.log(lo)) * (self.n_grid - 1)
        pos = np.clip(pos, 0.0, self.n_grid - 1 - 1e-9)
        self._lo = np.floor(pos).astype(int)
        self._w = pos - self._lo
        if self.run_index is None:
            self.run_index = np.zeros(v.size, dtype=int)
        self.run_index = np.asarray(self.run_index, dtype=int)
        if self.n_runs is None:
            self.n_runs = int(self.run_index.max()) + 1 if self.run_index.size else 1
        orders, slot = np.unique(
            np.atleast_1d(np.asarray(self.response_order, dtype=int)), return_inverse=True
        )
        several = orders.size > 1
        self._orders = tuple(int(n) for n in orders) if several else int(orders[0])
        self._order_slot = slot if several else None

    @property
    def run_positions(self) -> np.ndarray:
        """``(r - r_mean) / n_runs`` for r = 0 .. n_runs - 1."""
        r = np.arange(self.n_runs, dtype=float)
        return (r - r.mean()) / self.n_runs

    def __call__(
        self, model: AveragedModel | str, params: Mapping[str, ArrayLike]
    ) -> tuple[np.ndarray, np.ndarray]:
        """Model ``zeta`` and ``frequency_hz`` at the segments, shape ``B + (n,)``."""
        model = MODELS[model] if isinstance(model, str) else model
        zeta_g, f_g = model_curves_on_grid(
            model,
            params,
            self.grid,
            run_position=self.run_positions if model.uses_runs else None,
            response_order=self._orders,
        )
        return (
            self._interp(zeta_g, model.uses_runs, self._order_slot),
            self._interp(f_g, model.uses_runs),
        )

    def _interp(self, values: np.ndarray, per_run: bool, order_slot: np.ndarray | None = None) -> np.ndarray:
        if order_slot is not None:
            # one curve per response order: each segment reads its own order's
            index = (order_slot, self.run_index) if per_run else (order_slot,)
            a = values[(..., *index, self._lo)]
            b = values[(..., *index, self._lo + 1)]
        elif per_run:
            a = values[..., self.run_index, self._lo]
            b = values[..., self.run_index, self._lo + 1]
        else:
            # np.take: the same values as indexing, in half its time on the fits' arrays
            a = np.take(values, self._lo, axis=-1)
            b = np.take(values, self._lo + 1, axis=-1)
        return a + (b - a) * self._w


def model_curves(
    model: AveragedModel | str,
    params: Mapping[str, ArrayLike],
    velocity_in_s: ArrayLike,
    *,
    run_index: ArrayLike | None = None,
    n_runs: int | None = None,
    response_order: int = 2,
) -> tuple[np.ndarray, np.ndarray]:
    """Model damping ratio and damped frequency (Hz) at measured velocity amplitudes.

    Convenience wrapper around :class:`CurveGrid`; see there for the arguments.

    Examples
    --------
    A Dahl joint carrying 1 % of the stiffness, slipping at 1 in/s: damping grows and the
    frequency drops with amplitude.

    >>> params = {"f_lin_hz": 100.0, "zeta0": 0.002, "joint_stiffness_fraction": 0.01, "slip_velocity_in_s": 1.0}
    >>> zeta, frequency_hz = model_curves("dahl", params, [0.05, 5.0])
    >>> zeta.round(5).tolist(), frequency_hz.round(2).tolist()
    ([0.00211, 0.00303], [100.0, 99.56])
    """
    grid = CurveGrid(
        np.atleast_1d(np.asarray(velocity_in_s, dtype=float)),
        run_index=run_index,
        n_runs=n_runs,
        response_order=response_order,
        n_grid=64,
    )
    return grid(model, params)
