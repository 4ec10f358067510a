"""Finite-element model of the bolted lap-joint specimen (paper fig. 1).

Two 10" steel beams are spliced by two 3.25" plates, one above and one below,
all 0.25" x 1" sections, with a 0.3125" gap between the beam ends and one
0.25" bolt through each lap (plate / beam / plate).

Model
-----
The specimen is modelled as *layers* (left beam, right beam, top plate, bottom
plate) that share one transverse deflection line ``w(x)`` and its slope
``theta = w'`` (the layers stay in contact through the thickness, so they bend
together), while every layer keeps its own axial displacement ``u_layer(x)`` of
its centroid.  This is the classic partial-interaction layered beam (Newmark):

* each layer contributes Euler-Bernoulli bending ``EI_layer`` about its own
  centroid (cubic Hermite element) and bar stiffness ``EA`` (linear element),
  with consistent mass matrices for both;
* the layers are tied tangentially only through the interface contact:
  point springs (the stuck contact patches of :mod:`workflow.models.contact`) acting
  on the interface slip.

Interface slip (the quantity that drives friction): with plane sections,
the axial displacement at height ``z`` of a layer with centroid ``z_c`` is
``u_layer - (z - z_c) w'``.  At the interface between a beam (centroid
``z_b``) and a plate (centroid ``z_p``) the slip, plate surface minus beam
surface, is therefore

    s = u_plate - u_beam + (z_p - z_b) * w'

(the interface height cancels).  With infinitely stiff interface springs the
plates follow the beam's plane section and the overlap bends like one
0.75" thick composite section; with none they bend independently.

Units: inch, second, lbf; mass density in lbf s^2 / in^4.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.linalg

__all__ = [
    "G_IN_S2",
    "STEEL_E_PSI",
    "STEEL_DENSITY_LBF_S2_IN4",
    "MINDLIN_TANGENTIAL_TO_NORMAL",
    "DEFAULT_CONTACT_STIFFNESS_LBF_IN3",
    "SpecimenGeometry",
    "Interface",
    "InterfaceSprings",
    "SpecimenModel",
    "default_interface_springs",
    "LinearMode",
    "FirstMode",
    "first_mode",
]


G_IN_S2 = 386.0886
"""Standard gravity, in/s^2."""

STEEL_E_PSI = 29.0e6
"""Young's modulus of steel, psi."""

STEEL_DENSITY_LBF_S2_IN4 = 0.2836 / G_IN_S2
"""Mass density of steel: 0.2836 lbm/in^3 divided by g, lbf s^2 / in^4."""

MINDLIN_TANGENTIAL_TO_NORMAL = 2 * (1 - 0.3) / (2 - 0.3)
"""Ratio of tangential to normal contact stiffness (Mindlin, Poisson 0.3)."""

DEFAULT_CONTACT_STIFFNESS_LBF_IN3 = 1.0e6
"""Uniform tangential stiffness per unit area used when no contact model is
supplied, lbf/in^3: the uniform value that gives the same first frequency as
the no-washer contact patches of :mod:`workflow.models.contact` (whose stiffness is
concentrated near the bolt and tiny in the lightly clamped periphery)."""


@dataclass(frozen=True)
class SpecimenGeometry:
    """Dimensions of the jointed beam (inches) and instrument positions."""

    beam_length_in: float = 10.0
    plate_length_in: float = 3.25
    gap_in: float = 0.3125
    thickness_in: float = 0.25
    width_in: float = 1.0
    accelerometer_offset_in: float = 0.5
    """Accelerometer distance outside the joint (outside the left plate end)."""
    hammer_offset_in: float = 0.5
    """Hammer distance from the far (right) end, opposite the accelerometer."""
    suspension_offset_in: float = 4.5
    """Rubber-tubing suspension points, measured from each outer end."""

    @property
    def total_length_in(self) -> float:
        return 2.0 * self.beam_length_in + self.gap_in

    @property
    def plate_start_in(self) -> float:
        return 0.5 * self.total_length_in - 0.5 * self.plate_length_in

    @property
    def plate_end_in(self) -> float:
        return 0.5 * self.total_length_in + 0.5 * self.plate_length_in

    @property
    def overlap_length_in(self) -> float:
        return 0.5 * (self.plate_length_in - self.gap_in)

    @property
    def bolt_positions_in(self) -> tuple[float, float]:
        """Bolt axes, centred in each overlap (left lap, right lap)."""
        half = 0.5 * self.overlap_length_in
        return (self.plate_start_in + half, self.plate_end_in - half)

    @property
    def accelerometer_x_in(self) -> float:
        return self.plate_start_in - self.accelerometer_offset_in

    @property
    def hammer_x_in(self) -> float:
        return self.total_length_in - self.hammer_offset_in

    @property
    def suspension_x_in(self) -> tuple[float, float]:
        return (self.suspension_offset_in, self.total_length_in - self.suspension_offset_in)

    @property
    def area_in2(self) -> float:
        return self.thickness_in * self.width_in

    @property
    def inertia_in4(self) -> float:
        return self.width_in * self.thickness_in**3 / 12.0


@dataclass(frozen=True)
class _Layer:
    name: str
    x0_in: float
    x1_in: float
    z_in: float


@dataclass(frozen=True)
class Interface:
    """One beam/plate contact interface (4 in the specimen)."""

    lap: str
    """``left`` or ``right``."""
    side: str
    """``top`` or ``bottom``."""
    beam_layer: int
    plate_layer: int
    bolt_x_in: float
    outward: float
    """+1 when the overlap's outer (plate-end) side is at larger x... used to mirror
    patch positions so both laps are mirror images about the specimen centre."""


@dataclass(frozen=True)
class InterfaceSprings:
    """Tangential point springs on every interface (the stuck contact patches).

    Positions are along the beam axis relative to the bolt, positive towards the
    specimen centre; the same set is applied mirrored to both laps and to the top
    and bottom interfaces.
    """

    x_rel_in: np.ndarray
    stiffness_lbf_in: np.ndarray
    """Tangential (stuck) stiffness of each spring, lbf/in."""
    normal_stiffness_lbf_in: np.ndarray
    """Normal contact stiffness of each spring, lbf/in (keeps the layers together
    where they are clamped; elsewhere plate and beam may open)."""


def _hermite(xi: float, le: float) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Hermite shape functions and their x-derivatives at xi in [0, 1]."""
    n = np.array(
        [
            1 - 3 * xi**2 + 2 * xi**3,
            le * (xi - 2 * xi**2 + xi**3),
            3 * xi**2 - 2 * xi**3,
            le * (-(xi**2) + xi**3),
        ]
    )
    dn = np.array(
        [(-6 * xi + 6 * xi**2) / le, 1 - 4 * xi + 3 * xi**2, (6 * xi - 6 * xi**2) / le, -2 * xi + 3 * xi**2]
    )
    return n, dn


def _beam_element(ei: float, rho_a: float, le: float) -> tuple[np.ndarray, np.ndarray]:
    """Euler-Bernoulli element stiffness and consistent mass, dofs (w1, t1, w2, t2)."""
    k = (
        ei
        / le**3
        * np.array(
            [
                [12, 6 * le, -12, 6 * le],
                [6 * le, 4 * le**2, -6 * le, 2 * le**2],
                [-12, -6 * le, 12, -6 * le],
                [6 * le, 2 * le**2, -6 * le, 4 * le**2],
            ]
        )
    )
    m = (
        rho_a
        * le
        / 420.0
        * np.array(
            [
                [156, 22 * le, 54, -13 * le],
                [22 * le, 4 * le**2, 13 * le, -3 * le**2],
                [54, 13 * le, 156, -22 * le],
                [-13 * le, -3 * le**2, -22 * le, 4 * le**2],
            ]
        )
    )
    return k, m


def _bar_element(ea: float, rho_a: float, le: float) -> tuple[np.ndarray, np.ndarray]:
    """Axial bar element stiffness and consistent mass, dofs (u1, u2)."""
    k = ea / le * np.array([[1.0, -1.0], [-1.0, 1.0]])
    m = rho_a * le / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    return k, m


@dataclass
class SpecimenModel:
    """Assembled linear FE model of the specimen.

    Parameters
    ----------
    geometry : SpecimenGeometry
    elements_per_inch : float
        Mesh density along the axis (elements per inch).
    springs : InterfaceSprings or None
        Stuck contact stiffness; None uses a uniform clamped interface of
        ``DEFAULT_CONTACT_STIFFNESS_LBF_IN3`` over the whole overlap.
    """

    geometry: SpecimenGeometry = field(default_factory=SpecimenGeometry)
    elements_per_inch: float = 8.0
    springs: InterfaceSprings | None = None

    def __post_init__(self) -> None:
        g = self.geometry
        t = g.thickness_in
        self.layers = [
            _Layer("left_beam", 0.0, g.beam_length_in, 0.0),
            _Layer("right_beam", g.beam_length_in + g.gap_in, g.total_length_in, 0.0),
            _Layer("top_plate", g.plate_start_in, g.plate_end_in, t),
            _Layer("bottom_plate", g.plate_start_in, g.plate_end_in, -t),
        ]
        bl, br = g.bolt_positions_in
        self.interfaces = [
            Interface("left", "top", 0, 2, bl, +1.0),
            Interface("left", "bottom", 0, 3, bl, +1.0),
            Interface("right", "top", 1, 2, br, -1.0),
            Interface("right", "bottom", 1, 3, br, -1.0),
        ]
        if self.springs is None:
            self.springs = default_interface_springs(g)
        self._mesh()
        self._assemble()

    # ---------------------------------------------------------------- mesh
    def _mesh(self) -> None:
        g = self.geometry
        keys = {
            0.0,
            g.total_length_in,
            g.beam_length_in,
            g.beam_length_in + g.gap_in,
            g.plate_start_in,
            g.plate_end_in,
            g.accelerometer_x_in,
            g.hammer_x_in,
            *g.bolt_positions_in,
            *g.suspension_x_in,
        }
        keys = np.array(sorted(keys))
        xs = [keys[0]]
        for a, b in zip(keys[:-1], keys[1:]):
            n = max(1, int(np.ceil((b - a) * self.elements_per_inch - 1e-9)))
            xs.extend(a + (b - a) * np.arange(1, n + 1) / n)
        self.x_in = np.array(xs)
        n_nodes = self.x_in.size
        # Every layer owns (u, w, theta) at the global nodes inside its extent;
        # dof[layer][node, 0..2], -1 outside the layer.
        self.dof = []
        next_dof = 0
        for layer in self.layers:
            dofs = -np.ones((n_nodes, 3), dtype=int)
            inside = (self.x_in >= layer.x0_in - 1e-9) & (self.x_in <= layer.x1_in + 1e-9)
            count = int(inside.sum())
            dofs[inside] = next_dof + np.arange(3 * count).reshape(count, 3)
            next_dof += 3 * count
            self.dof.append(dofs)
        self.n_dofs = next_dof

    def _assemble(self) -> None:
        g = self.geometry
        e, rho = STEEL_E_PSI, STEEL_DENSITY_LBF_S2_IN4
        a, i = g.area_in2, g.inertia_in4
        k = np.zeros((self.n_dofs, self.n_dofs))
        m = np.zeros_like(k)
        for li in range(len(self.layers)):
            dof = self.dof[li]
            for el in range(self.x_in.size - 1):
                if dof[el, 0] < 0 or dof[el + 1, 0] < 0:
                    continue
                le = self.x_in[el + 1] - self.x_in[el]
                bend = np.array([dof[el, 1], dof[el, 2], dof[el + 1, 1], dof[el + 1, 2]])
                kb, mb = _beam_element(e * i, rho * a, le)
                k[np.ix_(bend, bend)] += kb
                m[np.ix_(bend, bend)] += mb
                ax = np.array([dof[el, 0], dof[el + 1, 0]])
                ka, ma = _bar_element(e * a, rho * a, le)
                k[np.ix_(ax, ax)] += ka
                m[np.ix_(ax, ax)] += ma
        springs = self.springs
        for interface in self.interfaces:
            for j, x_rel in enumerate(springs.x_rel_in):
                x = float(self.patch_x_in(interface, x_rel))
                for (idx, val), stiff in (
                    (self._slip_entries(interface, x), springs.stiffness_lbf_in[j]),
                    (self._gap_entries(interface, x), springs.normal_stiffness_lbf_in[j]),
                ):
                    k[np.ix_(idx, idx)] += stiff * np.outer(val, val)
        self.stiffness = k
        self.mass = m

    # ------------------------------------------------------------ operators
    def patch_x_in(self, interface: Interface, x_rel_in: np.ndarray | float) -> np.ndarray:
        """Absolute x of a patch given relative to the bolt (positive towards centre)."""
        return interface.bolt_x_in + interface.outward * np.asarray(x_rel_in, dtype=float)

    def _element_of(self, x_in: float) -> tuple[int, float, float]:
        el = int(np.clip(np.searchsorted(self.x_in, x_in, side="right") - 1, 0, self.x_in.size - 2))
        le = self.x_in[el + 1] - self.x_in[el]
        return el, (x_in - self.x_in[el]) / le, le

    def _layer_entries(self, layer: int, x_in: float, what: str) -> tuple[np.ndarray, np.ndarray]:
        """Dof indices and weights giving u, w or w' of one layer at x."""
        el, xi, le = self._element_of(x_in)
        dof = self.dof[layer]
        if dof[el, 0] < 0 or dof[el + 1, 0] < 0:
            raise ValueError(f"x = {x_in:.4f} in is outside layer {self.layers[layer].name}")
        if what == "u":
            return np.array([dof[el, 0], dof[el + 1, 0]]), np.array([1.0 - xi, xi])
        n, dn = _hermite(xi, le)
        idx = np.array([dof[el, 1], dof[el, 2], dof[el + 1, 1], dof[el + 1, 2]])
        return idx, (n if what == "w" else dn)

    def _slip_entries(self, interface: Interface, x_in: float) -> tuple[np.ndarray, np.ndarray]:
        zb = self.layers[interface.beam_layer].z_in
        zp = self.layers[interface.plate_layer].z_in
        zi = 0.5 * (zb + zp)
        parts = [
            self._layer_entries(interface.plate_layer, x_in, "u"),
            self._layer_entries(interface.beam_layer, x_in, "u"),
            self._layer_entries(interface.plate_layer, x_in, "dw"),
            self._layer_entries(interface.beam_layer, x_in, "dw"),
        ]
        # surface axial displacement = u - (z_interface - z_centroid) * w'
        scale = [1.0, -1.0, -(zi - zp), (zi - zb)]
        return (
            np.concatenate([p[0] for p in parts]),
            np.concatenate([s * p[1] for s, p in zip(scale, parts)]),
        )

    def _gap_entries(self, interface: Interface, x_in: float) -> tuple[np.ndarray, np.ndarray]:
        wp = self._layer_entries(interface.plate_layer, x_in, "w")
        wb = self._layer_entries(interface.beam_layer, x_in, "w")
        return np.concatenate([wp[0], wb[0]]), np.concatenate([wp[1], -wb[1]])

    def _row(self, entries: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        row = np.zeros(self.n_dofs)
        np.add.at(row, entries[0], entries[1])
        return row

    def deflection_operator(self, x_in: float) -> np.ndarray:
        """Row vector mapping the dof vector to the transverse deflection at x.

        On a beam where one exists, else (in the gap) the mean of the two plates.
        """
        beams = [
            li
            for li in (0, 1)
            if self.dof[li][self._element_of(x_in)[0], 0] >= 0
            and self.dof[li][self._element_of(x_in)[0] + 1, 0] >= 0
        ]
        if beams:
            return self._row(self._layer_entries(beams[0], x_in, "w"))
        return 0.5 * (
            self._row(self._layer_entries(2, x_in, "w")) + self._row(self._layer_entries(3, x_in, "w"))
        )

    def slip_operator(self, interface: Interface, x_in: float) -> np.ndarray:
        """Row vector mapping the dof vector to the interface slip at x.

        Slip = plate surface minus beam surface axial displacement, inches.
        """
        return self._row(self._slip_entries(interface, x_in))

    # -------------------------------------------------------------- modes
    @cached_property
    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """All modes: (natural frequencies in Hz, mass-normalised shapes as columns)."""
        # only the low modes are needed (mode 1, the measured band, rigid modes)
        n = min(self.n_dofs, 40)
        lam, vec = scipy.linalg.eigh(self.stiffness, self.mass, subset_by_index=[0, n - 1])
        lam = np.clip(lam, 0.0, None)
        return np.sqrt(lam) / (2.0 * np.pi), vec


def default_interface_springs(geometry: SpecimenGeometry, spacing_in: float = 0.02) -> InterfaceSprings:
    """Uniform clamped interface over the whole overlap, as point springs.

    Parameters
    ----------
    geometry : SpecimenGeometry
    spacing_in : float
        Spring spacing along the axis, inches.
    """
    half = 0.5 * geometry.overlap_length_in
    n = int(round(2 * half / spacing_in))
    x_rel = -half + (np.arange(n) + 0.5) * (2 * half / n)
    k = np.full(n, DEFAULT_CONTACT_STIFFNESS_LBF_IN3 * geometry.width_in * 2 * half / n)
    return InterfaceSprings(x_rel, k, k / MINDLIN_TANGENTIAL_TO_NORMAL)


@dataclass(frozen=True)
class LinearMode:
    """A linear mode as seen by the instruments."""

    frequency_hz: float
    accelerometer_participation: float
    """Mass-normalised mode shape at the accelerometer (in per unit modal coordinate)."""
    hammer_participation: float
    """Mass-normalised mode shape at the hammer point (in per unit modal coordinate)."""
    shape_in: np.ndarray
    """Mass-normalised transverse deflection at the first mode's ``x_in`` (in per unit
    modal coordinate): what a sensor elsewhere on the beam sees of this mode."""
    slip_per_xi: np.ndarray
    """Interface slip per unit modal coordinate at every interface spring (in/in), as
    :attr:`FirstMode.slip_per_xi`: how much the joint takes part in this mode."""


@dataclass(frozen=True)
class FirstMode:
    """The first flexible bending mode and what the measurement model needs."""

    frequency_hz: float
    x_in: np.ndarray
    """Deflection-line node positions, inches."""
    shape_in: np.ndarray
    """Mass-normalised transverse deflection at ``x_in`` (in per unit xi)."""
    node_positions_in: np.ndarray
    """Zero crossings of the deflection (the two nodes of mode 1), inches."""
    accelerometer_participation: float
    hammer_participation: float
    slip_per_xi: np.ndarray
    """Interface slip per unit modal coordinate at every interface spring (in/in),
    shape (n_interfaces, n_springs), same order as the springs."""
    higher_modes: tuple[LinearMode, ...]
    """Flexible modes above mode 1 and below the cut-off frequency."""
    total_mass_lbf_s2_in: float
    pitch_inertia_lbf_s2_in: float
    """Rigid-body mass and pitch inertia about the centre of mass (for the
    suspension modes)."""
    centre_of_mass_in: float


def first_mode(
    geometry: SpecimenGeometry | None = None,
    *,
    elements_per_inch: float = 8.0,
    springs: InterfaceSprings | None = None,
    higher_mode_cutoff_hz: float = 1100.0,
) -> FirstMode:
    """Modal analysis of the free-free specimen; return mode 1 and the linear rest.

    Parameters
    ----------
    geometry : SpecimenGeometry, optional
    elements_per_inch : float
        Mesh density.
    springs : InterfaceSprings, optional
        Stuck contact patches (from :mod:`workflow.models.contact`); default uniform.
    higher_mode_cutoff_hz : float
        Flexible modes above this are dropped (the acquisition's anti-alias
        filter removes them at 2560 samples/s).

    Returns
    -------
    FirstMode
    """
    geometry = geometry or SpecimenGeometry()
    model = SpecimenModel(geometry, elements_per_inch, springs)
    freqs, vecs = model.modes
    acc_row = model.deflection_operator(geometry.accelerometer_x_in)
    ham_row = model.deflection_operator(geometry.hammer_x_in)
    line = np.array([model.deflection_operator(x) for x in model.x_in])
    # Flexible bending modes: non-zero frequency and a real transverse deflection
    # (the layers' axial modes barely move the deflection line).
    deflection = np.abs(line @ vecs).max(axis=0)
    bending = deflection > 1e-3 * deflection.max()
    flexible = np.flatnonzero((freqs > 1.0) & bending)
    first = flexible[0]
    phi = vecs[:, first].copy()
    if ham_row @ phi < 0:  # sign convention: hammer point moves positively
        phi = -phi
    shape = line @ phi
    crossings = np.flatnonzero(np.sign(shape[:-1]) * np.sign(shape[1:]) < 0)
    nodes = model.x_in[crossings] - shape[crossings] * (model.x_in[crossings + 1] - model.x_in[crossings]) / (
        shape[crossings + 1] - shape[crossings]
    )
    slip_rows = [
        [model.slip_operator(itf, float(model.patch_x_in(itf, x))) for x in model.springs.x_rel_in]
        for itf in model.interfaces
    ]
    slip = np.array([[row @ phi for row in rows] for rows in slip_rows])
    higher = tuple(
        LinearMode(
            float(freqs[j]),
            float(acc_row @ vecs[:, j]),
            float(ham_row @ vecs[:, j]),
            shape_in=line @ vecs[:, j],
            slip_per_xi=np.array(slip_rows) @ vecs[:, j],
        )
        for j in flexible[1:]
        if freqs[j] <= higher_mode_cutoff_hz
    )
    # Rigid-body mass and pitch inertia: a rigid transverse translation and a
    # rigid rotation expressed in the layered dofs.
    translation = np.zeros(model.n_dofs)
    rotation = np.zeros(model.n_dofs)
    for li in range(len(model.layers)):
        inside = model.dof[li][:, 0] >= 0
        translation[model.dof[li][inside, 1]] = 1.0
        rotation[model.dof[li][inside, 1]] = model.x_in[inside]
        rotation[model.dof[li][inside, 2]] = 1.0
        # a rigid rotation also moves each layer's centroid axially by -z * angle
        rotation[model.dof[li][inside, 0]] = -model.layers[li].z_in
    mass = float(translation @ model.mass @ translation)
    x_cm = float(translation @ model.mass @ rotation) / mass
    about_cm = rotation - x_cm * translation
    inertia = float(about_cm @ model.mass @ about_cm)
    return FirstMode(
        frequency_hz=float(freqs[first]),
        x_in=model.x_in,
        shape_in=shape,
        node_positions_in=nodes,
        accelerometer_participation=float(acc_row @ phi),
        hammer_participation=float(ham_row @ phi),
        slip_per_xi=slip,
        higher_modes=higher,
        total_mass_lbf_s2_in=mass,
        pitch_inertia_lbf_s2_in=inertia,
        centre_of_mass_in=x_cm,
    )
