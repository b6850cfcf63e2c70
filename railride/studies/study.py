"""Statistics over many tracks: every controller on many random-track realisations, speeds,
payloads and damper faults, summarised as mean and 5th / 95th percentiles (docs/study.md).

One run gives one number per metric; on random track that number changes from one kilometre
to the next. `study` runs each controller on every combination of track seed and speed
(the population a statistic is taken over) for each condition, a load factor and a set of
damper faults, beside the healthy passive suspension on the same track, speed and load. Per
controller and condition it gives, for every RMS response and comfort index, the mean and the
5th and 95th percentiles of the value and of its reduction against passive (computed case by
case, on the same track). A user can then say "SAS (attitude+ride) improves N_MV by x %
(5-95 %: a to b) on FRA class 4 at 30-60 m/s".

The runs go through `railride.studies.sweep.run_cases`: compiled batches, a local or Dask executor,
and a run table on disk that a study resumes from; metrics are kept, time histories are not.
A run that diverges keeps its row with the time it diverged; the statistics leave it out and
the result lists it (`StudyResult.failed`). `study` returns a `StudyResult` with the result
protocol (`to_dict`, `to_pandas`, `plot`, `save`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import pandas as pd

from railride.errors import InputError
from railride import validation
from railride.studies.progress import shows_progress
from railride.studies.comparison import check_controllers
from railride.secondary.control import PAPER_CONTROLLERS, GainSet
from railride.secondary.provenance import judged_text
from railride.defaults import DEFAULT_DAMPER
from railride.secondary.faults import DamperFault, check_faults, parse_faults
from railride.analysis.comfort_record import intervals_in, n_mv_basis
from railride.analysis.metrics import RESPONSES
from railride.model.params import resolve_argument, vehicle_record
from railride.plots import PNG_DPI, FigureOptions
from railride.run.checks import check
from railride.run.solver import SolverSettings
from railride.secondary.sensing import SENSING, reads_bogies
from railride.studies.sweep import COMFORT_COLUMNS, Case, RunTable, run_cases, scenario_of
from railride.model.vehicle import Vehicle
from railride.secondary.suspension import Suspension, damper_record

#: the schema of `StudyResult.to_dict` (study.json)
SCHEMA = "railride.study/1"
#: the metrics a study summarises: the four RMS responses and the comfort indices
METRICS = (*(f"{r}_rms" for r in RESPONSES), *COMFORT_COLUMNS)
#: the metrics a study's trade-offs weigh: the four RMS responses and the comfort at the centre
TRADE_METRICS = (*(f"{r}_rms" for r in RESPONSES), "centre_N_MV_z")
#: a mean reduction within this many percent of passive is level, neither better nor worse (as
#: `railride.studies.comparison.LEVEL_TOLERANCE`, 1 %, in a comparison)
LEVEL_PERCENT = 1.0
#: the percentiles of the band
PERCENTILES = (5.0, 95.0)
#: a fault condition with no fault
HEALTHY = "none"


def fault_condition(text: str) -> tuple:
    """One fault condition: "none", or faults joined by "+" (e.g. "1R-off" or "1R-off+2L-on@2"),
    as their labels in corner order (`railride.secondary.faults.parse_faults`)."""
    text = str(text).strip()
    return () if text == HEALTHY else tuple(f.label for f in parse_faults(text.split("+")))


@dataclass(frozen=True, eq=False)
class StudyResult:
    """The result of `study`. ``cases``: one row per run (the run table's metrics, with the
    study's ``controller``, ``load``, ``stiffness``, ``fault``, ``delay``, ``track_seed`` and
    ``speed_m_s`` and, for the controlled runs, each metric's reduction in % against passive on
    the same track, speed, load and stiffness, ``<metric>_reduction``; then the gains each run's
    controller ran with, one column per gain a controller of the study reads, ``gain_pid_kp``
    for "pid.kp" (`gain_column`), NaN where it reads none). ``summary``: one row per
    controller, speed, condition (load, stiffness, fault, delay) and metric, over the track
    seeds: ``n`` (runs that did not diverge), ``mean``, ``p5``, ``p95`` of the value and
    ``reduction_mean``, ``reduction_p5``, ``reduction_p95``. Speeds and loads are design
    variables: they are never pooled into one band. ``failed``: the runs that diverged
    (controller, condition, seed, speed, time). ``settings``: what was run, the gains among it
    (``gains``, ``gains_provenance``, ``gains_values``: `GainSet.record`)."""

    cases: pd.DataFrame
    summary: pd.DataFrame
    settings: dict = field(default_factory=dict)
    failed: list = field(default_factory=list)
    #: when it was made (UTC, ISO 8601)
    date: str = ""

    def report_contents(self):
        """What this result shows in its HTML report (`railride.output.report.write_report`)."""
        from railride.output.report import study_contents

        return study_contents(self)

    def to_dict(self) -> dict:
        """The ``railride.study/1`` document: settings, per controller and condition every
        metric's statistics, and the failed runs."""
        from railride._version import __version__, versions

        groups = []
        for (name, speed, load, k, fault, delay), part in self.summary.groupby(
            ["controller", "speed_m_s", "load", "stiffness", "fault", "delay"], sort=False
        ):
            metrics = {}
            for _, row in part.iterrows():
                metrics[row["metric"]] = {
                    k: _finite(row[k])
                    for k in ("n", "mean", "p5", "p95", "reduction_mean", "reduction_p5", "reduction_p95")
                }
            groups.append(
                {
                    "controller": name,
                    "speed_m_s": float(speed),
                    "load": float(load),
                    "stiffness": float(k),
                    "fault": fault,
                    "delay": int(delay),
                    "metrics": metrics,
                }
            )
        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            "date": self.date,
            "settings": self.settings,
            "percentiles": list(PERCENTILES),
            "results": groups,
            "failed": self.failed,
            "trade_offs": [
                {k: (v.item() if isinstance(v, np.generic) else v) for k, v in entry.items()}
                for entry in self.trade_offs()
            ],
            "runs": int(len(self.cases)),
        }

    def to_pandas(self) -> pd.DataFrame:
        """The summary: one row per controller, condition and metric."""
        return self.summary.copy()

    def trade_offs(self) -> list[dict]:
        """Per controller and condition (speed, load, stiffness, fault, delay), the metrics of
        `TRADE_METRICS` its mean reduction against passive makes better (``better_on``: above
        `LEVEL_PERCENT`), worse (``worse_on``: below -`LEVEL_PERCENT`) and neither
        (``level_on``), each with its mean reduction in % (``reductions``). A controller that wins
        some by losing others has both lists filled: the study's trade-offs."""
        out = []
        keys = ["controller", "speed_m_s", "load", "stiffness", "fault", "delay"]
        part = self.summary[(self.summary["controller"] != "passive") & self.summary["metric"].isin(TRADE_METRICS)]
        for values, rows in part.groupby(keys, sort=False):
            red = {m: float(r) for m, r in zip(rows["metric"], rows["reduction_mean"]) if np.isfinite(r)}
            ordered = [m for m in TRADE_METRICS if m in red]
            out.append(
                {
                    **dict(zip(keys, values)),
                    "better_on": [m for m in ordered if red[m] > LEVEL_PERCENT],
                    "worse_on": [m for m in ordered if red[m] < -LEVEL_PERCENT],
                    "level_on": [m for m in ordered if abs(red[m]) <= LEVEL_PERCENT],
                    "reductions": {m: red[m] for m in ordered},
                }
            )
        return out

    def plot(self, ax=None, metrics=None):
        """Per metric (default the four RMS responses and N_MV at the carbody centre), the mean
        reduction against passive of each controller with its 5-95 % band, one group per
        condition (`railride.plots.study.plot_study`). Returns the figure."""
        from railride.plots.study import plot_study

        return plot_study(self, ax=ax, metrics=metrics)

    def save(self, folder, *, figure_formats=("png",), dpi: float = PNG_DPI, extra: dict | None = None) -> list:
        """study.json (`to_dict`, with the entries of ``extra`` after it: what the command line
        adds, its runs, wall time and command), study_summary.csv (`to_pandas`), study_runs.csv
        (`cases`) and study.png (`plot`; in each of ``figure_formats``, png, pdf, svg, PNG at
        ``dpi``) into ``folder``, all or nothing (other files, such as the run table runs.csv,
        stay). Returns the paths."""
        from railride.output.files import write_study_outputs

        return write_study_outputs(self, folder, figures=FigureOptions(figure_formats, dpi), extra=extra)


def _finite(value):
    value = float(value)
    return value if np.isfinite(value) else None


@shows_progress("study")
def study(
    controllers=PAPER_CONTROLLERS,
    *,
    scenario: str = "fra4",
    track_seeds=None,
    speeds=None,
    loads=(1.0,),
    stiffness=(1.0,),
    faults=(HEALTHY,),
    delays=(1,),
    sensing: str = "ideal",
    duration: float | None = None,
    start: float | None = None,
    gains: GainSet | None = None,
    damper: str = DEFAULT_DAMPER,
    vehicle=None,
    params=None,
    solver=None,
    window=None,
    executor=None,
    table: RunTable | None = None,
    progress=True,
) -> StudyResult:
    """Run ``controllers`` (names of `railride.secondary.control.CONTROLLERS`; passive is always the
    baseline) on ``scenario`` for every track seed (a random track's realisation; default 0 to
    9, none for the other scenarios) and speed (m/s; None: the scenario's); ``start`` [m]: a
    measured profile's section from there on (`railride.model.track.scenario`), for
    each load factor (`VehicleParams.loaded`), secondary stiffness factor (k_sz times it: a
    tolerance; `VehicleParams.load_changes`), fault condition ("none", or faults such as
    "1R-off" joined by "+"; faults apply to the controlled suspensions, passive stays healthy)
    and controller delay (in controller periods, `Suspension.delay`; 1: a demand takes effect
    one period after its sample), with every controller measuring through ``sensing``
    ("ideal": the exact states; "accelerometers": `railride.secondary.sensing.Accelerometers` with the
    default settings, their noise seeded per track seed),
    with ``gains`` (default the shipped gains: the controllers keep them whatever the load) and
    the ``damper`` model, on ``vehicle`` (``params`` is an alias: a preset name, the path of a
    parameters file or `VehicleParams`, default "paper"; the loads scale its carbody;
    ``settings["vehicle"]`` records it, `railride.model.params.vehicle_record`, and the runs'
    table names it in its ``vehicle`` column). Every setting is checked before the first run. ``executor``, ``table``
    and ``progress`` as for `railride.studies.sweep.run_cases` (True, the default: shown on
    stderr after 2 s, `railride.studies.progress`; False: silent).
    ``settings["gains_mismatch"]``:
    one line (`GainSet.mismatch`) when the gains were tuned for another vehicle, load or track
    than some of the runs'. ``settings["gains"]``, ``["gains_provenance"]`` and
    ``["gains_values"]``: the gains the runs ran, their source, how they were found and every
    value per controller (`GainSet.record`; docs/study.md, The gains). Returns a `StudyResult`."""
    from railride.analysis.metrics import check_window
    from railride.secondary.suspension import damper_model
    from railride.studies.sweep import other_settings
    from railride.model.track import RANDOM_NAMES, SCENARIOS, is_random

    from railride import arguments

    names = check_controllers(controllers)
    if not isinstance(scenario, str):
        raise InputError(f"scenario = {scenario!r}: allowed a scenario's name (e.g. fra4, paper-sine) or file:PATH")
    for name, value in (("track_seeds", track_seeds), ("speeds", speeds), ("loads", loads), ("stiffness", stiffness)):
        if value is not None:
            arguments.numbers(name, value)
    arguments.numbers("delays", delays, "whole numbers of controller periods")
    window = arguments.window("window", window)
    solver = SolverSettings.of(solver)
    base, source = resolve_argument(vehicle, params)
    vehicle = base
    gains = GainSet.of(gains, scenario)
    random = is_random(scenario)
    if not random and scenario not in ("paper-sine", "bump") and not scenario.startswith("file:"):
        # named before the seeds' check, which would otherwise speak of a track that is no track
        raise InputError(f"scenario = {scenario!r}: unknown; allowed: {', '.join(SCENARIOS)}")
    if track_seeds is not None and not random:
        raise InputError(
            f"track_seeds = {list(_items(track_seeds))}: track seeds apply to the random tracks "
            f"({', '.join(RANDOM_NAMES)}) only, not to {scenario!r}"
        )
    if track_seeds is None:
        track_seeds = range(10) if random else [None]
    seeds = [None if s is None else validation.seed("track_seeds", s) for s in _items(track_seeds)]
    speed_list = (
        [None] if speeds is None else [validation.number("speeds", v, "positive", "m/s") for v in _items(speeds)]
    )
    load_list = [
        validation.number("loads", v, "positive", allowed="a finite number > 0 (load factor)") for v in _items(loads)
    ]
    stiffness_list = [
        validation.number("stiffness", v, "positive", allowed="a finite number > 0 (the factor on k_sz)")
        for v in _items(stiffness)
    ]
    conditions = []
    for f in arguments.names("faults", faults, "fault conditions ('none', or faults joined by '+')"):
        try:
            conditions.append(fault_condition(f))
        except ValueError as exc:
            raise InputError(f"faults = {str(f)!r}: {exc}") from None
    from railride.engine.layout import MAX_DELAY

    what = "controller periods from a sample to its demand taking effect"
    delay_list = [validation.integer("delays", d, 1, MAX_DELAY, what) for d in _items(delays)]
    for name, values in (
        ("track_seeds", seeds),
        ("speeds", speed_list),
        ("loads", load_list),
        ("stiffness", stiffness_list),
        ("faults", conditions),
        ("delays", delay_list),
    ):
        if not values:
            raise InputError(f"{name}: give at least one value")
        twice = arguments.repeated(values)
        if twice is not None:  # a repeated condition would count its runs twice in the statistics
            v = twice[0]  # a fault condition as its text: "none" or its faults joined by "+"
            shown = ("+".join(v) or HEALTHY) if isinstance(v, tuple) else f"{v!r}"
            raise InputError(f"{name} = {shown}: listed twice; give each once")
    validation.choice("sensing", sensing, SENSING)
    if sensing != "ideal":
        car = Vehicle(vehicle)
        blind = [n for n in names if (c := gains.controller(n)) is not None and reads_bogies(c.gains(car)[0])]
        if blind:
            raise InputError(
                f"sensing = {sensing!r}: {', '.join(blind)} {'reads' if len(blind) == 1 else 'read'} the "
                "bogies' states, and the accelerometers "
                "are on the carbody only; leave them out"
            )
    model = damper_model(damper, 1.0)
    for cond in conditions:
        if cond:
            try:
                check_faults(cond, model)
            except InputError as exc:  # named as the argument it came from, as every other check is
                raise InputError(f"faults = {'+'.join(str(f) for f in cond)!r}: {exc}") from None

    def options_of(seed, v) -> tuple:
        opts: dict[str, Any] = {
            **({"seed": seed} if seed is not None else {}),
            **({"speed": v} if v is not None else {}),
            **({"duration": duration} if duration is not None else {}),
            **({"start": start} if start is not None else {}),
        }
        return tuple(sorted(opts.items()))

    # every setting is checked before the first run: the scenario at each speed (the seeds
    # differ in the realisation only), and every fault time against its duration
    speed_of, described = {}, {}
    controlled = [n for n in names if n != "passive"] or ["mr"]
    for v in speed_list:
        sc = scenario_of(scenario, options_of(seeds[0], v))
        # each condition's runs, checked by the check every simulation makes (railride.run.checks)
        for cond in conditions:
            faults = [DamperFault.parse(f) for f in cond]
            for n in controlled:
                try:
                    check(sc, vehicle, Suspension.named(n, gains, damper).with_faults(faults), solver, "mark")
                except InputError as exc:
                    if faults and str(exc).startswith("fault "):  # a fault's time: named by the condition
                        raise InputError(f"faults = {'+'.join(cond)!r}: {exc}") from None
                    raise
        speed_of[v] = sc.speed
        described[v] = sc.describe()
    # the window inside the runs, checked before the first; recorded with its open end (inf,
    # which JSON cannot hold) resolved, while the runs' keys keep it as given (resumable)
    window_record = None if window is None else [float(w) for w in check_window(tuple(window), sc.duration)]
    opts_of = {(seed, v): (options_of(seed, v), speed_of[v]) for seed in seeds for v in speed_list}
    cases, meta = [], []
    controlled = [n for n in names if n != "passive"]
    for load, k in [(load, k) for load in load_list for k in stiffness_list]:
        changes = vehicle.load_changes(load, k)
        for (seed, v), (options, speed) in opts_of.items():
            cases.append(Case(scenario, options, vehicle=changes))
            meta.append(("passive", load, k, HEALTHY, 1, seed, speed))
            for cond in conditions:
                label = "+".join(cond) if cond else HEALTHY
                for delay in delay_list:
                    for n in controlled:
                        case = Case(scenario, options, vehicle=changes, suspension=n, damper=damper, faults=cond)
                        if case.closed_loop:  # the accelerometers' noise differs from track to track
                            noise_seed = seed if seed is not None and sensing != "ideal" else 0
                            case = replace(case, delay=delay, sensing=sensing, seed=noise_seed)
                        cases.append(case)
                        meta.append((n, load, k, label, delay, seed, speed))
    record = vehicle_record(base, source, load_list)
    rows = run_cases(
        cases,
        executor=executor,
        table=table,
        base_gains=gains,
        params=vehicle,
        solver=solver,
        window=window,
        progress=progress,
        comfort=True,
        vehicle_columns=[{"vehicle": record["name"], "load": float(m[1])} for m in meta],
    )
    frame = rows.reset_index(drop=True).copy()
    info = pd.DataFrame(meta, columns=["controller", "load", "stiffness", "fault", "delay", "track_seed", "speed_m_s"])
    info.insert(1, "vehicle", record["name"])
    frame = pd.concat([info, frame.drop(columns=[c for c in info.columns if c in frame.columns])], axis=1)
    frame = _reductions(frame)
    gains_record = gains.record(names)
    frame = _with_gains(frame, gains_record["values"])
    speeds_run = list(dict.fromkeys(float(v) for v in frame["speed_m_s"]))
    summary = _summary(frame, names, speeds_run, load_list, stiffness_list, conditions, delay_list)
    failed = [
        {
            "controller": r.controller,
            "load": float(r.load),
            "stiffness": float(r.stiffness),
            "fault": r.fault,
            "delay_periods": int(r.delay),
            "track_seed": None if r.track_seed is None or r.track_seed != r.track_seed else int(r.track_seed),
            "speed_m_s": float(r.speed_m_s),
            "diverged_at_s": float(r.diverged_at_s),
        }
        for r in frame.itertuples()
        if np.isfinite(r.diverged_at_s)
    ]
    settings = {
        "scenario": scenario,
        "controllers": names,
        "track_seeds": seeds if random else None,
        "speeds_m_s": sorted({s for _, s in opts_of.values()}),
        "loads": load_list,
        "stiffness": stiffness_list,
        "faults": ["+".join(c) if c else HEALTHY for c in conditions],
        "delays_periods": delay_list,
        "sensing": sensing,
        "duration_s": duration,
        **({"start_m": float(start)} if start is not None else {}),
        "damper": damper_record(damper),
        # the gains the runs ran: where they came from, how they were found, every value
        "gains": gains_record["source"],
        "gains_provenance": gains_record["provenance"],
        "gains_values": gains_record["values"],
        "window_s": window_record,
        "vehicle": record,
        **other_settings(vehicle, solver),
        **solver.backend_record(),
    }
    # gains tuned for another vehicle, load or track: one line for every run (`GainSet.mismatch`)
    # described from the checked first seed's (the seeds differ in the realisation only): a
    # realisation made again here, after the runs, was serial work (20 of them, 0.19 s)
    tracks = [{**described[v], "seed": seed} if random else described[v] for seed, v in opts_of]
    if mismatch := gains.mismatch(record, tracks, names, damper):
        settings["gains_mismatch"] = mismatch
    # which runs' tracks the gains were tuned on: in-sample, a new speed, or held out
    if any(gains.controller(n) is not None for n in names) and (judged := judged_text(gains, tracks)):
        settings["tracks_judged"] = judged
    settings["comfort_basis"] = n_mv_basis(intervals_in(window_record, float(sc.duration)))
    from railride._version import utc_now

    return StudyResult(frame, summary, settings, failed, utc_now())


def _items(values) -> list:
    if isinstance(values, (str, bool)) or validation.is_number(values):  # one value (a bool is refused later)
        return [values]
    return list(values)


def gain_column(entry: str) -> str:
    """The column of the runs' table that holds the gain "table.entry": "pid.kp" -> "gain_pid_kp"."""
    return "gain_" + entry.replace(".", "_")


def _with_gains(frame: pd.DataFrame, values: dict) -> pd.DataFrame:
    """``frame`` with one column per gain that a controller of the study reads (`gain_column`):
    on each run the value its controller ran with, empty (NaN) where it reads none (passive)."""
    entries = list(dict.fromkeys(e for own in values.values() for e in own))
    table = pd.DataFrame(
        [[values[n].get(e, np.nan) for e in entries] for n in frame["controller"]],
        columns=[gain_column(e) for e in entries],
        index=frame.index,
        dtype=float,
    )
    return pd.concat([frame, table], axis=1)


def _reductions(frame: pd.DataFrame) -> pd.DataFrame:
    """Each controlled run's reduction in % against passive on the same track, speed and load."""
    key = ["load", "stiffness", "track_seed", "speed_m_s"]
    # no seed (not a random track): one key; the seeds as they are, since floats would merge
    # those past 2**53
    keys = frame[key].astype(object).where(frame[key].notna(), -1)
    passive = frame[list(METRICS)][frame["controller"] == "passive"].set_index(
        pd.MultiIndex.from_frame(keys[frame["controller"] == "passive"])
    )
    base = passive.reindex(pd.MultiIndex.from_frame(keys)).to_numpy()
    values = frame[list(METRICS)].to_numpy()
    with np.errstate(divide="ignore", invalid="ignore"):
        red = np.where(base != 0, (base - values) / base * 100.0, np.nan)
    red[frame["controller"].to_numpy() == "passive"] = np.nan
    out = frame.copy()
    for j, m in enumerate(METRICS):
        out[f"{m}_reduction"] = red[:, j]
    return out


def _summary(frame: pd.DataFrame, names, speeds, loads, stiffness, conditions, delays) -> pd.DataFrame:
    """One row per controller, speed, load, stiffness, fault, delay and metric: the statistics over
    the track seeds (the speeds and loads kept apart, never pooled)."""
    rows = []
    labels = ["+".join(c) if c else HEALTHY for c in conditions]
    # the rows of each setting, in the frame's order, found once (a mask per setting scanned the
    # whole frame each time: most of a study's last, serial, step)
    by = ["controller", "speed_m_s", "load", "stiffness", "fault", "delay"]
    groups = frame.groupby(by, sort=False).indices if len(frame) else {}
    finite = np.isfinite(frame["diverged_at_s"].to_numpy(dtype=float))
    values = {m: frame[m].to_numpy(dtype=float) for m in METRICS}
    values.update({f"{m}_reduction": frame[f"{m}_reduction"].to_numpy(dtype=float) for m in METRICS})
    for name in names:
        for speed, load, k in [(v, load, k) for v in speeds for load in loads for k in stiffness]:
            for label, delay in [(HEALTHY, 1)] if name == "passive" else [(f, d) for f in labels for d in delays]:
                at = groups.get((name, speed, load, k, label, delay), np.zeros(0, dtype=int))
                at = at[~finite[at]]  # the runs that did not diverge
                for m in METRICS:
                    x, r = values[m][at], values[f"{m}_reduction"][at]
                    x, r = x[np.isfinite(x)], r[np.isfinite(r)]
                    # both percentiles in one call: the same numbers, half the calls
                    px = np.percentile(x, PERCENTILES) if x.size else (np.nan, np.nan)
                    pr = np.percentile(r, PERCENTILES) if r.size else (np.nan, np.nan)
                    rows.append(
                        {
                            "controller": name,
                            "speed_m_s": speed,
                            "load": load,
                            "stiffness": k,
                            "fault": label,
                            "delay": delay,
                            "metric": m,
                            "n": int(x.size),
                            "mean": float(x.mean()) if x.size else np.nan,
                            "p5": float(px[0]),
                            "p95": float(px[1]),
                            "reduction_mean": float(r.mean()) if r.size else np.nan,
                            "reduction_p5": float(pr[0]),
                            "reduction_p95": float(pr[1]),
                        }
                    )
    return pd.DataFrame(rows)
