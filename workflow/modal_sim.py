"""Ring-down of one mode with a friction joint (paper eq. 9), batched over parameter sets.

Equation of motion (modal coordinate ``xi``, mass-normalised mode)::

    xi'' + 2 zeta0 omega xi' + omega^2 xi + f_extra(xi, xi', params) = -phi_s F_joint(u, v)
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
  integrates the remainder ``-phi_s (F - k_lin u - c_lin v) - f_extra``, which is small
  for a lightly damped joint. The error constant therefore scales with the size of the
  nonlinearity rather than with ``(omega h)^4`` alone, so ~20 steps per period give
  envelope errors far below 1e-3 (``bench/bench_integrator.py``).
* **Dahl without stiffness.** Dahl is rate independent; between velocity reversals its
  state is an exact function of slip (:func:`workflow.friction.dahl_branch_z`). The
  integrator keeps the last reversal ``(u_r, z_r)`` and the direction as per-set memory,
  and evaluates the joint force algebraically at every stage. The stiff rate
  ``sigma |v| / Fc`` (which may exceed omega by orders of magnitude in deep sliding)
  never enters a stability limit, and the kink of ``|v|`` at reversals is removed: a
  reversal inside a step is located by cubic Hermite interpolation of the slip, so only
  an O(h^4) local error remains per reversal (4th-order convergence is kept).
* **ODE internal states (LuGre).** ``z`` is integrated by the same Lawson RK4 with the
  relaxation rate ``a = sigma0 |v| / g(v)`` frozen at the start of the step and applied
  exactly (``exp(-a h)``). What is left explicit is the change of ``a`` within a step,
  ``~ a_max * omega * h``; the step is refined automatically so that
  ``a_max * omega * h^2 <= 0.05`` (``a_max`` from the largest slip velocity), which keeps it
  well inside RK4's stability region.
* **Output grid.** The step is ``1 / (fs_out * m)`` with an integer ``m`` chosen so that
  there are at least ``steps_per_period`` steps per period of the fastest (stuck-joint)
  frequency in the batch, so output samples fall on steps and need no interpolation.

Extending: subclass :class:`JointForce` (state count, force, memory update) and pass an
instance as ``model``; or pass ``extra_force`` for an additive modal force.
"""

from __future__ import annotations

import math
from typing import Callable, Mapping

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp
from scipy.signal import hilbert

from workflow import friction

__all__ = [
    "JointForce",
    "NoJoint",
    "DahlJoint",
    "LuGreJoint",
    "make_joint",
    "simulate_ringdown",
    "reference_ringdown",
    "oscillator_propagator",
    "envelope_relative_error",
]

ExtraForce = Callable[[np.ndarray, np.ndarray, Mapping[str, np.ndarray]], np.ndarray]


# ----------------------------------------------------------------------------- joints
class JointForce:
    """Joint force model on a 1-D batch of parameter sets (base class: no joint).

    Subclasses set ``n_states`` (ODE states integrated by the simulator), the linear
    parts ``stiffness_lbf_in`` / ``damping_lbf_s_in`` (absorbed into the exact
    propagator; any values are correct, good ones make the remainder small), and
    override :meth:`force` (and :meth:`end_step` for hysteretic memory).

    Parameters
    ----------
    params : mapping of array_like
        Model parameters, each broadcastable to ``(batch,)``.
    slip_per_modal : array_like
        ``phi_s``, joint slip per unit modal coordinate (in per unit xi).
    batch : int
        Number of parameter sets.
    """

    n_states = 0

    def __init__(self, params: Mapping[str, ArrayLike], slip_per_modal: ArrayLike, batch: int):
        self.params = {k: np.broadcast_to(np.asarray(v, float), (batch,)).copy()
                       for k, v in params.items()}
        self.phi = np.broadcast_to(np.asarray(slip_per_modal, float), (batch,)).copy()
        self.batch = batch
        self.stiffness_lbf_in = np.zeros(batch)
        self.damping_lbf_s_in = np.zeros(batch)

    def initial_states(self, u0_in: np.ndarray, v0_in_s: np.ndarray) -> np.ndarray:
        """ODE states at t = 0, shape ``(n_states, batch)``; also resets memory."""
        return np.zeros((self.n_states, self.batch))

    def force(self, u_in: np.ndarray, v_in_s: np.ndarray, w: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
        """Joint force (lbf) and ODE-state rates ``dw/dt`` at slip ``u``, velocity ``v``."""
        return np.zeros_like(u_in), np.zeros_like(w)

    def relaxation_rate(self, u_in: np.ndarray, v_in_s: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Linear decay rate (1/s) of each ODE state, applied exactly over a step."""
        return np.zeros_like(w)

    def max_relaxation_rate(self, v_max_in_s: np.ndarray) -> np.ndarray:
        """Upper bound of :meth:`relaxation_rate` for ``|v| <= v_max``, per set, 1/s."""
        return np.zeros(self.batch)

    def end_step(self, xi0: np.ndarray, eta0: np.ndarray, xi1: np.ndarray, eta1: np.ndarray,
                 h_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Update hysteretic memory after a step from (xi0, eta0) to (xi1, eta1) (modal units).

        Returns None, or ``(idx, d_xi, d_xi_dot)``: corrections of the modal state of the
        sets ``idx`` for an event inside the step (e.g. a reversal the stages missed).
        """
        return None

    def modal_remainder(self, xi: np.ndarray, eta: np.ndarray, w: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
        """Nonlinear modal force ``-phi (F - k_lin u - c_lin v)`` and ``dw/dt``."""
        u = self.phi * xi
        v = self.phi * eta
        f, dw = self.force(u, v, w)
        rem = -self.phi * (f - self.stiffness_lbf_in * u - self.damping_lbf_s_in * v)
        return rem, dw


class NoJoint(JointForce):
    """No joint force: the linear damped oscillator."""

    def modal_remainder(self, xi, eta, w):
        return np.zeros_like(xi), w


class DahlJoint(JointForce):
    """Dahl friction (paper eq. 4) evaluated exactly along slip branches.

    On a branch of direction ``s`` from the reversal ``(xi_r, z_r)`` the state is
    ``z(xi) = A0 + A1 exp(B xi + B0)`` with ``A0 = s Fc/sigma``, ``A1 = z_r - A0``,
    ``B = -sigma s phi / Fc``, ``B0 = -B xi_r`` (:func:`workflow.friction.dahl_branch_z`
    in modal units). These four numbers per set are the memory.
    Parameters: ``sigma`` (lbf/in), ``fc`` (lbf).
    """

    def __init__(self, params, slip_per_modal, batch):
        super().__init__(params, slip_per_modal, batch)
        self.sigma = self.params["sigma"]
        self.fc = self.params["fc"]
        if np.any(self.sigma <= 0) or np.any(self.fc <= 0):
            raise ValueError("Dahl parameters sigma and fc must be positive")
        self.stiffness_lbf_in = self.sigma.copy()
        # Remainder in modal units: K xi - Q z.
        self._q = self.phi * self.sigma
        self._k = self.phi * self.phi * self.sigma

    def initial_states(self, u0_in, v0_in_s):
        s = np.where(np.asarray(v0_in_s) < 0, -1.0, 1.0)
        z_sat = self.fc / self.sigma
        xi0 = np.asarray(u0_in, float) / self.phi
        b = -self.sigma / self.fc * s * self.phi
        # rows: A0, A1, B, B0 (virgin start: z = 0 at xi0)
        self.mem = np.stack([s * z_sat, -s * z_sat, b, -b * xi0])
        return np.zeros((0, self.batch))

    def z_of(self, xi: np.ndarray) -> np.ndarray:
        """Dahl state (inch) at modal displacement ``xi`` on the current branches."""
        a0, a1, b, b0 = self.mem
        # min(): a Runge-Kutta stage can look slightly past a reversal; keep exp finite.
        return a0 + a1 * np.exp(np.minimum(b * xi + b0, 50.0))

    def force(self, u_in, v_in_s, w):
        return self.sigma * self.z_of(np.asarray(u_in) / self.phi), w

    def modal_remainder(self, xi, eta, w):
        # Hot loop: 6 array operations and one exp.
        return self._k * xi - self._q * self.z_of(xi), w

    def end_step(self, xi0, eta0, xi1, eta1, h_s):
        # Velocity sign s is that of -B / phi: a reversal makes eta1 * B positive.
        flipped = eta1 * self.mem[2] > 0.0
        if not flipped.any():
            return None
        idx = np.flatnonzero(flipped)
        a0, a1, b, b0 = self.mem[:, idx]
        x0, v0, x1, v1 = xi0[idx], eta0[idx], xi1[idx], eta1[idx]
        # Reversal time from linear velocity; the Hermite displacement there is O(h^4)
        # accurate because xi is stationary at the reversal (error ~ theta error squared).
        theta = v0 / (v0 - v1)
        d = x1 - x0
        hv0, hv1 = h_s * v0, h_s * v1
        c2 = 3.0 * d - 2.0 * hv0 - hv1
        c3 = hv0 + hv1 - 2.0 * d
        x_r = x0 + theta * (hv0 + theta * (c2 + theta * c3))
        z_r = a0 + a1 * np.exp(b * x_r + b0)
        # The stages after the reversal used the old branch; add the missing impulse of
        # the (new - old) branch force over the rest of the step, else a one-signed O(h^3)
        # error per reversal accumulates. With xi - xi_r = alpha tau^2 / 2 the difference
        # grows as tau^2; one node at tau_e / sqrt(3) integrates tau^2 exactly, and
        # int (tau_e - tau) tau^2 = (tau_e / 4) int tau^2.
        alpha = (v1 - v0) / h_s
        tau_e = (1.0 - theta) * h_s
        e = np.exp(np.minimum(-b * alpha * tau_e * tau_e / 6.0, 50.0))
        dz = (z_r + a0) * e - (z_r - a0) / e - 2.0 * a0
        d_eta = -self._q[idx] * tau_e * dz
        self.mem[:, idx] = (-a0, z_r + a0, -b, b * x_r)
        return idx, 0.25 * tau_e * d_eta, d_eta


class LuGreJoint(JointForce):
    """LuGre friction (paper eq. 5, ``g`` in force units; see :mod:`workflow.friction`).

    One ODE state ``z`` (inch). Parameters: ``sigma0`` (lbf/in), ``sigma1`` (lbf s/in),
    ``alpha0``, ``alpha1`` (lbf), ``alpha2`` (lbf s/in), ``v0``, ``vd`` (in/s).
    """

    n_states = 1

    def __init__(self, params, slip_per_modal, batch):
        super().__init__(params, slip_per_modal, batch)
        p = self.params
        g_min = np.minimum(p["alpha0"], p["alpha0"] + p["alpha1"])
        if np.any(g_min <= 0) or np.any(p["sigma0"] <= 0):
            raise ValueError("LuGre needs sigma0 > 0 and g(v) = alpha0 + alpha1 exp(.) > 0")
        if np.any(p["v0"] <= 0) or np.any(p["vd"] <= 0):
            raise ValueError("LuGre velocities v0 and vd must be positive")
        self._g_min = g_min
        self.stiffness_lbf_in = p["sigma0"].copy()
        self.damping_lbf_s_in = p["sigma1"] + p["alpha2"]

    def _rate_coeff(self, v):
        p = self.params
        g = p["alpha0"] + p["alpha1"] * np.exp(-(v / p["v0"]) ** 2)
        return p["sigma0"] / g

    def force(self, u_in, v_in_s, w):
        p = self.params
        z = w[0]
        z_dot = v_in_s - self._rate_coeff(v_in_s) * np.abs(v_in_s) * z
        s1 = p["sigma1"] * np.exp(-(v_in_s / p["vd"]) ** 2)
        f = p["sigma0"] * z + s1 * z_dot + p["alpha2"] * v_in_s
        return f, z_dot[None, :]

    def relaxation_rate(self, u_in, v_in_s, w):
        return (self._rate_coeff(v_in_s) * np.abs(v_in_s))[None, :]

    def max_relaxation_rate(self, v_max_in_s):
        return self.params["sigma0"] / self._g_min * np.abs(v_max_in_s)


_JOINTS: dict[str, type[JointForce]] = {"none": NoJoint, "linear": NoJoint,
                                        "dahl": DahlJoint, "lugre": LuGreJoint}


def make_joint(model: str | type[JointForce], params: Mapping[str, ArrayLike],
               slip_per_modal: ArrayLike, batch: int) -> JointForce:
    """Build a :class:`JointForce` from a name (``none``, ``dahl``, ``lugre``) or class."""
    cls = _JOINTS.get(model) if isinstance(model, str) else model
    if cls is None:
        raise ValueError(f"unknown joint model {model!r}; expected one of {sorted(_JOINTS)}")
    return cls(params, slip_per_modal, batch)


# --------------------------------------------------------------------------- integrator
def oscillator_propagator(stiffness_per_s2: ArrayLike, damping_per_s: ArrayLike, t_s: float
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
    k = np.asarray(stiffness_per_s2, float)
    c = np.asarray(damping_per_s, float)
    mu = 0.5 * c
    om = np.sqrt((k - mu * mu).astype(complex))  # imaginary when overdamped
    cos = np.cos(om * t_s).real
    with np.errstate(divide="ignore", invalid="ignore"):
        sinc = np.where(np.abs(om) * t_s > 1e-8, (np.sin(om * t_s) / om).real, t_s)
    decay = np.exp(-mu * t_s)
    return (decay * (cos + mu * sinc), decay * sinc, -k * decay * sinc, decay * (cos - mu * sinc))


def _broadcast_batch(*arrays) -> int:
    shape = np.broadcast(*[np.asarray(a) for a in arrays]).shape
    if len(shape) > 1:
        raise ValueError(f"parameters must broadcast to a 1-D batch, got shape {shape}")
    return shape[0] if shape else 1


def simulate_ringdown(model: str | type[JointForce], params: Mapping[str, ArrayLike], *,
                      omega_rad_s: ArrayLike, zeta0: ArrayLike, slip_per_modal: ArrayLike = 1.0,
                      initial_velocity: ArrayLike, fs_out_hz: float, duration_s: float,
                      steps_per_period: int = 64, extra_force: ExtraForce | None = None,
                      ) -> dict[str, np.ndarray | int | float]:
    """Batched ring-down of eq. 9 by exponential (Lawson) RK4 with a fixed step.

    Parameters
    ----------
    model : {"dahl", "lugre", "none"} or JointForce subclass
        Joint force model.
    params : mapping of array_like
        Joint parameters (see :mod:`workflow.friction`), each broadcastable to the batch.
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
        Minimum number of steps per period of the stiffest (stuck-joint) frequency.
    extra_force : callable, optional
        ``f(xi, xi_dot, params) -> modal force`` added on the left-hand side (so it
        opposes motion when it has the sign of ``xi_dot`` or ``xi``), for extended models.
        ``params`` is the broadcast parameter dict, each entry of shape ``(batch,)``.

    Returns
    -------
    dict
        ``t_s`` (n,), ``displacement``, ``velocity``, ``acceleration`` (batch, n) in modal
        units, ``substeps`` (steps per output sample), ``steps_per_period`` (actual, for
        the stiffest set) and ``h_s`` (step).
    """
    batch = _broadcast_batch(omega_rad_s, zeta0, slip_per_modal, initial_velocity,
                             *params.values())
    joint = make_joint(model, params, slip_per_modal, batch)
    omega = np.broadcast_to(np.asarray(omega_rad_s, float), (batch,))
    zeta = np.broadcast_to(np.asarray(zeta0, float), (batch,))
    v_init = np.broadcast_to(np.asarray(initial_velocity, float), (batch,)).copy()
    phi = joint.phi

    k_lin = omega**2 + phi**2 * joint.stiffness_lbf_in
    c_lin = 2.0 * zeta * omega + phi**2 * joint.damping_lbf_s_in
    omega_max = float(np.sqrt(np.max(np.abs(k_lin))))
    n_out = int(round(duration_s * fs_out_hz))
    dt_out = 1.0 / fs_out_hz
    m = max(1, math.ceil(steps_per_period * omega_max / (2.0 * math.pi) * dt_out))
    # ODE states: keep (rate variation within a step) * h = a_max * omega * h^2 <= 0.05
    # (1 is stable; 0.05 keeps deep-sliding LuGre within ~1e-3 of Dahl, measured).
    a_max = float(np.max(joint.max_relaxation_rate(np.abs(phi * v_init)))) if joint.n_states else 0.0
    if a_max > 0:
        m = max(m, math.ceil(dt_out * math.sqrt(a_max * omega_max / 0.05)))
    h = dt_out / m
    hh = 0.5 * h

    e00, e01, e10, e11 = oscillator_propagator(k_lin, c_lin, hh)
    p00, p01, p10, p11 = oscillator_propagator(k_lin, c_lin, h)
    he01, he11 = hh * e01, hh * e11
    h6p01, h6p11, h3e01, h3e11 = h / 6 * p01, h / 6 * p11, h / 3 * e01, h / 3 * e11
    he01_full, he11_full = h * e01, h * e11

    p_b = joint.params
    xi = np.zeros(batch)
    eta = v_init.copy()
    w = joint.initial_states(phi * xi, phi * eta)
    has_w = joint.n_states > 0

    if extra_force is None:
        remainder = joint.modal_remainder
    else:
        def remainder(x, y, ws):
            r, dw = joint.modal_remainder(x, y, ws)
            return r - extra_force(x, y, p_b), dw

    # Rows are time: writing a row is contiguous, a column of (batch, n) is not (10x slower).
    disp = np.empty((n_out, batch))
    vel = np.empty((n_out, batch))
    acc = np.empty((n_out, batch))
    for j in range(n_out):
        for sub in range(m):
            n1, d1 = remainder(xi, eta, w)
            if sub == 0:  # the output sample is the start of this step
                disp[j], vel[j] = xi, eta
                acc[j] = n1 - k_lin * xi - c_lin * eta
            exi = e00 * xi + e01 * eta
            eeta = e10 * xi + e11 * eta
            pxi = p00 * xi + p01 * eta
            peta = p10 * xi + p11 * eta
            if has_w:
                a = joint.relaxation_rate(phi * xi, phi * eta, w)
                ez = np.exp(-a * hh)
                ez2 = ez * ez
                d1 = d1 + a * w
                w2 = ez * (w + hh * d1)
            else:
                w2 = w
            n2, d2 = remainder(exi + he01 * n1, eeta + he11 * n1, w2)
            if has_w:
                d2 = d2 + a * w2
                w3 = ez * w + hh * d2
            else:
                w3 = w
            n3, d3 = remainder(exi, eeta + hh * n2, w3)
            if has_w:
                d3 = d3 + a * w3
                w4 = ez2 * w + h * ez * d3
            else:
                w4 = w
            n4, d4 = remainder(pxi + he01_full * n3, peta + he11_full * n3, w4)
            n23 = n2 + n3
            xi_new = pxi + h6p01 * n1 + h3e01 * n23
            eta_new = peta + h6p11 * n1 + h3e11 * n23 + (h / 6) * n4
            if has_w:
                d4 = d4 + a * w4
                w = ez2 * w + (h / 6) * (ez2 * d1 + 2.0 * ez * (d2 + d3) + d4)
            fix = joint.end_step(xi, eta, xi_new, eta_new, h)
            if fix is not None:
                idx, dxi, deta = fix
                xi_new[idx] += dxi
                eta_new[idx] += deta
            xi, eta = xi_new, eta_new
    return {
        "t_s": np.arange(n_out) * dt_out,
        "displacement": np.ascontiguousarray(disp.T),
        "velocity": np.ascontiguousarray(vel.T),
        "acceleration": np.ascontiguousarray(acc.T),
        "substeps": m,
        "steps_per_period": 2.0 * math.pi / (omega_max * h),
        "h_s": h,
    }


# ---------------------------------------------------------------------------- reference
def reference_ringdown(model: str, params: Mapping[str, float], *, omega_rad_s: float,
                       zeta0: float, slip_per_modal: float = 1.0, initial_velocity: float,
                       fs_out_hz: float, duration_s: float, method: str = "LSODA",
                       rtol: float = 1e-10, extra_force: ExtraForce | None = None,
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
    extra_force : callable, optional
        As in :func:`simulate_ringdown` (called with scalars).

    Returns
    -------
    dict
        ``t_s``, ``displacement``, ``velocity``, ``acceleration`` (n,), ``nfev``.
    """
    phi = float(slip_per_modal)
    p = {k: float(v) for k, v in params.items()}
    if model == "dahl":
        rate = lambda z, v: friction.dahl_z_rate(z, v, p["sigma"], p["fc"])  # noqa: E731
        force = lambda z, v: p["sigma"] * z  # noqa: E731
        z_scale = p["fc"] / p["sigma"]
    elif model == "lugre":
        rate = lambda z, v: friction.lugre_z_rate(  # noqa: E731
            z, v, p["sigma0"], p["alpha0"], p["alpha1"], p["v0"])
        force = lambda z, v: friction.lugre_force(  # noqa: E731
            z, v, p["sigma0"], p["sigma1"], p["alpha0"], p["alpha1"], p["alpha2"],
            p["v0"], p["vd"])
        z_scale = min(p["alpha0"], p["alpha0"] + p["alpha1"]) / p["sigma0"]
    elif model in ("none", "linear"):
        rate = lambda z, v: 0.0 * z  # noqa: E731
        force = lambda z, v: 0.0 * z  # noqa: E731
        z_scale = 1.0
    else:
        raise ValueError(f"reference_ringdown supports dahl, lugre, none; got {model!r}")

    def accel(xi, eta, z):
        a = -2.0 * zeta0 * omega_rad_s * eta - omega_rad_s**2 * xi - phi * force(z, phi * eta)
        if extra_force is not None:
            a = a - extra_force(xi, eta, p)
        return a

    def rhs(_t, y):
        xi, eta, z = y
        return [eta, accel(xi, eta, z), rate(z, phi * eta)]

    n_out = int(round(duration_s * fs_out_hz))
    t = np.arange(n_out) / fs_out_hz
    x_scale = abs(initial_velocity) / omega_rad_s
    atol = rtol * np.array([x_scale, abs(initial_velocity), min(z_scale, abs(phi) * x_scale)])
    sol = solve_ivp(rhs, (0.0, t[-1]), [0.0, float(initial_velocity), 0.0], method=method,
                    t_eval=t, rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(f"reference integration failed: {sol.message}")
    xi, eta, z = sol.y
    return {"t_s": t, "displacement": xi, "velocity": eta,
            "acceleration": np.array([accel(a, b, c) for a, b, c in zip(xi, eta, z)]),
            "nfev": sol.nfev}


def envelope_relative_error(signal: ArrayLike, reference: ArrayLike, *, trim_fraction: float = 0.05,
                            floor_fraction: float = 1e-3) -> np.ndarray:
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
    es = np.abs(hilbert(np.asarray(signal, float), axis=-1))
    er = np.abs(hilbert(np.asarray(reference, float), axis=-1))
    n = es.shape[-1]
    lo, hi = int(trim_fraction * n), int((1 - trim_fraction) * n)
    es, er = es[..., lo:hi], er[..., lo:hi]
    keep = er > floor_fraction * er.max(axis=-1, keepdims=True)
    return np.max(np.where(keep, np.abs(es - er) / np.where(keep, er, 1.0), 0.0), axis=-1)
