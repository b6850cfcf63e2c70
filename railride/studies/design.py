"""Which controller for this vehicle: a robust design study, judged on track it never saw
(docs/design.md).

`design` tunes every law alike on a training set of random tracks (track classes x training
seeds x speeds x load factors; `railride.studies.tuning.tune` with ``over``, the inner loop
first where a law tracks a force), then judges every law and passive on held-out seeds of the
same track classes, at every speed and load, and returns a `DesignResult`
(`railride.studies.design_result`): per law, speed and load the mean and the 5th / 95th
percentiles over the held-out runs of every RMS response and comfort index (absolute and as a
ratio to passive on the same track, run by run) and of what the law asks of its dampers, the
ranking, and a recommendation in words built from those numbers.

Every input is checked before the first run: the training and the held-out seeds must not
share a seed, and the budget must let every law try each of its gains once. A law that
diverges, in tuning or on held-out track, is listed with where it diverged; the others go on.
The runs go through `railride.studies.sweep.run_cases` (a local or Dask executor, one run table
for both stages, so a design resumes where it stopped).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from railride import arguments, validation
from railride._version import versions
from railride.analysis.comfort_record import intervals_in, n_mv_basis
from railride.analysis.costs import COST_COLUMNS
from railride.defaults import DEFAULT_DAMPER
from railride.errors import InputError
from railride.studies.design_result import (
    METRICS,
    PERCENTILES,
    DesignResult,
    rank,
    recommend,
)
from railride.studies.design_result import diverged_laws as _diverged
from railride.studies import evolution
from railride.studies.objectives import DEFAULT_OBJECTIVE, OBJECTIVE_KINDS, TRAVEL_COLUMN, Objective
from railride.studies.sweep import Case, RunTable, run_cases
from railride.studies.tuning import PARAMETERS, STAGES, TUNED_CONTROLLERS, TuningCase, tune
from railride.studies.progress import shows_progress

#: the defaults of `design` (docs/design.md): FRA classes 4 and 5, 30-70 m/s, load factors 1
#: and 1.3, three training seeds and five held-out seeds, 20 s of track a run
DEFAULT_TRACKS = ("fra4", "fra5")
DEFAULT_SPEEDS = (30.0, 50.0, 70.0)
DEFAULT_LOADS = (1.0, 1.3)
DEFAULT_TRAIN_SEEDS = (1, 2, 3)
DEFAULT_TEST_SEEDS = (100, 101, 102, 103, 104)
DEFAULT_DURATION = 20.0
#: values per gain and sweep: coarser than `railride tune`'s 13, so that the budget below sweeps
#: every gain of SAS (attitude+ride) once
DEFAULT_VALUES = 7
#: gain sets per law (each scored on every run of the training set): just over the 128 that SAS
#: (attitude+ride), 14 gains in two stages, needs to sweep each gain once with 7 values (`min_budget`)
DEFAULT_BUDGET = 130
#: how a gain set's objectives over the training runs become one (`tune`'s ``aggregate``)
DEFAULT_AGGREGATE = "mean"
#: other spellings of the comfort objectives' names
COMFORT_ALIASES = {"nmv": "n_mv", "n_mv_z": "n_mv", "n-mv": "n_mv", "wz": "sperling"}


@dataclass(frozen=True)
class Plan:
    """The checked inputs of a design."""

    laws: tuple
    vehicle: Any  # VehicleParams
    source: Any  # what named it: a preset's name, a file's path or None
    loads: tuple
    tracks: tuple
    speeds: tuple
    train_seeds: tuple
    test_seeds: tuple
    duration: float
    objective: Objective
    aggregate: str
    budget: int
    values: int
    damper: Any
    solver: Any
    #: a measured profile's sections: track -> (the first section's start, a section's length) [m]
    sections: dict = field(default_factory=dict)
    #: how each law's gains are tuned (`railride.studies.evolution.OPTIMISERS`) and the seed of
    #: the evolution
    optimiser: str = "sensitivity"
    optimiser_seed: int = 0
    #: time in service: (speed, load) -> the point's share (they sum to 1); None: no weights, a
    #: law scored by its worst point (`service_shares`)
    service: dict | None = None

    def track_options(self, track: str, seed: int) -> tuple:
        """The scenario options that make "seed" ``seed`` of ``track``: a random track's
        realisation, or a measured profile's section ``seed`` (its start, `sections`)."""
        if track in self.sections:
            first, length = self.sections[track]
            return (("start", first + seed * length),)
        return (("seed", seed),)


def min_budget(law: str, values: int) -> int:
    """The fewest gain sets with which `tune` sweeps every gain of ``law`` at least once: the
    start, then per gain one sweep of ``values`` values and 0; a law tuned in stages
    (`railride.studies.tuning.STAGES`) gives each stage its share of what is left, and a stage
    may spend all of its share before the next begins."""
    stages = STAGES.get(law, (PARAMETERS[law],))
    sweep = values + 1
    budget = 1 + sum(len(s) for s in stages) * sweep
    while True:
        runs, ok = 1, True
        for k, stage in enumerate(stages):
            share = (budget - runs) // (len(stages) - k)
            if share < len(stage) * sweep:
                ok = False
                break
            runs += share
        if ok:
            return budget
        budget += 1


def _items(name: str, values) -> list:
    if values is None:
        raise InputError(f"{name} = None: give at least one value")
    if isinstance(values, (str, bool)) or validation.is_number(values):
        values = [values]
    try:
        out = list(values)
    except TypeError:
        raise InputError(f"{name} = {values!r}: give a list of values") from None
    if not out:
        raise InputError(f"{name} = []: empty; give at least one value")
    twice = arguments.repeated(out)  # most likely a slip: said, not dropped unsaid
    if twice is not None:
        raise InputError(f"{name} = {out!r}: {twice[0]!r} is listed twice; give each once")
    return out


def service_shares(speeds: tuple, loads: tuple, speed_shares=None, load_shares=None) -> dict | None:
    """The share of time in service of each (speed, load) of a design: the product of the
    speed's share of ``speed_shares`` and the load's of ``load_shares`` (each one number > 0
    per value of ``speeds`` and ``loads``, in their order, normalised to sum 1; None: equal),
    speed and load taken as independent. None where neither is given."""
    if speed_shares is None and load_shares is None:
        return None

    def shares(name: str, given, values: tuple, unit: str) -> list[float]:
        if given is None:
            return [1.0 / len(values)] * len(values)
        items = [given] if validation.is_number(given) else given
        try:
            if isinstance(items, (str, bytes, dict)):
                raise TypeError
            items = list(items)
        except TypeError:
            raise InputError(f"{name} = {given!r}: give a list of numbers, one per {unit}") from None
        rule = "a finite number > 0 (a share of the time in service)"
        numbers = [float(validation.number(name, x, "positive", allowed=rule)) for x in items]
        if len(numbers) != len(values):
            raise InputError(
                f"{name} = {','.join(f'{x:g}' for x in numbers)}: {len(numbers)} share{'s' * (len(numbers) != 1)} "
                f"for {len(values)} "
                f"{unit}{'s' * (len(values) != 1)} ({', '.join(f'{v:g}' for v in values)}); give one per {unit}, in "
                "their order"
            )
        top = max(numbers)  # scaled first: 1e308 + 1e308 would overflow to inf
        total = sum(x / top for x in numbers)
        return [x / top / total for x in numbers]

    by_speed = shares("speed_shares", speed_shares, speeds, "speed")
    by_load = shares("load_shares", load_shares, loads, "load")
    return {(float(v), float(x)): a * b for v, a in zip(speeds, by_speed) for x, b in zip(loads, by_load)}


def _laws(controllers) -> tuple:
    allowed = f"allowed: {', '.join(TUNED_CONTROLLERS)} (passive is always judged, as the baseline)"
    if controllers is None or controllers == "all":
        return TUNED_CONTROLLERS
    names = [str(c).strip() if isinstance(c, str) else c for c in _items("controllers", controllers)]
    for n in names:  # every name checked, "all" beside others too
        if n not in TUNED_CONTROLLERS and n not in ("passive", "all"):
            raise InputError(f"controllers = {n!r}: not a law with gains to tune; {allowed}, or all")
    laws = tuple(n for n in TUNED_CONTROLLERS if n in names or "all" in names)
    if not laws:
        raise InputError(f"controllers = {names!r}: no law to design; {allowed}")
    return laws


def _objective(objective) -> Objective:
    if objective is None:
        return DEFAULT_OBJECTIVE
    if isinstance(objective, Objective):
        return objective
    allowed = f"unknown objective; allowed: {', '.join(OBJECTIVE_KINDS)} (n_mv also as nmv, sperling as wz)"
    if isinstance(objective, str):
        name = objective.strip().lower()
        name = COMFORT_ALIASES.get(name, name)
        if name in ("minimax", "sum", "n_mv", "sperling"):
            return Objective(name)
        if name in OBJECTIVE_KINDS:
            raise InputError(
                f"objective = {objective!r}: needs its settings; pass an Objective({name!r}, ...) (its weights or "
                "bound), or one of minimax, sum, n_mv, sperling by name"
            )
    raise InputError(f"objective = {objective!r}: {allowed}")


def check_design(
    controllers=None,
    *,
    vehicle=None,
    loads=DEFAULT_LOADS,
    tracks=DEFAULT_TRACKS,
    speeds=DEFAULT_SPEEDS,
    objective=None,
    aggregate: str = DEFAULT_AGGREGATE,
    budget: int = DEFAULT_BUDGET,
    values: int = DEFAULT_VALUES,
    train_seeds=DEFAULT_TRAIN_SEEDS,
    test_seeds=DEFAULT_TEST_SEEDS,
    duration: float = DEFAULT_DURATION,
    damper=DEFAULT_DAMPER,
    solver=None,
    optimiser: str = "sensitivity",
    optimiser_seed: int = 0,
    speed_shares=None,
    load_shares=None,
) -> Plan:
    """Every input of `design`, checked before any work: an `InputError` names the option, the
    value and what is allowed. Returns the `Plan`."""
    from railride.model.params import resolve_argument
    from railride.model.track import RANDOM_NAMES, is_random
    from railride.model.track import scenario as make_scenario
    from railride.run.checks import check
    from railride.run.solver import SolverSettings
    from railride.secondary.control import GainSet
    from railride.secondary.suspension import Suspension, damper_model
    from railride.studies.tuning import AGGREGATES

    optimiser = validation.choice("optimiser", optimiser, evolution.OPTIMISERS)
    optimiser_seed = validation.seed("optimiser_seed", optimiser_seed)
    laws = _laws(controllers)
    base, source = resolve_argument(vehicle, None)
    rule = "a finite number > 0 (load factor)"
    load_list = tuple(
        dict.fromkeys(validation.number("loads", x, "positive", allowed=rule) for x in _items("loads", loads))
    )
    track_list = []
    for t in _items("tracks", tracks):
        if not isinstance(t, str) or not (is_random(t.strip()) or t.strip().startswith("file:")):
            raise InputError(
                f"tracks = {t!r}: not a random track or a measured profile; allowed {', '.join(RANDOM_NAMES)}, "
                "file:PATH"
            )
        track_list.append(t.strip())
    given_speeds = tuple(
        dict.fromkeys(validation.number("speeds", v, "positive", "m/s") for v in _items("speeds", speeds))
    )
    speed_list = tuple(sorted(given_speeds))
    # the shares follow the speeds as given, before they are sorted
    service = service_shares(given_speeds, load_list, speed_shares, load_shares)
    train = tuple(dict.fromkeys(validation.seed("train_seeds", s) for s in _items("train_seeds", train_seeds)))
    test = tuple(dict.fromkeys(validation.seed("test_seeds", s) for s in _items("test_seeds", test_seeds)))
    shared = [s for s in test if s in train]
    if shared:
        raise InputError(
            f"test_seeds = {list(test)}: {', '.join(map(str, shared))} also in train_seeds = {list(train)}; "
            "the held-out seeds must be seeds that tuning never sees"
        )
    duration = validation.number("duration", duration, "positive", "s")
    sections = {t: _sections(t, max(speed_list), duration, train + test) for t in track_list if t.startswith("file:")}
    obj = _objective(objective)
    validation.choice("aggregate", aggregate, AGGREGATES)
    values = validation.count("values", values, 3, what="values per gain and sweep")
    need = {law: min_budget(law, values) for law in laws}
    worst = max(need, key=lambda law: need[law])
    what = (
        f"gain sets per law: fewer cannot try every gain once; {worst} has {len(PARAMETERS[worst])} gains, "
        f"each tried at {values} values and at 0, after the start"
    )
    if optimiser == "evolution":  # the sweeps' values do not apply
        budget = validation.integer("budget", budget, evolution.MIN_BUDGET, what=evolution.BUDGET_RULE)
    else:
        budget = validation.integer("budget", budget, need[worst], what=what)
    model = damper_model(damper, 1.0)  # a known name or a model
    solver = SolverSettings.of(solver)
    # every held-out run, checked by the check every simulation makes before the first run of the
    # design (the seeds differ in the realisation only; `tune` checks its own set again)
    gains = GainSet.reference()
    for track in track_list:
        for v in speed_list:
            where = {"start": sections[track][0]} if track in sections else {"seed": test[0]}
            sc = make_scenario(track, **where, speed=v, duration=duration)
            for load in load_list:
                for law in laws:
                    check(sc, base.loaded(load), Suspension.named(law, gains, model), solver, "mark")
    return Plan(
        laws,
        base,
        source,
        load_list,
        tuple(dict.fromkeys(track_list)),
        speed_list,
        train,
        test,
        duration,
        obj,
        aggregate,
        budget,
        values,
        damper,
        solver,
        sections,
        optimiser,
        optimiser_seed,
        service,
    )


def _sections(track: str, speed: float, duration: float, seeds) -> tuple:
    """(the first section's start, a section's length) [m] of the measured profile ``track``:
    sections of the fastest run's distance (``speed`` x ``duration``) from its start at s >= 0
    on, section k the "seed" k, disjoint whatever the speed; an `InputError` naming the seed
    options where a seed has no section."""
    from railride.model.track import MeasuredTrack
    from railride.model.track import scenario as make_scenario

    length = speed * duration
    # the profile read at the design's own fastest run, not a scenario's default speed and length
    try:
        profile = make_scenario(track, speed=speed, duration=duration).track
    except InputError as exc:  # the profile is shorter than one run: name the design's options
        raise InputError(f"tracks = {track!r}, speeds up to {speed:g} m/s, duration = {duration:g} s: {exc}") from None
    assert isinstance(profile, MeasuredTrack)  # a file: scenario
    first = max(0.0, float(profile.s[0]))
    count = int((float(profile.s[-1]) - first) // length)
    beyond = [k for k in seeds if k >= count]
    if beyond:
        raise InputError(
            f"train_seeds, test_seeds = {list(seeds)}: {track} runs to s = {float(profile.s[-1]):g} m and holds "
            f"{count} section{'s' * (count != 1)} of {length:g} m (the fastest speed x the duration); a measured "
            f"profile's seeds are its sections, so give seeds below {count} (e.g. --train-seeds 0,1 --test-seeds "
            f"{min(2, max(count - 1, 0))}), or a shorter duration"
        )
    return first, length


@shows_progress("design")
def design(
    controllers=None,
    *,
    vehicle=None,
    loads=DEFAULT_LOADS,
    tracks=DEFAULT_TRACKS,
    speeds=DEFAULT_SPEEDS,
    objective=None,
    aggregate: str = DEFAULT_AGGREGATE,
    budget: int = DEFAULT_BUDGET,
    values: int = DEFAULT_VALUES,
    train_seeds=DEFAULT_TRAIN_SEEDS,
    test_seeds=DEFAULT_TEST_SEEDS,
    duration: float = DEFAULT_DURATION,
    damper=DEFAULT_DAMPER,
    solver=None,
    optimiser: str = "sensitivity",
    optimiser_seed: int = 0,
    speed_shares=None,
    load_shares=None,
    executor=None,
    table: RunTable | None = None,
    progress=True,
    log=None,
) -> DesignResult:
    """Which law for ``vehicle`` (a preset name, a parameters file or `VehicleParams`, default
    "paper") on the random ``tracks`` (FRA classes, german-low, german-high) at ``speeds``
    [m/s] and load factors ``loads``: tune each of ``controllers`` (laws with gains, default
    all) robustly, then judge it with passive on held-out seeds, and recommend one.

    Tuning: `railride.studies.tuning.tune` over every track x ``train_seeds`` x speed x load
    (``duration`` s each), ``objective`` (an `Objective`, "minimax" or "sum"; default
    `DEFAULT_OBJECTIVE`, the worst RMS ratio to passive) combined over those runs by
    ``aggregate`` ("mean" or "worst"), at most ``budget`` gain sets per law with ``values``
    values per gain and sweep, from the neutral reference gains; the inner loop first, on the
    damper rig, when a law tracks a force and the damper is an MR damper. ``optimiser``:
    "sensitivity" (that study) or "evolution" (SciPy's differential evolution over all of a
    law's gains at once, seeded by ``optimiser_seed``, within the same budget:
    `railride.studies.evolution`); either way every law's candidates of a round are one batch.

    Time in service: ``speed_shares`` and ``load_shares`` (one number > 0 per speed and load,
    normalised; `service_shares`) weigh each speed and load by its time in service, in the
    training runs' mean (``aggregate`` "mean") and in the ranking: a law's score is then the
    weighted mean of its scores at the speeds and loads, not its worst (`rank`). Without them
    every speed and load counts alike and a law is ranked by its worst.

    Judging: every law with its tuned gains and passive on every track x ``test_seeds`` x speed
    x load (seeds that tuning never saw). ``executor``, ``table`` (one `RunTable` for both
    stages: resumable) as for `railride.studies.sweep.run_cases`; ``progress``: True (shown on
    stderr after 2 s), False, or a callable ``progress(done, total, runs_per_second)``
    (`railride.studies.progress`); ``log(text)`` after each pass of tuning. Every input
    is checked before the first run (`check_design`). Returns a `DesignResult`.
    """
    from railride.model.params import vehicle_record
    from railride.secondary.control import GainSet
    from railride.secondary.suspension import damper_record
    from railride.studies.sweep import other_settings

    plan = check_design(
        controllers,
        vehicle=vehicle,
        loads=loads,
        tracks=tracks,
        speeds=speeds,
        objective=objective,
        aggregate=aggregate,
        budget=budget,
        values=values,
        train_seeds=train_seeds,
        test_seeds=test_seeds,
        duration=duration,
        damper=damper,
        solver=solver,
        optimiser=optimiser,
        optimiser_seed=optimiser_seed,
        speed_shares=speed_shares,
        load_shares=load_shares,
    )
    table = RunTable() if table is None else table
    if executor is None:  # the chunks that fill the threads, none more: one more took the default design above 2 GiB
        from railride.studies.executors import LocalExecutor

        executor = LocalExecutor(rows_beside=False)
    # the shares weigh the training runs' mean; the worst run is the worst whatever its weight
    weights = plan.service if plan.service is not None and plan.aggregate == "mean" else {}
    over = tuple(
        TuningCase(track, _options(plan, track, seed, v), load, weights.get((v, load), 1.0))
        for track in plan.tracks
        for load in plan.loads
        for seed in plan.train_seeds
        for v in plan.speeds
    )
    from railride.secondary import dampers

    inner = plan.damper not in dampers.IDEAL_NAMES and any("inner" in GainSet.tables_read(n) for n in plan.laws)
    tuned = tune(
        (("inner",) if inner else ()) + plan.laws,
        over=over,
        aggregate=plan.aggregate,
        budget=plan.budget,
        n_values=plan.values,
        objective=plan.objective,
        damper=plan.damper,
        vehicle=plan.vehicle if plan.source is None else plan.source,
        solver=plan.solver,
        executor=executor,
        table=table,
        progress=progress,
        log=log,
        before_after=False,
        optimiser=plan.optimiser,
        optimiser_seed=plan.optimiser_seed,
    )
    training = _training_frame(tuned.runs, plan)
    runs = _judge(plan, tuned.gains, executor, table, progress)
    summary = _summary(runs, plan)
    diverged = _diverged(tuned, training, runs, plan)
    ranking, points = rank(summary, plan.objective, plan.laws, {d["controller"] for d in diverged}, plan.service)
    if plan.service is not None:  # the ride over the time in service, beside the mean of the ratios
        from railride.studies.design_service import ranking_entries, service_rms

        rms = service_rms(runs, plan.service, plan.laws)
        for entry in ranking:
            entry.update(ranking_entries(rms, entry["controller"]))
    from railride.studies.design_probes import asks, fault_check, references

    leaders = [r["controller"] for r in ranking if r["ranked"]][:2]
    _run_ahead(plan, tuned.gains, executor, table, progress, asks(plan, leaders))
    refs = references(plan, tuned.gains, lambda **kw: _scores(plan, tuned.gains, executor, table, progress, **kw))
    faulted = fault_check(
        plan, leaders, points, lambda **kw: _scores(plan, tuned.gains, executor, table, progress, **kw)
    )
    settings = {
        "vehicle": vehicle_record(plan.vehicle, plan.source, list(plan.loads)),
        "clearance_m": plan.vehicle.z_stop,
        "tracks": list(plan.tracks),
        "speeds_m_s": list(plan.speeds),
        "loads": list(plan.loads),
        "controllers": list(plan.laws),
        "objective": plan.objective.to_dict(),
        "aggregate": plan.aggregate,
        **({"service": service_record(plan.service)} if plan.service is not None else {}),
        "optimiser": tuned.settings.get("optimiser", {"name": "sensitivity"}),
        "budget": plan.budget,
        "values": plan.values,
        "train_seeds": list(plan.train_seeds),
        "test_seeds": list(plan.test_seeds),
        "duration_s": plan.duration,
        "damper": damper_record(plan.damper),
        "dt_s": float(plan.solver.dt),
        **plan.solver.backend_record(),
        "inner_loop_tuned": inner,
        "training_runs_per_gain_set": len(over),
        "training_runs": int(len(training)),
        "judging_runs": int(len(runs)),
        "versions": versions(),
        "comfort_basis": n_mv_basis(intervals_in(None, float(plan.duration))),
        **other_settings(plan.vehicle, plan.solver),
    }
    text = recommend(ranking, points, summary, runs, plan.objective, settings, diverged)
    text = " ".join(t for t in (text, faulted.get("text") if faulted else None) if t)
    return DesignResult(
        references=refs,
        fault=faulted,
        summary=summary,
        runs=runs,
        ranking=ranking,
        points=points,
        recommendation=text,
        diverged=diverged,
        tuning=tuned,
        settings=settings,
        date=tuned.date,
    )


def service_record(service: dict) -> list[dict]:
    """The time in service as a result records it: each speed and load with its share."""
    return [{"speed_m_s": v, "load": x, "share": share} for (v, x), share in service.items()]


def _options(plan: Plan, track: str, seed: int, speed: float) -> tuple:
    """The scenario options of one run: the track's seed or section, the speed, the duration."""
    return tuple(sorted((*plan.track_options(track, seed), ("speed", speed), ("duration", plan.duration))))


def _training_frame(frame: pd.DataFrame | None, plan: Plan) -> pd.DataFrame:
    """The rows of the run table that tuning ran: the training seeds of the design's tracks
    (a resumed table may also hold the held-out runs of an earlier session)."""
    if frame is None or not len(frame):
        return pd.DataFrame()
    keep = pd.Series(False, index=frame.index)
    for track in plan.tracks:
        key = "start" if track in plan.sections else "seed"
        if f"scenario.{key}" not in frame:
            continue
        values = {dict(plan.track_options(track, k))[key] for k in plan.train_seeds}
        keep |= (frame["scenario"] == track) & frame[f"scenario.{key}"].isin(values)
    return frame[keep].reset_index(drop=True)


def _judge(
    plan: Plan, gains, executor, table, progress, laws=None, damper=None, faults=(), full: bool = True
) -> pd.DataFrame:
    """Every law of ``laws`` (default the plan's) with ``gains`` and passive on the held-out
    runs: one row per run, with the run's law, track, seed, speed and load, its metrics and
    costs, and each metric's ratio to passive on the same run (``<metric>_ratio``) and the
    objective of its ratios (``score``, inf where it diverged). ``damper`` (default the plan's)
    and ``faults`` apply to the laws, not to passive (`railride.studies.design_probes`). Not
    ``full``: only the comfort indices and costs the objective reads (the others NaN), for runs
    that are only scored."""
    laws = plan.laws if laws is None else laws
    cases, meta = _judge_cases(plan, laws, damper, faults)
    rows = _run_judged(plan, gains, executor, table, progress, cases, meta, full)
    rows = rows.reindex(columns=list(dict.fromkeys([*rows.columns, *METRICS])))  # NaN where not computed
    info = pd.DataFrame(meta, columns=["controller", "track", "track_seed", "speed_m_s", "load"])
    metrics = rows.reset_index(drop=True)[[*METRICS, "diverged_at_s"]].astype(float)
    frame = pd.concat([info, metrics], axis=1)
    key = ["track", "track_seed", "speed_m_s", "load"]
    passive = frame[frame["controller"] == "passive"].set_index(key)[list(METRICS)]
    base = passive.reindex(pd.MultiIndex.from_frame(frame[key])).to_numpy()
    values = frame[list(METRICS)].to_numpy()
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(base != 0, values / base, np.nan)
    for j, m in enumerate(METRICS):
        frame[f"{m}_ratio"] = ratio[:, j]
    # the objective of each run against passive on the same run, from every column it reads (a
    # comfort objective's floor points, the travel of a travel bound)
    cols = [*plan.objective.columns, *([TRAVEL_COLUMN] if plan.objective.needs_costs else [])]
    read = pd.concat([info, rows.reset_index(drop=True)[cols].astype(float)], axis=1)
    alone = read[read["controller"] == "passive"].set_index(key)[cols]
    score = plan.objective.of_runs(read, alone.reindex(pd.MultiIndex.from_frame(read[key])))
    frame["score"] = np.where(np.isfinite(frame["diverged_at_s"]), np.inf, score)
    return frame


def _judge_cases(plan: Plan, laws, damper=None, faults=()) -> tuple[list[Case], list[tuple]]:
    """The held-out runs of ``laws`` (with ``damper``, default the plan's, and ``faults``) and
    passive (`_judge`), and each one's (law, track, seed, speed, load)."""
    damper = plan.damper if damper is None else damper
    cases, meta = [], []
    for load in plan.loads:
        changes = plan.vehicle.load_changes(load)
        for track in plan.tracks:
            for seed in plan.test_seeds:
                for v in plan.speeds:
                    opts = _options(plan, track, seed, v)
                    for name in ("passive", *laws):
                        if name == "passive":
                            cases.append(Case(track, opts, vehicle=changes))
                        else:
                            law = Case(track, opts, vehicle=changes, suspension=name, damper=damper, faults=faults)
                            cases.append(law)
                        meta.append((name, track, seed, v, load))
    return cases, meta


def _run_judged(plan: Plan, gains, executor, table, progress, cases, meta, full: bool) -> pd.DataFrame:
    """`run_cases` of judged runs (`_judge_cases`): their rows, with comfort and costs where
    ``full`` or the objective reads them."""
    from railride.model.params import vehicle_record

    name = vehicle_record(plan.vehicle, plan.source)["name"]
    return run_cases(
        cases,
        executor=executor,
        table=table,
        base_gains=gains,
        params=plan.vehicle,
        solver=plan.solver,
        progress=progress,
        comfort=full or plan.objective.needs_comfort,
        costs=full or plan.objective.needs_costs,
        vehicle_columns=[{"vehicle": name, "load": float(m[4])} for m in meta],
    )


def _run_ahead(plan: Plan, gains, executor, table, progress, asks: list[dict]) -> None:
    """The runs of several `_scores` calls (their keyword arguments, ``asks``) as one
    `run_cases` call into ``table``, where those calls then find them: on a GPU one batch, not
    one per call, and on the CPU one batch that fills the cores."""
    if not asks:
        return
    cases, meta = [], []
    for ask in asks:
        c, m = _judge_cases(plan, ask["laws"], ask.get("damper"), ask.get("faults", ()))
        cases += c
        meta += m
    _run_judged(plan, gains, executor, table, progress, cases, meta, full=False)


def _scores(plan: Plan, gains, executor, table, progress, laws=None, damper=None, faults=()) -> list:
    """The points (`rank`) of ``laws`` judged with ``damper`` and ``faults``: per speed and load,
    each law's score there."""
    laws = plan.laws if laws is None else tuple(laws)
    runs = _judge(plan, gains, executor, table, progress, laws=laws, damper=damper, faults=faults, full=False)
    return rank(_summary(runs, plan, laws), plan.objective, laws, service=plan.service)[1]


def _summary(runs: pd.DataFrame, plan: Plan, laws=None) -> pd.DataFrame:
    """Per law (passive first), speed, load and metric (`METRICS`, then ``score``): the runs
    that did not diverge (``n``), the mean and the 5th / 95th percentiles of the value and of
    its ratio to passive."""
    lo, hi = PERCENTILES
    out = []
    for name in ("passive", *(plan.laws if laws is None else laws)):
        for v in plan.speeds:
            for load in plan.loads:
                part = runs[(runs["controller"] == name) & (runs["speed_m_s"] == v) & (runs["load"] == load)]
                part = part[~np.isfinite(part["diverged_at_s"])]
                for m in (*METRICS, "score"):
                    x = part[m].to_numpy(dtype=float)
                    r = part[f"{m}_ratio"].to_numpy(dtype=float) if m != "score" else np.array([])
                    x, r = x[np.isfinite(x)], r[np.isfinite(r)]
                    out.append(
                        {
                            "controller": name,
                            "speed_m_s": v,
                            "load": load,
                            "metric": m,
                            "n": int(len(part)),
                            "mean": float(x.mean()) if x.size else np.nan,
                            "p5": float(np.percentile(x, lo)) if x.size else np.nan,
                            "p95": float(np.percentile(x, hi)) if x.size else np.nan,
                            "ratio_mean": float(r.mean()) if r.size else np.nan,
                            "ratio_p5": float(np.percentile(r, lo)) if r.size else np.nan,
                            "ratio_p95": float(np.percentile(r, hi)) if r.size else np.nan,
                        }
                    )
    return pd.DataFrame(out)


__all__ = ["COST_COLUMNS", "DesignResult", "check_design", "design", "min_budget"]
