"""The small parsing helpers of the commands: numbers, lists, damper presets, voltages, vehicle
parameters, gains files, sensor noise and the scenario and random-track options. Each raises a
ValueError naming the option, its value and what is allowed (the commands turn it into exit
status 2)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Optional

from ..dampers import IDEAL_NAMES


# -- numbers and lists ----------------------------------------------------------------------------
def check_number(option: str, value: float, unit: str, *, allow_zero: bool = False) -> float:
    """A finite number > 0 (>= 0 with ``allow_zero``), else ValueError naming the option."""
    ok = math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok:
        rule = ">= 0" if allow_zero else "> 0"
        unit = f" {unit}" if unit else ""
        raise ValueError(f"{option} = {value:g}{unit}: must be a finite number {rule}")
    return float(value)


def check_int(option: str, value: int, minimum: int, what: str = "") -> int:
    if value < minimum:
        raise ValueError(f"{option} = {value}: must be a whole number >= {minimum}{what}")
    return value


def parse_float(option: str, text: str, item: str, what: str = "") -> float:
    try:
        value = float(item)
    except ValueError:
        raise ValueError(f"{option} = {text!r}: {item.strip()!r} is not a number{what}") from None
    if not math.isfinite(value):
        raise ValueError(f"{option} = {text!r}: {item.strip()!r} is not a finite number")
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
            raise ValueError(f"{option} = {text!r}: expected a range START:STOP:COUNT (e.g. "
                             f"20:80:13) or a list a,b,c of {kind}")
        start, stop = (parse_float(option, text, p) for p in parts[:2])
        try:
            count = int(parts[2])
        except ValueError:
            raise ValueError(f"{option} = {text!r}: COUNT = {parts[2].strip()!r} is not a whole "
                             "number") from None
        if count < 1:
            raise ValueError(f"{option} = {text!r}: COUNT = {count} must be >= 1")
        import numpy as np

        values = [_tidy(v) for v in np.linspace(start, stop, count)]
    else:
        items = text.split(",")
        if any(not item.strip() for item in items):
            raise ValueError(f"{option} = {text!r}: an empty item; give a range START:STOP:COUNT "
                             f"or {kind} separated by commas")
        values = [parse(item) if parse else parse_float(option, text, item) for item in items]
    if integer:
        bad = [v for v in values if not float(v).is_integer()]
        if bad:
            raise ValueError(f"{option} = {text!r}: {bad[0]:g} is not a whole number")
        values = [int(v) for v in values]
    seen = set()
    for v in values:
        if v in seen:
            raise ValueError(f"{option} = {text!r}: {v:g} is listed twice")
        seen.add(v)
    return values


def default_of(fn, name: str):
    """The default value of parameter ``name`` of the library function ``fn``."""
    import inspect

    return inspect.signature(fn).parameters[name].default


# -- vehicle, dampers, gains, sensor noise --------------------------------------------------------
def vehicle_from_options(params_file: Optional[Path], preset: Optional[str]):
    """(VehicleParams, the record for the JSON document)."""
    from ..params import VehicleParams

    if params_file is not None and preset is not None:
        raise ValueError("give either --params FILE or --preset NAME, not both")
    if params_file is not None:
        return VehicleParams.load(params_file), {"vehicle_params_file": str(params_file)}
    name = "paper" if preset is None else preset
    return VehicleParams.preset(name), {"vehicle_preset": name}


def damper_preset(option: str, name: str, *, rig: bool = False):
    """The damper ``name`` (railride.dampers.NAMES: the MR presets and "ideal"), else ValueError
    naming the option. ``rig``: the MR presets only (the ideal actuator has no force law to
    drive on the rig)."""
    from .. import dampers

    allowed = dampers.PRESETS if rig else dampers.NAMES
    if name not in allowed:
        why = (": the ideal actuator applies a vehicle controller's demand and has no force law "
               "to drive on the rig" if name in dampers.IDEAL_NAMES else ": unknown damper model")
        raise ValueError(f"{option} = {name!r}{why}; allowed: {', '.join(allowed)}")
    return dampers.preset(name)


def check_damper_scale(option: str, value: Optional[str], damper_name: str) -> float:
    """--damper-scale: a finite number > 0 (default 1), not for the ideal actuator."""
    if value is None:
        return 1.0
    try:  # read as text, so that a word gets the one-line error too
        number = float(value)
    except ValueError:
        raise ValueError(f"{option} = {value!r}: must be a finite number > 0") from None
    scale = check_number(option, number, "")
    if damper_name in IDEAL_NAMES:
        raise ValueError(f"{option} = {scale:g}: the ideal device (--damper {damper_name}) applies "
                         "the demand itself and has no force capacity to scale")
    return scale


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
        raise ValueError(f"{option} = {text!r}: not a number of volts (nor passive-off, "
                         "passive-on)") from None
    return damper.check_voltage(value, option)


def parse_voltages(option: str, text: str, damper) -> list[float]:
    """A comma-separated list of distinct voltages [V], each checked against the damper's range."""
    items = text.split(",")
    if any(not item.strip() for item in items):
        raise ValueError(f"{option} = {text!r}: an empty item; give volts separated by commas, "
                         "e.g. 0,1,2.25")
    values = [parse_voltage(option, item, damper) for item in items]
    seen = set()
    for v in values:
        if v in seen:
            raise ValueError(f"{option} = {text!r}: {v:g} V is listed twice")
        seen.add(v)
    return values


def load_gains(path: Optional[Path]):
    """The shipped gains, or --gains FILE with the library's message (file, table, entry)."""
    from ..control import GainSet

    if path is None:
        return GainSet.default()
    try:
        return GainSet.load(path)
    except ValueError as exc:
        raise ValueError(f"--gains: {exc}") from None


#: --sensor-noise items: (name, unit)
_NOISE_ITEMS = (("Z", "m"), ("ANGLE", "rad"), ("VEL", "m/s"), ("RATE", "rad/s"))


def parse_noise(option: str, text: str) -> list[float]:
    """Z,ANGLE,VEL,RATE: four standard deviations >= 0, else ValueError naming the option."""
    form = ",".join(n for n, _ in _NOISE_ITEMS)
    units = ", ".join(u for _, u in _NOISE_ITEMS)
    items = [item.strip() for item in text.split(",")]
    if len(items) != len(_NOISE_ITEMS):
        raise ValueError(f"{option} = {text!r}: expected four numbers {form} ({units}), "
                         f"got {len(items)} item(s)")
    values = []
    for (name, unit), item in zip(_NOISE_ITEMS, items):
        try:
            value = float(item)
        except ValueError:
            raise ValueError(f"{option} = {text!r}: {name} = {item!r} is not a number "
                             f"({unit})") from None
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"{option} = {text!r}: {name} = {item}: must be a finite "
                             f"number >= 0 ({unit}, a standard deviation)")
        values.append(value)
    return values


# -- scenarios and random tracks (fra1..fra6, german-low, german-high) ----------------------------
#: the options of the random-track scenarios: (option, keyword of track.scenario, unit)
TRACK_OPTIONS = (("--track-seed", "seed", ""), ("--min-wavelength", "min_wavelength", "m"),
                 ("--max-wavelength", "max_wavelength", "m"))
#: a random track's shortest wavelength must pass at speed / min_wavelength <= output rate /
#: RESOLUTION (the rule railride.simulation.simulate applies; checked here first so that the
#: message names the options and a sweep or tuning study fails before its first run)
RESOLUTION = 2.5


def random_tracks() -> tuple:
    from ..track import SPECTRA

    return SPECTRA


def track_options(scenario_name: str, seed: Optional[int], min_wavelength: Optional[float],
                  max_wavelength: Optional[float]) -> dict:
    """--track-seed, --min-wavelength, --max-wavelength -> the keyword arguments of
    track.scenario that were given, checked with the options' names."""
    given = {"seed": seed, "min_wavelength": min_wavelength, "max_wavelength": max_wavelength}
    out = {}
    for option, keyword, unit in TRACK_OPTIONS:
        value = given[keyword]
        if value is None:
            continue
        if keyword == "seed":
            out[keyword] = _check_track_seed(option, value)
        else:
            out[keyword] = check_number(option, value, unit)
    if out and scenario_name not in random_tracks():
        option, keyword, unit = next(o for o in TRACK_OPTIONS if o[1] in out)
        value = f"{out[keyword]:g}" + (f" {unit}" if unit else "")
        raise ValueError(f"{option} = {value}: applies to the random-track scenarios "
                         f"({', '.join(random_tracks())}) only, not to --scenario "
                         f"{scenario_name}")
    return out


def _check_track_seed(option: str, value) -> int:
    if isinstance(value, bool) or int(value) != value or value < 0:
        raise ValueError(f"{option} = {value}: must be a whole number >= 0 (the seed of the "
                         "random track)")
    return int(value)


def make_scenario(name: str, options: dict, output_rate: Optional[float] = None,
                  rate_option: str = "--output-rate"):
    """track.scenario(name, **options); a wavelength-band error names the options given, and a
    random track whose shortest wavelength the output rate cannot resolve is refused here."""
    from ..track import scenario as library_scenario

    if name in random_tracks():
        for option, keyword, unit in (("--amplitude", "amplitude", "m"),
                                      ("--wavelength", "wavelength", "m"),
                                      ("--rail-phase", "rail_phase", "deg")):
            if options.get(keyword) is not None:
                raise ValueError(f"{option} = {options[keyword]:g} {unit}: does not apply to a "
                                 f"random track ({name}); its options are --track-seed, "
                                 "--min-wavelength and --max-wavelength")
    try:
        scen = library_scenario(name, **options)
    except ValueError as exc:
        band = [(o, k, u) for o, k, u in TRACK_OPTIONS if k != "seed" and k in options]
        if band and "wavelength" in str(exc):
            given = ", ".join(f"{o} = {options[k]:g} {u}" for o, k, u in band)
            raise ValueError(f"{given}: {exc}") from None
        if str(exc).startswith("unknown scenario"):
            raise ValueError(f"--scenario: {exc}") from None
        raise
    if output_rate is not None:
        _check_resolvable(scen, options, output_rate, rate_option)
    return scen


def _check_resolvable(scen, options: dict, output_rate: float, rate_option: str) -> None:
    lam = getattr(scen.track, "min_wavelength", None)
    if lam is None or not (math.isfinite(output_rate) and output_rate > 0):
        return  # not a random track; a bad rate is the library's to report
    if scen.speed / lam > output_rate / RESOLUTION:
        default = "" if "min_wavelength" in options else " (the default)"
        raise ValueError(
            f"--min-wavelength = {lam:g} m{default} at --speed {scen.speed:g} m/s is "
            f"{scen.speed / lam:g} Hz, more than {rate_option} {output_rate:g} Hz / "
            f"{RESOLUTION:g} = {output_rate / RESOLUTION:g} Hz can resolve: raise --min-wavelength "
            f"or lower --speed" + (f" or raise {rate_option}" if rate_option.startswith("--") else ""))


def _scenario_options(**given) -> dict:
    """The keyword arguments of track.scenario that were given (None: the scenario's default)."""
    return {k: float(v) for k, v in given.items() if v is not None}


def case_options(options: dict) -> dict:
    """Scenario options for a sweep.Case: the track seed as a NumPy integer.

    Case stores Python ints as floats, and a random track refuses a float seed; a NumPy
    integer passes through Case unchanged (a workaround until Case keeps whole numbers)."""
    import numpy as np

    return {k: (np.int64(v) if k == "seed" else v) for k, v in options.items()}


def study_scenario(name: str, *, amplitude: Optional[float], wavelength: Optional[float],
                   rail_phase: Optional[float], speed: Optional[float], duration: Optional[float],
                   track_seed: Optional[int], min_wavelength: Optional[float],
                   max_wavelength: Optional[float]):
    """(scenario, its options for sweep.Case) of the runs of a study (tune, pareto), checked
    before the first run; every run stores its time histories at the library's default rate."""
    from ..defaults import DEFAULT_OUTPUT_RATE

    options = _scenario_options(amplitude=amplitude, wavelength=wavelength, rail_phase=rail_phase,
                                speed=speed, duration=duration)
    options.update(track_options(name, track_seed, min_wavelength, max_wavelength))
    scen = make_scenario(name, options, DEFAULT_OUTPUT_RATE, "the runs' output rate")
    return scen, case_options(options)
