"""``railride sweep``: a grid of cases (every combination of the given values) run by
railride.sweep.run_cases, with its table and document.

The grid builder (the section "the grid") turns the options into the cases and the grid values
each row reports, checking every option and every scenario of the grid before the first run."""

from __future__ import annotations

import dataclasses
import itertools
import json
from enum import Enum
from typing import Annotated, Optional

import typer

from .. import __version__
from ..dampers import IDEAL_NAMES
from ..defaults import DEFAULT_DAMPER
from ._app import app
from ._common import (RunProgress, errors, interruptible, make_executor, open_run_table, stderr_is_terminal,
                      wide_stdout_console, write_folder)
from ._options import (DtOption, MaxWavelengthOption, MinWavelengthOption, RunDurationOption, RunsScenarioOption,
                       SchedulerFileOption, SchedulerOption, SweepComfortOption, SweepDamperOption,
                       SweepDamperScaleOption, SweepGainsOption, SweepOutOption, SweepResumeOption, WindowOption,
                       WorkersOption)
from ._parsing import (case_options, check_number, damper_preset, load_gains, make_scenario, parse_noise,
                       parse_voltage, random_tracks, track_options, value_list)
from ._render import RESPONSE_LABELS, damper_text, fmt

SCHEMA_SWEEP = "railride.sweep/1"

#: the controllers a gain table acts in (a --gain of `sweep` combines with these only)
GAIN_CONTROLLERS = {"inner": ("pid", "sas-attitude", "sas-attitude-ride"), "pid": ("pid",),
                    "attitude": ("sas-attitude", "sas-attitude-ride"),
                    "ride": ("sas-attitude-ride",)}
#: the scenario options a sweep can vary: (option, keyword of track.scenario, column, unit)
SWEEP_AXES = (("--speed", "speed", "speed_m_s", "m/s"), ("--wavelength", "wavelength", "wavelength_m", "m"),
              ("--amplitude", "amplitude", "amplitude_m", "m"),
              ("--rail-phase", "rail_phase", "rail_phase_deg", "deg"),
              ("--track-seed", "seed", "track_seed", ""))

#: the keys of Scenario.describe() that each swept scenario option sets
_SCENARIO_KEYS = {"speed": ("speed_m_s",), "wavelength": ("wavelength_m", "length_m"),
                  "amplitude": ("amplitude_m", "height_m"), "rail_phase": ("rail_phase_deg",),
                  "seed": ("seed",)}

#: (column, heading) of the comfort indices the sweep table shows with --comfort
SWEEP_COMFORT_TABLE = (("centre_aw_Wk", "a_w Wk\ncentre\n(m/s^2)"),
                       ("centre_N_MV_z", "N_MV,z\ncentre"), ("front_N_MV_z", "N_MV,z\nfront"),
                       ("rear_N_MV_z", "N_MV,z\nrear"))


class SweepFormat(str, Enum):
    table = "table"
    json = "json"
    csv = "csv"


@app.command("sweep")
def sweep_command(
    suspension: Annotated[str, typer.Option(
        "--suspension", "--controllers", metavar="NAME[,NAME...]",
        help="Suspensions, comma-separated: passive, mr (constant --voltage), pid, sas-attitude, "
             "sas-attitude-ride. --controllers is the same option.")] = "passive",
    speed: Annotated[Optional[str], typer.Option(
        "--speed", metavar="VALUES",
        help="Vehicle speeds [m/s]: START:STOP:COUNT (linear, inclusive) or a,b,c "
             "(default: the scenario's, 55.56).")] = None,
    wavelength: Annotated[Optional[str], typer.Option(
        "--wavelength", metavar="VALUES",
        help="paper-sine: wavelengths [m]; bump: bump lengths [m]. A range or a list.")] = None,
    amplitude: Annotated[Optional[str], typer.Option(
        "--amplitude", metavar="VALUES",
        help="paper-sine: sine amplitudes [m]; bump: heights [m]. A range or a list.")] = None,
    rail_phase: Annotated[Optional[str], typer.Option(
        "--rail-phase", metavar="VALUES",
        help="paper-sine: phase lags of the right rail [deg]. A range or a list.")] = None,
    voltage: Annotated[Optional[str], typer.Option(
        "--voltage", metavar="VALUES",
        help="mr only: constant command voltages [V] within the damper's range, a range or a list "
             "(passive-off, passive-on allowed in a list; default: passive-off).")] = None,
    gain: Annotated[Optional[list[str]], typer.Option(
        "--gain", metavar="TABLE.ENTRY=VALUES",
        help="Controllers only: values of one gain, e.g. pid.kd=1e4,1e5 or attitude.kp_z=0:4e5:5; "
             "repeatable (each adds a grid axis). Tables inner, pid, attitude, ride.")] = None,
    noise: Annotated[Optional[str], typer.Option(
        "--noise", metavar="Z,ANGLE,VEL,RATE",
        help="Controllers only: sensor noise, standard deviations [m, rad, m/s, rad/s].")] = None,
    seed: Annotated[Optional[str], typer.Option(
        "--seed", metavar="VALUES",
        help="With --noise: seeds of the sensor noise, whole numbers >= 0, a range or a list "
             "(default 0). Not the track: see --track-seed.")] = None,
    track_seed: Annotated[Optional[str], typer.Option(
        "--track-seed", metavar="VALUES",
        help="Random tracks only: seeds of the track's realisation, whole numbers >= 0, a "
             "range or a list (default 0); a grid axis for every suspension.")] = None,
    min_wavelength: MinWavelengthOption = None,
    max_wavelength: MaxWavelengthOption = None,
    scenario: RunsScenarioOption = "paper-sine",
    duration: RunDurationOption = None,
    dt: DtOption = None,
    damper: SweepDamperOption = None,
    damper_scale: SweepDamperScaleOption = None,
    gains: SweepGainsOption = None,
    window: WindowOption = None,
    workers: WorkersOption = None,
    scheduler: SchedulerOption = None,
    scheduler_file: SchedulerFileOption = None,
    out: SweepOutOption = None,
    resume: SweepResumeOption = False,
    format: Annotated[SweepFormat, typer.Option(
        "--format", case_sensitive=False,
        help="Output on stdout: a table, JSON (a list of row objects) or CSV.")] = SweepFormat.table,
    comfort: SweepComfortOption = True,
) -> None:
    """Run a grid of cases: every combination of the given values (a cartesian product).

    The scenario axes (--speed, --wavelength, --amplitude, --rail-phase, --track-seed) apply
    to every suspension; --voltage combines with mr only, --gain, --noise and --seed (the
    sensor noise's) with the controllers they act in; the other suspensions run once per
    scenario combination. Prints one row per run: the grid values and the RMS of the four
    carbody responses.
    """
    import time

    with errors():
        from .. import report
        from .. import sweep as sweep_lib

        grid = _build_grid(suspension=suspension, scenario=scenario, speed=speed,
                           wavelength=wavelength, amplitude=amplitude, rail_phase=rail_phase,
                           track_seed=track_seed, min_wavelength=min_wavelength,
                           max_wavelength=max_wavelength, duration=duration, voltage=voltage,
                           gain=gain, noise=noise, seed=seed, damper=damper,
                           damper_scale=damper_scale, gains=gains, dt=dt, window=window)
        table, table_path = open_run_table(out, resume)
        executor, executor_record = make_executor(workers, scheduler, scheduler_file)
    try:
        with interruptible(table, table_path), errors():
            with RunProgress(stderr_is_terminal(), "sweeping") as progress:
                t0 = time.perf_counter()
                frame = sweep_lib.run_cases(grid.cases, executor=executor, table=table,
                                            base_gains=grid.base_gains, dt=grid.dt, window=grid.window,
                                            progress=progress, comfort=comfort)
                wall = time.perf_counter() - t0
            metrics = _metric_columns() + (list(sweep_lib.COMFORT_COLUMNS) if comfort else [])
            rows, diverged = _rows(grid, frame, metrics)
            doc = {
                **_sweep_document(grid, rows, metrics, diverged=diverged, comfort=comfort),
                "runs": len(table.frame),
                "runs_evaluated": progress.evaluated,
                "runs_per_second": progress.evaluated / wall if wall > 0 else 0.0,
                "wall_time_s": wall,
                "executor": executor_record,
            }
            text = json.dumps(rows, indent=2, allow_nan=False)  # refuses NaN before writing
            if out is not None:
                write_folder(out, lambda: report.write_sweep_outputs(out, doc))
    finally:
        executor.close()
    if format is SweepFormat.json:
        typer.echo(text)
        return
    if format is SweepFormat.csv:
        import pandas as pd

        typer.echo(pd.DataFrame(rows, columns=doc["columns"]).to_csv(index=False), nl=False)
        return
    wide_stdout_console().print(_sweep_table(rows, grid.columns, _caption(grid, doc, rows, wall)))


# -- the grid -----------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class _Grid:
    """The cases of a sweep, the grid values each row reports (``rows``, one per case, keys
    ``columns``) and the settings the document records."""

    scenario: str
    suspensions: list
    #: the suspensions among them that run an outer-loop controller
    controllers: list
    has_mr: bool
    damper_name: str
    #: whether --damper-scale was given (a grid axis then)
    scaled: bool
    scales: list
    #: (option, keyword of track.scenario, column, values) of each swept scenario option
    axes: list
    volts: list
    #: (gain name, values) of each --gain
    gain_axes: list
    noise_values: Optional[tuple]
    seeds: list
    base_gains: object
    dt: float
    window: Optional[tuple]
    #: the scenario of the first grid point, described, and the last one built (for its duration)
    first_record: dict
    scen: object
    columns: list
    cases: list
    rows: list


def _build_grid(*, suspension, scenario, speed, wavelength, amplitude, rail_phase, track_seed,
                min_wavelength, max_wavelength, duration, voltage, gain, noise, seed, damper,
                damper_scale, gains, dt, window) -> _Grid:
    """The options -> a _Grid, every option and every scenario of the grid checked."""
    from ..defaults import DEFAULT_DT
    from ..metrics import check_window, parse_window

    suspensions = _suspension_list(suspension)
    controllers = [s for s in suspensions if s in GAIN_CONTROLLERS["inner"]]
    has_mr = "mr" in suspensions
    listed = ", ".join(suspensions)
    _check_applies(listed, has_mr, controllers, voltage=voltage, gain=gain, noise=noise,
                   gains=gains, seed=seed, damper=damper, damper_scale=damper_scale)
    damper_name, damper_model, scales = _dampers(damper, damper_scale, has_mr, listed)
    track = track_options(scenario, None, min_wavelength, max_wavelength)
    axes = _scenario_axes(scenario, speed=speed, wavelength=wavelength, amplitude=amplitude,
                          rail_phase=rail_phase, track_seed=track_seed)
    volts = _voltages(voltage, damper_model) if has_mr else []
    gain_axes = _gain_axes(gain, controllers, listed)
    noise_values = None if noise is None else tuple(parse_noise("--noise", noise))
    seeds = [0] if seed is None else value_list("--seed", seed, integer=True)
    bad = [s for s in seeds if s < 0]
    if bad:
        raise ValueError(f"--seed = {seed!r}: {bad[0]} is negative; seeds are whole numbers >= 0")
    base_gains = load_gains(gains)
    dt = DEFAULT_DT if dt is None else check_number("--dt", dt, "s")
    common = {} if duration is None else {"duration": float(duration)}
    common.update(track)
    combos, first_record, scen = _scenarios(scenario, axes, common)
    window_value = None
    if window is not None:
        window_value = check_window(parse_window(window), scen.duration)

    columns = ["suspension"] + [column for _, _, column, _ in axes]
    if damper_scale is not None:
        columns.append("damper_scale")
    if has_mr:
        columns.append("voltage_v")
    columns += [name for name, _ in gain_axes]
    if noise_values is not None:
        columns.append("seed")
    grid = _Grid(scenario=scenario, suspensions=suspensions, controllers=controllers,
                 has_mr=has_mr, damper_name=damper_name, scaled=damper_scale is not None,
                 scales=scales, axes=axes, volts=volts, gain_axes=gain_axes,
                 noise_values=noise_values, seeds=seeds, base_gains=base_gains, dt=dt,
                 window=window_value, first_record=first_record, scen=scen, columns=columns,
                 cases=[], rows=[])
    cases, rows = _cases(grid, combos, common)
    return dataclasses.replace(grid, cases=cases, rows=rows)


def _suspension_list(text: str) -> list[str]:
    """--suspension: comma-separated, known, each once."""
    from ..sweep import SUSPENSIONS

    items = [s.strip() for s in text.split(",")]
    if any(not s for s in items):
        raise ValueError(f"--suspension = {text!r}: an empty item; give names separated "
                         f"by commas from {', '.join(SUSPENSIONS)}")
    unknown = [s for s in items if s not in SUSPENSIONS]
    if unknown:
        raise ValueError(f"--suspension = {text!r}: unknown suspension {unknown[0]!r}; "
                         f"allowed: {', '.join(SUSPENSIONS)}")
    if len(set(items)) != len(items):
        twice = next(s for s in items if items.count(s) > 1)
        raise ValueError(f"--suspension = {text!r}: {twice} is listed twice")
    return items


def _check_applies(listed: str, has_mr: bool, controllers: list, *, voltage, gain, noise, gains,
                   seed, damper, damper_scale) -> None:
    """What applies where: --voltage to mr, --gain, --noise and --gains to the controllers,
    --seed with --noise, --damper and --damper-scale to mr and the controllers."""
    if voltage is not None and not has_mr:
        raise ValueError(f"--voltage = {voltage!r}: applies to --suspension mr only "
                         f"(--suspension is {listed})")
    for option, given in (("--gain", gain), ("--noise", noise), ("--gains", gains)):
        if given and not controllers:
            value = given[0] if isinstance(given, list) else str(given)
            raise ValueError(f"{option} = {value!r}: applies to the controllers pid, "
                             f"sas-attitude, sas-attitude-ride only (--suspension is {listed})")
    if seed is not None and noise is None:
        raise ValueError(f"--seed = {seed!r}: applies with --noise only (without it the "
                         "measurements are ideal)")
    if damper is not None and not (has_mr or controllers):
        raise ValueError(f"--damper = {damper!r}: applies to mr and the controllers only "
                         f"(--suspension is {listed})")
    if damper_scale is not None and not (has_mr or controllers):
        raise ValueError(f"--damper-scale = {damper_scale!r}: applies to mr and the "
                         f"controllers only (--suspension is {listed})")


def _dampers(damper: Optional[str], damper_scale: Optional[str], has_mr: bool, listed: str):
    """(damper name, its model, the force scales of the grid)."""
    damper_name = DEFAULT_DAMPER if damper is None else damper
    damper_model = damper_preset("--damper", damper_name)
    if damper_name in IDEAL_NAMES and has_mr:
        raise ValueError(f"--damper = {damper_name!r}: applies to the controllers only; mr runs at a "
                         f"constant voltage, which the ideal actuator has not (--suspension "
                         f"is {listed})")
    scales = [1.0]
    if damper_scale is not None:
        if damper_name in IDEAL_NAMES:
            raise ValueError(f"--damper-scale = {damper_scale!r}: the ideal device "
                             f"(--damper {damper_name}) applies the demand itself and has no force "
                             "capacity to scale")
        scales = [check_number("--damper-scale", v, "")
                  for v in value_list("--damper-scale", damper_scale)]
    return damper_name, damper_model, scales


def _scenario_axes(scenario: str, **texts) -> list:
    """The swept scenario options (SWEEP_AXES, keyword -> its text or None): a list of
    (option, keyword, column, values)."""
    axes = []
    for option, keyword, column, _ in SWEEP_AXES:
        text = texts["track_seed" if keyword == "seed" else keyword]
        if text is None:
            continue
        if keyword == "seed":
            values = value_list(option, text, integer=True)
            bad = [v for v in values if v < 0]
            if bad:
                raise ValueError(f"--track-seed = {text!r}: {bad[0]} is negative; track "
                                 "seeds are whole numbers >= 0")
            if scenario not in random_tracks():
                raise ValueError(f"--track-seed = {text!r}: applies to the random-track "
                                 f"scenarios ({', '.join(random_tracks())}) only, not to "
                                 f"--scenario {scenario}")
        else:
            values = value_list(option, text)
        axes.append((option, keyword, column, values))
    return axes


def _voltages(voltage: Optional[str], damper_model) -> list[float]:
    """The voltages of mr: --voltage, else v_min (passive-off)."""
    if voltage is None:
        return [float(damper_model.v_min)]
    volts = value_list("--voltage", voltage,
                       parse=lambda item: parse_voltage("--voltage", item, damper_model))
    return [damper_model.check_voltage(v, "--voltage") for v in volts]


def _gain_axes(gain: Optional[list[str]], controllers: list, listed: str) -> list:
    """The --gain options: a list of (gain name, values), each name once and acting in a
    controller of --suspension."""
    gain_axes = []
    for text in gain or []:
        name, values = _gain_option(text)
        if any(name == n for n, _ in gain_axes):
            raise ValueError(f"--gain = {text!r}: {name} is given twice")
        acts_in = GAIN_CONTROLLERS[name.partition(".")[0]]
        if not any(c in acts_in for c in controllers):
            raise ValueError(f"--gain = {text!r}: {name} acts in {', '.join(acts_in)} only, "
                             f"which --suspension ({listed}) does not list")
        gain_axes.append((name, values))
    return gain_axes


def _gain_option(text: str) -> tuple[str, list[float]]:
    """--gain TABLE.ENTRY=VALUES -> ("table.entry", values)."""
    from ..tuning import PARAMETERS

    name, sep, values_text = text.partition("=")
    name = name.strip()
    if name.startswith("sas."):  # the gains file's [sas.attitude] and [sas.ride]
        name = name[len("sas."):]
    known = [p for ps in PARAMETERS.values() for p in ps]
    if not sep or not values_text.strip():
        raise ValueError(f"--gain = {text!r}: expected TABLE.ENTRY=VALUES, e.g. pid.kd=1e4,1e5 "
                         "or attitude.kp_z=0:4e5:5")
    if name not in known:
        table = name.partition(".")[0]
        if table in PARAMETERS:
            allowed = ", ".join(PARAMETERS[table])
        else:
            allowed = "inner.*, pid.*, attitude.*, ride.* (" + ", ".join(known[:5]) + ", ...)"
        raise ValueError(f"--gain = {text!r}: unknown gain {name!r}; allowed: {allowed}")
    values = value_list(f"--gain {name}", values_text)
    bad = [v for v in values if v < 0]
    if bad:
        raise ValueError(f"--gain = {text!r}: {bad[0]:g} is negative; gains are >= 0")
    return name, values


def _scenarios(scenario: str, axes: list, common: dict):
    """(the combinations of the axes' values, the first scenario described, the last scenario):
    every scenario of the grid must be valid before anything runs."""
    from ..defaults import DEFAULT_OUTPUT_RATE

    combos = list(itertools.product(*[values for *_, values in axes]))
    first_record = None
    for combo in combos:
        options = {**common, **{kw: v for (_, kw, _, _), v in zip(axes, combo)}}
        try:
            # every run stores its time histories at the library's default rate
            scen = make_scenario(scenario, options, DEFAULT_OUTPUT_RATE, "the runs' output rate")
        except ValueError as exc:
            if str(exc).startswith("--"):  # names its options and values already
                raise
            given = ", ".join(f"{opt} {v:g}" for (opt, *_), v in zip(axes, combo))
            raise ValueError(f"{given}: {exc}" if given else str(exc)) from None
        first_record = first_record or scen.describe()
    return combos, first_record, scen


def _cases(grid: _Grid, combos: list, common: dict) -> tuple[list, list]:
    """(the cases, the grid values of each): for each suspension and scenario combination, passive
    once, mr per scale and voltage, a controller per scale, gain combination and noise seed."""
    from .. import sweep as sweep_lib

    cases, rows = [], []
    for s in grid.suspensions:
        for combo in combos:
            options = case_options({**common, **{kw: v for (_, kw, _, _), v in zip(grid.axes, combo)}})
            base = {c: None for c in grid.columns}
            base.update({"suspension": s, **{column: v for (_, _, column, _), v in zip(grid.axes, combo)}})
            if s == "passive":
                cases.append(sweep_lib.Case(grid.scenario, options))
                rows.append(base)
            elif s == "mr":
                for x in grid.scales:
                    for v in grid.volts:
                        cases.append(sweep_lib.Case(grid.scenario, options, suspension="mr",
                                                    damper=grid.damper_name, voltage=v,
                                                    damper_scale=x))
                        rows.append({**base, "voltage_v": v,
                                     **({"damper_scale": x} if grid.scaled else {})})
            else:
                mine = [(n, vs) for n, vs in grid.gain_axes if s in GAIN_CONTROLLERS[n.partition(".")[0]]]
                for x in grid.scales:
                    for values in itertools.product(*[vs for _, vs in mine]):
                        changes = tuple(zip([n for n, _ in mine], values))
                        for sd in (grid.seeds if grid.noise_values is not None else [0]):
                            cases.append(sweep_lib.Case(
                                grid.scenario, options, suspension=s, damper=grid.damper_name,
                                gains=changes, noise=grid.noise_values or (), seed=sd,
                                damper_scale=x))
                            row = {**base, **dict(changes)}
                            if grid.scaled:
                                row["damper_scale"] = x
                            if grid.noise_values is not None:
                                row["seed"] = sd
                            rows.append(row)
    return cases, rows


# -- the results ----------------------------------------------------------------------------------
def _metric_columns() -> list[str]:
    from ..metrics import RESPONSES, STATISTICS

    return [f"{r}_{s}" for s in STATISTICS for r in RESPONSES]


def _rows(grid: _Grid, frame, metrics: list[str]):
    """(one row per case: its grid values, metrics and key; whether any run diverged)."""
    rows = []
    diverged = frame["diverged_at_s"].notna() if "diverged_at_s" in frame else [False] * len(grid.cases)
    for case, values, (_, result), bad in zip(grid.cases, grid.rows, frame.iterrows(), diverged):
        row = {**values, **{m: None if bad else float(result[m]) for m in metrics}}
        if any(diverged):  # a run that diverged has no metrics, but the time it went
            row["diverged_at_s"] = float(result["diverged_at_s"]) if bad else None
        rows.append({**row, "key": case.key})
    return rows, any(diverged)


def _utc_now() -> str:
    from datetime import datetime, timezone

    return datetime.now(timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def _sweep_document(grid: _Grid, rows: list[dict], metrics: list[str], *, diverged: bool,
                    comfort: bool) -> dict:
    """The JSON document of `sweep` (sweep.json) up to its run counts and timing."""
    # the scenario's fixed settings (the swept ones are grid axes)
    swept = {key for _, kw, _, _ in grid.axes for key in _SCENARIO_KEYS[kw]}
    scenario_record = {k: v for k, v in grid.first_record.items() if k not in swept}
    return {
        "schema": SCHEMA_SWEEP,
        "railride_version": __version__,
        "date": _utc_now(),
        "settings": {
            "scenario": scenario_record,
            "grid": {"suspension": grid.suspensions,
                     **{column: values for _, _, column, values in grid.axes},
                     **({"damper_scale": grid.scales} if grid.scaled else {}),
                     **({"voltage_v": grid.volts} if grid.has_mr else {}),
                     **{name: values for name, values in grid.gain_axes},
                     **({"seed": grid.seeds} if grid.noise_values is not None else {})},
            "damper": grid.damper_name if (grid.has_mr or grid.controllers) else None,
            "gains_source": grid.base_gains.source if grid.controllers else None,
            "sensor_noise": None if grid.noise_values is None else dict(
                zip(("displacement", "angle", "velocity", "angular_rate"), grid.noise_values)),
            "dt_s": float(grid.dt),
            "window_s": None if grid.window is None else list(grid.window),
            # only with --comfort: the document stays as it was without it
            **({"comfort": _sweep_comfort_settings(grid.scen.duration, grid.window)}
               if comfort else {}),
        },
        "columns": grid.columns + metrics + (["diverged_at_s"] if diverged else []) + ["key"],
        "rows": rows,
    }


def _sweep_comfort_settings(duration: float, window) -> dict:
    """settings.comfort of a sweep with --comfort: the columns, where the positions are and
    what N_MV_z is (the same for every run of the grid, whose runs share one duration)."""
    from ..comfort import INDEX_UNITS, INTERVAL_S
    from ..sweep import COMFORT_COLUMNS, COMFORT_INDICES

    start, end = window or (0.0, duration)
    n = max(1, int((end - start + 1e-9) // INTERVAL_S))
    unit = {i: INDEX_UNITS["aw" if i.startswith("aw_") else "vdv" if i.startswith("vdv_") else i]
            for _, i in COMFORT_INDICES}
    return {"columns": list(COMFORT_COLUMNS),
            "units": {c: unit[i] for (_, i), c in zip(COMFORT_INDICES, COMFORT_COLUMNS)},
            "positions": {"centre": "x = 0", "front": "x = +l (above the front bogie centre)",
                          "rear": "x = -l (above the rear bogie centre)"},
            "n_intervals": n,
            "notes": ["N_MV_z is the vertical term of EN 12299 only: the model has no lateral "
                      "or longitudinal motion",
                      f"N_MV_z from {n} interval{'s' if n != 1 else ''} of 5 s"
                      + (" (EN 12299 evaluates 60, 5 minutes): an indication only"
                         if n < 60 else "")]}


def _caption(grid: _Grid, doc: dict, rows: list[dict], wall: float) -> str:
    """The sweep table's caption: the scenario, the dampers and gains, the runs."""
    from ..report import describe_scenario

    st = doc["settings"]
    start, end = grid.window or (0.0, grid.scen.duration)
    lines = [f"scenario at the first grid point: {describe_scenario(grid.first_record)}, "
             f"{grid.scen.duration:g} s, dt {grid.dt:g} s, RMS over {start:g}-{end:g} s"]
    if st["damper"]:
        lines.append(damper_text(st) + (f"; gains {st['gains_source']}" if grid.controllers else ""))
    lines.append(f"{len(rows)} run{'s' if len(rows) != 1 else ''}: {doc['runs_evaluated']} evaluated now, "
                 f"{len(rows) - doc['runs_evaluated']} from the run table; wall time {wall:.1f} s")
    n_bad = sum(r.get("diverged_at_s") is not None for r in rows)
    if n_bad:
        lines.append(f"{n_bad} run{'s' if n_bad > 1 else ''} diverged (a response left +-1000 or "
                     "stopped being finite): no metrics, shown as -; see diverged_at_s in the JSON")
    return "\n".join(lines)


def _sweep_table(rows: list[dict], grid_columns: list[str], caption: str):
    from rich.markup import escape
    from rich.table import Table

    table = Table(title="Sweep: RMS of the carbody responses, one row per run",
                  caption=escape(caption))
    table.add_column("#", justify="right")
    for c in grid_columns:
        heading = {"speed_m_s": "speed\n(m/s)", "wavelength_m": "wavelength\n(m)",
                   "amplitude_m": "amplitude\n(m)", "rail_phase_deg": "rail phase\n(deg)",
                   "voltage_v": "voltage\n(V)", "track_seed": "track\nseed",
                   "damper_scale": "damper\nscale",
                   "seed": "noise\nseed"}.get(c, c)
        table.add_column(escape(heading), justify="left" if c == "suspension" else "right",
                         no_wrap=c == "suspension")
    for key, label in RESPONSE_LABELS.items():
        table.add_column(label.replace(" (", "\n("), justify="right")
    comfort = [(c, h) for c, h in SWEEP_COMFORT_TABLE if rows and c in rows[0]]
    for _, heading in comfort:
        table.add_column(escape(heading), justify="right")
    for i, row in enumerate(rows, start=1):
        cells = [str(i)]
        for c in grid_columns:
            v = row[c]
            cells.append("-" if v is None else (escape(v) if isinstance(v, str) else f"{v:g}"))
        cells += [fmt(row[f"{k}_rms"], "#.4g") for k in RESPONSE_LABELS]
        cells += [fmt(row[c], "#.3g") for c, _ in comfort]
        table.add_row(*cells)
    return table
