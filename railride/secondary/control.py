"""Outer-loop controllers and the force-tracking inner loop (docs/control.md).

Every outer loop here is linear in the measured carbody states: with m = (z_c, phi_c, theta_c,
z_c', phi_c', theta_c') and xi the time integral of (z_c, phi_c, theta_c), the desired corner
forces (on the carbody, up +, corners 1R, 1L, 2R, 2L) are

    f_d = G m + H xi.

`Controller.gains(vehicle)` builds G (4 x 6) and H (4 x 3) from the gains and the vehicle's
geometry; the compiled step applies them at the controller's sample rate, and the one place
where the semi-active nonlinearity lives is the engine's voltage law, for these the inner loop
(`InnerLoop`), which turns f_d and the measured damper force into a voltage clipped to the
damper's range.

The other semi-active laws (skyhook, groundhook, hybrid, clipped-optimal: `railride.secondary.controllers`)
are registered here beside the paper's: `CONTROLLERS` names every suspension a comparison can
run, and a `GainSet` (a gains file) holds every law's gains.

Corner displacements are z_i = (T_c^T q_c)_i, T_c the carbody rows of the secondary force map
T (rows heave, pitch, roll). The decoupling transformation of the SAS distributes a demanded
generalised force Q_d = (F_z, M_pitch, M_roll) over the corners with the right inverse
T_c^+ = T_c^T (T_c T_c^T)^-1, computed from the geometry (the paper's printed eq. 18-19 are
garbled).
"""

from __future__ import annotations

import copy
import dataclasses
import functools
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Callable, ClassVar, NamedTuple

import numpy as np

from railride.errors import InputError
from railride.secondary.controllers import (  # noqa: F401 (carbody_map, decoupling, ZeroDemand: their home before)
    ClippedOptimal,
    GainTable,
    Groundhook,
    Hybrid,
    Skyhook,
    SkyhookOnOff,
    ZeroDemand,
    carbody_map,
    decoupling,
)
from railride import validation
from railride.model import plausible
from railride.validation import param, validate_fields
from railride.model.vehicle import CORNER_NAMES, Vehicle


@dataclass(frozen=True)
class InnerLoop(GainTable):
    """Force tracking, paper eq. 12-14: v = clip(G (f_d - B f) sgn(f), v_min, v_max)."""

    B: float = param("-", "feedback weight of the measured damper force", "nonnegative")
    G: float = param("V/N", "gain from force error to voltage", "nonnegative")
    name = "inner"
    label = "inner loop"

    def __post_init__(self):
        validate_fields(self, "inner-loop gain", plausible.INNER_LOOP)


@dataclass(frozen=True)
class PID(GainTable):
    """Four identical decentralised PID loops on the carbody's corner displacements
    (paper Fig. 4): f_d,i = -(kp z_i + ki int z_i dt + kd z_i')."""

    kp: float = param("N/m", "proportional gain", "nonnegative")
    ki: float = param("N/(m s)", "integral gain", "nonnegative")
    kd: float = param("N s/m", "derivative gain", "nonnegative")
    name = "pid"
    label = "PID"

    def __post_init__(self):
        validate_fields(self, "PID gain", plausible.PID)

    def gains(self, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
        TcT = carbody_map(vehicle).T  # corner displacement from (z, phi, theta)
        return -np.hstack([self.kp * TcT, self.kd * TcT]), -self.ki * TcT


@dataclass(frozen=True)
class Attitude(GainTable):
    """SAS attitude loop (paper Fig. 3, 7): PD on carbody heave, pitch and roll giving
    Q_d = -(kp_z z + kd_z z', kp_phi phi + kd_phi phi', kp_theta theta + kd_theta theta'),
    distributed by the decoupling transformation f = T_c^+ Q_d."""

    kp_z: float = param("N/m", "heave proportional gain", "nonnegative")
    kd_z: float = param("N s/m", "heave derivative gain", "nonnegative")
    kp_phi: float = param("N m/rad", "pitch proportional gain", "nonnegative")
    kd_phi: float = param("N m s/rad", "pitch derivative gain", "nonnegative")
    kp_theta: float = param("N m/rad", "roll proportional gain", "nonnegative")
    kd_theta: float = param("N m s/rad", "roll derivative gain", "nonnegative")
    name = "attitude"
    label = "SAS attitude loop"

    def __post_init__(self):
        validate_fields(self, "SAS attitude gain", plausible.ATTITUDE)


@dataclass(frozen=True)
class Ride(GainTable):
    """SAS ride loop: per-corner PD on the carbody corner's displacement and velocity,
    subtracted from the decoupled attitude demand: f_d,i = f_DTS,i - (kp_i z_i + kd_i z_i')."""

    kp_1R: float = param("N/m", "corner 1R proportional gain", "nonnegative")
    kp_1L: float = param("N/m", "corner 1L proportional gain", "nonnegative")
    kp_2R: float = param("N/m", "corner 2R proportional gain", "nonnegative")
    kp_2L: float = param("N/m", "corner 2L proportional gain", "nonnegative")
    kd_1R: float = param("N s/m", "corner 1R derivative gain", "nonnegative")
    kd_1L: float = param("N s/m", "corner 1L derivative gain", "nonnegative")
    kd_2R: float = param("N s/m", "corner 2R derivative gain", "nonnegative")
    kd_2L: float = param("N s/m", "corner 2L derivative gain", "nonnegative")
    name = "ride"
    label = "SAS ride loop"

    def __post_init__(self):
        validate_fields(self, "SAS ride gain", plausible.RIDE)

    def kp(self) -> np.ndarray:
        return np.array([getattr(self, f"kp_{c}") for c in CORNER_NAMES])

    def kd(self) -> np.ndarray:
        return np.array([getattr(self, f"kd_{c}") for c in CORNER_NAMES])


@dataclass(frozen=True)
class SAS:
    """Stability Augmentation System: the attitude loop, with or without the ride loop
    (6 + 8 = the paper's fourteen parameters)."""

    attitude: Attitude
    ride: Ride | None = None

    @property
    def name(self) -> str:
        return "sas-attitude" if self.ride is None else "sas-attitude-ride"

    @property
    def label(self) -> str:
        return "SAS (attitude)" if self.ride is None else "SAS (attitude+ride)"

    def gains(self, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
        a = self.attitude
        kp = np.diag([a.kp_z, a.kp_phi, a.kp_theta])
        kd = np.diag([a.kd_z, a.kd_phi, a.kd_theta])
        G = -decoupling(vehicle) @ np.hstack([kp, kd])
        if self.ride is not None:
            TcT = carbody_map(vehicle).T
            G = G - np.hstack([self.ride.kp()[:, None] * TcT, self.ride.kd()[:, None] * TcT])
        return G, np.zeros((4, 3))

    def to_dict(self) -> dict:
        out = {"attitude": self.attitude.to_dict()}
        if self.ride is not None:
            out["ride"] = self.ride.to_dict()
        return out


def outer_gains(controller, vehicle: Vehicle) -> tuple[np.ndarray, np.ndarray]:
    """An outer loop's ``gains(vehicle)`` as float arrays, checked: G with 4 rows (one per
    corner; its columns are the caller's to map), H of shape (4, 3) on the integrals, every value
    finite. A controller of one's own that gives anything else is an InputError naming it, before
    a run (a NaN gain would otherwise read as a diverging run)."""
    name = getattr(controller, "name", controller)
    try:
        G, H = controller.gains(vehicle)
        G, H = np.asarray(G, dtype=float), np.asarray(H, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(
            f"controller {name!r}: gains(vehicle) must give (G, H), two arrays of numbers ({exc})"
        ) from None
    if G.ndim != 2 or G.shape[0] != 4:
        raise InputError(
            f"controller {name!r}: gains(vehicle) gave G of shape {G.shape}; it needs 4 rows, one per corner"
        )
    if H.shape != (4, 3):
        raise InputError(
            f"controller {name!r}: gains(vehicle) gave H of shape {H.shape}; allowed (4, 3), on the integrals of the "
            "carbody's bounce, roll and pitch (zeros for none)"
        )
    for what, values in (("G", G), ("H", H)):
        bad = np.argwhere(~np.isfinite(values))
        if bad.size:
            i, j = bad[0]
            raise InputError(
                f"controller {name!r}: gains(vehicle) gave {what}[{i}, {j}] = {values[i, j]}; gains must be finite"
            )
    return G, H


# -- gains files --------------------------------------------------------------------------------
class _OuterLoop(NamedTuple):
    tables: tuple  # the gain tables it reads besides the inner loop's
    build: Callable  # GainSet -> the outer loop
    label: str
    inner: bool = True  # whether its voltage law reads the inner loop's gains ("tracking")


#: the outer loops a gains file defines, by name: the paper's, then those of railride.secondary.controllers;
#: a new controller is a class with ``gains(vehicle)``, ``name`` and ``to_dict()``, and an entry here
_OUTER_LOOPS = {
    "pid": _OuterLoop(("pid",), lambda g: g.pid, "PID"),
    "sas-attitude": _OuterLoop(("attitude",), lambda g: SAS(g.attitude), "SAS (attitude)"),
    # its own attitude loop (table ride_attitude), so that each law is tuned on its own gains
    "sas-attitude-ride": _OuterLoop(
        ("ride_attitude", "ride"), lambda g: SAS(g.ride_attitude, g.ride), "SAS (attitude+ride)"
    ),
    "skyhook": _OuterLoop(("skyhook",), lambda g: g.skyhook, Skyhook.label),
    # the skyhook's demand, switched on and off (no force tracking: no inner loop), on its own gains
    "skyhook-on-off": _OuterLoop(
        ("skyhook_on_off",), lambda g: SkyhookOnOff(**g.skyhook_on_off.to_dict()), SkyhookOnOff.label, False
    ),
    "groundhook": _OuterLoop(("groundhook",), lambda g: g.groundhook, Groundhook.label),
    "hybrid": _OuterLoop(("hybrid",), lambda g: g.hybrid, Hybrid.label),
    "clipped-optimal": _OuterLoop(("clipped_optimal",), lambda g: g.clipped_optimal, ClippedOptimal.label, False),
}
#: the outer loops by name
OUTER_LOOPS = tuple(_OUTER_LOOPS)
#: MR dampers held at a constant voltage, no outer loop: the baselines of a semi-active study
CONSTANT_VOLTAGE = {"passive-on": "v_max", "passive-off": "v_min"}
#: every suspension a comparison can name: passive, the outer loops, the constant-voltage baselines
CONTROLLERS = ("passive", *OUTER_LOOPS, *CONSTANT_VOLTAGE)
#: the paper's comparison (its Table 1): what `railride compare` runs by default
PAPER_CONTROLLERS = ("passive", "pid", "sas-attitude", "sas-attitude-ride")
LABELS = {
    "passive": "Passive",
    **{name: loop.label for name, loop in _OUTER_LOOPS.items()},
    "passive-on": "Passive-on",
    "passive-off": "Passive-off",
}
#: the gain tables by their "table.entry" name: (the table in a gains file, its class)
_TABLES = {
    "inner": ("inner", InnerLoop),
    "pid": ("pid", PID),
    "attitude": ("sas.attitude", Attitude),
    "ride": ("sas.ride", Ride),
    "ride_attitude": ("sas.ride_attitude", Attitude),
    "skyhook": ("skyhook", Skyhook),
    "skyhook_on_off": ("skyhook_on_off", Skyhook),
    "groundhook": ("groundhook", Groundhook),
    "hybrid": ("hybrid", Hybrid),
    "clipped_optimal": ("clipped_optimal", ClippedOptimal),
}
#: the tables a gains file of railride 0.3.0 and before has not: they take the packaged reference
_LATER_TABLES = ("skyhook", "groundhook", "hybrid", "clipped_optimal")
#: the tables a law once shared with another (before railride 0.4.0): a file without one
#: gives it the other's gains, as those versions did (the paper tunes its ride loop on top of
#: the attitude loop of SAS (attitude))
_OWN_COPIES = {"ride_attitude": "attitude", "skyhook_on_off": "skyhook"}


@functools.lru_cache(maxsize=1)
def _reference_gains() -> "GainSet":
    return GainSet.reference()


@dataclass(frozen=True)
class GainSet:
    """Every controller's gains, as read from a gains file. ``provenance``: the file's
    [provenance] table (how the gains were found), empty when it has none. ``from_reference``:
    the tables the file (or the constructor) did not give, which took the packaged reference
    values (`reference`): a file of railride 0.3.0 and before has no [skyhook], [groundhook],
    [hybrid] or [clipped_optimal]. Neither takes part in comparisons, so equal gains are equal
    whatever their history. Every law reads its own tables (`tables_read`); ``ride_attitude``
    (the attitude loop of SAS (attitude+ride)) and ``skyhook_on_off``, absent from a file
    written before railride 0.4.0, take the gains of ``attitude`` and ``skyhook``, which those
    laws read then."""

    inner: InnerLoop
    pid: PID
    attitude: Attitude
    ride: Ride
    source: str = "<built>"
    provenance: dict = field(default_factory=dict, compare=False, repr=False)
    skyhook: Skyhook | None = None
    groundhook: Groundhook | None = None
    hybrid: Hybrid | None = None
    clipped_optimal: ClippedOptimal | None = None
    from_reference: tuple = field(default=(), compare=False, repr=False)
    ride_attitude: Attitude | None = None
    skyhook_on_off: Skyhook | None = None

    #: the gain tables, as a "table.entry" name spells them (the file's [sas.attitude] is "attitude")
    TABLES: ClassVar[tuple] = tuple(_TABLES)
    #: the paper's tables, which every gains file holds (and every run key writes out)
    PAPER_TABLES: ClassVar[tuple] = ("inner", "pid", "attitude", "ride")

    def __post_init__(self):
        missing = tuple(t for t in _LATER_TABLES if getattr(self, t) is None)
        if missing:
            reference = _reference_gains()
            for t in missing:
                object.__setattr__(self, t, reference.table(t))
            object.__setattr__(self, "from_reference", tuple(dict.fromkeys(self.from_reference + missing)))
        for t, source in _OWN_COPIES.items():
            if getattr(self, t) is None:
                object.__setattr__(self, t, getattr(self, source))
                if source in self.from_reference:  # a copy of reference values is reference values
                    object.__setattr__(self, "from_reference", (*self.from_reference, t))
        for t, (key, kind) in _TABLES.items():
            if type(getattr(self, t)) is not kind:  # SkyhookOnOff is a Skyhook, but not its table
                raise InputError(f"{t} = {getattr(self, t)!r}: must be a railride {kind.__name__} (table [{key}])")

    @classmethod
    def entry_names(cls, table: str) -> tuple[str, ...]:
        """The "table.entry" names of ``table``, in the order of its fields."""
        kind = _TABLES[cls._table_name(table)][1]
        return tuple(f"{table}.{f.name}" for f in dataclasses.fields(kind))

    @staticmethod
    def entry_unit(entry: str) -> str | None:
        """The unit of the gain "table.entry", or None for an unknown table or entry."""
        table, _, name = entry.partition(".")
        kind = _TABLES.get(table, (None, None))[1]
        units = {f.name: f.metadata.get("unit") for f in dataclasses.fields(kind)} if kind else {}
        return units.get(name)

    @staticmethod
    def tables_read(controller: str) -> tuple[str, ...]:
        """The tables the outer loop ``controller`` and its inner loop read (none for the
        constant-voltage baselines; the on-off and clipped voltage laws read no inner loop)."""
        if controller in CONSTANT_VOLTAGE:
            return ()
        if controller not in _OUTER_LOOPS:
            raise InputError(f"controller = {controller!r}: allowed {', '.join(CONTROLLERS[1:])}")
        loop = _OUTER_LOOPS[controller]
        return ("inner",) * loop.inner + loop.tables

    @classmethod
    def tuned_entries(cls, controller: str) -> tuple[str, ...]:
        """The "table.entry" gains a tuning study of ``controller`` varies: the entries of its
        own tables, not the inner loop's (shared by every law that tracks a force, tuned on the
        damper rig) and not those its table fixes (`GainTable.fixed`: the LQR's r, since only
        the ratios of the weights shape its gain). Empty for the constant-voltage baselines."""
        out: tuple[str, ...] = ()
        for t in cls.tables_read(controller):
            if t != "inner":
                fixed: tuple = getattr(_TABLES[t][1], "fixed", ())
                out += tuple(e for e in cls.entry_names(t) if e.partition(".")[2] not in fixed)
        return out

    @classmethod
    def _table_name(cls, table: str) -> str:
        if table not in cls.TABLES:
            raise InputError(f"gain table {table!r}: allowed {', '.join(cls.TABLES)}")
        return table

    def table(self, name: str):
        """The gains of table ``name`` (one of `TABLES`)."""
        return getattr(self, self._table_name(name))

    def value(self, entry: str) -> float:
        """The gain called "table.entry", e.g. "pid.kp"."""
        table, _, name = entry.partition(".")
        if table not in self.TABLES or not name:
            raise InputError(f"gain {entry!r}: expected table.entry with table one of {', '.join(self.TABLES)}")
        gains = self.table(table)
        if name not in gains.to_dict():
            raise InputError(f"unknown gain {entry!r}; allowed: {', '.join(self.entry_names(table))}")
        return float(getattr(gains, name))

    def entries(self, tables=TABLES) -> dict[str, float]:
        """Every gain of ``tables`` by its "table.entry" name."""
        return {f"{t}.{k}": float(v) for t in tables for k, v in self.table(t).to_dict().items()}

    def apply(self, changes) -> "GainSet":
        """These gains with ``changes``, ("table.entry", value) pairs (or a dict), applied; the
        source stays, the provenance does not (they are other gains)."""
        grouped: dict[str, dict] = {}
        for name, value in changes.items() if isinstance(changes, dict) else changes:
            table, _, entry = name.partition(".")
            if table not in self.TABLES or not entry:
                raise InputError(f"gain {name!r}: expected table.entry with table one of {', '.join(self.TABLES)}")
            grouped.setdefault(table, {})[entry] = value
        tables = {t: self.table(t) for t in self.TABLES}
        for table, entries in grouped.items():
            tables[table] = tables[table].replace(**entries)
        kept = tuple(t for t in self.from_reference if t not in grouped)
        return GainSet(**tables, source=self.source, from_reference=kept)

    def untuned(self, controllers) -> list[str]:
        """The ``controllers`` whose gains the study that made these gains did not tune (its
        [provenance] ``controllers``; in files before railride 0.4.0, its ``phases``, the
        tables it tuned): judged beside tuned ones, they start at a disadvantage."""
        if "controllers" in self.provenance:
            tuned = set(self.provenance["controllers"])
            return [n for n in controllers if n in OUTER_LOOPS and n not in tuned]
        phases = set(self.provenance.get("phases", ()))
        return [
            n
            for n in controllers
            if n in OUTER_LOOPS
            and any(_OWN_COPIES.get(t, t) not in phases for t in self.tables_read(n) if t != "inner")
        ]

    def tuning_budget(self, controllers) -> dict | None:
        """How alike the ``controllers`` were tuned, from the [provenance] of these gains: the
        budget of vehicle runs each law had and the runs each used ({"budget": B, "runs":
        {name: n}}; for a robust tuning, gain sets, and ``runs_per_gain_set``), and where the file
        says, why each study stopped (``stopped``: {name: "budget", "converged" or "passes"}), or
        None when the gains file records no budget (files before 0.4.0)."""
        budget = self.provenance.get("budget")
        studies = self.provenance.get("studies", {})
        runs = {n: studies[n]["runs"] for n in controllers if n in studies}
        if budget is None or not runs:
            return None
        # a robust tuning's budget counts gain sets, each scored on every run of its tuning set
        per_set = len(self.provenance.get("tuning_set") or ()) or None
        # why each study stopped: its budget spent, converged, or out of passes
        stopped = {n: studies[n]["stopped"] for n in runs if studies[n].get("stopped")}
        return {
            "budget": budget,
            "runs": runs,
            **({"runs_per_gain_set": per_set} if per_set else {}),
            **({"stopped": stopped} if stopped else {}),
        }

    def tuned_on(self, record: dict | None) -> bool:
        """Whether these gains were tuned on the track ``record`` (`Scenario.describe`), as the
        file's [provenance] scenario record (or, for a robust tuning, its tuning set) says:
        judged there, they are judged in-sample: the same track at the same speed, whatever the
        duration and the load (`railride.secondary.provenance.judged_on`)."""
        from railride.secondary.provenance import IN_SAMPLE, judged_on

        judged = judged_on(self, record)
        return judged is not None and judged[0] == IN_SAMPLE

    def mismatch(
        self, vehicle: dict | None = None, scenarios=None, controllers=None, damper=None, damper_scale=None
    ) -> str | None:
        """One line when a run with these gains leaves the case they were tuned for (another
        vehicle, load or track, as their [provenance] says), naming what differs and the
        `railride tune` command that would tune for the run; None when it does not, or when the
        gains record no tuning. ``vehicle``: the run's `railride.model.params.vehicle_record`;
        ``scenarios``: its `Scenario.describe` record, or a study's list of them;
        ``controllers``: the suspensions it runs (None: a controller among them); none that
        reads gains, no line; ``damper``, ``damper_scale``: the run's dampers (a name, model or
        record; None: not compared) (`railride.secondary.provenance.mismatch`)."""
        from railride.secondary.provenance import mismatch

        return mismatch(self, vehicle, scenarios, controllers, damper, damper_scale)

    def record(self, controllers) -> dict:
        """What a result records of these gains for the runs of ``controllers``: ``source`` (as
        far as it is still true), ``provenance`` (JSON's values, or None) and ``values`` (per
        controller, every gain it reads), `railride.secondary.provenance.gains_record`."""
        from railride.secondary.provenance import gains_record

        return gains_record(self, controllers)

    def controller(self, name: str):
        """The outer loop called ``name`` (None for the passive suspension and the
        constant-voltage baselines, which have none)."""
        if name == "passive" or name in CONSTANT_VOLTAGE:
            return None
        if name not in _OUTER_LOOPS:
            raise InputError(f"unknown controller {name!r}; allowed: {', '.join(CONTROLLERS)}")
        return _OUTER_LOOPS[name].build(self)

    def to_toml(self, tables=TABLES, *, provenance: bool = True) -> str:
        """A gains file of ``tables`` (default all: a complete file to start from), after the
        [provenance] table of these gains where they have one and ``provenance`` is True
        (`railride.secondary.provenance.provenance_toml`: `load` of the file has the same
        provenance); `key_text` leaves it out."""
        from railride.secondary.provenance import provenance_toml

        lines = [provenance_toml(self.provenance)] if provenance and self.provenance else []
        for t in tables:
            key, obj = _TABLES[self._table_name(t)][0], self.table(t)
            lines.append(f"[{key}]")
            for f in dataclasses.fields(obj):
                lines.append(f"{f.name} = {getattr(obj, f.name)!r}  # {f.metadata['unit']}")
            lines.append("")
        return "\n".join(lines)

    def key_text(self) -> str:
        """These gains as the key of a run holds them (`railride.studies.sweep.run_cases`): the paper's
        tables as `to_toml` writes them, then each later table that differs from the packaged
        reference, so that the keys of runs of railride 0.3.0 and before stay what they were."""
        reference = _reference_gains()

        def kept(t):
            if t in _OWN_COPIES:  # one that holds the table it once shared adds nothing
                return self.table(t) != self.table(_OWN_COPIES[t])
            return t in self.PAPER_TABLES or self.table(t) != reference.table(t)

        return self.to_toml([t for t in self.TABLES if kept(t)], provenance=False)

    @classmethod
    def from_toml(cls, text: str, source: str = "<string>", *, complete: bool = False) -> "GainSet":
        """Read [inner], [pid], [sas.attitude], [sas.ride], [sas.ride_attitude], [skyhook],
        [skyhook_on_off], [groundhook], [hybrid], [clipped_optimal]; every entry of a table must
        be present, known, numeric and obey its rule; the error names the file, the table and
        the entry. [skyhook], [groundhook], [hybrid] and [clipped_optimal] may be absent (files
        of railride 0.3.0 and before): they take the packaged reference values, listed in
        ``from_reference``; [sas.ride_attitude] and [skyhook_on_off] may be absent (files before
        0.4.0): they take the gains of [sas.attitude] and [skyhook]; with ``complete`` every
        table must be there."""
        data = validation.parse_toml(text, source)
        unknown_top = sorted(set(data) - {"inner", "pid", "sas", "provenance", *_LATER_TABLES, "skyhook_on_off"})
        if unknown_top:
            allowed = ", ".join(f"[{key}]" for key, _ in _TABLES.values())
            raise InputError(f"{source}: unknown table(s) {', '.join(unknown_top)}; allowed: {allowed}, [provenance]")
        built = {}
        for t, (key, kind) in _TABLES.items():
            head, _, sub = key.partition(".")
            table = data.get(head)
            if sub:
                table = table.get(sub) if isinstance(table, dict) else None
            if table is None and (t in _LATER_TABLES or t in _OWN_COPIES) and not complete:
                continue  # GainSet takes the reference values (or the shared table's) and records it
            names = [f.name for f in dataclasses.fields(kind)]
            if not isinstance(table, dict):
                raise InputError(f"{source}: missing table [{key}] with entries {', '.join(names)}")
            unknown = sorted(set(table) - set(names))
            if unknown:
                raise InputError(f"{source}: unknown entry {unknown[0]!r} in [{key}]; allowed: {', '.join(names)}")
            missing = [n for n in names if n not in table]
            if missing:
                raise InputError(f"{source}: missing entry {missing[0]!r} in [{key}]")
            for n in names:
                v = table[n]
                if not validation.is_number(v):
                    raise InputError(f"{source}: entry {n!r} in [{key}] = {validation.shown(v)} is not a number")
            try:
                built[t] = kind(**table)
            except ValueError as exc:
                raise InputError(f"{source}: [{key}] {exc}") from None
        provenance = data.get("provenance", {})
        if not isinstance(provenance, dict):
            raise InputError(f"{source}: [provenance] must be a table, not {provenance!r}")
        return cls(**built, source=source, provenance=provenance)

    @classmethod
    def load(cls, path: str | Path) -> "GainSet":
        path = Path(path)
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise InputError(f"cannot read gains file {path}: {exc.strerror}") from None
        return cls.from_toml(text, source=str(path))

    @classmethod
    def default(cls) -> "GainSet":
        """The shipped gains (railride/data/gains.toml; its header says where they come from)."""
        return cls._packaged("gains.toml")

    @classmethod
    def robust(cls) -> "GainSet":
        """The shipped robust gains (railride/data/robust_gains.toml): every law tuned by
        `railride design` on random track of FRA classes 4 and 5 over a range of speeds and
        loads, and judged on track seeds it never saw; its [provenance] says on what."""
        return cls._packaged(SHIPPED["robust"])

    @classmethod
    def named(cls, name: str) -> "GainSet":
        """A shipped gain set by name: "paper" (`default`, tuned on the paper's sine) or
        "robust" (`robust`)."""
        if name not in SHIPPED:
            raise InputError(f"gains = {name!r}: not a shipped gain set; allowed {', '.join(SHIPPED)} or a gains file")
        return cls._packaged(SHIPPED[name])

    @classmethod
    def for_tracks(cls, scenarios=None) -> "GainSet":
        """The shipped set a run takes when it is given none (docs/tuning.md, Shipped gains):
        the robust gains where every track of the run is real track (random or measured,
        `REAL_TRACK`), else the paper's sine-tuned gains. ``scenarios``: a `Scenario`, its
        `describe` record, a scenario name, or a list of them; None: the paper's gains."""
        items = [] if scenarios is None else scenarios
        if isinstance(items, (str, dict)) or hasattr(items, "describe"):
            items = [items]
        profiles = [_profile(s) for s in items]
        return cls.robust() if profiles and all(p in REAL_TRACK for p in profiles) else cls.default()

    @classmethod
    def of(cls, gains, scenarios=None) -> "GainSet":
        """A gains argument as a `GainSet`: None, the shipped set for ``scenarios``
        (`for_tracks`); a `GainSet`; a shipped set's name ("paper", "robust"); or a gains
        file's path."""
        if gains is None:
            return cls.for_tracks(scenarios)
        if isinstance(gains, GainSet):
            return gains
        if isinstance(gains, str) and gains in SHIPPED:
            return cls.named(gains)
        if isinstance(gains, (str, Path)):
            return cls.load(gains)
        raise InputError(
            f"gains = {gains!r}: allowed a GainSet, a gains file's path or a shipped set ({', '.join(SHIPPED)})"
        )

    @classmethod
    def reference(cls) -> "GainSet":
        """The neutral start of the tuning study (railride/data/reference_gains.toml): every gain
        scaled from the passive suspension, the default start of `railride.studies.tuning.tune` and
        `railride tune`; installed with the package so the study can be repeated anywhere."""
        return cls._packaged("reference_gains.toml")

    @classmethod
    def _packaged(cls, name: str) -> "GainSet":
        # read once a process (a study asks for the shipped set every chunk, and parsing the
        # file took 10 ms); each caller gets its own copy of the provenance, the one mutable part
        kept = _packaged_gains(name)
        return dataclasses.replace(kept, provenance=copy.deepcopy(kept.provenance))


@functools.lru_cache(maxsize=None)
def _packaged_gains(name: str) -> GainSet:
    """A gains file installed with the package, parsed: complete, as the packaged files hold
    every table (the reference fills the others' gaps)."""
    text = resources.files("railride").joinpath(f"data/{name}").read_text(encoding="utf-8")
    return GainSet.from_toml(text, source=f"railride/data/{name}", complete=True)


#: the shipped gain sets by name (`GainSet.named`; --gains NAME on the command line)
SHIPPED = {"paper": "gains.toml", "robust": "robust_gains.toml"}
#: the track profiles the robust gains serve by default: real track, random or measured; the
#: paper's deterministic inputs (sine, bump) take the gains tuned on the paper's sine
REAL_TRACK = ("random", "measured")


def _profile(scenario) -> str | None:
    """A scenario's profile ("sine", "cosine-bump", "random", "measured"), from a `Scenario`,
    its record or its name."""
    if isinstance(scenario, dict):
        return scenario.get("profile")
    if hasattr(scenario, "describe"):
        return scenario.describe().get("profile")
    if isinstance(scenario, str):
        from railride.model.track import is_random

        name = scenario.strip()
        return "random" if is_random(name) else "measured" if name.startswith("file:") else "deterministic"
    return None


@dataclass(frozen=True)
class SensorNoise:
    """White noise added to every controller sample of the measured carbody states
    (standard deviations), from a seeded generator: runs with the same seed see the same noise."""

    displacement: float = param("m", "heave displacement noise", "nonnegative")
    angle: float = param("rad", "pitch and roll angle noise", "nonnegative")
    velocity: float = param("m/s", "heave velocity noise", "nonnegative")
    angular_rate: float = param("rad/s", "pitch and roll rate noise", "nonnegative")
    seed: int = param("-", "seed of the noise generator", "seed")

    def __post_init__(self):
        validate_fields(self, "sensor noise", plausible.SENSOR_NOISE)  # the seed as int, never through a float

    def samples(self, n: int) -> np.ndarray:
        """(n, 6) noise for m = (z, phi, theta, z', phi', theta')."""
        sd = np.array([self.displacement, self.angle, self.angle, self.velocity, self.angular_rate, self.angular_rate])
        return np.random.default_rng(self.seed).standard_normal((n, 6)) * sd
