"""The vehicle as a linear state-space model x' = A x + B u, y = C x + D u (docs/linear.md).

Three secondaries are linear and have one here:

* ``"passive"`` (or a passive `Suspension` with viscous dampers): the vehicle with its
  secondary dashpots. Inputs: the rails and four corner forces acting in parallel with the
  dashpots (an actuator beside the passive damper, or zero).
* ``"plant"``: the vehicle without the secondary vertical dashpots, the plant an actuator acts
  on. Inputs: the rails and the four corner forces.
* an ideal actuator under a linear outer loop (`Suspension.ideal(controller)`): the corner
  forces are the demand f_d = G m + H xi of the loop (`railride.secondary.control`), applied
  continuously; the three integrals xi of the carbody displacements are states. Inputs: the
  rails only. The engine samples and holds the demand at the control rate; this model is its
  continuous-time limit.

States: q (the vehicle's DOFs: nine, ten where the carbody bends) and q', in the order and
with the names of `Vehicle.dof_names` (`railride.model.vehicle.DOF_NAMES`, then
``carbody_bending``), then xi for a closed loop. Rail inputs: the heights z_1L ... z_4R [m]
and their time derivatives [m/s] (the equations hold both: M q'' + C q' + K q = -(K_w w +
C_w w') + T f). Outputs: the DOFs, the carbody accelerations (and its bending's, where it
bends), the floor accelerations at the front and rear bogie centres and the carbody centre
(a = z'' - x pitch'' + phi(x) eta'', `Vehicle.floor_point`, as
`railride.analysis.comfort.floor_acceleration`), the secondary deflections and the secondary
forces on the carbody, per corner.

`LinearModel.to_control()` gives a python-control ``StateSpace`` with these names (when that
package is installed) and `LinearModel.to_mat()` a MATLAB file.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from railride.errors import InputError
from railride.model.params import VehicleParams, resolve_vehicle, vehicle_record
from railride.model.vehicle import CORNER_NAMES, DOF_NAMES, N_DOF, RAILS, WHEELSETS, Vehicle
from railride.secondary.control import outer_gains

SCHEMA = "railride.linear/1"
#: the secondaries `linear_model` takes by name
SECONDARIES = ("passive", "plant")
RAIL_HEIGHTS = tuple(f"rail_height_{w}{r}" for w in WHEELSETS for r in RAILS)
RAIL_RATES = tuple(f"rail_rate_{w}{r}" for w in WHEELSETS for r in RAILS)
CORNER_FORCES = tuple(f"secondary_force_{c}" for c in CORNER_NAMES)
#: x [m] of the floor points, as multiples of the bogie semi-spacing l (front +)
FLOOR_POINTS = {"centre": 0.0, "front": 1.0, "rear": -1.0}


@dataclass(frozen=True, eq=False)
class LinearModel:
    """x' = A x + B u, y = C x + D u with named ``states``, ``inputs`` and ``outputs`` and
    their ``units``; ``secondary`` says what sits in the secondary ("passive", "plant" or the
    outer loop's name on the ideal actuator); ``params`` the vehicle (with its load) and
    ``vehicle`` its record: name, load and values (`railride.model.params.vehicle_record`;
    None: made from ``params``). Checked at construction: shapes agree and every entry is
    finite."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    units: dict
    secondary: str
    params: VehicleParams
    vehicle: dict | None = None
    #: a closed loop's outer loop: its name and every gain it applies (None: no controller)
    controller: dict | None = None

    def __post_init__(self):
        n, m, p = len(self.states), len(self.inputs), len(self.outputs)
        for name, matrix, shape in (
            ("A", self.A, (n, n)),
            ("B", self.B, (n, m)),
            ("C", self.C, (p, n)),
            ("D", self.D, (p, m)),
        ):
            if np.shape(matrix) != shape:
                raise InputError(f"{name} has shape {np.shape(matrix)}: must be {shape} for the names given")
            if not np.all(np.isfinite(matrix)):
                raise InputError(f"{name} holds a value that is not finite: check the vehicle parameters")

    def record(self) -> dict:
        """The vehicle's record: name, load and values (`railride.model.params.vehicle_record`)."""
        return vehicle_record(self.params) if self.vehicle is None else self.vehicle

    def index(self, kind: str, name: str) -> int:
        """Where ``name`` is among the ``kind`` ("states", "inputs", "outputs")."""
        from railride import validation

        names = getattr(self, validation.choice("kind", kind, ("states", "inputs", "outputs")))
        if name not in names:
            raise InputError(f"{kind[:-1]} {name!r} is not in the model; allowed: {', '.join(names)}")
        return names.index(name)

    def corner_forces(self) -> np.ndarray:
        """The rows of C (4 x states) that give the secondary forces on the carbody, per corner:
        a closed loop's demand G x + H xi."""
        return self.C[[self.index("outputs", f"secondary_force_{c}_on_carbody") for c in CORNER_NAMES]]

    def frequency_response(self, frequency_hz) -> np.ndarray:
        """G(j 2 pi f) = C (j 2 pi f I - A)^-1 B + D for every frequency [Hz]: (n_f, outputs,
        inputs), complex."""
        from railride import validation

        f = validation.frequencies("frequency_hz", frequency_hz)
        s = 2j * np.pi * f
        n = self.A.shape[0]
        X = np.linalg.solve(s[:, None, None] * np.eye(n) - self.A, np.broadcast_to(self.B, (f.size, *self.B.shape)))
        return self.C @ X + self.D

    def poles(self) -> np.ndarray:
        """The eigenvalues of A [1/s]."""
        return np.linalg.eigvals(self.A)

    def to_dict(self) -> dict:
        """The ``railride.linear/1`` document: names, units and the four matrices as lists."""
        from railride._version import __version__, versions

        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            "secondary": self.secondary,
            "controller": self.controller,
            "vehicle": self.record(),
            "vehicle_params": self.params.to_dict(),
            "states": list(self.states),
            "inputs": list(self.inputs),
            "outputs": list(self.outputs),
            "units": dict(self.units),
            **{k: getattr(self, k).tolist() for k in "ABCD"},
        }

    def to_control(self):
        """A python-control ``StateSpace`` with the names of states, inputs and outputs. Needs
        the ``control`` package (``pip install control``)."""
        try:
            import control
        except ImportError:
            raise ImportError(
                "to_control needs the python-control package: pip install control "
                "(or use to_mat, or the A, B, C, D arrays)"
            ) from None
        return control.ss(
            self.A,
            self.B,
            self.C,
            self.D,
            states=list(self.states),
            inputs=list(self.inputs),
            outputs=list(self.outputs),
            name=f"railride_{self.secondary}".replace("-", "_"),
        )

    def to_mat(self, path) -> None:
        """A MATLAB .mat file (scipy.io, format 5) with A, B, C, D, the names as cell arrays
        (state_names, input_names, output_names), their units, the secondary, the vehicle's
        name and load, a closed loop's gains (``controller_gains``, its JSON text) and the
        versions that made it (``railride_version``, ``versions``, JSON text); written
        atomically."""
        import json
        from pathlib import Path

        from scipy.io import savemat

        from railride._io import atomic_write
        from railride._version import __version__, versions

        def cells(names):
            return np.array(list(names), dtype=object).reshape(-1, 1)

        content = {
            **{k: getattr(self, k) for k in "ABCD"},
            "state_names": cells(self.states),
            "input_names": cells(self.inputs),
            "output_names": cells(self.outputs),
            "state_units": cells(self.units[s] for s in self.states),
            "input_units": cells(self.units[s] for s in self.inputs),
            "output_units": cells(self.units[s] for s in self.outputs),
            "secondary": self.secondary,
            "vehicle_name": str(self.record()["name"]),
            "load": float(self.record()["load"]),
            "controller_gains": json.dumps(self.controller, default=float) if self.controller else "",
            "railride_version": __version__,
            "versions": json.dumps(versions()),
        }
        atomic_write(Path(path), lambda tmp: savemat(tmp, content, do_compression=True))


def _check_secondary(suspension, vehicle: Vehicle):
    """(secondary name, coefficient of the secondary dashpots [N s/m], outer loop or None)."""
    from railride.secondary.dampers import Ideal, Viscous
    from railride.secondary.suspension import Suspension

    if suspension is None or suspension == "passive":
        return "passive", vehicle.params.c_sz, None
    if suspension == "plant":
        return "plant", 0.0, None
    if not isinstance(suspension, Suspension):
        raise InputError(
            f"suspension = {suspension!r}: must be 'passive', 'plant' or a Suspension "
            "(passive viscous dampers, or the ideal actuator under an outer loop)"
        )
    s = suspension
    extras = [n for n, v in (("faults", s.faults), ("sensing", s.sensing), ("sensor_noise", s.sensor_noise)) if v]
    if s.delay != 1:
        extras.append("delay")
    if extras:
        raise InputError(
            f"suspension with {', '.join(extras)}: the linear model has none of them; give the suspension without them"
        )
    if s.controller is None and (s.damper is None or isinstance(s.damper, Viscous)):
        c = vehicle.params.c_sz if s.damper is None else s.damper.c
        return "passive", float(c), None
    if isinstance(s.damper, Ideal) and not s.damper.dissipative:
        return s.controller.name, 0.0, s.controller
    raise InputError(
        f"suspension {s.describe()}: not linear. The linear model covers the passive viscous "
        "dampers and the ideal actuator (Suspension.ideal) under an outer loop; MR dampers and "
        "the ideal semi-active damper switch and clip"
    )


def _outer_gains(controller, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
    """The loop's demand f_d = G_full (q, q') + H xi with G over the vehicle's whole state (4 x
    2 n_dof): a gain on the carbody's six rigid states (4 x 6) or on the rigid vehicle's (4 x
    18) reads nothing of the carbody's bending."""
    G, H = outer_gains(controller, vehicle)
    n = vehicle.n_dof
    full = np.zeros((4, 2 * n))
    if G.shape == (4, 6):
        full[:, :3], full[:, n : n + 3] = G[:, :3], G[:, 3:]
    elif G.shape == (4, 2 * N_DOF):
        full[:, :N_DOF], full[:, n : n + N_DOF] = G[:, :N_DOF], G[:, N_DOF:]
    elif G.shape == (4, 2 * n):
        full = G
    else:
        raise InputError(
            f"controller {controller.name!r}: its gain has shape {G.shape}; allowed (4, 6) on the carbody "
            f"states, (4, {2 * N_DOF}) on the rigid vehicle's (q, q') or (4, {2 * n}) on this vehicle's"
        )
    return full, H


def linear_model(params=None, suspension=None, *, vehicle=None, load: float = 1.0) -> LinearModel:
    """The state-space model of the vehicle ``params`` (``vehicle`` is an alias: `VehicleParams`,
    a preset name or a parameters file; default "paper"), with the load factor ``load`` on its
    carbody (`VehicleParams.loaded`), with ``suspension``: "passive" (default, or None),
    "plant", or a `railride.Suspension` that is linear (passive viscous dampers, or the ideal
    actuator under an outer loop). See the module's docstring for states, inputs and outputs."""
    from railride.secondary.provenance import json_values

    vehicle_params, record = resolve_vehicle(vehicle, params, load)
    vehicle = Vehicle(vehicle_params)
    secondary, c_dashpot, controller = _check_secondary(suspension, vehicle)
    Cd = vehicle.C0 + c_dashpot * vehicle.T @ vehicle.T.T
    nd = vehicle.n_dof  # 9, or 10 where the carbody bends
    names, dof_units = vehicle.dof_names, vehicle.dof_units
    n = 2 * nd
    Minv = 1.0 / np.diag(vehicle.M)
    # x' = A x + B u with x = (q, q'), u = (w, w', f)
    A = np.zeros((n, n))
    A[:nd, nd:] = np.eye(nd)
    A[nd:, :nd] = -Minv[:, None] * vehicle.K
    A[nd:, nd:] = -Minv[:, None] * Cd
    B = np.zeros((n, 20))
    B[nd:, 0:8] = -Minv[:, None] * vehicle.K_w
    B[nd:, 8:16] = -Minv[:, None] * vehicle.C_w
    B[nd:, 16:20] = Minv[:, None] * vehicle.T
    # the corner force on the carbody: the dashpot's -c x' (x = T^T q) plus the input f
    force_x = np.hstack([np.zeros((4, nd)), -c_dashpot * vehicle.T.T])
    force_u = np.hstack([np.zeros((4, 16)), np.eye(4)])
    states = [*names, *(f"{d}_rate" for d in names)]
    inputs = [*RAIL_HEIGHTS, *RAIL_RATES, *CORNER_FORCES]
    units = {d: u for d, u in zip(names, dof_units)}
    units |= {f"{d}_rate": f"{u}/s" for d, u in zip(names, dof_units)}
    units |= {k: "m" for k in RAIL_HEIGHTS} | {k: "m/s" for k in RAIL_RATES} | {k: "N" for k in CORNER_FORCES}
    if controller is not None:  # close the loop: f = G_full x + H xi, xi' = carbody displacements
        G, H = _outer_gains(controller, vehicle)
        Bf = B[:, 16:20]
        # the integrals are states only where the loop reads them (else poles at 0 that nothing sees)
        k = 3 if np.any(H) else 0
        A = np.block([[A + Bf @ G, Bf @ H[:, :k]], [np.eye(k, n), np.zeros((k, k))]])
        B = np.vstack([B[:, :16], np.zeros((k, 16))])
        force_x = np.hstack([G, H[:, :k]])
        force_u = np.zeros((4, 16))
        integrals = [f"{d}_integral" for d in names[:k]]
        states += integrals
        units |= {k: f"{units[d]} s" for k, d in zip(integrals, DOF_NAMES[:3])}
        inputs = inputs[:16]
    nx, nu = A.shape[0], B.shape[1]
    pad = nx - n  # the integrals' columns
    accel_x, accel_u = A[nd:n], B[nd:n]  # q'' rows
    rows_x, rows_u, outputs = [], [], []

    def add(name, unit, cx, du):
        outputs.append(name)
        units[name] = unit
        rows_x.append(cx)
        rows_u.append(du)

    for i, d in enumerate(names):
        add(d, dof_units[i], np.eye(nx)[i], np.zeros(nu))
    for i in vehicle.carbody_dofs:
        add(f"{names[i]}_acceleration", f"{dof_units[i]}/s^2", accel_x[i], accel_u[i])
    for point, share in FLOOR_POINTS.items():
        x = share * vehicle_params.l
        cx, du = accel_x[0] - x * accel_x[1], accel_u[0] - x * accel_u[1]
        if vehicle.n_dof > N_DOF:  # plus phi(x) eta'' (`Vehicle.floor_point`)
            phi = vehicle.floor_point(x)[N_DOF]
            cx, du = cx + phi * accel_x[N_DOF], du + phi * accel_u[N_DOF]
        add(f"floor_acceleration_{point}", "m/s^2", cx, du)
    for c, corner in enumerate(CORNER_NAMES):
        add(
            f"secondary_deflection_{corner}",
            "m",
            np.concatenate([vehicle.T[:, c], np.zeros(nd + pad)]),
            np.zeros(nu),
        )
    for c, corner in enumerate(CORNER_NAMES):
        fx = np.concatenate([force_x[c], np.zeros(nx - force_x.shape[1])])
        add(f"secondary_force_{corner}_on_carbody", "N", fx, force_u[c])
    return LinearModel(
        A,
        B,
        np.array(rows_x),
        np.array(rows_u),
        tuple(states),
        tuple(inputs),
        tuple(outputs),
        units,
        secondary,
        vehicle_params,
        record,
        None if controller is None else {"name": controller.name, "gains": json_values(controller.to_dict())},
    )


def linear_suspensions(controllers, gains) -> dict[str, object]:
    """Names (or linear `Suspension` values) -> {name: "passive" or a Suspension on the ideal
    actuator}; "all" is passive and every outer loop. A suspension named as one before it but
    not equal to it (one law with two gain sets) is kept as "name-2" ("-3", ...), not dropped."""
    from railride.secondary.control import OUTER_LOOPS
    from railride.secondary.suspension import Suspension

    if isinstance(controllers, (str, Suspension)):
        controllers = [c.strip() for c in controllers.split(",")] if isinstance(controllers, str) else [controllers]
    controllers = list(controllers)
    if "all" in controllers:
        controllers = ["passive", *OUTER_LOOPS]
    out: dict[str, object] = {}
    for c in controllers:
        if isinstance(c, Suspension):
            key, k = c.name, 1
            while key in out and out[key] != c:
                k += 1
                key = f"{c.name}-{k}"
            out[key] = c
        elif c in ("passive", "plant"):
            out[c] = c
        elif c in OUTER_LOOPS:
            out[c] = Suspension.named(c, gains, damper="ideal")
        else:
            raise InputError(
                f"controllers = {c!r}: not a linear suspension; allowed: passive, plant, "
                f"{', '.join(OUTER_LOOPS)} (each on the ideal actuator), or all"
            )
    if not out:
        raise InputError("controllers: give at least one (passive, or an outer loop on the ideal actuator)")
    return out
