"""Friction contact models of the lap joint.

Two joint models are provided:

* **Patch (Iwan-type) micro-slip model.** The bolt preload (torque -> force by
  ``T = K F d``) is spread over the configuration's bearing area with a pressure
  that decays away from the bolt.  The area is split into small contact
  patches; each is a Jenkins element (tangential contact stiffness in series
  with a Coulomb slider of limit ``mu p A_patch``), driven by the interface
  slip of the specimen's first mode.  Patches far from the bolt carry little
  pressure and slip first: that spread of slip thresholds is micro-slip.
* **Dahl model** (paper eq. 4): ``dz/dt = v - sigma |v| z / Fc``, ``F = sigma z``.

For both, closed forms are given for a harmonic displacement of amplitude
``A``: the energy dissipated per cycle and the first-harmonic (describing
function, secant) stiffness.  Units: inch, lbf, psi.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.special

from workflow.models import specimen

# ----------------------------------------------------------------- Jenkins


__all__ = [
    "jenkins_dissipation_per_cycle",
    "jenkins_secant_stiffness",
    "jenkins_force_update",
    "dahl_secant_stiffness",
    "JointParameters",
    "bolt_preload_lbf",
    "ContactPatches",
    "contact_patches",
    "strip_springs",
    "JointModes",
    "joint_first_mode",
    "patch_describing_function",
    "equivalent_damping",
]


def jenkins_dissipation_per_cycle(slip_amplitude_in, stiffness_lbf_in, slip_force_lbf):
    """Energy dissipated per cycle by a Jenkins element under harmonic slip, in*lbf.

    ``D = 4 Fs (A - Fs / k)`` when ``k A > Fs``, else 0 (the element sticks).

    Parameters
    ----------
    slip_amplitude_in : array_like
        Amplitude ``A`` of the imposed relative displacement, in.
    stiffness_lbf_in : array_like
        Stuck (tangential contact) stiffness ``k``, lbf/in.
    slip_force_lbf : array_like
        Coulomb limit ``Fs``, lbf.
    """
    a = np.abs(np.asarray(slip_amplitude_in, dtype=float))
    fs = np.asarray(slip_force_lbf, dtype=float)
    k = np.asarray(stiffness_lbf_in, dtype=float)
    return 4.0 * fs * np.maximum(a - fs / k, 0.0)


def jenkins_secant_stiffness(slip_amplitude_in, stiffness_lbf_in, slip_force_lbf):
    """First-harmonic in-phase stiffness of a Jenkins element, lbf/in.

    With ``cos(theta*) = 1 - 2 Fs / (k A)`` (the phase at which a stuck
    element starts to slide in each half cycle),
    ``k_eq = k (theta* - sin(theta*) cos(theta*)) / pi``; ``k_eq = k`` while stuck.
    """
    a = np.abs(np.asarray(slip_amplitude_in, dtype=float))
    k = np.asarray(stiffness_lbf_in, dtype=float)
    fs = np.asarray(slip_force_lbf, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(a > 0, fs / (k * a), np.inf)
    cos_t = np.clip(1.0 - 2.0 * ratio, -1.0, 1.0)
    theta = np.arccos(cos_t)
    return k * (theta - np.sin(theta) * cos_t) / np.pi


def jenkins_force_update(force_lbf, slip_increment_in, stiffness_lbf_in, slip_force_lbf):
    """Advance Jenkins element forces by a slip increment (vectorised over patches).

    Exact for a monotone increment: elastic trial force, then return to the
    Coulomb limit.  Returns the new forces, lbf.
    """
    trial = force_lbf + stiffness_lbf_in * slip_increment_in
    return np.clip(trial, -slip_force_lbf, slip_force_lbf)


# -------------------------------------------------------------------- Dahl


def dahl_secant_stiffness(amplitude, sigma, coulomb_force):
    """First-harmonic in-phase stiffness of the Dahl model.

    From the steady-loop branch of :func:`workflow.models.friction.dahl_dissipation_per_cycle`
    (tip force ``Fc tanh s`` at amplitude ``A``),
    ``k_eq = 2 Fc I1(s) / (A cosh s)``, ``s = sigma A / Fc``
    (``I1`` the modified Bessel function); ``k_eq -> sigma`` as ``A -> 0``.
    Evaluated with the exponentially scaled Bessel function to avoid overflow.
    """
    a = np.abs(np.asarray(amplitude, dtype=float))
    s = sigma * a / coulomb_force
    with np.errstate(divide="ignore", invalid="ignore"):
        # I1(s)/cosh(s) = i1e(s) * 2 / (1 + exp(-2 s))
        k = 2.0 * coulomb_force * scipy.special.i1e(s) * 2.0 / (1.0 + np.exp(-2.0 * s)) / a
    return np.where(s > 1e-8, k, sigma)


# -------------------------------------------------------- bolted interface


@dataclass(frozen=True)
class JointParameters:
    """Physical parameters of the bolted interface (same for every configuration)."""

    bolt_torque_in_lbf: float = 85.0
    nut_factor: float = 0.2
    """Torque coefficient K in T = K F d (dry steel, ~0.2)."""
    bolt_diameter_in: float = 0.25
    hole_radius_in: float = 0.133
    """Clearance hole radius (17/64" drill); no contact inside it."""
    friction_coefficient: float = 0.12
    """Dry/lightly oiled mill-finish steel."""
    pressure_decay_length_in: float = 0.2
    """Gaussian decay length of the clamping pressure away from the hole edge,
    ``p ~ exp(-((r - r_hole) / l)^2)``: about the plate thickness, the depth over
    which the head load spreads; beyond a few l the surfaces barely touch."""
    contact_stiffness_lbf_in3: float = 3.0e6
    """Tangential contact stiffness per unit area at the reference pressure."""
    reference_pressure_psi: float = 1000.0
    stiffness_pressure_exponent: float = 1.0 / 3.0
    """Tangential stiffness ~ p^(1/3) (Mindlin: a Hertzian contact's tangential
    stiffness grows as the cube root of its normal load)."""
    patch_size_in: float = 0.02
    geometry: specimen.SpecimenGeometry = field(default_factory=specimen.SpecimenGeometry)

    @property
    def preload_lbf(self) -> float:
        """Bolt clamping force from the torque, lbf."""
        return bolt_preload_lbf(self.bolt_torque_in_lbf, self.nut_factor, self.bolt_diameter_in)


def bolt_preload_lbf(torque_in_lbf: float, nut_factor: float, diameter_in: float) -> float:
    """Clamping force from tightening torque, ``F = T / (K d)``, lbf."""
    return torque_in_lbf / (nut_factor * diameter_in)


@dataclass(frozen=True)
class ContactPatches:
    """Contact patches of one interface (all four interfaces are mirror images)."""

    x_rel_in: np.ndarray
    """Axial position relative to the bolt, positive towards the specimen centre, in."""
    y_in: np.ndarray
    area_in2: np.ndarray
    pressure_psi: np.ndarray
    stiffness_lbf_in: np.ndarray
    """Tangential stuck stiffness of each patch, lbf/in."""
    slip_force_lbf: np.ndarray
    """Coulomb limit mu p A of each patch, lbf."""


def contact_patches(bearing_area_in2: float, params: JointParameters | None = None) -> ContactPatches:
    """Split one interface's bearing area into Jenkins patches.

    The bearing region is the set of grid cells nearest to the bolt (outside
    the clearance hole, inside the overlap) whose total area is the
    configuration's bearing area, so a washer's small area is a small ring and
    the no-washer area fills the overlap.  The preload is spread over it with
    ``p ~ exp(-((r - r_hole) / l)^2)``.

    Parameters
    ----------
    bearing_area_in2 : float
        Area over which micro-slip can occur, in^2.
    params : JointParameters, optional
    """
    params = params or JointParameters()
    g = params.geometry
    h = params.patch_size_in
    half_x, half_y = 0.5 * g.overlap_length_in, 0.5 * g.width_in
    nx, ny = int(round(2 * half_x / h)), int(round(2 * half_y / h))
    xc = -half_x + (np.arange(nx) + 0.5) * (2 * half_x / nx)
    yc = -half_y + (np.arange(ny) + 0.5) * (2 * half_y / ny)
    xx, yy = np.meshgrid(xc, yc, indexing="ij")
    r = np.hypot(xx, yy).ravel()
    cell_area = (2 * half_x / nx) * (2 * half_y / ny)
    outside_hole = r >= params.hole_radius_in
    available = outside_hole.sum() * cell_area
    if not 0 < bearing_area_in2 <= available * (1 + 1e-9):
        raise ValueError(
            f"bearing area {bearing_area_in2} in^2 must be positive and fit in "
            f"the overlap ({available:.3f} in^2 outside the bolt hole)"
        )
    candidates = np.flatnonzero(outside_hole)
    order = candidates[np.argsort(r[candidates], kind="stable")]
    n_cells = max(1, int(round(bearing_area_in2 / cell_area)))
    chosen = np.sort(order[:n_cells])
    area = np.full(chosen.size, bearing_area_in2 / chosen.size)
    weight = np.exp(-(((r[chosen] - params.hole_radius_in) / params.pressure_decay_length_in) ** 2))
    pressure = params.preload_lbf * weight / np.sum(weight * area)
    k_area = (
        params.contact_stiffness_lbf_in3
        * (pressure / params.reference_pressure_psi) ** params.stiffness_pressure_exponent
    )
    return ContactPatches(
        x_rel_in=xx.ravel()[chosen],
        y_in=yy.ravel()[chosen],
        area_in2=area,
        pressure_psi=pressure,
        stiffness_lbf_in=k_area * area,
        slip_force_lbf=params.friction_coefficient * pressure * area,
    )


def strip_springs(patches: ContactPatches) -> tuple[specimen.InterfaceSprings, np.ndarray]:
    """Lump patches at equal axial position into FE point springs.

    The beam model has no transverse (y) coordinate, so patches across the
    width share their slip.  Returns the springs and, per patch, the index of
    its strip.
    """
    strips, index = np.unique(np.round(patches.x_rel_in, 9), return_inverse=True)
    k_t = np.bincount(index, weights=patches.stiffness_lbf_in)
    return specimen.InterfaceSprings(strips, k_t, k_t / specimen.MINDLIN_TANGENTIAL_TO_NORMAL), index


@dataclass(frozen=True)
class JointModes:
    """A configuration's first mode with its contact patches."""

    patches: ContactPatches
    mode: specimen.FirstMode
    slip_per_xi: np.ndarray
    """Interface slip per unit modal coordinate of every patch on every
    interface, shape (n_interfaces, n_patches), in."""

    @property
    def omega_rad_s(self) -> float:
        return 2 * np.pi * self.mode.frequency_hz


def joint_first_mode(
    bearing_area_in2: float, params: JointParameters | None = None, elements_per_inch: float = 8.0
) -> JointModes:
    """First mode of the specimen with this configuration's stuck contact patches."""
    params = params or JointParameters()
    patches = contact_patches(bearing_area_in2, params)
    springs, index = strip_springs(patches)
    mode = specimen.first_mode(params.geometry, elements_per_inch=elements_per_inch, springs=springs)
    return JointModes(patches, mode, mode.slip_per_xi[:, index])


def patch_describing_function(modal_amplitude, slip_per_xi, stiffness_lbf_in, slip_force_lbf):
    """Friction dissipation per cycle and stiffness loss of the patch model.

    Parameters
    ----------
    modal_amplitude : array_like, shape (n,)
        Amplitude of the modal coordinate xi.
    slip_per_xi : ndarray
        Interface slip per unit xi of every patch (any shape, broadcast
        against ``stiffness_lbf_in`` and ``slip_force_lbf``).

    Returns
    -------
    dissipation_in_lbf : ndarray, shape (n,)
        Energy dissipated per cycle by all patches.
    modal_stiffness_loss : ndarray, shape (n,)
        Loss of modal stiffness (units of omega^2 for mass-normalised modes):
        ``sum s^2 (k - k_eq(|s| a))``.
    """
    a = np.atleast_1d(np.asarray(modal_amplitude, dtype=float))
    s = np.abs(np.asarray(slip_per_xi, dtype=float)).ravel()
    k = np.broadcast_to(stiffness_lbf_in, np.shape(slip_per_xi)).ravel()
    fs = np.broadcast_to(slip_force_lbf, np.shape(slip_per_xi)).ravel()
    dissipation = np.empty(a.size)
    loss = np.empty(a.size)
    onset = fs / (k * np.where(s > 0, s, np.inf))  # modal amplitude at slip onset
    for i, amp in enumerate(a):
        active = onset < amp  # stuck patches contribute nothing to either
        sa = s[active] * amp
        dissipation[i] = jenkins_dissipation_per_cycle(sa, k[active], fs[active]).sum()
        loss[i] = np.sum(s[active] ** 2 * (k[active] - jenkins_secant_stiffness(sa, k[active], fs[active])))
    return dissipation, loss


def equivalent_damping(modal_amplitude, omega0_rad_s, zeta0, dissipation_in_lbf, modal_stiffness_loss):
    """Equivalent damping ratio and natural frequency of the nonlinear mode.

    The first-harmonic balance of a mass-normalised mode gives
    ``omega^2 = omega0^2 - loss``; energy balance over one cycle at potential
    energy ``omega^2 a^2 / 2`` gives ``zeta = zeta0 omega0 / omega +
    D / (2 pi omega^2 a^2)`` (so that ``da/dt = -zeta omega a``).

    Returns
    -------
    zeta : ndarray
    omega_rad_s : ndarray
        Undamped equivalent natural frequency, rad/s.
    """
    a = np.asarray(modal_amplitude, dtype=float)
    omega2 = omega0_rad_s**2 - np.asarray(modal_stiffness_loss, dtype=float)
    omega = np.sqrt(omega2)
    zeta = zeta0 * omega0_rad_s / omega + np.asarray(dissipation_in_lbf) / (2 * np.pi * omega2 * a**2)
    return zeta, omega
