"""The grid of a sweep: every combination of the given values, as `railride.studies.sweep.Case`s.

`grid` takes each axis as Python values (speeds, wavelengths, amplitudes, rail phases, track
seeds, suspensions, voltages, gain values, noise seeds, damper scales) and returns a
`SweepGrid`: the cases, the grid values each case reports and the settings a sweep records.
The scenario axes apply to every suspension; voltages to mr only; gains, sensor noise and its
seeds to the controllers they act in; damper scales to mr and the controllers. Every value and
every scenario of the grid is checked here, before the first run.
"""

from __future__ import annotations

import math

import dataclasses
import itertools
import numbers
from collections.abc import Mapping
from typing import Any


from railride.errors import InputError
from railride import arguments, validation
from railride.secondary.control import CONSTANT_VOLTAGE, OUTER_LOOPS, GainSet
from railride.defaults import DEFAULT_DAMPER
from railride.run.solver import SolverSettings
from railride.secondary.suspension import damper_model

#: the scenario options a sweep can vary: (keyword of `grid`, keyword of
#: `railride.model.track.scenario`, grid column, unit)
SCENARIO_AXES = (
    ("speed", "speed", "speed_m_s", "m/s"),
    ("wavelength", "wavelength", "wavelength_m", "m"),
    ("amplitude", "amplitude", "amplitude_m", "m"),
    ("rail_phase", "rail_phase", "rail_phase_deg", "deg"),
    ("track_seed", "seed", "track_seed", ""),
)
#: the keys of `Scenario.describe` that each swept scenario option sets (in the grid, not in
#: the scenario record)
SCENARIO_KEYS = {
    "speed": ("speed_m_s",),
    "wavelength": ("wavelength_m", "length_m"),
    "amplitude": ("amplitude_m", "height_m"),
    "rail_phase": ("rail_phase_deg",),
    "seed": ("seed",),
}
#: the controllers that read each gain table (a gain axis combines with these only)
GAIN_CONTROLLERS = {t: tuple(c for c in OUTER_LOOPS if t in GainSet.tables_read(c)) for t in GainSet.TABLES}
#: the voltages named by words: passive-off is the damper's lowest voltage, passive-on its highest
VOLTAGE_WORDS = CONSTANT_VOLTAGE
#: the options of the random tracks besides the seed: (keyword, unit)
_BAND = (("min_wavelength", "m"), ("max_wavelength", "m"))


@dataclasses.dataclass(frozen=True)
class SweepGrid:
    """The cases of a sweep and what it records (`grid` makes it).

    ``cases``: one `railride.studies.sweep.Case` per run, in order: for each suspension and each
    combination of the scenario axes, passive once, mr per damper scale and voltage, a
    controller per damper scale, combination of its gains and noise seed. ``values``: the grid
    values of each case (column -> value, None where an axis does not act), with the keys
    ``columns``. ``axes``: (keyword of `railride.model.track.scenario`, column, values) of each swept
    scenario option; ``first_scenario``: the first grid point's scenario (`Scenario.describe`);
    ``duration``: the runs' duration [s] (every run of a grid has the same)."""

    scenario: str
    suspensions: tuple
    axes: tuple
    damper: Any  # a name or a model of railride.secondary.dampers
    #: the damper scales; None when not an axis (every run at 1)
    damper_scales: tuple | None
    #: the voltages of mr; None without mr
    voltages: tuple | None
    #: ("table.entry", values) of each gain axis
    gains: tuple
    noise: tuple | None
    #: the sensor noise's seeds (0 alone without noise)
    seeds: tuple
    base_gains: GainSet
    solver: SolverSettings
    #: (start, end) of the metrics [s], or None for the whole run
    window: tuple | None
    first_scenario: dict
    duration: float
    columns: tuple
    cases: tuple = dataclasses.field(repr=False)
    values: tuple = dataclasses.field(repr=False)

    def __len__(self) -> int:
        return len(self.cases)

    @property
    def controllers(self) -> tuple:
        """The suspensions that run an outer-loop controller."""
        return tuple(s for s in self.suspensions if s in OUTER_LOOPS)

    def scenario_record(self) -> dict:
        """The scenario's fixed settings: `first_scenario` without the swept options (they are
        grid axes)."""
        swept = {key for kw, _, _ in self.axes for key in SCENARIO_KEYS[kw]}
        return {k: v for k, v in self.first_scenario.items() if k not in swept}

    def grid_values(self) -> dict:
        """Each axis and its values (column -> list): the suspensions, the swept scenario
        options, the damper scales, voltages, gains and noise seeds where they are axes."""
        return {
            "suspension": list(self.suspensions),
            **{column: list(values) for _, column, values in self.axes},
            **({"damper_scale": list(self.damper_scales)} if self.damper_scales is not None else {}),
            **({"voltage_v": list(self.voltages)} if self.voltages is not None else {}),
            **{name: list(values) for name, values in self.gains},
            **({"seed": list(self.seeds)} if self.noise is not None else {}),
        }


@dataclasses.dataclass(frozen=True)
class _Words:
    """How the checks of `grid` name a field and show what was given: by default the keyword
    and the value; the command line passes its option names and the text typed."""

    names: Mapping
    texts: Mapping

    def name(self, key: str) -> str:
        return self.names.get(key, key)

    def given(self, key: str, value, entry: str | None = None) -> str:
        text = self.texts.get(key)
        if isinstance(text, Mapping):  # one text per entry (the gains)
            text = text.get(entry) if entry is not None else next(iter(text.values()), None)
        if text is not None:
            return f"{self.name(key)} = {text!r}"
        label = self.name(key) if entry is None or key in self.names else f"{key}[{entry!r}]"
        return f"{label} = {validation.shown(value)}"


def _g(value) -> str:
    """A number as the grid's messages show it (20, not 20.0)."""
    if validation.is_number(value) and not isinstance(value, numbers.Integral):
        return f"{value:g}"
    return validation.shown(value)  # a whole number exactly (a seed), or its size past 30 digits


def _obeys(value, rule: str) -> bool:
    """Whether ``value`` is a finite number obeying `validation.RULES` ``rule``."""
    return validation.obeys(value, rule)


def _values(words: _Words, key: str, values) -> list | None:
    """The values of an axis as a list (a single value is an axis of one); None if not given."""
    if values is None:
        return None
    if validation.is_number(values) or isinstance(values, str):
        values = [values]
    values = list(values)
    if not values:
        raise InputError(f"{words.given(key, values)}: give one or more values")
    return values


def _numbers(words: _Words, key: str, values, rule: str = "finite", unit: str = "") -> list[float]:
    """Every value obeying ``rule``, as floats."""
    for v in values:
        if not _obeys(v, rule):
            raise InputError(
                f"{words.name(key)} = {_g(v)}{' ' + unit if unit else ''}: must be {validation.rule_words(rule)}"
            )
    return [float(v) for v in values]


def _seeds(words: _Words, key: str, values, what: str) -> list[int]:
    """Every value a seed, as Python ints (never through a float); a whole float (3.0) is the
    seed 3, as `railride.model.track.RandomTrack` takes it."""
    whole = [
        int(v) if not isinstance(v, numbers.Integral) and _obeys(v, "finite") and float(v).is_integer() else v
        for v in values
    ]
    for item in whole:
        if isinstance(item, bool) or not isinstance(item, numbers.Integral):
            raise InputError(
                f"{words.given(key, values)}: {_g(item)} is not a whole number; {what} are whole numbers >= 0"
            )
        v = int(item)
        if v < 0:
            raise InputError(f"{words.given(key, values)}: {v} is negative; {what} are whole numbers >= 0")
        if v > validation.SEED_MAX:
            raise InputError(
                f"{words.given(key, values)}: {validation.shown(v)} is too large; {what} are at most 2**64 - 1"
            )
    return [int(v) for v in whole]


def voltage_value(value, damper) -> float:
    """A voltage of mr: a number [V], or a word of `VOLTAGE_WORDS` (passive-off, passive-on)
    read from ``damper``'s range; not checked against the range."""
    if isinstance(value, str) and value in VOLTAGE_WORDS:
        return float(getattr(damper, VOLTAGE_WORDS[value]))
    return float(value) if validation.is_number(value) else value


def grid(
    suspensions="passive",
    *,
    scenario: str = "paper-sine",
    speed=None,
    wavelength=None,
    amplitude=None,
    rail_phase=None,
    track_seed=None,
    duration: float | None = None,
    min_wavelength: float | None = None,
    max_wavelength: float | None = None,
    voltage=None,
    gains: Mapping | None = None,
    noise=None,
    seed=None,
    damper: str | None = None,
    damper_scale=None,
    base_gains: GainSet | None = None,
    solver: SolverSettings | None = None,
    window=None,
    names: Mapping | None = None,
    texts: Mapping | None = None,
) -> SweepGrid:
    """The cases of a sweep: every combination of the given values (a cartesian product).

    ``suspensions``: a name or a list of names (passive, mr, pid, sas-attitude,
    sas-attitude-ride). Scenario axes, for every suspension (lists of values; None: the
    scenario's default, not an axis): ``speed`` [m/s], ``wavelength`` [m] (a bump's length),
    ``amplitude`` [m] (a bump's height), ``rail_phase`` [deg] (paper-sine), ``track_seed``
    (random tracks). ``duration`` [s], ``min_wavelength`` and ``max_wavelength`` [m] (random
    tracks) are one setting for the whole grid. ``voltage``: the voltages of mr [V] within the
    damper's range (numbers or passive-off, passive-on; default passive-off). ``gains``: gain
    axes of the controllers they act in, {"table.entry": [values]} (e.g. {"pid.kd": [1e4,
    1e5]}), changes to ``base_gains`` (default the shipped `GainSet.default`). ``noise``: the
    controllers' sensor noise (four standard deviations: displacement [m], angle [rad],
    velocity [m/s], angular rate [rad/s]) with the seeds ``seed`` (default [0]). ``damper``:
    the damper of mr and the controllers (`railride.secondary.dampers.NAMES`, default railway; the ideal
    devices with the controllers only); ``damper_scale``: factors on its force capacity, an axis
    of mr and the controllers (passive runs once, unscaled). ``solver``: the `SolverSettings` of
    every run; ``window``: (start, end) [s] of the metrics (end may be inf: the end of the run).

    A ValueError names the field, the value and what is allowed; ``names`` (keyword -> name)
    and ``texts`` (keyword -> the text a value was read from; for ``gains``, entry -> text) let
    a caller such as the command line word it in its own terms.
    """
    from railride.secondary import dampers
    from railride.analysis.metrics import check_window

    words = _Words(names or {}, texts or {})
    listed, suspensions = _suspensions(words, suspensions)
    controllers = [s for s in suspensions if s in OUTER_LOOPS]
    has_mr = "mr" in suspensions
    # passive-on and passive-off are mr at the damper's v_max and v_min
    constant = [s for s in suspensions if s in CONSTANT_VOLTAGE]
    voltage, damper_scale = _values(words, "voltage", voltage), _values(words, "damper_scale", damper_scale)
    seed = _values(words, "seed", seed)
    _check_applies(
        words,
        listed,
        has_mr,
        controllers,
        constant,
        voltage=voltage,
        gains=gains,
        noise=noise,
        base_gains=base_gains,
        seed=seed,
        damper=damper,
        damper_scale=damper_scale,
    )
    damper_name = DEFAULT_DAMPER if damper is None else damper
    if isinstance(damper_name, str) and damper_name not in dampers.NAMES:
        raise InputError(
            f"{words.given('damper', damper_name)}: unknown damper model; allowed: {', '.join(dampers.NAMES)}"
        )
    the_model = damper_model(damper_name)  # a name or a model: resolved here, once
    ideal = the_model.law == dampers.LAW_IDEAL
    if ideal and (has_mr or constant):
        fixed = "mr" if has_mr else constant[0]
        raise InputError(
            f"{words.given('damper', damper_name)}: applies to the controllers only; "
            f"{fixed} runs at a constant voltage, which the ideal actuator has not "
            f"({words.name('suspensions')} is {listed})"
        )
    scales = None
    if damper_scale is not None:
        if ideal:
            raise InputError(
                f"{words.given('damper_scale', damper_scale)}: the ideal device "
                f"({words.name('damper')} {damper_name}) applies the demand itself and has no "
                "force capacity to scale"
            )
        from railride.secondary.dampers import check_scale

        # each factor within the plausible range here, before any run, named as the user named it
        scales = [
            check_scale(words.name("damper_scale"), x)
            for x in _numbers(words, "damper_scale", damper_scale, "positive")
        ]
    band = _band(words, scenario, min_wavelength, max_wavelength)
    axes = _scenario_axes(
        words,
        scenario,
        speed=speed,
        wavelength=wavelength,
        amplitude=amplitude,
        rail_phase=rail_phase,
        track_seed=track_seed,
    )
    volts = None
    if has_mr:
        model = the_model
        volts = (
            [float(model.v_min)]
            if voltage is None
            else [model.check_voltage(voltage_value(v, model), words.name("voltage")) for v in voltage]
        )
    gain_axes = _gain_axes(words, gains, controllers, listed)
    noise = None if noise is None else tuple(float(v) for v in noise)
    seeds = [0] if seed is None else _seeds(words, "seed", seed, "seeds")
    base_gains = GainSet.of(base_gains, scenario)
    solver = SolverSettings.of(solver)
    common = {} if duration is None else {"duration": _duration(words, duration, solver.output_rate)}
    common.update(band)
    _check_count(words, axes, suspensions, scales, volts, gain_axes, seeds if noise is not None else None)
    combos, record, run_duration = _scenarios(
        words, scenario, axes, common, min_wavelength is not None, solver.output_rate
    )
    if window is not None:
        try:
            window = check_window(tuple(window), run_duration)
        except ValueError as exc:  # "window = ..." in the caller's words
            name = words.name("window")
            raise InputError(str(exc).replace("window", name, 1) if name != "window" else str(exc)) from None

    columns = ["suspension"] + [column for _, column, _ in axes]
    if scales is not None:
        columns.append("damper_scale")
    if has_mr:
        columns.append("voltage_v")
    columns += [name for name, _ in gain_axes]
    if noise is not None:
        columns.append("seed")
    made = SweepGrid(
        scenario=scenario,
        suspensions=tuple(suspensions),
        axes=tuple((kw, column, tuple(values)) for kw, column, values in axes),
        damper=damper_name,
        damper_scales=None if scales is None else tuple(scales),
        voltages=None if volts is None else tuple(volts),
        gains=tuple((n, tuple(vs)) for n, vs in gain_axes),
        noise=noise,
        seeds=tuple(seeds),
        base_gains=base_gains,
        solver=solver,
        window=window,
        first_scenario=record,
        duration=run_duration,
        columns=tuple(columns),
        cases=(),
        values=(),
    )
    cases, values = _cases(made, combos, common)
    return dataclasses.replace(made, cases=tuple(cases), values=tuple(values))


def _suspensions(words: _Words, given) -> tuple[str, list[str]]:
    """(the suspensions as the messages list them, the list): known, each once."""
    from railride.secondary.suspension import NAMES

    items = [given] if isinstance(given, str) else list(given)
    if not items:
        raise InputError(f"{words.given('suspensions', items)}: give one or more of {', '.join(NAMES)}")
    unknown = [s for s in items if s not in NAMES]
    if unknown:
        raise InputError(
            f"{words.given('suspensions', given)}: unknown suspension {unknown[0]!r}; allowed: {', '.join(NAMES)}"
        )
    twice = arguments.repeated(items)
    if twice:
        raise InputError(f"{words.given('suspensions', given)}: {twice[0]} is listed twice")
    return ", ".join(items), items


def _check_applies(words: _Words, listed: str, has_mr: bool, controllers: list, constant: list, **given) -> None:
    """What applies where: voltages to mr, gains, noise and base gains to the controllers,
    noise seeds with noise, the damper and its scales to mr, passive-on, passive-off and the
    controllers."""
    among = f"({words.name('suspensions')} is {listed})"
    if given["voltage"] is not None and not has_mr:
        raise InputError(
            f"{words.given('voltage', given['voltage'])}: applies to {words.name('suspensions')} mr only {among}"
        )
    for key in ("gains", "noise", "base_gains"):
        if given[key] is not None and not controllers and (key != "gains" or given[key]):
            shown = getattr(given[key], "source", given[key])  # a GainSet by its file
            raise InputError(
                f"{words.given(key, shown)}: applies to the controllers {', '.join(OUTER_LOOPS)} only {among}"
            )
    if given["seed"] is not None and given["noise"] is None:
        raise InputError(
            f"{words.given('seed', given['seed'])}: applies with {words.name('noise')} only "
            "(without it the measurements are ideal)"
        )
    for key in ("damper", "damper_scale"):
        if given[key] is not None and not (has_mr or controllers or constant):
            # passive-on and passive-off are mr runs
            raise InputError(f"{words.given(key, given[key])}: applies to mr and the controllers only {among}")


def _band(words: _Words, scenario: str, min_wavelength, max_wavelength) -> dict:
    """The wavelength band of a random track that was given, checked."""
    from railride.model.track import RANDOM_NAMES, is_random

    out = {}
    for key, unit in _BAND:
        value = {"min_wavelength": min_wavelength, "max_wavelength": max_wavelength}[key]
        if value is not None:
            out[key] = _numbers(words, key, [value], "positive", unit)[0]
    if out and not is_random(scenario):
        key, unit = next(b for b in _BAND if b[0] in out)
        raise InputError(
            f"{words.name(key)} = {out[key]:g} {unit}: applies to the random-track scenarios "
            f"({', '.join(RANDOM_NAMES)}) only, not to {words.name('scenario')} {scenario}"
        )
    return out


def _scenario_axes(words: _Words, scenario: str, **given) -> list:
    """The swept scenario options: (keyword of track.scenario, column, values) each."""
    from railride.model.track import RANDOM_NAMES, is_random

    axes = []
    for key, keyword, column, unit in SCENARIO_AXES:
        values = _values(words, key, given[key])
        if values is None:
            continue
        if keyword == "seed":
            values = _seeds(words, key, values, "track seeds")
            if not is_random(scenario):
                raise InputError(
                    f"{words.given(key, values)}: applies to the random-track scenarios "
                    f"({', '.join(RANDOM_NAMES)}) only, not to {words.name('scenario')} {scenario}"
                )
        else:
            values = _numbers(words, key, values, unit=unit)
            if is_random(scenario) and key != "speed":
                raise InputError(
                    f"{words.name(key)} = {values[0]:g} {unit}: does not apply to a random track "
                    f"({scenario}); its options are {words.name('track_seed')}, "
                    f"{words.name('min_wavelength')} and {words.name('max_wavelength')}"
                )
        axes.append((keyword, column, values))
    return axes


def _gain_axes(words: _Words, gains: Mapping | None, controllers: list, listed: str) -> list:
    """The gain axes: ("table.entry", values) each, a known gain acting in a listed controller,
    its values >= 0."""
    known = [n for t in GainSet.TABLES for n in GainSet.entry_names(t)]
    axes = []
    for name, values in (gains or {}).items():
        values = _values(words, "gains", [] if values is None else values) or []
        given = words.given("gains", values, name)
        if name not in known:
            table = str(name).partition(".")[0]
            allowed = (
                ", ".join(GainSet.entry_names(table))
                if table in GainSet.TABLES
                else ", ".join(f"{table}.*" for table in GainSet.TABLES) + " (" + ", ".join(known[:5]) + ", ...)"
            )
            raise InputError(f"{given}: unknown gain {name!r}; allowed: {allowed}")
        bad = [v for v in values if not _obeys(v, "nonnegative")]
        if bad:
            finite = _obeys(bad[0], "finite")
            raise InputError(
                f"{given}: {_g(bad[0])} is {'negative' if finite else 'not a finite number'}; gains are >= 0"
            )
        acts_in = GAIN_CONTROLLERS[name.partition(".")[0]]
        if not any(c in acts_in for c in controllers):
            # the tables that do act in the listed controllers, with this entry: where the user meant
            hint = [
                f"{table}.{name.partition('.')[2]}"
                for table, laws in GAIN_CONTROLLERS.items()
                if any(c in laws for c in controllers) and f"{table}.{name.partition('.')[2]}" in known
            ]
            raise InputError(
                f"{given}: {name} acts in {', '.join(acts_in)} only, which "
                f"{words.name('suspensions')} ({listed}) does not list"
                + (f"; in {listed}: {', '.join(hint)}" if hint else "")
            )
        axes.append((name, [float(v) for v in values]))
    return axes


def _scenarios(words: _Words, scenario: str, axes: list, common: dict, min_given: bool, output_rate: float):
    """(the combinations of the axes' values, the first scenario described, the runs'
    duration): every scenario of the grid must be valid before anything runs, and a random
    track's shortest wavelength must show at the runs' output rate (as `simulate` requires)."""
    from railride.model.track import scenario as make_scenario

    combos = list(itertools.product(*[values for *_, values in axes]))
    record, duration = None, None
    # the combinations of one profile together (speed varies last), so that each random-track
    # realisation is synthesised once here, however few the track store keeps
    profile = [j for j, (kw, *_) in enumerate(axes) if kw != "speed"]
    for combo in sorted(combos, key=lambda combo: [combo[j] for j in profile]):
        options = {**common, **{kw: v for (kw, _, _), v in zip(axes, combo)}}
        try:
            scen = make_scenario(scenario, **options)
        except ValueError as exc:
            band = [(k, u) for k, u in _BAND if k in options]
            if band and "wavelength" in str(exc):
                named = ", ".join(f"{words.name(k)} = {options[k]:g} {u}" for k, u in band)
                raise InputError(f"{named}: {exc}") from None
            if str(exc).startswith("unknown scenario"):
                raise InputError(f"{words.name('scenario')}: {exc}") from None
            text, others = str(exc), []
            for (kw, _, _), v in zip(axes, combo):
                key = _key(kw)
                if text.startswith(f"{key} = "):  # the message names this axis and its value itself
                    text = words.name(key) + text[len(key) :]
                else:
                    others.append(f"{words.name(key)} {v:g}")
            raise InputError(f"{', '.join(others)}: {text}" if others else text) from None
        _check_resolvable(words, scen, min_given, output_rate)
        if combo == combos[0]:
            record = scen.describe()
        duration = scen.duration
    return combos, record, duration


def grid_size(axes: list, suspensions: list, scales, volts, gain_axes: list, seeds) -> int:
    """The number of cases `_cases` makes of these axes, counted without making them: per
    scenario combination, passive once, mr per scale and voltage, passive-on/off per scale, a
    controller per scale, combination of its gains and noise seed (``seeds`` None: no noise)."""
    n_scales = len(scales) if scales is not None else 1
    per_combo = 0
    for s in suspensions:
        if s == "passive":
            per_combo += 1
        elif s in CONSTANT_VOLTAGE:
            per_combo += n_scales
        elif s == "mr":
            per_combo += n_scales * len(volts or ())
        else:
            mine = [vs for n, vs in gain_axes if s in GAIN_CONTROLLERS[n.partition(".")[0]]]
            per_combo += n_scales * math.prod(map(len, mine)) * (len(seeds) if seeds is not None else 1)
    return math.prod(len(values) for *_, values in axes) * per_combo


def _check_count(words: _Words, axes: list, suspensions: list, scales, volts, gain_axes: list, seeds) -> None:
    """`railride.limits.check` on the grid's cases (`VALUE_BYTES` each, as the command line
    counts a range's values) before any is made: each axis's values pass alone, but their
    product can be past the memory (1e5 speeds x 1e5 amplitudes) and would take hours to build."""
    from railride import limits

    n = grid_size(axes, suspensions, scales, volts, gain_axes, seeds)
    if limits.VALUE_BYTES * n <= limits.max_memory():
        return
    shape = [f"{len(values)} {words.name(_key(kw))}" for kw, _, values in axes]
    shape.append(f"{len(suspensions)} {words.name('suspensions')}")
    shape += [f"{len(v)} {words.name('damper_scale')}" for v in [scales] if v is not None]
    shape += [f"{len(v)} {words.name('voltage')}" for v in [volts] if v is not None and len(v) > 1]
    shape += [f"{len(vs)} {words.name('gains')} {name}" for name, vs in gain_axes]
    shape += [f"{len(v)} {words.name('seed')}" for v in [seeds] if v is not None]
    limits.check(limits.VALUE_BYTES * n, f"a grid of {n} runs ({' x '.join(shape)})", "give fewer values")


def _duration(words: _Words, duration, output_rate: float) -> float:
    """The runs' duration, checked once for the whole grid (a scenario's check would name the
    first grid point as if that point were wrong), in the caller's words."""
    from railride.run.checks import output_samples

    name = words.name("duration")
    try:
        value = validation.number("duration", duration, "positive", "s")
        output_samples(value, output_rate)
    except ValueError as exc:
        raise InputError(name + str(exc)[len("duration") :]) from None
    return value


def _key(keyword: str) -> str:
    """The `grid` keyword of a scenario keyword."""
    return next(key for key, kw, *_ in SCENARIO_AXES if kw == keyword)


def _check_resolvable(words: _Words, scen, min_given: bool, output_rate: float) -> None:
    """`railride.run.solver.check_resolution` (a random track's shortest wavelength must show at
    the runs' output rate), its error naming the grid's fields."""
    from railride.run.solver import RESOLUTION, check_resolution, shortest_wavelength

    try:
        check_resolution(scen, output_rate)
    except ValueError:
        field, lam = shortest_wavelength(scen.track) or ("min_wavelength", math.nan)
        mw, speed = words.name("wavelength" if field == "length" else field), words.name("speed")
        default = "" if min_given or field != "min_wavelength" else " (the default)"
        raise InputError(
            f"{mw} = {lam:g} m{default} at {speed} {scen.speed:g} m/s is "
            f"{scen.speed / lam:g} Hz, more than the runs' output rate {output_rate:g} Hz / {RESOLUTION:g} = "
            f"{output_rate / RESOLUTION:g} Hz can resolve: raise {mw} or lower {speed}"
        ) from None


def _cases(g: SweepGrid, combos: list, common: dict) -> tuple[list, list]:
    """(the cases, the grid values of each): for each suspension and scenario combination, passive
    once, mr per scale and voltage, a controller per scale, gain combination and noise seed."""
    from railride.studies.case import Case

    scaled = g.damper_scales is not None
    cases, values = [], []
    for s in g.suspensions:
        for combo in combos:
            given = {**common, **{kw: v for (kw, _, _), v in zip(g.axes, combo)}}
            options = tuple(sorted(given.items()))  # Case keeps a seed a Python int
            base = {c: None for c in g.columns}
            base.update({"suspension": s, **{column: v for (_, column, _), v in zip(g.axes, combo)}})
            if s == "passive":
                cases.append(Case(g.scenario, options))
                values.append(base)
            elif s in CONSTANT_VOLTAGE:  # an mr run at the damper's v_max or v_min
                v = float(getattr(damper_model(g.damper), CONSTANT_VOLTAGE[s]))
                for x in g.damper_scales or (1.0,):
                    cases.append(Case(g.scenario, options, suspension="mr", damper=g.damper, voltage=v, damper_scale=x))
                    row: dict = dict(base)
                    if g.voltages is not None:  # a voltage column: mr is swept too
                        row["voltage_v"] = v
                    if scaled:
                        row["damper_scale"] = x
                    values.append(row)
            elif s == "mr":
                for x in g.damper_scales or (1.0,):
                    for v in g.voltages or ():
                        cases.append(
                            Case(g.scenario, options, suspension="mr", damper=g.damper, voltage=v, damper_scale=x)
                        )
                        values.append({**base, "voltage_v": v, **({"damper_scale": x} if scaled else {})})
            else:
                mine = [(n, vs) for n, vs in g.gains if s in GAIN_CONTROLLERS[n.partition(".")[0]]]
                for x in g.damper_scales or (1.0,):
                    for gains in itertools.product(*[vs for _, vs in mine]):
                        changes = tuple(zip([n for n, _ in mine], gains))
                        for sd in g.seeds if g.noise is not None else (0,):
                            cases.append(
                                Case(
                                    g.scenario,
                                    options,
                                    suspension=s,
                                    damper=g.damper,
                                    gains=changes,
                                    noise=g.noise or (),
                                    seed=sd,
                                    damper_scale=x,
                                )
                            )
                            row = {**base, **dict(changes)}
                            if scaled:
                                row["damper_scale"] = x
                            if g.noise is not None:
                                row["seed"] = sd
                            values.append(row)
    return cases, values
