"""The semi-active control laws a railway engineer compares the paper's SAS against
(docs/control.md): skyhook, on-off skyhook, groundhook, their hybrid and the clipped-optimal
LQR of Dyke et al. (1996), besides the corner geometry every outer loop shares.

Each law is a linear map from the measured states to the desired corner forces on the
carbody (up +, corners 1R, 1L, 2R, 2L), f_d = G m + H xi, built here as gain matrices:
G is 4 x 6 over the carbody states m = (z_c, phi_c, theta_c, z_c', phi_c', theta_c'), or
4 x 18 over the whole state (q, q') in DOF order (`railride.model.vehicle.DOF_NAMES`) for the laws
that read the bogies. The class attribute ``voltage_law`` (`railride.secondary.dampers.VOLTAGE_LAWS`)
says how the MR dampers' voltage follows the demand; the nonlinearity itself lives in the
compiled engine.

The secondary deflection at the corners is x = T^T q (T = `Vehicle.T`, carbody point minus
bogie point); the bogie point of corner c moves with -(T[3:, c] . q[3:]).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import scipy.linalg

from railride.errors import InputError
from railride.model import plausible
from railride.validation import is_number, param, shown, validate_fields
from railride.model.vehicle import N_DOF, Vehicle


def carbody_map(vehicle: Vehicle) -> np.ndarray:
    """T_c (3 x 4): generalised force (heave, pitch, roll) on the carbody from corner forces."""
    return vehicle.T[:3].copy()


def decoupling(vehicle: Vehicle) -> np.ndarray:
    """T_c^+ (4 x 3), the right inverse of T_c: corner forces for a generalised force demand."""
    Tc = carbody_map(vehicle)
    return Tc.T @ np.linalg.inv(Tc @ Tc.T)


def bogie_point_velocity(vehicle: Vehicle) -> np.ndarray:
    """(4 x n) map from q' to the absolute vertical velocity of each corner's bogie point,
    -(T[3:9, c] . q'[3:9]): the bogie rows of T with a minus sign, the carbody's (its rigid
    DOFs and, where it bends, its bending) left out."""
    out = -vehicle.T.T.copy()
    out[:, :3] = 0.0
    out[:, 9:] = 0.0
    return out


class GainTable:
    """A frozen dataclass of gains (one table of a gains file): ``replace`` with a change
    checked by name, ``to_dict`` for the records."""

    # declared for the type checker: every subclass is a frozen dataclass with these
    __dataclass_fields__: ClassVar[dict]
    name: str
    label: str
    #: entries a tuning study leaves as they are (`railride.studies.tuning`): those that only set a scale
    fixed: ClassVar[tuple] = ()

    def replace(self, **changes):
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise InputError(
                f"unknown gain(s) {', '.join(sorted(unknown))} for {self.name}; allowed: "
                f"{', '.join(f.name for f in dataclasses.fields(self))}"
            )
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


def _full_state(G6: np.ndarray, n: int = N_DOF) -> np.ndarray:
    """A 4 x 6 gain on the carbody states as the 4 x 2n gain on the vehicle's (q, q') it is
    (n = `Vehicle.n_dof`: 9, or 10 with the carbody's bending)."""
    G = np.zeros((4, 2 * n))
    G[:, :3], G[:, n : n + 3] = G6[:, :3], G6[:, 3:]
    return G


@dataclass(frozen=True)
class ZeroDemand:
    """A closed loop without an outer loop: the demand f_d is 0 at every corner, so the inner
    loop holds the MR dampers at their lowest force (and the ideal devices apply none)."""

    name = "none"
    label = "no outer loop"

    def gains(self, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros((4, 6)), np.zeros((4, 3))

    def to_dict(self) -> None:
        return None  # no gains: a result records null


@dataclass(frozen=True)
class Skyhook(GainTable):
    """Modal continuous skyhook: dampers between the carbody and the sky on its absolute heave,
    pitch and roll velocities, Q_d = -(c_z z_c', c_phi phi_c', c_theta theta_c'), spread over
    the corners by the decoupling transformation, f_d = T_c^+ Q_d."""

    c_z: float = param("N s/m", "heave skyhook damping", "nonnegative")
    c_phi: float = param("N m s/rad", "pitch skyhook damping", "nonnegative")
    c_theta: float = param("N m s/rad", "roll skyhook damping", "nonnegative")
    name = "skyhook"
    label = "Skyhook"
    voltage_law = "tracking"

    def __post_init__(self):
        validate_fields(self, "skyhook gain", plausible.SKYHOOK)

    def gains(self, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
        G = np.zeros((4, 6))
        G[:, 3:] = -decoupling(vehicle) @ np.diag([self.c_z, self.c_phi, self.c_theta])
        return G, np.zeros((4, 3))


@dataclass(frozen=True)
class SkyhookOnOff(Skyhook):
    """On-off skyhook: the skyhook demand, with each damper at v_max where that demand is a
    force it can give while dissipating (f_d x' < 0) and at v_min elsewhere."""

    name = "skyhook-on-off"
    label = "Skyhook on-off"
    voltage_law = "on-off"


@dataclass(frozen=True)
class Groundhook(GainTable):
    """Groundhook: at each corner a damper between the bogie point and the ground, the force on
    the bogie -c_g v_b,c, so the demand on the carbody is f_d,c = +c_g v_b,c (v_b,c the bogie
    point's absolute velocity). Reads the bogie states."""

    c_g: float = param("N s/m", "groundhook damping per corner", "nonnegative")
    name = "groundhook"
    label = "Groundhook"
    voltage_law = "tracking"

    def __post_init__(self):
        validate_fields(self, "groundhook gain", plausible.GROUNDHOOK)

    def gains(self, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
        n = vehicle.M.shape[0]
        G = np.zeros((4, 2 * n))
        G[:, n:] = self.c_g * bogie_point_velocity(vehicle)
        return G, np.zeros((4, 3))


@dataclass(frozen=True)
class Hybrid(GainTable):
    """Hybrid skyhook-groundhook: f_d = alpha f_skyhook + (1 - alpha) f_groundhook, alpha in
    [0, 1] (1: skyhook alone, 0: groundhook alone)."""

    alpha: float = param("-", "share of the skyhook demand", "nonnegative")
    c_z: float = param("N s/m", "heave skyhook damping", "nonnegative")
    c_phi: float = param("N m s/rad", "pitch skyhook damping", "nonnegative")
    c_theta: float = param("N m s/rad", "roll skyhook damping", "nonnegative")
    c_g: float = param("N s/m", "groundhook damping per corner", "nonnegative")
    name = "hybrid"
    label = "Hybrid"
    voltage_law = "tracking"

    def __post_init__(self):
        a = self.alpha
        if is_number(a) and math.isfinite(float(a)) and not 0.0 <= float(a) <= 1.0:
            raise InputError(
                f"hybrid gain 'alpha' = {shown(a)} (share of the skyhook demand, -): must be a number in [0, 1]"
            )
        validate_fields(self, "hybrid gain", plausible.HYBRID)

    def gains(self, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
        sky, _ = Skyhook(self.c_z, self.c_phi, self.c_theta).gains(vehicle)
        ground, _ = Groundhook(self.c_g).gains(vehicle)
        return self.alpha * _full_state(sky, vehicle.M.shape[0]) + (1.0 - self.alpha) * ground, np.zeros((4, 3))


#: the LQR designs solved, by (weights, vehicle parameters), at most _LQR_SIZE of them
_LQR: dict = {}
_LQR_SIZE = 256


@dataclass(frozen=True)
class ClippedOptimal(GainTable):
    """Clipped-optimal control (Dyke et al. 1996): the LQR state feedback f_d = -K x on the
    whole state x = (q, q'), designed on the vehicle's linear model with the secondary vertical
    dampers' places empty (M q'' + C0 q' + K q = T f, the corner forces f the input, the rails
    left out as disturbances), minimising

        J = int (x^T Q x + r f^T f) dt,

    Q diagonal, weighting the carbody's heave, pitch and roll and their rates (the bogies
    unweighted). Each MR damper is then switched: v_max where (f_d - f) f > 0, else v_min."""

    q_z: float = param("N^2/m^2", "weight on the carbody heave", "nonnegative")
    q_phi: float = param("N^2/rad^2", "weight on the carbody pitch", "nonnegative")
    q_theta: float = param("N^2/rad^2", "weight on the carbody roll", "nonnegative")
    qd_z: float = param("N^2 s^2/m^2", "weight on the carbody heave velocity", "nonnegative")
    qd_phi: float = param("N^2 s^2/rad^2", "weight on the carbody pitch rate", "nonnegative")
    qd_theta: float = param("N^2 s^2/rad^2", "weight on the carbody roll rate", "nonnegative")
    r: float = param("-", "weight on the squared corner forces", "positive")
    name = "clipped-optimal"
    label = "Clipped-optimal"
    voltage_law = "clipped"
    # Q and r scaled together give the same gain: only the ratios Q / r are free
    fixed = ("r",)

    def __post_init__(self):
        validate_fields(self, "clipped-optimal weight", plausible.CLIPPED_OPTIMAL)

    def design_model(self, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(A, B, Q, R) of the design: x' = A x + B f on x = (q, q') without the secondary
        vertical dampers, and the weights of J."""
        n = vehicle.M.shape[0]  # 9, or 10 with the carbody's bending
        minv = 1.0 / np.diag(vehicle.M)[:, None]
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = -minv * vehicle.K
        A[n:, n:] = -minv * vehicle.C0
        B = np.zeros((2 * n, 4))
        B[n:] = minv * vehicle.T
        q = np.zeros(2 * n)
        q[:3] = self.q_z, self.q_phi, self.q_theta
        q[n : n + 3] = self.qd_z, self.qd_phi, self.qd_theta
        return A, B, np.diag(q), self.r * np.eye(4)

    def lqr(self, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
        """(K, P): the LQR gain K = R^-1 B^T P (4 x 18) and P, the stabilising solution of the
        continuous algebraic Riccati equation A^T P + P A - P B R^-1 B^T P + Q = 0. Kept for
        the weights and vehicle (`_LQR`): a study solves the same design for every run of a
        chunk, 10 ms each."""
        key = (self, vehicle.params)
        if key not in _LQR:
            A, B, Q, R = self.design_model(vehicle)
            P = scipy.linalg.solve_continuous_are(A, B, Q, R)
            if len(_LQR) >= _LQR_SIZE:
                _LQR.clear()
            _LQR[key] = (np.linalg.solve(R, B.T @ P), P)
        K, P = _LQR[key]
        return K.copy(), P.copy()

    def gains(self, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
        K, _ = self.lqr(vehicle)
        return -K, np.zeros((4, 3))
