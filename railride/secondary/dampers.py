"""Secondary vertical damper models (docs/dampers.md): viscous, simple Bouc-Wen MR, Spencer MR.

Sign convention, for every model: x is the damper's extension (the secondary deflection delta,
carbody minus bogie, so x' > 0 when the carbody rises relative to the bogie) and F is the force
the damper resists with, positive in tension: F = c x' for a dashpot. The force on the carbody
is f = -F, on the bogie +F.

Bouc-Wen form used here (Spencer et al. 1997; Dyke et al. 1996):

    z' = -gamma |w| z |z|^(n-1) - beta w |z|^n + A w,

with w = x' (simple model) or w = x' - y' (Spencer). gamma multiplies |w| and beta multiplies w.
Part of the literature (e.g. Wen 1976, Ismail et al. 2009) writes the same equation with the
names swapped, beta on |w| and gamma on w: check which form a published parameter set assumes
before using it here. For gamma >= beta and gamma + beta > 0 the hysteretic variable stays in
|z| <= (A / (gamma + beta))^(1/n) (`BoucWen.z_bound`).

Voltage dependence and coil lag: u' = -eta (u - v), v the commanded voltage in [v_min, v_max];
alpha = alpha_a + alpha_b u, c0 = c0a + c0b u (Spencer also c1 = c1a + c1b u). The preload
k x0 of a gas accumulator balances at static equilibrium and is dropped, so the spring
terms act on x, not x - x0.

Each law also has a plain NumPy reference here (`rates`), used by the tests to check the
compiled version in `railride.engine.kernels`.

`Ideal` is no damper but a reference for the MR dampers: a force actuator that applies the
outer loop's demand exactly (closed loop only; with the same gains the MR dampers can do
better). `BoucWen.scaled` / `Spencer.scaled` give the same damper with its force capacity
multiplied by a factor.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from railride.errors import InputError
from railride import validation
from railride.engine.layout import (  # the engine's codes and slots (loads no numba)
    LAW_BOUC_WEN,
    LAW_IDEAL,
    LAW_SPENCER,
    LAW_VISCOUS,
    N_PACKED,
    P_C0A,
    P_C1A,
    P_DISSIPATIVE,
    P_K1,
    P_V_MAX,
    P_Z_BOUND,
    P_ALPHA_A,
)
from railride.engine.layout import (  # noqa: F401  (their codes, read as rr.dampers.VOLTAGE_LAWS and the like)
    N_DAMPER_STATES,
    VOLTAGE_CLIPPED,
    VOLTAGE_LAWS,
    VOLTAGE_ON_OFF,
    VOLTAGE_TRACKING,
)
from railride.validation import param, validate_fields


class _Damper:
    """Shared behaviour of the damper parameter sets."""

    # declared for the type checker: every subclass is a frozen dataclass with these
    __dataclass_fields__: ClassVar[dict]
    law: int
    model: ClassVar[str]
    v_min: float
    v_max: float

    def replace(self, **changes):
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise InputError(
                f"unknown damper parameter(s) {', '.join(sorted(unknown))}; allowed: "
                f"{', '.join(f.name for f in dataclasses.fields(self))}"
            )
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict:
        """The model, the preset it equals (or None) and every parameter."""
        name = next(
            (k for k, v in {**PRESETS, "ideal": IDEAL, "ideal-damper": IDEAL_DAMPER}.items() if v == self), None
        )
        return {"model": self.model, "preset": name, **dataclasses.asdict(self)}

    @classmethod
    def describe(cls) -> list[tuple[str, str, str]]:
        return [(f.name, f.metadata["unit"], f.metadata["doc"]) for f in dataclasses.fields(cls)]

    def check_voltage(self, v: float, name: str = "voltage") -> float:
        if not (validation.obeys(v, "finite") and self.v_min <= v <= self.v_max):
            raise InputError(
                f"{name} = {validation.shown(v)} V: must lie in [{self.v_min:g}, {self.v_max:g}] V "
                f"for this {self.model} damper"
            )
        return float(v)


@dataclass(frozen=True)
class Viscous(_Damper):
    """A linear dashpot F = c x' (the passive secondary damper)."""

    c: float = param("N s/m", "damping coefficient", "nonnegative")
    model = "viscous"
    law = LAW_VISCOUS
    v_min = 0.0
    v_max = 0.0

    def __post_init__(self):
        validate_fields(self, "damper parameter")

    def pack(self) -> np.ndarray:
        p = np.zeros(N_PACKED)
        p[P_C0A] = self.c  # F = c0 x'
        return p

    def rates(self, x, xd, z, y, u, v):
        return self.c * np.asarray(xd, dtype=float), 0.0 * z, 0.0 * y, 0.0 * u


@dataclass(frozen=True)
class BoucWen(_Damper):
    """Simple Bouc-Wen MR damper (paper eq. 10-11, with |x'| where eq. 11 prints |x|):
    F = c0(u) x' + k0 x + alpha(u) z."""

    alpha_a: float = param("N/m", "hysteretic force coefficient at 0 V", "nonnegative")
    alpha_b: float = param("N/(m V)", "hysteretic force coefficient per volt", "nonnegative")
    c0a: float = param("N s/m", "viscous coefficient at 0 V", "nonnegative")
    c0b: float = param("N s/(m V)", "viscous coefficient per volt", "nonnegative")
    k0: float = param(
        "N/m", "stiffness k0 (simple model: the accumulator; Spencer: in series with the hysteresis)", "nonnegative"
    )
    A: float = param("-", "Bouc-Wen A: initial slope dz/dx")
    n: float = param("-", "Bouc-Wen exponent", "at_least_one")
    gamma: float = param("1/m^n", "Bouc-Wen gamma (multiplies |w| z |z|^(n-1))", "finite")
    beta: float = param("1/m^n", "Bouc-Wen beta (multiplies w |z|^n)", "finite")
    eta: float = param("1/s", "coil lag rate: u' = -eta (u - v)")
    v_min: float = param("V", "lowest command voltage", "nonnegative")
    v_max: float = param("V", "highest command voltage")
    model = "bouc-wen"
    law = LAW_BOUC_WEN

    def __post_init__(self):
        validate_fields(self, "damper parameter")
        _check_shape(self)

    @property
    def z_bound(self) -> float:
        """Upper bound of |z| for gamma >= beta: (A / (gamma + beta))^(1/n) [m] (gamma and beta in 1/m^n)."""
        return (self.A / (self.gamma + self.beta)) ** (1.0 / self.n)

    #: the parameters that carry force: F scales with them at the same motion and voltage
    FORCE_PARAMETERS: ClassVar[tuple[str, ...]] = ("alpha_a", "alpha_b", "c0a", "c0b", "k0")

    def scaled(self, factor: float):
        """The same damper with its force capacity times ``factor`` (> 0): every force
        parameter (`FORCE_PARAMETERS`) multiplied, so that for the same motion and voltage the
        force is ``factor`` times as large and the internal states (z, y, u) are unchanged."""
        factor = check_scale("factor", factor)
        return self.replace(**{n: factor * getattr(self, n) for n in self.FORCE_PARAMETERS})

    def pack(self) -> np.ndarray:
        p = np.zeros(N_PACKED)
        p[P_ALPHA_A : P_V_MAX + 1] = [
            self.alpha_a,
            self.alpha_b,
            self.c0a,
            self.c0b,
            self.k0,
            self.A,
            self.n,
            self.gamma,
            self.beta,
            self.eta,
            self.v_min,
            self.v_max,
        ]
        p[P_Z_BOUND] = self.z_bound
        return p

    def rates(self, x, xd, z, y, u, v):
        """NumPy reference: (F, z', y', u') for extension x, rate xd, states z, y, u and command v."""
        x, xd, z, u = (np.asarray(a, dtype=float) for a in (x, xd, z, u))
        alpha = self.alpha_a + self.alpha_b * u
        c0 = self.c0a + self.c0b * u
        zd = _bouc_wen_z_rate(z, xd, self.A, self.n, self.gamma, self.beta)
        return c0 * xd + self.k0 * x + alpha * z, zd, 0.0 * z, -self.eta * (u - v)


@dataclass(frozen=True)
class Spencer(BoucWen):
    """Spencer et al. (1997) modified Bouc-Wen MR damper: the simple model's parameters plus a
    dashpot c1 in series and an accumulator spring k1,

        F  = c1(u) y' + k1 x
        y' = (alpha(u) z + c0(u) x' + k0 (x - y)) / (c0(u) + c1(u))
        z' = Bouc-Wen of w = x' - y'

    where c0 is the high-velocity viscous coefficient and k0 the stiffness in series with the
    hysteresis. The dashpot c1 gives the force roll-off at low velocity that the simple model
    lacks. x0 (accumulator preload position) is kept for the record; its preload is dropped.
    """

    c1a: float = param("N s/m", "low-velocity (series) viscous coefficient at 0 V", "positive")
    c1b: float = param("N s/(m V)", "low-velocity viscous coefficient per volt", "nonnegative")
    k1: float = param("N/m", "accumulator stiffness", "nonnegative")
    x0: float = param("m", "accumulator initial displacement (preload dropped)", "finite")
    model = "spencer"
    law = LAW_SPENCER
    # y' is a ratio of force terms, unchanged when all of them scale; F = c1 y' + k1 x scales
    FORCE_PARAMETERS = BoucWen.FORCE_PARAMETERS + ("c1a", "c1b", "k1")

    def pack(self) -> np.ndarray:
        p = super().pack()
        p[P_C1A : P_K1 + 1] = [self.c1a, self.c1b, self.k1]
        return p

    def rates(self, x, xd, z, y, u, v):
        """NumPy reference: (F, z', y', u')."""
        x, xd, z, y, u = (np.asarray(a, dtype=float) for a in (x, xd, z, y, u))
        alpha = self.alpha_a + self.alpha_b * u
        c0 = self.c0a + self.c0b * u
        c1 = self.c1a + self.c1b * u
        yd = (alpha * z + c0 * xd + self.k0 * (x - y)) / (c0 + c1)
        zd = _bouc_wen_z_rate(z, xd - yd, self.A, self.n, self.gamma, self.beta)
        return c1 * yd + self.k1 * x, zd, yd, -self.eta * (u - v)


@dataclass(frozen=True)
class Ideal(_Damper):
    """The ideal actuator: the corner force on the carbody equals the outer loop's demand f_d,
    sampled and held like every demand, with no inner loop, voltage or clipping. It may push
    energy in, which a damper cannot: a reference for a law's gains, not a bound. It has
    no states and no parameters, and works in a closed loop only (`railride.Suspension.ideal`).

    In the stepper its command slot carries the held demand f_d (on the carbody, up +), so
    F = -f_d in the damper's convention (tension +) and the force on the carbody is f = f_d.
    """

    #: True: the ideal *semi-active* damper ("ideal-damper"): the demand when it dissipates
    #: energy (F x' >= 0), no force otherwise: what any damper that can only resist the relative
    #: motion across it could give of a demand, a reference for a law's gains (not a bound: with
    #: the same gains an MR damper's lag and hysteresis change the loop, and can do better).
    dissipative: bool = False

    law = LAW_IDEAL
    v_min = 0.0
    v_max = 0.0

    @property
    def model(self) -> str:  # type: ignore[override]  # a class constant elsewhere
        return "ideal-damper" if self.dissipative else "ideal"

    def pack(self) -> np.ndarray:
        p = np.zeros(N_PACKED)
        p[P_DISSIPATIVE] = 1.0 if self.dissipative else 0.0
        return p

    def rates(self, x, xd, z, y, u, v):
        """NumPy reference: F = -v with v the demand on the carbody (dissipative: 0 where
        F x' < 0); no state moves."""
        z = np.asarray(z, dtype=float)
        F = -np.asarray(v, dtype=float) + 0.0 * z
        if self.dissipative:
            F = np.where(F * np.asarray(xd, dtype=float) < 0.0, 0.0, F)
        return F, 0.0 * z, 0.0 * z, 0.0 * z

    def scaled(self, factor: float):
        raise InputError(
            f"factor = {factor!r}: {ideal_words(self.model)} follows the demand and has no force capacity to scale"
        )


def check_scale(name: str, value) -> float:
    """A force-capacity scale: a finite number > 0 within `railride.model.plausible.DAMPER_SCALE`,
    else ValueError naming ``name``."""
    from railride.model.plausible import DAMPER_SCALE as r

    scale = validation.number(
        name, value, "positive", allowed="a finite number > 0 (the factor on the damper's force parameters)"
    )
    if not r.low <= scale <= r.high:
        raise InputError(f"{name} = {validation.shown(value)}: must be between {r.low:g} and {r.high:g} ({r.why})")
    return scale


def _check_shape(d) -> None:
    if d.n < 1:
        raise InputError(f"damper parameter 'n' = {d.n!r}: must be >= 1")
    if d.gamma + d.beta <= 0:
        raise InputError(
            f"damper parameters gamma = {d.gamma!r}, beta = {d.beta!r}: gamma + beta must be "
            "> 0, or the hysteretic variable grows without bound"
        )
    if d.v_max <= d.v_min:
        raise InputError(f"damper voltage range [{d.v_min!r}, {d.v_max!r}] V: v_max must exceed v_min")


def _bouc_wen_z_rate(z, w, A, n, gamma, beta):
    az = np.abs(z)
    return -gamma * np.abs(w) * z * az ** (n - 1) - beta * w * az**n + A * w


# -- presets ------------------------------------------------------------------------------------
#: Dyke, Spencer, Sain & Carlson (1996), simple Bouc-Wen fit of their small-scale damper
#: (gamma, beta in 1/m for n = 1).
DYKE1996 = BoucWen(
    alpha_a=1.0872e5,
    alpha_b=4.9616e5,
    c0a=4.40,
    c0b=44.0,
    k0=0.0,
    A=1.2,
    n=1.0,
    gamma=300.0,
    beta=300.0,
    eta=50.0,
    v_min=0.0,
    v_max=2.25,
)

#: The vehicle default (docs/dampers.md, Presets): dyke1996 with the force parameters alpha_a, alpha_b,
#: c0a, c0b, k0 multiplied by 8, about 1.7 kN at 0 V and 20 kN at 2.25 V.
RAILWAY = DYKE1996.scaled(8)

#: Spencer, Dyke, Sain & Carlson (1997), "Phenomenological model for magnetorheological
#: dampers", J. Eng. Mech. 123(3), Table 1, converted from N, cm to SI: c0a 21.0 N s/cm,
#: c0b 3.50 N s/(cm V), k0 46.9 N/cm, c1a 283 N s/cm, c1b 2.95 N s/(cm V), k1 5.00 N/cm,
#: x0 14.3 cm, alpha_a 140 N/cm, alpha_b 695 N/(cm V), gamma = beta = 363 cm^-2, A = 301,
#: n = 2, eta = 190 1/s; the prototype's command range 0-2.25 V.
SPENCER1997 = Spencer(
    alpha_a=1.40e4,
    alpha_b=6.95e4,
    c0a=2.10e3,
    c0b=3.50e2,
    k0=4.69e3,
    A=301.0,
    n=2.0,
    gamma=3.63e6,
    beta=3.63e6,
    eta=190.0,
    v_min=0.0,
    v_max=2.25,
    c1a=2.83e4,
    c1b=2.95e2,
    k1=5.00e2,
    x0=0.143,
)

#: the MR damper presets (the models the rig can drive)
PRESETS = {"dyke1996": DYKE1996, "railway": RAILWAY, "spencer1997": SPENCER1997}
#: the MR models by the name their records give (a damper file's ``model``)
MR_MODELS = {"bouc-wen": BoucWen, "spencer": Spencer}


def record_name(record) -> str:
    """How outputs name a damper by its record (`to_dict`) or name: the preset it equals, else
    "<model> (own parameters)" (a damper file's or a model's given as such)."""
    if isinstance(record, dict):
        return record.get("preset") or f"{record.get('model', 'MR')} (own parameters)"
    return str(record)


#: the ideal actuator, by name "ideal" beside the presets (closed loop only)
IDEAL = Ideal()
#: the ideal semi-active damper, by name "ideal-damper" (closed loop only)
IDEAL_DAMPER = Ideal(dissipative=True)
#: the names of the ideal bounds (no voltage, no inner loop, closed loop only)
IDEAL_NAMES = ("ideal", "ideal-damper")


def ideal_words(name: str) -> str:
    """How a message names the ideal device ``name`` ("ideal" or "ideal-damper")."""
    return "the ideal semi-active damper" if name == "ideal-damper" else "the ideal actuator"


#: every name `preset` knows
NAMES = (*PRESETS, *IDEAL_NAMES)


def preset(name: str):
    """A named damper: dyke1996, railway (the vehicle default), spencer1997, or the ideal
    actuator "ideal"."""
    if name == "ideal":
        return IDEAL
    if name == "ideal-damper":
        return IDEAL_DAMPER
    try:
        return PRESETS[name]
    except (KeyError, TypeError):
        raise InputError(f"unknown damper model {name!r}; allowed: {', '.join(NAMES)}") from None


def stiffness_estimate(damper, xd: float, z: float, u: float) -> float:
    """A bound on the fastest rate of the damper's internal states [1/s] (for sub-stepping):
    the Jacobian of z' (and y') with |z| taken at least at its bound, since from z = 0 the rate
    grows within a step."""
    if damper.law in (LAW_VISCOUS, LAW_IDEAL):
        return 0.0
    gb = abs(damper.gamma) + abs(damper.beta)
    az = max(abs(z), damper.z_bound)
    lam = damper.n * gb * abs(xd) * az ** (damper.n - 1) + damper.eta
    if damper.law == LAW_SPENCER:
        alpha = damper.alpha_a + damper.alpha_b * u
        cs = damper.c0a + damper.c0b * u + damper.c1a + damper.c1b * u
        lam += ((damper.A + gb * az**damper.n) * alpha + damper.k0) / cs
    return lam
