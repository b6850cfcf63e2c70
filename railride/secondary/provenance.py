"""Where a gains file's gains were tuned, and whether a run is that case (docs/tuning.md, Provenance).

`railride tune` writes a [provenance] table into the gains file it makes (`TuneResult.gains_toml`):
besides the study's settings, the vehicle (``vehicle``: its name; ``vehicle_values``: its
parameters), the load factor (``load``, a list for a robust tuning over several), the tracks
(``scenario_record``, or ``tuning_set`` for a robust tuning; in short ``scenarios`` and
``speeds_m_s``). A file whose provenance names no vehicle (one of railride 0.4.0 and before) was
tuned on the paper's vehicle at load 1; a file with no provenance at all records no tuning, and
nothing is said about it.

`mismatch` turns that into one line when a run leaves the case the gains were tuned for (another
vehicle, load or track), with the `railride tune` command that would tune for the run
(`tune_command`); `provenance_toml` (`railride.secondary.toml_text`) writes the table back as TOML
(`GainSet.to_toml`)."""

from __future__ import annotations

import dataclasses

import datetime
import json
import math
import numbers
import shlex

from railride.secondary.toml_text import provenance_toml  # noqa: F401 (its home before)

#: what gains whose provenance names no vehicle were tuned on: the paper's vehicle, unloaded
DEFAULT_VEHICLE = "paper"
DEFAULT_LOAD = 1.0
#: the scenario `railride tune` tunes on when --scenario is not given
DEFAULT_SCENARIO = "paper-sine"
#: keys of `Scenario.describe` -> (the option of `railride tune` that sets it, its word, its unit)
_TRACK_OPTIONS = {
    "speed_m_s": ("--speed", "speed", "m/s"),
    "seed": ("--track-seed", "seed", ""),
    "amplitude_m": ("--amplitude", "amplitude", "m"),
    "height_m": ("--amplitude", "height", "m"),
    "wavelength_m": ("--wavelength", "wavelength", "m"),
    "length_m": ("--wavelength", "length", "m"),  # the bump's (a random track's is no option)
    "rail_phase_deg": ("--rail-phase", "rail phase", "deg"),
    "min_wavelength_m": ("--min-wavelength", "shortest wavelength", "m"),
    "max_wavelength_m": ("--max-wavelength", "longest wavelength", "m"),
    "duration_s": ("--duration", "duration", "s"),
    "start_m": ("--start", "start", "m"),  # a measured profile's section
}
#: how many values of a list a line shows before it says how many there are
_SHOWN = 5


def tuned_vehicle(provenance: dict) -> tuple[str, dict | None, bool]:
    """(name, values or None, recorded) of the vehicle the gains were tuned on; ``recorded``
    False: the provenance names none and the paper's vehicle is assumed."""
    vehicle = provenance.get("vehicle")
    if isinstance(vehicle, dict):  # the whole record as a table
        return str(vehicle.get("name", DEFAULT_VEHICLE)), vehicle.get("values"), True
    if vehicle is None:
        return DEFAULT_VEHICLE, None, False
    values = provenance.get("vehicle_values")
    return str(vehicle), values if isinstance(values, dict) else None, True


def tuned_loads(provenance: dict) -> list[float]:
    """The load factors the gains were tuned at (1 where the provenance names none)."""
    load = provenance.get("load")
    if load is None and isinstance(provenance.get("vehicle"), dict):
        load = provenance["vehicle"].get("load")
    load = DEFAULT_LOAD if load is None else load
    return [float(x) for x in (load if isinstance(load, list) else [load])]


def tuned_tracks(provenance: dict) -> list[dict]:
    """The scenario records the gains were tuned on: the tuning set's (without their loads and
    weights), or the one ``scenario_record``; empty where the provenance has neither."""
    if isinstance(provenance.get("tuning_set"), list):
        return [{k: v for k, v in r.items() if k not in ("load", "weight")} for r in provenance["tuning_set"]]
    record = provenance.get("scenario_record")
    return [record] if isinstance(record, dict) else []


def mismatch(
    gains, vehicle: dict | None = None, scenarios=None, controllers=None, damper=None, damper_scale=None
) -> str | None:
    """One line when a run with ``gains`` (a `GainSet`) leaves the case they were tuned for, else
    None. ``vehicle``: the run's `railride.model.params.vehicle_record` (its load a list where a
    study runs several; None: the paper's vehicle at load 1); ``scenarios``: the run's track, a
    `Scenario.describe` record or a list of them (a study's). The vehicle differs when its
    values do (by name where the gains' provenance has no values and names no preset); a load
    differs when it is none of the tuned loads; a track when the gains were not tuned on it
    (`GainSet.tuned_on`, whatever the duration); the dampers when ``damper`` (the run's damper: a
    name, a model or its record, with its ``damper_scale``) has other parameters than those the
    gains were tuned with (dyke1996 x 8 is railway; None: not compared). Any track or load of a
    robust tuning matches,
    and so does what it spans: a load between its least and largest, and a random track of a
    spectrum it was tuned on with several seeds, at any seed and a speed within its speeds.
    The line names what differs and the `railride tune` command that tunes for the run
    (`tune_command`). Gains without provenance record no tuning: None; so do ``controllers``
    (names, when given) of which none reads the gains (passive, constant voltages)."""
    provenance = gains.provenance
    if not provenance:
        return None
    if controllers is not None and all(gains.controller(n) is None for n in controllers):
        return None
    vehicle = vehicle or {"name": DEFAULT_VEHICLE, "load": DEFAULT_LOAD}
    records = [scenarios] if isinstance(scenarios, dict) else [r for r in (scenarios or ()) if r is not None]
    loads = vehicle.get("load", DEFAULT_LOAD)
    loads = [float(x) for x in (loads if isinstance(loads, list) else [loads])]
    tuned = tuned_loads(provenance)
    differs = []
    other = _other_values(provenance, vehicle)
    if other is not None:  # the same name with other values: the values that differ
        named = str(vehicle.get("name")) == tuned_vehicle(provenance)[0] and other
        differs.append(f"vehicle {vehicle.get('name')}" + (f" (other values: {_words(other)})" if named else ""))
    other_loads = [x for x in loads if not _load_covered(x, tuned)]
    if other_loads:
        differs.append(f"load{'s' * (len(other_loads) > 1)} {_list(other_loads)}")
    other_damper = _other_damper(provenance, damper, damper_scale)
    if other_damper:
        differs.append(other_damper)
    off = [r for r in records if _on_track(gains, r) is False]
    if off:
        differs.append(f"track{'s' * (len(off) > 1)} {_tracks_text(off, tuned_tracks(provenance))}")
    if not differs:
        return None
    # another vehicle, load or damper wants every track tuned again; else the tracks they were not tuned on
    retune = records if len(differs) > (1 if off else 0) else off
    ran = (damper, damper_scale)  # the run's dampers, whether or not the gains' were others: tuning for the run
    line = (
        f"the gains {gains.source} were tuned for {_tuned_text(provenance)}; this run has {', '.join(differs)}; "
        f"tune for it with: {tune_command(vehicle, retune, *ran)}"
    )
    scaled = ran[1] is not None and float(ran[1]) != 1.0  # design has no --damper-scale
    if retune and all(r.get("profile") == "random" for r in retune) and not scaled:
        # gains tuned on one realisation fit that realisation: a design tunes on some seeds, judges on others
        line += f"; or, for gains judged on seeds they were not tuned on: {design_command(vehicle, retune, ran[0])}"
    return line


def _damper_option(damper) -> list[str]:
    """A command's ``--damper`` for the run's ``damper`` (none for the default or None; a model
    of the user's own parameters as its file, ``FILE.toml``)."""
    from railride.defaults import DEFAULT_DAMPER

    damper = _damper_record(damper)
    if isinstance(damper, dict):  # a record: the preset it equals by name, else the user's own file
        damper = damper.get("preset") or damper.get("name") or "FILE.toml"
    if damper is None or damper == DEFAULT_DAMPER:
        return []
    return ["--damper", shlex.quote(damper) if damper != "FILE.toml" else damper]


def _damper_key(damper, scale):
    """What makes two dampers the same to a controller's gains: the law and every parameter of
    the model at its scale (railway = dyke1996 x 8), or the name of an ideal device or of
    what is not a model; None for no damper."""
    from railride.secondary import dampers

    if damper is None:
        return None
    model = damper
    if isinstance(damper, str):
        model = dampers.PRESETS.get(damper)
        if model is None:  # an ideal device, or a name this railride does not know
            return damper
    elif isinstance(damper, dict):  # a record: the model's fields
        values = {k: v for k, v in damper.items() if k not in ("model", "preset")}
        try:
            model = dampers.MR_MODELS[damper.get("model")](**values)
        except (KeyError, TypeError, ValueError):
            return json.dumps(damper, sort_keys=True, default=str)
    scale = 1.0 if scale is None else float(scale)
    if scale != 1.0 and isinstance(model, dampers.BoucWen):
        model = model.scaled(scale)
    if not isinstance(model, dampers.BoucWen):
        return getattr(model, "model", str(model))
    return (model.model, tuple(float(v) for v in dataclasses.astuple(model)))


def _damper_record(damper):
    """A damper argument as a record: a name stays a name, a model gives its `to_dict`."""
    return damper.to_dict() if not isinstance(damper, (str, dict)) and hasattr(damper, "to_dict") else damper


def _damper_words(damper, scale) -> str:
    """A damper in a line's words: its name (x the scale), or "bouc-wen (own parameters)"."""
    from railride.secondary.dampers import record_name

    name = record_name(_damper_record(damper))
    scale = 1.0 if scale is None else float(scale)
    return f"{name} x {scale:g}" if scale != 1.0 else name


def _other_damper(provenance: dict, damper, scale) -> str | None:
    """The words "damper X (the gains': Y)" when the run's damper is not the one the gains were
    tuned with, naming the parameters that differ where both are the same model; None when it
    is, or when either is not known (old files name none)."""
    tuned = provenance.get("damper")
    if damper is None or tuned is None:
        return None
    tuned_scale = provenance.get("damper_scale", 1.0)
    ran, before = _damper_key(damper, scale), _damper_key(tuned, tuned_scale)
    if ran == before:
        return None
    run_words, tuned_words = _damper_words(damper, scale), _damper_words(tuned, tuned_scale)
    words = f"damper {run_words} (the gains' damper: {tuned_words}"
    # a preset's name (and scale) says what differs; a damper of one's own parameters, which
    # values (of the same model)
    own = any(isinstance(r, dict) and not r.get("preset") for r in map(_damper_record, (damper, tuned)))
    if own and isinstance(ran, tuple) and isinstance(before, tuple) and ran[0] == before[0]:
        from railride.secondary import dampers

        names = [f.name for f in dataclasses.fields(dampers.MR_MODELS[ran[0]])]
        other = [f"{n} {a:.4g} against {b:.4g}" for n, a, b in zip(names, ran[1], before[1]) if a != b]
        shown = other[:_SHOWN] + ([f"{len(other) - _SHOWN} more"] if len(other) > _SHOWN else [])
        words += f"; other values: {', '.join(shown)}"
    return words + ")"


def design_command(vehicle: dict | None, scenarios, damper=None) -> str:
    """The `railride design` command line for a run on ``vehicle`` and the random tracks
    ``scenarios`` (and ``damper``, `tune_command`'s): its vehicle, loads, damper, track classes
    and speeds (the rest its defaults)."""
    named, loads = _vehicle_options(vehicle)
    parts = ["railride", "design", *named, "--load", ",".join(_number(x) for x in loads), *_damper_option(damper)]
    parts += ["--track", ",".join(dict.fromkeys(shlex.quote(str(r.get("name"))) for r in scenarios))]
    speeds = list(dict.fromkeys(r["speed_m_s"] for r in scenarios if r.get("speed_m_s") is not None))
    if speeds:
        parts += ["--speed", ",".join(_number(v) for v in speeds)]
    return " ".join(parts)


#: how a run's track stands to the tracks its gains were tuned on (`judged_on`)
IN_SAMPLE, SAME_TRACK, HELD_OUT = "in-sample", "tuned track, other speed", "held out"
#: the keys of a track record that name its rail, not the run over it
_RUN_KEYS = ("duration_s", "speed_m_s", "load")


def judged_on(gains, record: dict | None) -> tuple[str, str] | None:
    """How a run on the track ``record`` (`Scenario.describe`) judges ``gains`` (a `GainSet`):
    (kind, sentence), kind one of `IN_SAMPLE` (the gains were tuned on this rail at this speed,
    whatever the duration and load: the run repeats part of their tuning), `SAME_TRACK` (this
    rail, only at other speeds) and `HELD_OUT` (a rail tuning never ran on: another seed of a
    random spectrum is another rail). None when the provenance names no tuned track or the run
    has none."""
    tracks = tuned_tracks(gains.provenance)
    if not tracks or not isinstance(record, dict):
        return None

    same = [t for t in tracks if _same_but(t, record, _RUN_KEYS) or _overlaps(t, record)]
    speed = record.get("speed_m_s")
    what = _rail_text(record)
    if record.get("profile") == "measured":  # a stretch of a line: the design's sections
        what = f"the stretch of {record.get('name')} this run covers"
    if any(speed is not None and _same(t.get("speed_m_s"), speed) for t in same):
        if len(tracks) == 1:
            return IN_SAMPLE, (
                "The gains were tuned on this same single track: the reductions are in-sample, not a test on "
                "another track."
            )
        return IN_SAMPLE, (
            f"In-sample: this track ({what}) at this speed is in the gains' tuning set, so these results "
            "repeat part of their tuning; they are not a test on a track tuning never saw."
        )
    if same:
        speeds = _list(dict.fromkeys(t.get("speed_m_s") for t in same))
        return SAME_TRACK, (
            f"Not held out: the gains were tuned on this track ({what}), at {speeds} m/s; only the speed is new."
        )
    line = [t for t in tracks if _same_line(t, record)]
    if record.get("profile") == "measured" and any(_same_but(t, record, (*_RUN_KEYS, "profile_sha256")) for t in line):
        return HELD_OUT, (
            f"Held out: the measured profile {record.get('name')} changed since the gains were tuned on it (other "
            "values at the same path), so tuning never ran on this rail."
        )
    if record.get("profile") == "measured" and line:
        speeds = _list(dict.fromkeys(t.get("speed_m_s") for t in line))
        sections = list(dict.fromkeys(t.get("source") for t in line))
        other = "another stretch" if len(sections) == 1 else "other stretches"
        starts = list(dict.fromkeys(t["start_m"] for t in line if t.get("start_m") is not None))
        at = f" (from s = {_list(starts)} m)" if starts else ""
        return HELD_OUT, (
            f"Held out: tuning never ran on {what}; the gains were tuned on {other} of it{at}, at {speeds} m/s."
        )
    if line:  # its name, other settings
        what = _tracks_text([record], tracks)
    return (
        HELD_OUT,
        f"Held out: tuning never ran on this track, {what}. The gains were tuned on {_tracks_tuned(tracks)}.",
    )


def judged_text(gains, records: list) -> str | None:
    """`judged_on` for a study's many runs (``records``, `Scenario.describe` records), in one
    sentence: which track seeds (or tracks) and speeds are in-sample, which the tuned rail at a
    new speed, which held out. None where the gains name no tuned track."""
    kinds: dict[str, list[dict]] = {}
    for r in records:
        judged = judged_on(gains, r)
        if judged is None:
            return None
        kinds.setdefault(judged[0], []).append(r)
    words = {
        IN_SAMPLE: "in-sample (tuned on this track at this speed)",
        SAME_TRACK: "the tuned track at a new speed",
        HELD_OUT: "held out (tuning never ran on this track)",
    }
    parts = []
    for kind in (IN_SAMPLE, SAME_TRACK, HELD_OUT):
        own = kinds.get(kind, [])
        if not own:
            continue
        seeds = list(dict.fromkeys(r["seed"] for r in own if r.get("seed") is not None))
        names = list(dict.fromkeys(str(r.get("name")) for r in own))
        speeds = list(dict.fromkeys(r["speed_m_s"] for r in own if r.get("speed_m_s") is not None))
        what = f"seed{'s' * (len(seeds) > 1)} {_list(sorted(seeds))}" if seeds else ", ".join(names)
        parts.append(f"{words[kind]}: {what}" + (f" at {_list(sorted(speeds))} m/s" if speeds else ""))
    return f"Against the tracks the gains were tuned on ({_tracks_tuned(tuned_tracks(gains.provenance))}): " + (
        "; ".join(parts) + "."
    )


#: a measured profile's record keys that change with the section it starts at
_SECTION_KEYS = ("source", "rows", "s_end_m", "start_m")


#: what a track record holds since a later version: compared only where both records hold it
_LATER_KEYS = ("profile_sha256",)


def _same_but(tuned: dict, record: dict, keys) -> bool:
    """Whether two track records are equal but for ``keys`` and for what the earlier of them
    did not record yet (`_LATER_KEYS`: gains tuned before a measured profile's values were
    recorded match by its path)."""
    leave = set(keys) | {k for k in _LATER_KEYS if k not in tuned or k not in record}
    if _same_file(tuned, record):  # one file's values under two paths: its name and source are the path
        leave |= {"name", "source", "spectrum"}
    return {k: v for k, v in tuned.items() if k not in leave} == {k: v for k, v in record.items() if k not in leave}


def _same_file(tuned: dict, record: dict) -> bool:
    """Whether two records read the same file's values (a measured profile's ``profile_sha256``,
    a spectrum table's ``spectrum_sha256``), whatever the paths they were read by
    (file:line.csv and file:/data/line.csv)."""
    for key in ("profile_sha256", "spectrum_sha256"):
        sha = tuned.get(key)
        if sha is not None and sha == record.get(key):
            return True
    return False


def _same_line(tuned: dict, record: dict) -> bool:
    """Whether two track records name the same line: the same scenario name, or the same
    measured profile under another path (`_same_file`)."""
    return str(tuned.get("name")) == str(record.get("name")) or _same_file(tuned, record)


def _overlaps(tuned: dict, record: dict) -> bool:
    """Whether a run on a measured profile covers some of the rail a tuning run on the same
    file covered (a design's sections, `railride.studies.design`). A record names its start
    only in words, but its ``s_end_m`` is the file's end less its start, so two records'
    starts differ by the difference of their ends."""
    if record.get("profile") != "measured" or tuned.get("profile") != "measured":
        return False
    if not _same_but(tuned, record, (*_RUN_KEYS, *_SECTION_KEYS)):
        return False
    try:
        offset = float(record["s_end_m"]) - float(tuned["s_end_m"])  # the tuning run's start, from the run's
        run_length = float(record["speed_m_s"]) * float(record["duration_s"])
        tuned_length = float(tuned["speed_m_s"]) * float(tuned["duration_s"])
    except (KeyError, TypeError, ValueError):
        return False
    return offset < run_length and offset + tuned_length > 0.0


def _rail_text(record: dict) -> str:
    seed = record.get("seed")
    return str(record.get("name")) + (f", seed {seed}" if seed is not None else "")


def tuned_words(provenance: dict) -> str | None:
    """The tracks a gains file was tuned on in words (every track of a robust tuning set, its
    seeds or sections and speeds), or None where its provenance names none."""
    tracks = tuned_tracks(provenance)
    if not tracks and not provenance.get("scenarios"):
        return None
    return _tracks_tuned(tracks, provenance.get("scenarios"), provenance.get("speeds_m_s"))


def _tracks_tuned(tracks: list[dict], names=None, speeds=None) -> str:
    """The tracks of ``tracks`` in words: their names (seeds) at their speeds; ``names`` and
    ``speeds`` where the records give none (a provenance written by hand may hold those alone)."""
    names = list(dict.fromkeys(str(t.get("name")) for t in tracks)) or [str(n) for n in names or []]
    seeds = list(dict.fromkeys(t["seed"] for t in tracks if t.get("seed") is not None))
    speeds = list(dict.fromkeys(t["speed_m_s"] for t in tracks if t.get("speed_m_s") is not None)) or speeds or []
    starts = list(dict.fromkeys(t["start_m"] for t in tracks if t.get("start_m") is not None))
    text = ", ".join(names) + (f" (seed{'s' * (len(seeds) > 1)} {_list(seeds)})" if seeds else "")
    text += f" (from s = {_list(starts)} m)" if starts else ""  # a measured profile's sections
    return text + (f" at {_list(speeds)} m/s" if speeds else "")


def _vehicle_options(vehicle: dict | None) -> tuple[list[str], list[float]]:
    """A command's ``--vehicle`` for the run's vehicle (none for the default), and its loads."""
    vehicle = vehicle or {}
    name = str(vehicle.get("name", DEFAULT_VEHICLE))
    named = [] if name == DEFAULT_VEHICLE else ["--vehicle", "FILE.toml" if name == "custom" else shlex.quote(name)]
    loads = vehicle.get("load", DEFAULT_LOAD)
    return named, list(dict.fromkeys(float(x) for x in (loads if isinstance(loads, list) else [loads])))


def tune_command(vehicle: dict | None, scenarios=(), damper=None, damper_scale=None) -> str:
    """The `railride tune` command line that tunes for a run on ``vehicle`` (a `vehicle_record`,
    its load a number or a list), the tracks ``scenarios`` (`Scenario.describe` records) and the
    dampers ``damper`` and ``damper_scale`` (None: the command's default; a damper of the user's
    own parameters is said as ``--damper FILE.toml``, its file): the options that differ from
    the command's defaults. Several track seeds or loads are one
    robust tuning (the command takes lists); other settings that take several values (speeds,
    scenarios) name the first, and the line says which others want a tuning of their own."""
    named, loads = _vehicle_options(vehicle)
    parts = ["railride", "tune", *named]
    if loads != [DEFAULT_LOAD]:
        parts += ["--load", ",".join(_number(x) for x in loads)]
    parts += _damper_option(damper)
    if damper_scale is not None and float(damper_scale) != 1.0:
        parts += ["--damper-scale", _number(damper_scale)]
    records = [scenarios] if isinstance(scenarios, dict) else [r for r in scenarios if r is not None]
    others = []
    if records:
        names = list(dict.fromkeys(str(r.get("name")) for r in records))
        main = names[0]
        if main != DEFAULT_SCENARIO:
            parts += ["--scenario", shlex.quote(main)]
        own = [r for r in records if str(r.get("name")) == main]
        defaults = _default_record(main)
        for key, (option, word, unit) in _TRACK_OPTIONS.items():
            if key == "length_m" and own[0].get("profile") != "cosine-bump":
                continue
            values = list(dict.fromkeys(r[key] for r in own if r.get(key) is not None))
            if not values or values == [defaults.get(key)]:
                continue
            if key == "seed":  # several seeds: one robust tuning
                parts += [option, ",".join(str(v) for v in values)]
                continue
            parts += [option, _number(values[0])]
            if len(values) > 1:
                others.append(f"{word} {_list(values[1:])}{' ' + unit if unit else ''}")
        if len(names) > 1:
            others.append(f"scenario{'s' * (len(names) > 2)} {', '.join(names[1:])}")
    return " ".join(parts) + (f" (and one tuning each for {'; '.join(others)})" if others else "")


def gains_record(gains, controllers) -> dict:
    """What a result records of the gains it ran (docs/study.md, The gains): ``source``, where
    they came from as far as it is still true (`stated_source`); ``provenance``, their
    [provenance] table in JSON's values (`json_values`: how they were found, e.g. by `railride
    tune`), None where they record none; ``values``, per controller of ``controllers``, every
    gain it reads by its "table.entry" name (`gain_values`)."""
    return {
        "source": stated_source(gains),
        "provenance": json_values(gains.provenance) if gains.provenance else None,
        "values": {n: gain_values(gains, n) for n in controllers},
    }


def gain_values(gains, controller: str) -> dict[str, float]:
    """Every gain that ``controller`` reads (its outer loop's tables and its inner loop's,
    `GainSet.tables_read`), by "table.entry"; empty for passive and the constant voltages."""
    return gains.entries(() if controller == "passive" else gains.tables_read(controller))


def stated_source(gains) -> str:
    """The source of ``gains`` as a record may state it: ``gains.source``, with ", changed: ..."
    and the gains that differ where it names a gains file (packaged, e.g. "railride/data/gains.toml",
    or on disk) whose values these no longer are (`GainSet.apply` keeps the source of the
    gains it changes): a reader is never told a file's gains ran when others did."""
    source = str(gains.source)
    original = _file_gains(type(gains), source)
    if original is None:
        return source
    ours, theirs = gains.entries(), original.entries()
    changed = [e for e in ours if ours[e] != theirs.get(e)]
    return f"{source}, changed: {_words(changed)}" if changed else source


def _file_gains(kind, source: str):
    """The gains the file ``source`` holds (a packaged file by its "railride/data/NAME" name,
    else a path on disk), or None where it names no readable gains file."""
    from importlib import resources
    from pathlib import Path

    from railride.errors import InputError

    packaged = source.removeprefix("railride/data/")
    try:
        if packaged != source and packaged.endswith(".toml"):
            text = resources.files("railride").joinpath(f"data/{packaged}").read_text(encoding="utf-8")
        elif source.endswith(".toml") and Path(source).is_file():
            text = Path(source).read_text(encoding="utf-8")
        else:
            return None
        return kind.from_toml(text, source)
    except (OSError, InputError, ValueError):
        return None


def json_values(value):
    """``value`` (a [provenance] table as `tomllib` reads it) in JSON's values: dates and times
    as ISO 8601 text, a number that is not finite as None, tuples as lists, keys as text."""
    if isinstance(value, dict):
        return {str(k): json_values(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_values(v) for v in value]
    if isinstance(value, (datetime.datetime, datetime.date, datetime.time)):
        return value.isoformat()
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(value, numbers.Real):
        return float(value) if math.isfinite(value) else None
    return str(value)


# -- comparisons --------------------------------------------------------------------------------
def _other_values(provenance: dict, run: dict) -> list[str] | None:
    """None where the run's vehicle record is the one the gains were tuned on (the same values,
    of those both records have, a preset's name standing for its values; else the same name),
    else the names of the values that differ (empty where names were compared)."""
    from railride.model.params import PRESETS, VehicleParams

    name, values, _ = tuned_vehicle(provenance)
    if values is None and name in PRESETS:
        values = PRESETS[name].to_dict()
    run_values = run.get("values")
    if values is None or not isinstance(run_values, dict):
        return None if name == str(run.get("name")) else []
    # an optional field (an element the vehicle may not have: the bending, the stops) that a
    # record leaves out holds its default (TOML keeps no None; older records lack the field);
    # other fields are compared where both records have them
    optional = {f.name: f.default for f in dataclasses.fields(VehicleParams) if f.default is not dataclasses.MISSING}
    common = [k for k in run_values if k in values]
    extra = [k for k in dict.fromkeys([*run_values, *values]) if k in optional and k not in common]
    other = [k for k in common + extra if not _same(values.get(k, optional.get(k)), run_values.get(k, optional.get(k)))]
    return other if other or not common else None


def _load_covered(load: float, tuned: list[float]) -> bool:
    """A load is covered by one it was tuned at, or by a robust tuning's range of loads (two or
    more, the load between the least and the largest)."""
    if any(math.isclose(load, t, rel_tol=1e-12) for t in tuned):
        return True
    return len(set(tuned)) > 1 and min(tuned) <= load <= max(tuned)


def _range_covered(tracks: list[dict], record: dict) -> bool:
    """Whether a robust tuning on random track covers ``record``: the tuning set holds two or
    more seeds of the same spectrum over the same wavelength band, and the record's speed lies
    within the tuned speeds' range; its seed and duration do not matter (every realisation of
    a spectrum is the same track in the statistical sense)."""
    if record.get("profile") != "random":
        return False
    keys = ("min_wavelength_m", "max_wavelength_m", "spectrum_sha256")  # a table's values, not its path
    same = [
        t
        for t in tracks
        if t.get("profile") == "random" and _same_line(t, record) and all(_same(t.get(k), record.get(k)) for k in keys)
    ]
    seeds = {t.get("seed") for t in same}
    speeds = [float(t["speed_m_s"]) for t in same if t.get("speed_m_s") is not None]
    speed = record.get("speed_m_s")
    if len(seeds) < 2 or not speeds or speed is None:
        return False
    return min(speeds) * (1 - 1e-12) <= float(speed) <= max(speeds) * (1 + 1e-12)


def _words(names: list[str]) -> str:
    return ", ".join(names[:_SHOWN]) + (f" and {len(names) - _SHOWN} more" if len(names) > _SHOWN else "")


def _on_track(gains, record: dict) -> bool | None:
    """Whether the gains were tuned on the track ``record`` whatever its duration; None where
    their provenance does not say. A hand-written provenance may give ``scenarios`` and
    ``speeds_m_s`` alone."""
    provenance = gains.provenance
    tracks = tuned_tracks(provenance)
    if tracks:
        if _range_covered(tracks, record):
            return True
        durations = {t.get("duration_s") for t in tracks} | {record.get("duration_s")}
        return any(gains.tuned_on({**record, "duration_s": d} if "duration_s" in record else record) for d in durations)
    names, speeds = provenance.get("scenarios"), provenance.get("speeds_m_s")
    if not names and not speeds:
        return None
    speed = record.get("speed_m_s")
    return (not names or record.get("name") in names) and (
        not speeds or (speed is not None and any(_same(speed, s) for s in speeds))
    )


def _same(a, b) -> bool:
    if isinstance(a, numbers.Real) and isinstance(b, numbers.Real) and not isinstance(a, bool):
        return math.isclose(float(a), float(b), rel_tol=1e-12, abs_tol=0.0) or a == b
    return a == b


def _default_record(name: str) -> dict:
    """The record of scenario ``name`` with its defaults (empty where it cannot be made: a
    measured profile's file that is gone)."""
    import warnings

    from railride.model.track import scenario

    try:
        with warnings.catch_warnings():  # only its defaults are read: no run, nothing to warn of
            warnings.simplefilter("ignore")
            return scenario(name).describe()
    except (ValueError, OSError):
        return {}


# -- words --------------------------------------------------------------------------------------
def _tuned_text(provenance: dict) -> str:
    name, _, recorded = tuned_vehicle(provenance)
    loads = tuned_loads(provenance)
    text = f"vehicle {name}, load{'s' * (len(loads) > 1)} {_list(loads)}"
    if not recorded:
        text += " (assumed: the file names no vehicle)"
    tracks = tuned_tracks(provenance)
    if tracks or provenance.get("scenarios"):
        text += f", on {_tracks_tuned(tracks, provenance.get('scenarios'), provenance.get('speeds_m_s'))}"
    return text


def _tracks_text(records: list[dict], tuned: list[dict]) -> str:
    """The tracks of ``records`` in a few words: per scenario, the settings whose values are
    none of the tuned tracks' of that scenario (its speed where it is another scenario)."""
    out = []
    for name in dict.fromkeys(str(r.get("name")) for r in records):
        own = [r for r in records if str(r.get("name")) == name]
        same = [t for t in tuned if any(_same_line(t, r) for r in own)]
        found = []
        for k, (_, word, unit) in _TRACK_OPTIONS.items():
            if k == "duration_s" or (k not in same[0] if same else k != "speed_m_s"):
                continue
            values = list(dict.fromkeys(r[k] for r in own if k in r and not any(_same(r[k], t.get(k)) for t in same)))
            if values:
                found.append(f"{word} {_list(values)}{' ' + unit if unit else ''}")
        for key, what in (("spectrum_sha256", "spectrum table"), ("profile_sha256", "measured profile")):
            if _file_changed(own, same, key):
                found.append(f"the {what} changed since tuning")
        out.append(name + (f" ({'; '.join(found)})" if found else ""))
    return ", ".join(out)


def _file_changed(records: list[dict], tuned: list[dict], key: str) -> bool:
    """Whether a file the runs read (a spectrum table, psd:PATH, or a measured profile,
    file:PATH) is not the one the gains were tuned on: the same path, other values (the
    records' ``spectrum_sha256`` or ``profile_sha256``)."""
    runs = {r.get(key) for r in records} - {None}
    before = {t.get(key) for t in tuned} - {None}
    return bool(runs and before and not runs <= before)


def _list(values) -> str:
    """Numbers as a short list: all of up to five, else the first three, "...", the last and
    how many."""
    shown = [_number(v) for v in values]
    if len(shown) > _SHOWN:
        return f"{', '.join(shown[:3])}, ..., {shown[-1]} ({len(shown)} values)"
    return ", ".join(shown)


def _number(value) -> str:
    """A number as short as it reads back exactly (55.56, 1.3, 60), anything else as text."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return str(value)
    if isinstance(value, numbers.Integral):
        return str(int(value))
    short = f"{float(value):g}"
    return short if float(short) == float(value) else repr(float(value))
