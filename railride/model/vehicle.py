"""The vehicle assembled from the element table of docs/model.md, Equations: nine rigid DOFs,
and a tenth, the carbody's first vertical bending mode, where its parameters give one
(docs/model.md, Flexible carbody).

Every suspension element is a spring k and a damper c on a deflection that is linear in the
DOFs q and the rail inputs w: delta = a.q + e.w.  The equations of motion

    M q'' + C q' + K q = -(K_w w + C_w w') + T f

follow by assembly: K = sum k a a^T, K_w = sum k a e^T, and likewise C, C_w with c.  Nothing
downstream retypes an equation: matrices, modes, frequency responses and the compiled stepper
all come from `Vehicle`.

Orderings used everywhere:

* DOFs q: carbody bounce, pitch, roll; front bogie bounce, pitch, roll; rear bogie (same);
  then, for a flexible carbody, its bending eta (the centre's deflection, m).
* rail inputs w: z_1L, z_1R, z_2L, z_2R, z_3L, z_3R, z_4L, z_4R (wheelset 1 leads).
* secondary corners (forces f): 1R, 1L, 2R, 2L (bogie 1 is the front one, R is y = -d_s).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg
import scipy.optimize
import xarray as xr

from railride.errors import InputError
from railride import validation
from railride.engine.layout import N_RAIL, N_RIGID
from railride.model import beam
from railride.model.params import PRESET_SOURCES, PRESETS, VehicleParams

#: the rigid vehicle's DOFs (`Vehicle.n_dof` is 10 for a bending carbody; the engine pads a rigid
#: vehicle's matrices to its own size)
N_DOF = N_RIGID

DOF_NAMES = (
    "carbody_bounce",
    "carbody_pitch",
    "carbody_roll",
    "front_bogie_bounce",
    "front_bogie_pitch",
    "front_bogie_roll",
    "rear_bogie_bounce",
    "rear_bogie_pitch",
    "rear_bogie_roll",
)
DOF_UNITS = ("m", "rad", "rad") * 3
#: the tenth DOF of a flexible carbody: its first vertical bending mode, the centre's deflection
BENDING_NAME = "carbody_bending"
BENDING_UNIT = "m"
#: what each DOF is, in words (the ``long_name`` of its channel)
DOF_LONG_NAMES = tuple(
    f"{body} {motion}"
    for body in ("carbody", "front bogie", "rear bogie")
    for motion in ("bounce displacement", "pitch angle", "roll angle")
)
#: ... and of its velocity
DOF_RATE_LONG_NAMES = tuple(
    f"{body} {motion}"
    for body in ("carbody", "front bogie", "rear bogie")
    for motion in ("bounce velocity", "pitch rate", "roll rate")
)
BENDING_LONG_NAME = "carbody first vertical bending: the centre's deflection from the rigid body"
CORNER_NAMES = ("1R", "1L", "2R", "2L")
WHEELSETS = (1, 2, 3, 4)
RAILS = ("L", "R")
#: the attributes of the label coordinates of the results (CF conventions: a label has the units
#: "", a dimensionless number "1"): secondary corners, wheelsets, rails, floor positions, the
#: samples of a batch and time
LABEL_ATTRS = {
    "corner": {"long_name": "secondary suspension corner (bogie 1 leads; R at y = -d_s)", "units": ""},
    "wheelset": {"long_name": "wheelset (1 leads)", "units": ""},
    "rail": {"long_name": "rail (L left, R right)", "units": ""},
    "position": {"long_name": "carbody floor position", "units": ""},
    "sample": {"long_name": "sample of the batch", "units": ""},
    "time": {"long_name": "time", "units": "s"},
}
N_RAIL_INPUT = N_RAIL

_BODY_OFFSET = {"carbody": 0, "front_bogie": 3, "rear_bogie": 6}


@dataclass(frozen=True)
class Element:
    """One suspension element: delta = a.q + e.w, with spring k [N/m] and damper c [N s/m]
    (an angular deflection in rad for the anti-roll bar: k in N m/rad)."""

    name: str
    group: str
    k: float
    c: float
    a: np.ndarray  # (n_dof,) coefficients on the DOFs (9, or 10 with the carbody's bending)
    e: np.ndarray  # (8,) coefficients on the rail inputs


def _rail_index(wheelset: int, rail: str) -> int:
    return 2 * (wheelset - 1) + (0 if rail == "L" else 1)


def _point(body: str, x: float, y: float, n: int = N_DOF) -> np.ndarray:
    """a-vector (of ``n`` DOFs) of the vertical motion of point (x, y) of a body as a rigid
    body: z - x*phi + y*theta."""
    a = np.zeros(n)
    i = _BODY_OFFSET[body]
    a[i], a[i + 1], a[i + 2] = 1.0, -x, y
    return a


def _carbody_point(p: VehicleParams, x: float, y: float) -> np.ndarray:
    """a-vector of the vertical motion of the carbody's point (x, y): z_c - x phi_c + y theta_c,
    plus phi(x) eta where the carbody bends (`railride.model.beam.mode_shape`)."""
    if not p.flexible:
        return _point("carbody", x, y)
    a = _point("carbody", x, y, N_DOF + 1)
    assert p.L_c is not None  # a flexible carbody has its length (VehicleParams' check)
    a[N_DOF] = beam.mode_shape(x, p.L_c)
    return a


def _wheelset_point(wheelset: int, y: float, half_gauge: float) -> np.ndarray:
    """e-vector of z_w + y*theta_w, the wheelset following its rails."""
    e = np.zeros(N_RAIL_INPUT)
    e[_rail_index(wheelset, "L")] = 0.5 + y / (2.0 * half_gauge)
    e[_rail_index(wheelset, "R")] = 0.5 - y / (2.0 * half_gauge)
    return e


def _wheelset_roll(wheelset: int, half_gauge: float) -> np.ndarray:
    """e-vector of theta_w = (z_L - z_R) / (2a)."""
    e = np.zeros(N_RAIL_INPUT)
    e[_rail_index(wheelset, "L")] = 1.0 / (2.0 * half_gauge)
    e[_rail_index(wheelset, "R")] = -1.0 / (2.0 * half_gauge)
    return e


def element_table(p: VehicleParams) -> list[Element]:
    """The element list of docs/model.md, Equations, in code: 36 elements, an anti-roll bar
    per bogie (group "anti_roll_bar") where k_ar > 0, and the carbody's bending (group
    "carbody_bending", its modal stiffness and damping on the tenth DOF) where it bends. Nothing
    downstream counts them: the matrices are sums over the list and the secondary force map
    picks its group by name."""
    n = N_DOF + 1 if p.flexible else N_DOF
    elements: list[Element] = []
    zero_e = np.zeros(N_RAIL_INPUT)
    bogies = (("front_bogie", +p.l, (1, 2)), ("rear_bogie", -p.l, (3, 4)))
    for bi, (bogie, x_b, wheelsets) in enumerate(bogies, start=1):
        o = _BODY_OFFSET[bogie]
        # secondary vertical, one per corner; R before L to match the force order
        for side, y in (("R", -p.d_s), ("L", +p.d_s)):
            a = _carbody_point(p, x_b, y) - _point(bogie, 0.0, y, n)
            elements.append(Element(f"secondary vertical {bi}{side}", "secondary_vertical", p.k_sz, p.c_sz, a, zero_e))
        # secondary lateral and longitudinal act through roll and pitch only; one of each on
        # each side of the bogie (the paper's eq. 2, 3, 5, 6 carry 2 k_sy, 2 k_sx per bogie and
        # the appendix gives the values per side)
        for side in ("R", "L"):
            a = np.zeros(n)
            a[2], a[o + 2] = p.h_cs, p.h_ts
            elements.append(Element(f"secondary lateral {bi}{side}", "secondary_lateral", p.k_sy, p.c_sy, a, zero_e))
            a = np.zeros(n)
            a[1], a[o + 1] = p.h_cs, p.h_ts
            elements.append(
                Element(f"secondary longitudinal {bi}{side}", "secondary_longitudinal", p.k_sx, p.c_sx, a, zero_e)
            )
        # anti-roll bar, one per bogie: a torsion spring on the carbody's roll relative to the
        # bogie's, delta = theta_c - theta_bi (rad), k_ar in N m/rad, no damping. Left out when
        # k_ar = 0, so that a vehicle without one keeps its 36 elements and its matrices bit
        # for bit.
        if p.k_ar > 0.0:
            a = np.zeros(n)
            a[2], a[o + 2] = 1.0, -1.0
            elements.append(Element(f"anti-roll bar {bi}", "anti_roll_bar", p.k_ar, 0.0, a, zero_e))
        for wheelset, x_axle in zip(wheelsets, (+p.b, -p.b)):
            for side, y in (("R", -p.d_p), ("L", +p.d_p)):
                box = f"{wheelset}{side}"
                a = _point(bogie, x_axle, y, n)
                e = -_wheelset_point(wheelset, y, p.a)
                elements.append(Element(f"primary vertical {box}", "primary_vertical", p.k_pz, p.c_pz, a, e))
                a = np.zeros(n)
                a[o + 1] = p.h_tp
                elements.append(
                    Element(f"primary longitudinal {box}", "primary_longitudinal", p.k_px, p.c_px, a, zero_e)
                )
                a = np.zeros(n)
                a[o + 2] = p.h_tp
                e = p.h_wp * _wheelset_roll(wheelset, p.a)
                elements.append(Element(f"primary lateral {box}", "primary_lateral", p.k_py, p.c_py, a, e))
    if p.flexible:
        # the carbody's bending: the free beam's modal stiffness and damping on eta, from the
        # bending frequency of the free carbody and the modal damping ratio
        m_eta = beam.modal_mass_factor() * p.m_c
        f_bend = p.bending_hz
        assert f_bend is not None  # flexible: f_bend or EI_c
        omega = 2.0 * np.pi * f_bend
        a = np.zeros(n)
        a[N_DOF] = 1.0
        bending = Element(
            "carbody bending", "carbody_bending", m_eta * omega**2, 2.0 * p.zeta_bend * omega * m_eta, a, zero_e
        )
        elements.append(bending)
    return elements


@dataclass(frozen=True)
class Mode:
    """One mode of the passive vehicle (`Vehicle.modes`); every number is finite.

    ``resolved`` is False where one of the mode's roots lies within the eigen-solvers' rounding
    of zero, which grows with the vehicle's fastest root (`resolution`): its numbers are then
    bounds, not values (docs/model.md, Modes and frequency response)."""

    label: str
    frequency_hz: float  # undamped natural frequency, from (K, M)
    damped_frequency_hz: float  # |Im lambda|: 0 for an overdamped mode
    damping_ratio: float  # -Re lambda/|lambda|; an overdamped pair of real roots: >= 1
    shape: np.ndarray  # undamped mode shape, normalised to unit kinetic energy
    resolved: bool = True

    def to_dict(self) -> dict:
        return {
            "label": self.label,
            "frequency_hz": float(self.frequency_hz),
            "damped_frequency_hz": float(self.damped_frequency_hz),
            "damping_ratio": float(self.damping_ratio),
        }


class Vehicle:
    """Matrices, modes and frequency responses of the vehicle for one parameter set: nine rigid
    DOFs, and the carbody's bending as a tenth where the parameters give it (`n_dof`,
    `dof_names`). A bending frequency at or below the carbody's rigid modes on its suspension
    is an InputError naming the field."""

    def __init__(self, params: VehicleParams | str | None = None):
        # a preset name or a parameters file as well, as everywhere a vehicle is asked for
        self.params = VehicleParams.of(params)
        p = self.params
        #: the number of DOFs: 9 (rigid carbody) or 10 (the carbody's bending last)
        self.n_dof = N_DOF + 1 if p.flexible else N_DOF
        #: the DOFs' names in the order of q (`DOF_NAMES`, then `BENDING_NAME` where it bends)
        self.dof_names = (*DOF_NAMES, BENDING_NAME) if p.flexible else DOF_NAMES
        #: their units
        self.dof_units = (*DOF_UNITS, BENDING_UNIT) if p.flexible else DOF_UNITS
        self.elements = element_table(p)
        masses = [p.m_c, p.I_cy, p.I_cx, p.m_b, p.I_by, p.I_bx, p.m_b, p.I_by, p.I_bx]
        if p.flexible:
            masses.append(beam.modal_mass_factor() * p.m_c)  # m_eta = mu m_c
        self.M = np.diag(masses)
        A = np.array([el.a for el in self.elements])  # (n_el, n_dof)
        E = np.array([el.e for el in self.elements])  # (n_el, 8)
        k = np.array([el.k for el in self.elements])
        c = np.array([el.c for el in self.elements])
        self.K = A.T @ (k[:, None] * A)
        self.C = A.T @ (c[:, None] * A)
        self.K_w = A.T @ (k[:, None] * E)
        self.C_w = A.T @ (c[:, None] * E)
        sec = [i for i, el in enumerate(self.elements) if el.group == "secondary_vertical"]
        #: secondary force map (9, 4): columns are the a-vectors of the secondary vertical elements
        self.T = A[sec].T.copy()
        #: damping without the secondary vertical dashpots (those become the forces f)
        self.C0 = self.C - p.c_sz * self.T @ self.T.T
        #: x of each wheelset relative to the carbody centre; wheelset j lags wheelset 1 by
        #: (x1 - xj) / V
        self.wheelset_x = np.array([p.l + p.b, p.l - p.b, -p.l + p.b, -p.l - p.b])
        if p.flexible:
            self._check_bending()

    @property
    def carbody_dofs(self) -> tuple[int, ...]:
        """Where the carbody's DOFs sit in q: bounce, pitch, roll, and its bending where it bends."""
        return (0, 1, 2, N_DOF) if self.params.flexible else (0, 1, 2)

    def floor_point(self, x: float, y: float = 0.0) -> np.ndarray:
        """The a-vector (n_dof) of the vertical motion of the carbody floor's point (x, y) [m
        from the centre; front +, left +]: z_c - x phi_c + y theta_c, plus phi(x) eta where the
        carbody bends (x then within the carbody, |x| <= L_c / 2)."""
        x = validation.number("x", x, "finite", "m")
        y = validation.number("y", y, "finite", "m")
        p = self.params
        half = 0.5 * p.L_c if p.flexible and p.L_c is not None else None
        if half is not None and abs(x) > half:
            raise InputError(
                f"x = {validation.shown(x)} m: the floor point must lie on the carbody, within +-L_c/2 = "
                f"{validation.shown(half)} m of its centre"
            )
        return _carbody_point(p, x, y)

    def rigid_modes(self) -> list[tuple[str, float]]:
        """(label, undamped frequency [Hz]) of the vehicle's nine rigid-body modes, the carbody
        taken rigid (the first nine rows and columns of M and K), by frequency."""
        n = N_DOF
        w2, shapes = scipy.linalg.eigh(self.K[:n, :n], self.M[:n, :n])
        mass = np.diag(self.M)[:n]
        return [
            (_label(shapes[:, i], mass, DOF_NAMES), float(np.sqrt(max(w2[i], 0.0)) / (2 * np.pi))) for i in range(n)
        ]

    def _check_bending(self) -> None:
        """The bending frequency must lie above the carbody's rigid modes on its suspension:
        below them the flexible mode would be the slowest carbody mode, no bending of a body."""
        p = self.params
        carbody = [(label, f) for label, f in self.rigid_modes() if label.startswith("carbody")]
        label, highest = max(carbody, key=lambda m: m[1])
        f = p.bending_hz
        assert f is not None  # called for a flexible carbody
        if not f > highest:
            field, value, unit = ("f_bend", p.f_bend, "Hz") if p.f_bend is not None else ("EI_c", p.EI_c, "N m^2")
            given = "" if field == "f_bend" else f" (a bending frequency of {validation.shown(f)} Hz)"
            raise InputError(
                f"vehicle parameter {field!r} = {validation.shown(value)} {unit}{given}: the carbody's bending "
                f"must lie above its rigid-body modes on the suspension; the highest, {label}, is at "
                f"{highest:.4g} Hz"
            )

    @property
    def wheelset_lag_distance(self) -> np.ndarray:
        """x1 - x_j [m]: how far behind the leading wheelset each wheelset runs."""
        return self.wheelset_x[0] - self.wheelset_x

    @cached_property
    def state_matrix(self) -> np.ndarray:
        """A of x' = A x for x = (q, q') with the passive secondary dampers, rails fixed
        (2 n_dof square)."""
        n = self.n_dof
        Minv = 1.0 / np.diag(self.M)
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -Minv[:, None] * self.K
        A[n:, n:] = -Minv[:, None] * self.C
        return A

    # -- modal analysis ---------------------------------------------------------------------
    def modes(self) -> list[Mode]:
        """Undamped and damped modes of the passive vehicle, sorted by undamped frequency;
        every number finite.

        Undamped modes solve K phi = w^2 M phi. Damped modes are the eigenvalues lambda of the
        state matrix: damped frequency |Im lambda|, damping ratio -Re lambda / |lambda|. An
        overdamped mode is a pair of real roots -s1, -s2: damped frequency 0 and damping
        ratio (s1 + s2) / (2 sqrt(s1 s2)) >= 1, which is c / (2 sqrt(k m)) for one DOF. Damped
        and undamped modes are paired by the modal assurance criterion of their displacement
        shapes. Labels name the DOF group holding most of the mode's kinetic energy ("carbody
        bending" for the flexible carbody's bending mode).

        No vehicle the ranges allow has a rigid-body mode (every spring is > 0, so K is
        positive definite) or a growing one (C >= 0): a root at or past zero is rounding. A
        mode with a root within `resolution` of zero (the solvers' rounding, which grows with
        the fastest root) is not ``resolved``: its numbers are finite but say only that it is
        slow (w^2 <= 0 shown as 0 Hz) or, for an overdamped pair whose slower root rounding
        hides, heavily damped (the ratio of a root at the resolution: a lower bound).
        """
        n = self.n_dof
        w2, shapes = scipy.linalg.eigh(self.K, self.M)
        lam, vecs = np.linalg.eig(self.state_matrix)
        damped = _damped_modes(lam, vecs[:n])
        mac = np.array([[_mac(shapes[:, i], d[2]) for d in damped] for i in range(n)])
        _, match = scipy.optimize.linear_sum_assignment(-np.nan_to_num(mac))  # rows come back as 0..n-1
        floor = resolution(w2)
        out = []
        for i in range(n):  # eigh sorts by frequency
            omega_d, zeta, _, damped_resolved = damped[match[i]]
            out.append(
                Mode(
                    _label(shapes[:, i], np.diag(self.M), self.dof_names),
                    float(np.sqrt(max(w2[i], 0.0)) / (2 * np.pi)),
                    float(omega_d / (2 * np.pi)),
                    float(zeta),
                    shapes[:, i],
                    bool(w2[i] > floor and damped_resolved),
                )
            )
        return out

    # -- frequency response -----------------------------------------------------------------
    def frequency_response(self, frequency_hz, speed: float, rails="in-phase") -> xr.Dataset:
        """Complex response of the passive vehicle per unit rail amplitude.

        ``rails`` sets the rail pattern: "in-phase" (z_L = z_R), "anti-phase" (z_L = -z_R), or
        a pair of complex weights (c_L, c_R). Every wheelset sees the same pattern delayed by
        its lag distance / speed. The result holds the DOF responses (per metre of rail
        amplitude; ``carbody_bending`` too where the carbody bends), carbody CG acceleration
        (rigid: z_c''), the floor accelerations at the centre and over the bogie centres
        (``floor_acceleration`` over ``position``: `floor_point`, with the bending), corner
        displacements and the rail cross-level angle (z_L - z_R)/(2a) of the pattern, all over
        the ``frequency`` coordinate in Hz.
        """
        f = validation.frequencies("frequency_hz", frequency_hz)
        speed = validation.number("speed", speed, "positive", "m/s")
        if isinstance(rails, str):
            patterns = {"in-phase": (1.0 + 0j, 1.0 + 0j), "anti-phase": (1.0 + 0j, -1.0 + 0j)}
            if rails not in patterns:
                raise InputError(f"rails = {rails!r}: allowed 'in-phase', 'anti-phase' or (c_L, c_R)")
            cL, cR = patterns[rails]
        else:
            try:
                cL, cR = (complex(c) for c in rails)
            except (TypeError, ValueError):
                raise InputError(
                    f"rails = {validation.shown(rails)}: allowed 'in-phase', 'anti-phase' or a pair of complex "
                    "weights (c_L, c_R)"
                ) from None
            if not (np.isfinite(cL) and np.isfinite(cR)):
                raise InputError(f"rails = {validation.shown(rails)}: the weights must be finite")
        omega = 2 * np.pi * f
        lag = self.wheelset_lag_distance / speed
        H = np.empty((f.size, self.n_dof), dtype=complex)
        for n, w in enumerate(omega):
            delay = np.exp(-1j * w * lag)  # (4,)
            W = np.empty(N_RAIL_INPUT, dtype=complex)
            W[0::2], W[1::2] = cL * delay, cR * delay
            Z = -(w**2) * self.M + 1j * w * self.C + self.K
            H[n] = np.linalg.solve(Z, -(self.K_w + 1j * w * self.C_w) @ W)
        positions = {"centre": 0.0, "front": self.params.l, "rear": -self.params.l}
        ds = xr.Dataset(
            coords={
                "frequency": ("frequency", f, {"long_name": "frequency", "units": "Hz"}),
                "corner": ("corner", list(CORNER_NAMES), LABEL_ATTRS["corner"]),
                "position": ("position", list(positions), LABEL_ATTRS["position"]),
            }
        )

        def per_metre(long_name: str, units: str) -> dict:
            return {"long_name": f"{long_name} per metre of rail amplitude (complex)", "units": units}

        long_names = (*DOF_LONG_NAMES, BENDING_LONG_NAME)
        for i, name in enumerate(self.dof_names):
            ds[name] = ("frequency", H[:, i], per_metre(long_names[i], f"{self.dof_units[i]}/m"))
        ds["carbody_acceleration"] = (
            "frequency",
            -(omega**2) * H[:, 0],
            per_metre("carbody CG vertical acceleration", "(m/s^2)/m"),
        )
        floor = np.array([self.floor_point(x) for x in positions.values()]).T  # (n_dof, 3)
        ds["floor_acceleration"] = (
            ("frequency", "position"),
            -(omega**2)[:, None] * (H @ floor),
            per_metre("carbody floor vertical acceleration at (x, 0)", "(m/s^2)/m"),
        )
        x_attrs = {"long_name": "x of the floor position from the carbody centre (front +)", "units": "m"}
        ds = ds.assign_coords(x_m=("position", list(positions.values()), x_attrs))
        corner = H @ self.T  # T^T q: the secondary deflection at each corner
        body = list(self.carbody_dofs)
        corner_body = H[:, body] @ self.T[body]  # the carbody part alone: corner displacement
        ds["carbody_corner_displacement"] = (
            ("frequency", "corner"),
            corner_body,
            per_metre("carbody vertical displacement above each secondary corner", "m/m"),
        )
        ds["secondary_deflection"] = (
            ("frequency", "corner"),
            corner,
            per_metre("secondary vertical deflection, carbody minus bogie (extension +)", "m/m"),
        )
        ds.attrs.update(
            speed_m_s=speed,
            rail_L=str(cL),
            rail_R=str(cR),
            cross_level_angle_per_m=str((cL - cR) / (2 * self.params.a)),
        )
        return ds


#: the schema of `presets_document` (docs/schemas/railride.vehicles-1.json)
SCHEMA_VEHICLES = "railride.vehicles/1"


def presets_document(names=None) -> dict:
    """The named vehicles (`railride.model.params.PRESETS`; ``names``: some of them, in this
    order; default all) with where their values come from (`PRESET_SOURCES`) and their modes
    (`Vehicle.modes`, by undamped frequency: nine rigid-body modes, and the carbody's bending
    where it bends): ``railride vehicles --format json``. An unknown name is an InputError that
    lists the presets."""
    from railride._version import __version__, versions

    names = list(PRESETS) if names is None else list(names)
    presets = []
    for name in names:
        params = VehicleParams.preset(name)
        modes = [m.to_dict() for m in Vehicle(params).modes()]
        presets.append({"name": name, "source": PRESET_SOURCES[name], "modes": modes})
    return {"schema": SCHEMA_VEHICLES, "railride_version": __version__, "versions": versions(), "presets": presets}


def _mac(u: np.ndarray, v: np.ndarray) -> float:
    return float(abs(np.vdot(u, v)) ** 2 / (np.vdot(u, u).real * np.vdot(v, v).real))


def resolution(roots: np.ndarray) -> float:
    """How close to zero a root of an eigen-solver is rounding: the solver's backward error,
    double precision's eps times the largest root, times the matrix's size (Anderson et al.,
    LAPACK Users' Guide, 3rd ed., SIAM 1999, ch. 4: a backward-stable solver's eigenvalues are
    off by about eps times the matrix's norm)."""
    return float(roots.size * np.finfo(float).eps * np.max(np.abs(roots)))


def _damped_modes(lam: np.ndarray, shapes: np.ndarray) -> list[tuple[float, float, np.ndarray, bool]]:
    """(omega_d, zeta, shape, resolved) per mode from the state-matrix eigenpairs: a complex
    pair, or an overdamped pair of real roots. LAPACK returns real roots with an imaginary part
    of exactly 0 and complex ones in conjugate pairs, so that split takes no tolerance (one
    relative to the fastest root took the slow complex pairs of a stiff vehicle for real roots)."""
    out = []
    floor = resolution(lam)
    for i in np.flatnonzero(lam.imag > 0.0):
        wn = abs(lam[i])
        # no root of a passive vehicle grows (C >= 0): a real part past 0 is rounding (a
        # lightly damped mode's ratio of -2e-6), shown as 0; past the floor, not resolved
        decay = -lam[i].real
        out.append((lam[i].imag, max(decay, 0.0) / wn, shapes[:, i], bool(wn > floor and decay > -floor)))
    # overdamped: pair the real roots whose shapes agree best
    remaining = list(np.flatnonzero(lam.imag == 0.0))
    while len(remaining) >= 2:
        i = remaining.pop(0)
        j = max(remaining, key=lambda r: np.nan_to_num(_mac(shapes[:, i], shapes[:, r])))
        remaining.remove(j)
        # a passive vehicle's real roots lie below 0; one at or past -floor is a slower root
        # that rounding hides: taken at -floor, the ratio is a lower bound, not an infinity
        s1, s2 = sorted((-lam[i].real, -lam[j].real))
        resolved = s1 > floor
        s1, s2 = max(s1, floor), max(s2, floor)
        out.append((0.0, (s1 + s2) / (2.0 * np.sqrt(s1 * s2)), shapes[:, i].real, resolved))
    return out


def _label(shape: np.ndarray, mass: np.ndarray, names=DOF_NAMES) -> str:
    """Name a mode after the DOF (of ``names``, in the order of q) with the largest share of
    kinetic energy: "carbody bending" for the flexible carbody's."""
    energy = mass * np.abs(shape) ** 2
    i = int(np.argmax(energy))
    body, motion = names[i].rsplit("_", 1)
    if body == "carbody":
        return f"carbody {motion}"
    other = i + 3 if i < 6 else i - 3
    if energy[other] > energy[i] / 3:
        phase = "in phase" if shape[i] * shape[other] > 0 else "anti-phase"
        return f"bogie {motion} ({phase})"
    return f"{body.replace('_', ' ')} {motion}"
