"""The small parsing helpers of the commands: numbers, lists, damper presets, voltages, vehicle
parameters, gains files, sensor noise and the scenario and random-track options. Each raises a
ValueError naming the option, its value and what is allowed (the commands turn it into exit
status 2)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

from railride.errors import InputError


# -- numbers and lists ----------------------------------------------------------------------------
def parse_float(option: str, text: str, item: str, what: str = "") -> float:
    try:
        value = float(item)
    except ValueError:
        raise InputError(f"{option} = {text!r}: {item.strip()!r} is not a number{what}") from None
    if not math.isfinite(value):
        raise InputError(f"{option} = {text!r}: {item.strip()!r} is not a finite number")
    return value


def _tidy(value: float) -> float:
    """A range value without float noise (20:80:13 gives 25, not 25.000000000000004)."""
    return float(f"{value:.12g}")


def value_list(option: str, text: str, *, integer: bool = False, parse=None) -> list:
    """START:STOP:COUNT (linear, inclusive) or a,b,c -> distinct values, else ValueError naming
    the option. ``parse(item)`` reads a list item (default: a number)."""
    text = text.strip()
    kind = "whole numbers" if integer else "numbers"
    if ":" in text:
        parts = text.split(":")
        if len(parts) != 3:
            raise InputError(
                f"{option} = {text!r}: expected a range START:STOP:COUNT (e.g. 20:80:13) or a list a,b,c of {kind}"
            )
        number = _whole if integer else parse_float
        start, stop = (number(option, text, p) for p in parts[:2])
        try:
            count = int(parts[2])
        except ValueError:
            raise InputError(f"{option} = {text!r}: COUNT = {parts[2].strip()!r} is not a whole number") from None
        if count < 1:
            raise InputError(f"{option} = {text!r}: COUNT = {count} must be >= 1")
        if count == 1 and start != stop:  # one value of a range is its START: STOP would be dropped unsaid
            raise InputError(
                f"{option} = {text!r}: COUNT = 1 gives START alone; give COUNT >= 2 for values from START to "
                "STOP, or START alone"
            )
        from railride.limits import VALUE_BYTES, check

        # each value is a Python number in a list and a set, and a case of the runs: ~1 kB
        check(VALUE_BYTES * count, f"{option} = {text!r}: {count} values", "give a smaller COUNT")
        if integer:
            from fractions import Fraction

            # exact steps between whole numbers: seeds past 2**53 are not rounded
            span = Fraction(stop) - Fraction(start)  # exact, for floats (1e3) too
            step = span / max(count - 1, 1)
            if Fraction(start).denominator == 1 and step.denominator != 1:  # exact: 1.00001 reads as 1 at 4 digits
                raise InputError(
                    f"{option} = {text!r}: the step (STOP - START) / (COUNT - 1) = {step} is not a whole number"
                )
            values = [start + i * step for i in range(count)]
        else:
            import numpy as np

            values = [_tidy(v) for v in np.linspace(start, stop, count)]
    else:
        items = text.split(",")
        if any(not item.strip() for item in items):
            raise InputError(
                f"{option} = {text!r}: an empty item; give a range START:STOP:COUNT or {kind} separated by commas"
            )
        number = _whole if integer and not parse else parse_float
        values = [parse(item) if parse else number(option, text, item) for item in items]
        if parse:  # a word read as a number (passive-off as 0 V): a repeat is named as the user wrote it
            written: dict = {}
            for item, v in zip(items, values):
                if v in written:
                    raise InputError(
                        f"{option} = {text!r}: {item.strip()!r} is listed twice"
                        + (f" (as {written[v]!r})" if written[v] != item.strip() else "")
                    )
                written[v] = item.strip()
    if integer:
        bad = [v for v in values if v != int(v)]
        if bad:
            raise InputError(f"{option} = {text!r}: {_about(bad[0])} is not a whole number")
        values = [int(v) for v in values]
    seen = set()
    for v in values:
        if v in seen:
            raise InputError(f"{option} = {text!r}: {_shown(v)} is listed twice")
        seen.add(v)
    return values


def number_items(option: str, text: str) -> list[float]:
    """a,b,c -> the numbers, repeats allowed (shares, weights), else ValueError naming the option."""
    items = [item.strip() for item in text.split(",")]
    if any(not item for item in items):
        raise InputError(f"{option} = {text!r}: an empty item; give numbers separated by commas")
    return [parse_float(option, text, item) for item in items]


def _whole(option: str, text: str, item: str):
    """A list item of whole numbers: an int read exactly (a seed past 2**53 stays itself),
    else the number it is (3.0, 1e3; one with a fraction is refused by `value_list`)."""
    try:
        return int(item.strip())
    except ValueError:
        return parse_float(option, text, item)


def _about(value) -> str:
    """A number that is not whole, to four digits: a float, or a step of a range between
    whole numbers (a Fraction), which may be too large for a float."""
    try:
        return f"{float(value):.4g}"
    except OverflowError:
        from railride.validation import shown

        return f"about {shown(round(value)).split(' (')[0]}"  # without "(a 400-digit whole number)"


def _shown(value) -> str:
    from railride.validation import shown

    return f"{value:g}" if isinstance(value, float) else shown(value)


def default_of(fn, name: str):
    """The default value of parameter ``name`` of the library function ``fn``."""
    import inspect

    return inspect.signature(fn).parameters[name].default


# -- solver settings ------------------------------------------------------------------------------
#: the library's names of the step and rate options, for its errors (`_common.option_names`)
SOLVER_FIELDS = {
    "dt": "--dt",
    "output_rate": "--output-rate",
    "control_rate": "--control-rate",
    "backend": "--backend",
    "method": "--method",
}
#: the solver's fields in a command whose output rate is not an option (sweep, study): the rate is
#: named in words, not as a setting the user could pass
FIXED_RATE_FIELDS = {"dt": "--dt", "output_rate": "output rate", "backend": "--backend", "method": "--method"}


def solver_from_options(**given):
    """--dt, --output-rate, --control-rate, --backend, --method (None: not given) -> a railride.SolverSettings, the
    others at their defaults; the settings check themselves."""
    from railride.run.solver import SolverSettings

    return SolverSettings(**{k: v for k, v in given.items() if v is not None})


def not_given(**given) -> list[str]:
    """The names of the options left at their defaults (None), for `_common.option_names`."""
    return [k for k, v in given.items() if v is None]


# -- vehicle, dampers, gains, sensor noise --------------------------------------------------------
def vehicle_source(vehicle: Optional[str], preset: Optional[str] = None):
    """--vehicle NAME|FILE.toml (--params is the same option) or --preset NAME as the library
    takes a vehicle: the preset's name, the file's Path, or None (the default preset), checked
    before any work (the file is read): an unknown name that is no file is an InputError naming
    --vehicle, the presets and that a FILE.toml is accepted."""
    from railride.model.params import VehicleParams

    if vehicle is not None and preset is not None:
        raise InputError("give either --vehicle NAME|FILE.toml (or --params) or --preset NAME, not both")
    if preset is not None:
        try:
            VehicleParams.preset(preset)
        except InputError as exc:
            raise InputError(f"--preset: {exc}") from None
        return preset
    if vehicle is None:
        return None
    return VehicleParams.resolve(vehicle, "--vehicle")[1]


def vehicle_from_options(vehicle: Optional[str], preset: Optional[str], load: Optional[float] = None):
    """(the VehicleParams to run: --load scales the carbody's mass and inertias,
    `VehicleParams.loaded`; the vehicle's entries of a run's JSON document): ``vehicle``, the
    record of every output (`railride.model.params.vehicle_record`: name, load, values),
    then ``vehicle_preset`` or ``vehicle_params_file`` and, when --load is given,
    ``load_factor``, as the documents have always named the vehicle."""
    source, params, record = _vehicle(vehicle, preset, load)
    named: dict = (
        {"vehicle_params_file": str(source)} if isinstance(source, Path) else {"vehicle_preset": source or "paper"}
    )
    if load is not None:
        named["load_factor"] = float(load)
    return params, {"vehicle": record, **named}


def vehicle_arguments(vehicle: Optional[str], preset: Optional[str], load: Optional[float] = None) -> dict:
    """--vehicle (--params), --preset and --load as the keyword arguments of a study
    (``vehicle=``, ``load=``), checked before any work."""
    source, _, record = _vehicle(vehicle, preset, load)
    return {"vehicle": source, "load": record["load"]}


def _vehicle(vehicle: Optional[str], preset: Optional[str], load: Optional[float]):
    """(the source, the loaded parameters, the record) of the vehicle options."""
    from railride.cli._common import option_names
    from railride.model.params import resolve_vehicle

    source = vehicle_source(vehicle, preset)
    with option_names({"load": "--load"}):
        params, record = resolve_vehicle(source, load=1.0 if load is None else load, field="--vehicle")
    return source, params, record


def damper_preset(option: str, name: str, *, rig: bool = False):
    """The damper model of the option's text ``name``: a name of railride.secondary.dampers.NAMES
    (the MR presets and the ideal devices) or the path of a damper file (a ``[damper]`` table,
    railride.secondary.damper_file), else ValueError naming the option. ``rig``: MR dampers only
    (the ideal actuator has no force law to drive on the rig)."""
    from railride.secondary import dampers

    value = damper_argument(option, name, rig=rig)
    return dampers.preset(value) if isinstance(value, str) else value


def damper_argument(option: str, name, *, rig: bool = False):
    """What a command passes on as its ``damper=``: a preset's or ideal device's name as given,
    the model of a damper file; the errors of `damper_preset`. None stays None (the default)."""
    from railride.secondary import damper_file, dampers

    if name is None:
        return None
    if rig and name in dampers.IDEAL_NAMES:
        raise InputError(
            f"{option} = {name!r}: {dampers.ideal_words(name)} follows a vehicle controller's demand and has no "
            f"force law to drive on the rig; allowed: {', '.join(dampers.PRESETS)}, or the path of a FILE.toml "
            "with a [damper] table"
        )
    return damper_file.resolve(name, option, allowed=dampers.PRESETS if rig else dampers.NAMES)


def parse_scale(option: str, text: Optional[str]) -> float:
    """--damper-scale as a number (default 1; read as text, so that a word gets the one-line
    error too); its value is the damper's to check."""
    if text is None:
        return 1.0
    for kind in (int, float):  # as typed: the damper's message then shows 2, not 2.0
        try:
            return kind(text)
        except ValueError:
            pass
    raise InputError(f"{option} = {text!r}: must be a finite number > 0")


def parse_voltage(option: str, text: str, damper) -> float:
    """One voltage [V]: a number, ``passive-off`` (v_min) or ``passive-on`` (v_max), checked
    against the damper's range."""
    text = text.strip()
    keywords = {"passive-off": damper.v_min, "passive-on": damper.v_max}
    if text in keywords:
        return float(keywords[text])
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{option} = {text!r}: not a number of volts (nor passive-off, passive-on)") from None
    return damper.check_voltage(value, option)


def parse_voltages(option: str, text: str, damper) -> list[float]:
    """A comma-separated list of distinct voltages [V], each checked against the damper's range."""
    items = text.split(",")
    if any(not item.strip() for item in items):
        raise InputError(f"{option} = {text!r}: an empty item; give volts separated by commas, e.g. 0,1,2.25")
    values = [parse_voltage(option, item, damper) for item in items]
    seen = set()
    for v in values:
        if v in seen:
            raise InputError(f"{option} = {text!r}: {v:g} V is listed twice")
        seen.add(v)
    return values


def load_gains(path: Optional[Path]):
    """--gains: None where it is not given (the library takes the shipped set for the track,
    `GainSet.for_tracks`), a shipped set by name (paper, robust), else the file, with the
    library's message (file, table, entry)."""
    from railride.secondary.control import SHIPPED, GainSet

    if path is None:
        return None
    try:
        return GainSet.named(str(path)) if str(path) in SHIPPED else GainSet.load(path)
    except ValueError as exc:
        raise InputError(f"--gains: {exc}") from None


#: --sensor-noise items: (name, unit)
_NOISE_ITEMS = (("Z", "m"), ("ANGLE", "rad"), ("VEL", "m/s"), ("RATE", "rad/s"))


def parse_noise(option: str, text: str) -> list[float]:
    """Z,ANGLE,VEL,RATE: four standard deviations >= 0, else ValueError naming the option."""
    form = ",".join(n for n, _ in _NOISE_ITEMS)
    units = ", ".join(u for _, u in _NOISE_ITEMS)
    items = [item.strip() for item in text.split(",")]
    if len(items) != len(_NOISE_ITEMS):
        raise InputError(f"{option} = {text!r}: expected four numbers {form} ({units}), got {len(items)} item(s)")
    values = []
    for (name, unit), item in zip(_NOISE_ITEMS, items):
        try:
            value = float(item)
        except ValueError:
            raise InputError(f"{option} = {text!r}: {name} = {item!r} is not a number ({unit})") from None
        if not (math.isfinite(value) and value >= 0):
            raise InputError(
                f"{option} = {text!r}: {name} = {item}: must be a finite number >= 0 ({unit}, a standard deviation)"
            )
        values.append(value)
    return values


# -- scenarios and random tracks (fra1..fra6, german-low, german-high) ----------------------------
#: the options of the random-track scenarios: (option, keyword of track.scenario, unit)
TRACK_OPTIONS = (
    ("--track-seed", "seed", ""),
    ("--min-wavelength", "min_wavelength", "m"),
    ("--max-wavelength", "max_wavelength", "m"),
)
#: the library's names of the random-track options, for its errors (`_common.option_names`)
TRACK_FIELDS = {keyword: option for option, keyword, _ in TRACK_OPTIONS}
#: the profiles' field names in the library's errors -> the options that set them
PROFILE_FIELDS = {
    "amplitude": "--amplitude",
    "height": "--amplitude",
    "wavelength": "--wavelength",
    "length": "--wavelength",
    "rail_phase": "--rail-phase",
    "speed": "--speed",
    "duration": "--duration",
    "start": "--start",
}


#: a run's fields in the library's errors -> the options (compare, simulate): the solver's and
#: the profile's, which the run's own checks name too (``duration = 1e-308 s must be ...``)
RUN_FIELDS = {**SOLVER_FIELDS, **PROFILE_FIELDS}


def random_tracks() -> tuple:
    """The random tracks by name, as messages list them (a user's table as psd:PATH)."""
    from railride.model.track import RANDOM_NAMES

    return RANDOM_NAMES


def is_random_track(name) -> bool:
    from railride.model.track import is_random

    return is_random(name)


def track_options(
    scenario_name: str, seed: Optional[int], min_wavelength: Optional[float], max_wavelength: Optional[float]
) -> dict:
    """--track-seed, --min-wavelength, --max-wavelength -> the keyword arguments of
    track.scenario that were given (their values are the track's to check, `make_scenario`)."""
    given = {"seed": seed, "min_wavelength": min_wavelength, "max_wavelength": max_wavelength}
    out = {k: v for k, v in given.items() if v is not None}
    if out and not is_random_track(scenario_name):
        option, keyword, unit = next(o for o in TRACK_OPTIONS if o[1] in out)
        value = f"{out[keyword]:g}" + (f" {unit}" if unit else "")
        raise InputError(
            f"{option} = {value}: applies to the random-track scenarios "
            f"({', '.join(random_tracks())}) only, not to --scenario "
            f"{scenario_name}"
        )
    return out


def make_scenario(name: str, options: dict, output_rate: Optional[float] = None, rate_option: str = "--output-rate"):
    """track.scenario(name, **options), and with ``output_rate`` [Hz] the library's check that
    it resolves the track (`railride.run.solver.check_resolution`; ``rate_option`` names the option
    that sets the rate, or says what does). The library's errors name the options."""
    from railride.run.solver import check_resolution
    from railride.model.track import scenario as library_scenario

    if is_random_track(name):
        for option, keyword, unit in (
            ("--amplitude", "amplitude", "m"),
            ("--wavelength", "wavelength", "m"),
            ("--rail-phase", "rail_phase", "deg"),
        ):
            if options.get(keyword) is not None:
                raise InputError(
                    f"{option} = {options[keyword]:g} {unit}: does not apply to a "
                    f"random track ({name}); its options are --track-seed, "
                    "--min-wavelength and --max-wavelength"
                )
    from railride.cli._common import option_names

    fields = {
        **TRACK_FIELDS,
        **PROFILE_FIELDS,
        **({"output_rate": rate_option} if rate_option.startswith("--") else {}),
    }
    defaults = [k for k in TRACK_FIELDS if k not in options]
    try:
        with option_names(fields, defaults):
            scen = library_scenario(name, **options)
            if output_rate is not None:
                check_resolution(scen, output_rate)
    except ValueError as exc:
        band = [(o, k, u) for o, k, u in TRACK_OPTIONS if k != "seed" and k in options]
        if band and str(exc).startswith("wavelength band"):
            given = ", ".join(f"{o} = {options[k]:g} {u}" for o, k, u in band)
            raise InputError(f"{given}: {exc}") from None
        if str(exc).startswith("unknown scenario"):
            raise InputError(f"--scenario: {exc}") from None
        table_errors(name, str(exc), "--scenario")
        raise
    return scen


def table_errors(name: str, message: str, option: str) -> None:
    """A spectrum table's own error (it names the scenario: "scenario 'psd:PATH': ...") as the
    error of the option that gave the table; nothing for any other error."""
    if message.startswith(f"scenario {name!r}"):
        raise InputError(f"{option} {message[len('scenario ') :]}") from None


def check_table(option: str, name: str) -> None:
    """A spectrum table (psd:PATH) read before any work, its errors naming ``option``; nothing
    for any other scenario (its own checks come with it)."""
    from railride.model import psd_table

    if psd_table.is_table(name):
        try:
            psd_table.table(name)
        except ValueError as exc:
            table_errors(name, str(exc), option)
            raise


def _scenario_options(**given) -> dict:
    """The keyword arguments of track.scenario that were given (None: the scenario's default)."""
    return {k: float(v) for k, v in given.items() if v is not None}


def case_options(options: dict) -> dict:
    """Scenario options for a sweep.Case (which keeps the track seed a Python int)."""
    return dict(options)


def study_scenario(
    name: str,
    *,
    amplitude: Optional[float],
    wavelength: Optional[float],
    rail_phase: Optional[float],
    speed: Optional[float],
    duration: Optional[float],
    track_seed: Optional[int],
    min_wavelength: Optional[float],
    max_wavelength: Optional[float],
    start: Optional[float] = None,
):
    """(scenario, its options for sweep.Case) of the runs of a study (tune, pareto), checked
    before the first run (whether the runs' output rate resolves it is the study's check);
    ``start``: a measured profile's section (--start; the library checks the scenario)."""
    options = _scenario_options(
        amplitude=amplitude, wavelength=wavelength, rail_phase=rail_phase, speed=speed, duration=duration
    )
    options.update(track_options(name, track_seed, min_wavelength, max_wavelength))
    if start is not None:
        options["start"] = start
    return make_scenario(name, options), case_options(options)
