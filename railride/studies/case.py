"""A `Case`: one run described by plain settings (scenario and its options, vehicle parameter
changes, suspension, gain changes), so that it can travel to a Dask worker and has a stable key
(`Case.key`, which the run tables of sweeps, tuning and studies resume by)."""

from __future__ import annotations

import functools
import hashlib
import json
import numbers
from dataclasses import dataclass, fields

from railride._cache import hashable
from railride.errors import InputError
from railride.defaults import DEFAULT_DAMPER, DEFAULT_DURATION
from railride.model.track import source_sha256
from railride.secondary.control import CONSTANT_VOLTAGE
from railride.secondary.suspension import NAMES, Suspension

#: raised whenever the physics change the metrics of a run with the same settings, so that run
#: tables from before do not resume into the new model. 2: two secondary lateral and two
#: longitudinal springs per bogie, and the paper sine's entry taper.
MODEL_REVISION = 2
#: the suspensions a case can name (`Suspension.named`)
SUSPENSIONS = NAMES


@dataclass(frozen=True)
class Case:
    """One run. ``scenario_options`` are keyword arguments of `railride.model.track.scenario`,
    ``vehicle`` changes to the study's vehicle parameters (`run_cases`' ``params``, default the
    `paper` preset), ``gains`` changes to the base gain set as "table.entry" (e.g. "pid.kp",
    "attitude.kd_z", "ride.kp_1R", "inner.G"). ``suspension`` is passive, mr (constant
    ``voltage``) or a controller name; a controller may see sensor noise (``noise``: standard
    deviations displacement [m], angle [rad], velocity [m/s], angular rate [rad/s]) drawn with
    ``seed``. ``damper`` names the dampers of mr and the controllers (`railride.secondary.dampers.NAMES`;
    "ideal", the ideal actuator, with a controller only) and ``damper_scale`` multiplies an MR
    damper's force capacity (`BoucWen.scaled`); it must stay 1 for passive and the ideal
    actuator, which have none to scale. `to_suspension` gives the run's `Suspension`
    (`Suspension.named`, which also checks these settings when the case is made)."""

    scenario: str = "paper-sine"
    scenario_options: tuple = ()
    vehicle: tuple = ()
    suspension: str = "passive"
    damper: str = DEFAULT_DAMPER
    voltage: float | None = None
    gains: tuple = ()
    noise: tuple = ()
    seed: int = 0
    damper_scale: float = 1.0
    faults: tuple = ()  # damper faults as their text, e.g. ("1R-off@2",) (`railride.secondary.faults`)
    delay: int = 1  # a controller's delay in controller periods (`Suspension.delay`)
    sensing: str = "ideal"  # what a controller measures: "ideal" or "accelerometers" (`railride.secondary.sensing`)

    def __post_init__(self):
        from railride.secondary import dampers

        if self.suspension not in SUSPENSIONS:
            raise InputError(f"suspension = {self.suspension!r}; allowed: {', '.join(SUSPENSIONS)}")
        object.__setattr__(self, "damper_scale", dampers.check_scale("damper_scale", self.damper_scale))
        for name in ("scenario_options", "vehicle", "gains"):
            value = getattr(self, name)
            if isinstance(value, dict):
                value = tuple(sorted(value.items()))
            object.__setattr__(self, name, tuple((str(k), _plain(k, v)) for k, v in value))
        object.__setattr__(self, "noise", tuple(float(v) for v in self.noise))
        object.__setattr__(self, "seed", _plain("seed", self.seed))
        from railride.secondary.sensing import SENSING

        if self.sensing not in SENSING:
            raise InputError(f"sensing = {self.sensing!r}: allowed {', '.join(SENSING)}")
        from railride.secondary.faults import DamperFault

        faults = (self.faults,) if isinstance(self.faults, (str, DamperFault)) else self.faults
        object.__setattr__(
            self, "faults", tuple(f.label if isinstance(f, DamperFault) else DamperFault.parse(f).label for f in faults)
        )
        if self.noise and len(self.noise) != 4:
            raise InputError(f"noise = {self.noise!r}: four standard deviations or none")
        # the suspension's checks, here rather than in a batch: once per setting (a tuning
        # round makes tens of thousands of cases of a few suspensions)
        _check_suspension(self._suspension_key())

    def _suspension_key(self) -> tuple:
        """The settings `Suspension.named` reads (`_named_suspension`), gains aside."""
        return (
            self.suspension,
            self.damper,
            self.damper_scale,
            self.voltage,
            self.noise,
            self.seed,
            self.delay,
            self.sensing,
            self.faults,
        )

    @property
    def closed_loop(self) -> bool:
        return _closed_loop(self.suspension)

    def _named(self, gains) -> Suspension:
        return _named_suspension(self._suspension_key(), gains)

    def to_suspension(self, base_gains=None) -> Suspension:
        """The run's `Suspension`: `Suspension.named` with the case's gain changes applied to
        ``base_gains`` (default the shipped set for the case's track, `GainSet.for_tracks`)."""
        from railride.secondary.control import GainSet

        if not self.closed_loop:
            return self._named(None)
        base = GainSet.of(base_gains, self.scenario)
        return self._named(base.apply(self.gains))

    @staticmethod
    def suspensions(cases, base_gains=None) -> list[Suspension]:
        """`to_suspension` of each case, one object for the cases that differ only in their
        track options and vehicle (a tuning round's runs of one gain set over its conditions):
        the same suspension, made once."""
        made: dict[tuple, Suspension] = {}
        out = []
        for c in cases:
            # the shipped gains are chosen by the track's name (`GainSet.of`)
            settings = (c.scenario, c.gains, *c._suspension_key())
            if hashable(settings) is None:  # a setting that is no plain value: its own suspension
                out.append(c.to_suspension(base_gains))
                continue
            if settings not in made:
                made[settings] = c.to_suspension(base_gains)
            out.append(made[settings])
        return out

    @property
    def key(self) -> str:
        """A stable identity for the run table (same settings and model, same key, in any
        session). The model revision is part of it, so a run table from an earlier model is
        not taken for this one's on resume. Made once a case and revision (a study asks for it
        several times a run); the fields it is made from are frozen."""
        kept = self.__dict__.get("_key")
        if kept is not None and kept[0] == MODEL_REVISION:
            return kept[1]
        key = self._make_key()
        object.__setattr__(self, "_key", (MODEL_REVISION, key))
        return key

    def _make_key(self) -> str:
        d = self.to_dict()
        if "seed" in d["scenario_options"]:
            # as text, as when the track seed travelled as a NumPy integer: the keys of runs on
            # random tracks stay what they were
            d["scenario_options"]["seed"] = str(d["scenario_options"]["seed"])
        sha = source_sha256(self.scenario)
        if sha is not None:  # a file's values, not its path: an edited file's runs are run again
            d["scenario_sha256"] = sha
        text = json.dumps({**d, "model_revision": MODEL_REVISION}, sort_keys=True, default=str)
        return hashlib.sha1(text.encode()).hexdigest()[:16]

    def to_dict(self) -> dict:
        # the fields as they are: plain numbers, text and tuples of them (made so at construction),
        # which dataclasses.asdict would copy item by item, a study's largest Python cost a run
        d = {name: getattr(self, name) for name in _FIELDS}
        for name in ("scenario_options", "vehicle", "gains"):
            d[name] = dict(d[name])
        if d["damper_scale"] == 1.0:  # the default is left out: a scale appears only when set
            del d["damper_scale"]
        if not d["faults"]:  # the same: the keys of healthy runs stay what they were
            del d["faults"]
        if d["delay"] == 1:
            del d["delay"]
        if d["sensing"] == "ideal":
            del d["sensing"]
        return d

    @property
    def duration(self) -> float:
        """The run's duration [s] as its options give it (the scenarios' default,
        `railride.defaults.DEFAULT_DURATION`, where they give none)."""
        return float(self._duration_given())

    def _duration_given(self):
        """The duration as the options hold it (a number made a float at construction, `_plain`;
        anything else as given, for the scenario's check to name)."""
        return dict(self.scenario_options).get("duration", DEFAULT_DURATION)

    @property
    def group(self) -> tuple:
        """Cases that can share one compiled batch."""
        duration = self._duration_given()
        kind = "passive" if self.suspension == "passive" else ("closed" if self.closed_loop else "mr")
        # sensor noise is one setting per batch
        return (
            duration,
            kind,
            self.damper if kind != "passive" else "",
            (self.noise, self.seed) if kind == "closed" else (),
            self.damper_scale if kind != "passive" else 1.0,
            self.sensing if kind == "closed" else "ideal",  # one sensing model per batch
        )


#: the fields of a case, in their order (`Case.to_dict`: `dataclasses.fields` took 9 us a call)
_FIELDS = tuple(f.name for f in fields(Case))


def _closed_loop(suspension: str) -> bool:
    return suspension not in ("passive", "mr", *CONSTANT_VOLTAGE)


def _named_suspension(settings: tuple, gains) -> Suspension:
    """A case's `Suspension` from its settings (`Case._suspension_key`) and ``gains``."""
    from railride.secondary.control import SensorNoise

    suspension, damper, damper_scale, voltage, noise, seed, delay, sensing, faults = settings

    # noise reaches the controllers only (passive and mr runs ignore it, as they always did)
    sensor_noise = None
    if noise and _closed_loop(suspension):
        displacement, angle, velocity, angular_rate = noise
        sensor_noise = SensorNoise(displacement, angle, velocity, angular_rate, seed=seed)
    named = Suspension.named(suspension, gains, damper, damper_scale, voltage, sensor_noise)
    if delay != 1:
        named = named.with_delay(delay)
    if sensing != "ideal":
        from railride.secondary.sensing import Accelerometers

        named = named.with_sensing(Accelerometers(seed=seed))
    return named.with_faults(faults) if faults else named


def _check_suspension(settings: tuple) -> None:
    """`Suspension.named`'s checks of a case's suspension settings (`Case._suspension_key`), once
    per setting (an error is raised again each time, as it is not kept); every time for settings
    that cannot be hashed, whose checks then name what is wrong."""
    if hashable(settings) is None:
        _named_suspension(settings, None)
    else:
        _checked(settings)


@functools.lru_cache(maxsize=1024)
def _checked(settings: tuple) -> None:
    _named_suspension(settings, None)


def scenario_of(name: str, options):
    """`railride.model.track.scenario` of a case's scenario and options (pairs, as `Case` holds them).
    Not kept here: a random track's realisation comes from `railride.model.track`'s store and the
    tables from the simulation's, each bounded by bytes and keyed by settings; scenarios kept
    here held their realisations beyond that bound (32 of them, up to 220 MB)."""
    from railride.model.track import scenario as make_scenario

    return make_scenario(name, **dict(options))


def _plain(name: str, value):
    """A number of a case as a plain Python number: a seed a whole one as given (an int, never
    through a float, which rounds seeds past 2**53), any other a float; NumPy scalars too, so
    that keys and records hold plain numbers. Anything else is left for the checks that own it."""
    if type(value) is float or type(value) is str:  # most values, as they are (and quickly: a
        return value  # tuning round makes tens of thousands of cases)
    from railride import validation

    if not validation.is_number(value):
        return value
    if name == "seed" and isinstance(value, numbers.Integral):
        return int(value)
    try:
        return float(value)
    except OverflowError:  # a whole number past any float: the scenario's check names it
        return int(value)


def scenario_options(name: str, value) -> dict:
    """``value`` (None or a mapping) as the options `railride.model.track.scenario` takes: an
    input error naming ``name`` for anything else, or an option it does not take."""
    import inspect

    from railride import arguments
    from railride.model.track import scenario

    allowed = [p for p in inspect.signature(scenario).parameters if p != "name"]
    return arguments.options(name, value, allowed)
