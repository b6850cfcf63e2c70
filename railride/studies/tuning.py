"""Controller tuning: every law by the same sensitivity study, objective and budget of runs.

The study is the paper's (its section V): one gain at a time is swept over log-spaced values
(and 0) around its current value while the others stay fixed; the best value is kept; passes
over all the law's gains repeat. What the paper leaves open is made equal for every law, so
that a comparison does not favour the law that got more tuning:

- each law (`TUNED_CONTROLLERS`) is tuned on its own gains (`GainSet.tuned_entries`) from the
  same start gains, with the same objective on the same runs;
- each gets the same budget of vehicle runs (distinct gain sets scored, the start included).
  The study ends when its next sweep would not fit the budget. A pass that improves the
  objective by less than ``tol`` narrows the span of the sweeps to its square root, so a law
  with few gains spends its budget refining them; it ends early ("converged") when the span
  falls below ``min_span``;
- the ride loop of SAS (attitude+ride) starts from zero gains, as in the paper's phase 2.

The inner loop (B, G) belongs to the damper, not to a law: it is tuned first on the damper
rig's force tracking (the paper's Fig. 6 demands), which costs no vehicle run, and every law
that tracks a force uses it.

A vehicle run is scored by a named `Objective` over the four RMS ratios to passive (docs/
tuning.md); every output of a study states it. Every vehicle evaluation goes through
`railride.studies.sweep.run_cases`, so it can run on a Dask cluster and lands in the run table; the
study is deterministic given the results, so a resumed study replays its path from the table
and only evaluates what is missing. `tune` returns a `railride.studies.tune_result.TuneResult`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from railride.errors import InputError
from railride.secondary.control import OUTER_LOOPS, GainSet
from railride.defaults import DEFAULT_DAMPER
from railride.analysis.metrics import RESPONSES
from railride.model.params import resolve_argument, vehicle_record
from railride.studies.progress import shows_progress
from railride.studies.objectives import (  # noqa: F401 (re-exported: the objectives' old home)
    DEFAULT_OBJECTIVE,
    INFEASIBLE_OFFSET,
    INFEASIBLE_SCALE,
    OBJECTIVE_KINDS,
    RATIO_NAMES,
    Objective,
)
from railride.secondary import dampers
from railride import limits, validation
from railride.run.checks import check
from railride.run.solver import SolverSettings
from railride.studies import evolution
from railride.studies.lockstep import OwnChunks, lockstep
from railride.studies.sweep import Case, RunTable, run_cases
from railride.studies.tune_result import SCHEMA, Curve, Study, TuneResult  # noqa: F401 (their home before)
from railride.secondary.suspension import Suspension, damper_record

#: the laws with free gains, in the order a study tunes them: every outer loop (the
#: constant-voltage baselines have no gains)
TUNED_CONTROLLERS = tuple(n for n in OUTER_LOOPS if GainSet.tuned_entries(n))
#: what `tune` can tune: the inner loop (on the damper rig), then the laws
TUNABLE = ("inner", *TUNED_CONTROLLERS)
#: the gains each study varies, by "table.entry"
PARAMETERS = {"inner": GainSet.entry_names("inner"), **{n: GainSet.tuned_entries(n) for n in TUNED_CONTROLLERS}}
#: the source of the gains `tune` returns (their [provenance] says how they were found, and
#: from which start gains)
TUNED_SOURCE = "<tuned by railride.studies.tuning.tune>"
#: the default budget of vehicle runs per law: two full passes of the law with the most gains
#: (SAS attitude+ride: 14 gains x 14 new values per sweep = 196 runs a pass)
DEFAULT_BUDGET = 400
#: laws made of loops, tuned loop by loop as the paper does (its phases 1 and 2): SAS
#: (attitude+ride)'s attitude loop with the ride loop off (zero gains), then its ride loop from
#: zero on top; each stage may spend its share of what the budget has left
STAGES = {"sas-attitude-ride": (GainSet.entry_names("ride_attitude"), GainSet.entry_names("ride"))}
#: the passes of the inner loop's study on the rig (it has no budget of vehicle runs)
INNER_PASSES = 5

#: the neutral gains of railride/data/reference_gains.toml (`GainSet.reference`), by
#: "table.entry": where the sweep of a gain that is 0 is centred, and the centre of the search
#: box of the global methods
REFERENCE = GainSet.reference().entries()


def _utc_now() -> str:
    from datetime import datetime, timezone

    return datetime.now(timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def _rms(rows: pd.DataFrame) -> np.ndarray:
    return rows[[f"{r}_rms" for r in RESPONSES]].to_numpy()


#: what a candidate value of a sweep holds while it waits to run: the value, its case (a gain
#: set) and its row in the run table, about 2 kB; the runs themselves are checked by simulate
CANDIDATE_BYTES = 2048
#: the widest span of a sweep (`_candidates`): 28 decades around the current value, where the
#: outer-loop gains are allowed 0 to 1e14 (docs/cli.md); far wider the candidates overflow (1e308)
MAX_SPAN = 1e14


def _candidates(current: float, parameter: str, n_values: int, span: float, gains: GainSet) -> list[float]:
    """The values a sweep of ``parameter`` tries: 0, the current value and ``n_values``
    log-spaced from current / span to current x span (around the reference value when the
    current one is 0), to four significant digits; those its table refuses (a blend above 1,
    B = 0, which ignores the measured force) are left out."""
    ref = current if current > 0 else REFERENCE[parameter]
    values = ref * np.logspace(-math.log10(span), math.log10(span), n_values)
    # four significant digits: gains a person can read and type, nothing lost to the study
    vals = sorted({0.0, float(current), *[float(f"{v:.4g}") for v in values]})
    if parameter == "inner.B":
        vals = [v for v in vals if v > 0]
    table, _, entry = parameter.partition(".")
    return [v for v in vals if _allowed(gains.table(table), entry, v)]


def _allowed(table, entry: str, value: float) -> bool:
    try:
        table.replace(**{entry: value})
    except ValueError:
        return False
    return True


@dataclass(frozen=True)
class TuningCase:
    """One run of a tuning set: a scenario (`railride.model.track.scenario` name and options), a
    load factor (`VehicleParams.loaded`) and its weight in the mean over the set (``aggregate``
    "mean"; a design's time in service at the run's speed and load: `railride.studies.design`)."""

    scenario: str
    options: tuple = ()
    load: float = 1.0
    weight: float = 1.0

    def __post_init__(self):
        rule = "a finite number > 0 (the case's weight in the mean)"
        object.__setattr__(self, "weight", float(validation.number("weight", self.weight, "positive", allowed=rule)))


def tuning_set(scenario: str = "fra4", *, track_seeds=None, speeds=None, loads=(1.0,), duration=None) -> tuple:
    """The `TuningCase` of every combination of track seed (random tracks only), speed [m/s]
    and load factor: what `tune(over=...)` scores each gain set on."""
    seeds = [None] if track_seeds is None else [validation.seed("track_seeds", x) for x in track_seeds]
    speeds = [None] if speeds is None else [validation.number("speeds", v, "positive", "m/s") for v in speeds]
    loads = [validation.number("loads", x, "positive", allowed="a finite number > 0 (load factor)") for x in loads]
    out = []
    for load in loads:
        for seed in seeds:
            for v in speeds:
                opts = {
                    **({"seed": seed} if seed is not None else {}),
                    **({"speed": v} if v is not None else {}),
                    **({"duration": duration} if duration is not None else {}),
                }
                out.append(TuningCase(scenario, tuple(sorted(opts.items())), load))
    return tuple(out)


#: how a tuning set's objectives become one: their mean, or the worst
AGGREGATES = ("mean", "worst")


def _check_controllers(controllers) -> tuple:
    from railride import arguments

    for c in arguments.names("controllers", controllers, "controller names"):
        if c not in TUNABLE:
            fixed = " (it has no gains to tune)" if c in ("passive", "passive-on", "passive-off") else ""
            raise InputError(f"controller = {c!r}{fixed}: allowed {', '.join(TUNABLE)}")
    return tuple(c for c in TUNABLE if c in controllers)  # the order they run


def _inner_left_out(controllers, gains, damper) -> str | None:
    """What a tuning that lists laws using the MR dampers' tracking inner loop, but not "inner",
    leaves untuned, in one line; None where nothing is (the inner loop listed, the ideal devices,
    or only laws with on-off or clipped voltages, which read no inner-loop gain)."""
    if "inner" in controllers or damper in dampers.IDEAL_NAMES:
        return None
    users = [n for n in controllers if "inner" in GainSet.tables_read(n)]  # as `design` lists it
    if not users:
        return None
    inner = gains.inner
    return (
        f"the inner loop is not tuned: its B = {inner.B:g} and G = {inner.G:g} V/N stay at the start values, "
        f"though the MR dampers of {', '.join(users)} follow it; list 'inner' to tune it too"
    )


@shows_progress("tuning")
def tune(
    controllers=TUNABLE,
    *,
    budget: int = DEFAULT_BUDGET,
    scenario: str = "paper-sine",
    scenario_options=None,
    gains: GainSet | None = None,
    objective: Objective | None = None,
    damper: str = DEFAULT_DAMPER,
    executor=None,
    table: RunTable | None = None,
    n_values: int = 13,
    span: float = 30.0,
    tol: float = 1e-3,
    min_span: float = 1.05,
    vehicle=None,
    params=None,
    solver=None,
    window=None,
    progress=True,
    log=None,
    damper_scale: float = 1.0,
    before_after: bool = True,
    over=None,
    aggregate: str = "mean",
    optimiser: str = "sensitivity",
    optimiser_seed: int = 0,
) -> TuneResult:
    """Tune ``controllers`` (names from `TUNABLE`; default all: the inner loop, then every law)
    from ``gains`` (default the neutral `GainSet.reference`), minimising ``objective`` (default
    `DEFAULT_OBJECTIVE`) on ``scenario``, each law with at most ``budget`` vehicle runs.

    Per pass, each gain of the law is swept over ``n_values`` log-spaced values from 1/span to
    span times its current value (and 0); a pass that improves the objective by less than
    ``tol`` (relative) narrows the span to its square root; a law's study ends when the next
    sweep would not fit its budget, or when the span falls below ``min_span``. The inner loop
    is tuned on the damper rig (at most `INNER_PASSES` passes, stopping at ``tol``).
    ``damper_scale`` scales the MR dampers' force capacity (`railride.secondary.dampers.BoucWen.scaled`);
    the inner loop then tracks demands scaled alike. ``vehicle`` (``params`` is an alias): a
    preset name, the path of a parameters file or `VehicleParams` (default "paper"), recorded
    in ``settings["vehicle"]`` with the load factors of the runs
    (`railride.model.params.vehicle_record`); ``solver``: the `SolverSettings` of every vehicle
    run; both are recorded in ``settings`` where they differ from the defaults (the run keys). Every setting is
    checked before the first run. ``progress``: True (the default: shown on stderr after 2 s,
    `railride.studies.progress`), False (silent) or a callable ``progress(done, total,
    runs_per_second)`` after each chunk;
    ``log(text)`` after each pass.

    ``before_after``: at the end, run each law tuned (and, when the inner loop was tuned, each
    law that uses it) with the start and with the tuned gains (through the run table, where
    most of these runs already are).

    ``over``: robust tuning. A set of `TuningCase` (`tuning_set`: track seeds, speeds, load
    factors) in place of ``scenario``: each gain set is scored on every case, against the
    passive run of the same case, and the case objectives become one by ``aggregate`` ("mean"
    or "worst"). The budget still counts gain sets; each costs one run per case. No
    before/after rows (they belong to one scenario).

    ``optimiser``: "sensitivity" (the study above) or "evolution": SciPy's differential
    evolution over all of a law's gains at once, in the log10 box of
    `railride.studies.optimise`, with the same objective, runs and budget
    (`railride.studies.evolution`; ``optimiser_seed`` seeds it; ``n_values``, ``span``, ``tol``
    and ``min_span`` are the study's and do not apply). Either way the laws step together: each
    round's gain sets of every law are one batch of runs (`lockstep`). Returns a `TuneResult`.
    """
    from railride.secondary.suspension import damper_model
    from railride.studies.sweep import other_settings
    from railride.model.track import scenario as make_scenario

    controllers = _check_controllers(controllers)
    solver = SolverSettings.of(solver)
    vehicle, source = resolve_argument(vehicle, params)
    from railride import arguments
    from railride.studies.case import scenario_options as scenario_options_of

    gains = GainSet.reference() if gains is None else GainSet.of(gains)
    objective = arguments.instance("objective", objective, Objective, "an Objective") or DEFAULT_OBJECTIVE
    opts = tuple(sorted(scenario_options_of("scenario_options", scenario_options).items()))
    window = arguments.window("window", window)
    before_after = arguments.flag("before_after", before_after)
    table = RunTable() if table is None else table
    damper_model(damper, damper_scale)  # a known name, and a scale it has
    if "inner" in controllers and damper in dampers.IDEAL_NAMES:
        raise InputError(
            f"damper = {damper!r} with 'inner': the ideal devices have no force-tracking loop to "
            "tune; leave out the inner loop"
        )
    damper_scale = dampers.check_scale("damper_scale", damper_scale)
    validation.choice("optimiser", optimiser, evolution.OPTIMISERS)
    optimiser_seed = validation.seed("optimiser_seed", optimiser_seed)
    validation.count("n_values", n_values, 3)
    # room for the start and one whole sweep (the values and 0): a smaller budget tunes nothing
    what = f"the start run and one sweep of {n_values} values and 0"
    if optimiser == "evolution":  # the sweeps' values do not apply
        budget = validation.integer("budget", budget, evolution.MIN_BUDGET, what=evolution.BUDGET_RULE)
    else:
        budget = validation.integer("budget", budget, n_values + 2, what=what)
    limits.check(
        CANDIDATE_BYTES * n_values,
        f"a sweep of {n_values} candidate values",
        "use fewer values (13 a gain and pass is the default)",
    )
    for name, value in (("span", span), ("min_span", min_span)):
        if not 1 < validation.number(name, value, "finite", allowed="a finite number > 1") <= MAX_SPAN:
            raise InputError(
                f"{name} = {validation.shown(value)}: must be a finite number > 1 and <= {MAX_SPAN:g} (28 "
                "decades around the current value, more than any sweep needs)"
            )
    validation.number("tol", tol, "nonnegative")
    validation.choice("aggregate", aggregate, AGGREGATES)
    if over is not None:
        cases_set = tuple(arguments.sequence("over", over, "allowed a list of TuningCase (tuning_set())"))
        if not cases_set or not all(isinstance(c, TuningCase) for c in cases_set):
            raise InputError("over: give a non-empty sequence of railride.studies.tuning.TuningCase (tuning_set())")
        if scenario_options:
            raise InputError("scenario_options with over: the tuning set names its own scenarios")
    else:
        cases_set = (TuningCase(scenario, opts, 1.0),)
    scens = [make_scenario(c.scenario, **dict(c.options)) for c in cases_set]
    # the cases' weights in the mean (all 1 but where a design weighs its speeds and loads)
    weighted = any(c.weight != 1.0 for c in cases_set)
    weights = np.array([c.weight for c in cases_set])
    # the runs of every case, checked by the check every simulation makes (railride.run.checks),
    # before the first: a law of the set on the case's vehicle (the laws share the dampers)
    law = next((n for n in controllers if n != "inner"), "pid")
    for c, sc in zip(cases_set, scens):
        check(sc, vehicle.loaded(c.load), Suspension.named(law, gains, damper, damper_scale), solver, "mark")
    scen = scens[0]
    untuned = _inner_left_out(controllers, gains, damper)
    if untuned is not None:
        import warnings

        from railride.errors import TuningWarning

        warnings.warn(
            untuned, TuningWarning, stacklevel=validation.caller_level()
        )  # the user's call, past the progress wrapper
    result = TuneResult(
        gains,
        objective=objective,
        start=gains,
        controllers=controllers,
        scenario=scen.describe(),
        settings={
            "damper": damper_record(damper),
            "damper_scale": damper_scale,
            "dt_s": solver.dt,
            **solver.backend_record(),
            "budget": budget,
            "values": n_values,
            "span": float(span),
            "tolerance": float(tol),
            "min_span": float(min_span),
            "start_gains": gains.source,
            **({"inner_loop_not_tuned": untuned} if untuned is not None else {}),
            **({"optimiser": evolution.record(optimiser_seed)} if optimiser == "evolution" else {}),
            "vehicle": vehicle_record(vehicle, source, list(dict.fromkeys(c.load for c in cases_set))),
            **other_settings(vehicle, solver),
            **(
                {
                    "tuning_set": [
                        {**sc.describe(), "load": c.load, **({"weight": c.weight} if weighted else {})}
                        for c, sc in zip(cases_set, scens)
                    ],
                    "aggregate": aggregate,
                }
                if over is not None
                else {}
            ),
        },
    )

    loads = [vehicle.load_changes(c.load) for c in cases_set]
    # the load of a run by its vehicle changes, for its row in the run table
    vehicle_name = result.settings["vehicle"]["name"]
    load_of = {Case(vehicle=ld).vehicle: float(c.load) for c, ld in zip(cases_set, loads)}

    def run(cases, executor=executor):
        return run_cases(
            cases,
            executor=executor,
            table=table,
            base_gains=gains,
            params=vehicle,
            solver=solver,
            window=window,
            progress=progress,
            vehicle_columns=[{"vehicle": vehicle_name, "load": load_of[c.vehicle]} for c in cases],
            # only what the objective reads: the keys of plain tunings stay as they were
            comfort=objective.needs_comfort,
            costs=objective.needs_costs,
        )

    passive_rows = run([Case(c.scenario, c.options, vehicle=ld) for c, ld in zip(cases_set, loads)])
    passives = _rms(passive_rows)
    passive = passives[0]
    result = dataclasses.replace(result, passive=dict(zip(RESPONSES, passive)))  # a result is frozen
    inner: dict[str, float] = {}  # the inner loop's changes, which every law's runs carry
    if "inner" in controllers:
        result.studies.append(_tune_inner(gains, inner, n_values, span, tol, result, log, damper, damper_scale))

    def case(name, change, k=0):
        gains = tuple(sorted({**inner, **change}.items()))
        c = cases_set[k]
        return Case(
            c.scenario,
            c.options,
            vehicle=loads[k],
            suspension=name,
            damper=damper,
            damper_scale=damper_scale,
            gains=gains,
        )

    def score(asked: dict) -> dict:
        """The objective of every gain set asked, by law: one batch of runs for all of them."""
        k = len(cases_set)
        parts = [[case(name, cs, j) for cs in sets for j in range(k)] for name, sets in asked.items()]
        rows = run([c for part in parts for c in part], executor=OwnChunks(executor, parts))
        out, at = {}, 0
        for name, sets in asked.items():
            # each law's rows, change set by change set, each over the k cases: case j's are j, j + k, ...
            part, at = rows.iloc[at : at + len(sets) * k], at + len(sets) * k
            # every run against the passive run of its case, in one call (row by row, as k calls were)
            per_case = objective.of_runs(part, passive_rows.iloc[np.tile(np.arange(k), len(sets))])
            per_case = per_case.reshape(len(sets), k)
            if aggregate == "worst":
                out[name] = per_case.max(axis=1)
            else:  # all weights 1: the plain mean, bit for bit as before weights
                out[name] = np.average(per_case, axis=1, weights=weights) if weighted else per_case.mean(axis=1)
        return out

    laws = [name for name in controllers if name != "inner"]
    if optimiser == "evolution":
        searches = {n: evolution.search(n, PARAMETERS[n], _start(n, gains), budget, optimiser_seed, log) for n in laws}
    else:
        searches = {n: _study(n, gains, budget, n_values, float(span), tol, min_span, log) for n in laws}
    tuned: dict[str, dict] = {}  # each law's gains as its study left them
    for name, (study, tuned[name], *traces) in lockstep(searches, score).items():
        result.studies.append(study)
        if traces:  # the sensitivity study's curves and passes, law by law
            result.curves.extend(traces[0])
            result.history.extend(traces[1])
    tuned_gains = gains.apply({**inner, **{k: v for own in tuned.values() for k, v in own.items()}})
    result = dataclasses.replace(result, gains=tuned_gains)
    if before_after and over is None:
        result = dataclasses.replace(result, before_after=_before_after(result, run, case, tuned, inner, damper))
    result = dataclasses.replace(result, runs=table.frame, date=_utc_now())
    # the tuned gains carry the [provenance] their gains file holds, not the start's source: a
    # run with them records how they were found (`GainSet.record`, `GainSet.mismatch`)
    provenance = GainSet.from_toml(result.gains_toml()).provenance
    gains = dataclasses.replace(result.gains, source=TUNED_SOURCE, provenance=provenance)
    return dataclasses.replace(result, gains=gains)


def _start(name: str, start: GainSet) -> dict:
    """Every gain of law ``name`` where its study starts, by "table.entry": ``start``'s, the ride
    loop of SAS (attitude+ride) at zero (the paper's phase 2)."""
    own = dict.fromkeys(GainSet.entry_names("ride"), 0.0) if name == "sas-attitude-ride" else {}
    return {e: own.get(e, start.value(e)) for e in PARAMETERS[name]}


def _study(name, start, budget, n_values, start_span, tol, min_span, log):
    """One law's study, as a generator (`lockstep`): passes over its gains until the budget or
    the span runs out; yields the gain sets of each sweep (each every gain of the law, by
    "table.entry") and receives their objectives. Returns the `Study`, the law's gains at the
    end (by "table.entry"), its `Curve` list and its history (the objective after each pass)."""
    entries = PARAMETERS[name]
    own: dict[str, float] = {}
    if name == "sas-attitude-ride":  # the paper's phase 2: the ride loop joins with zero gains
        own.update(dict.fromkeys(GainSet.entry_names("ride"), 0.0))
    study = Study(name, entries, budget, span=start_span)
    curves: list[Curve] = []
    history: list[dict] = []

    def value(p):
        return own.get(p, start.value(p))

    def full(change) -> dict:
        # every gain of the law, so that one set of gains is one case (and one run) however reached
        return {**{e: value(e) for e in entries}, **change}

    def key(change):
        return tuple(sorted(full(change).items()))

    seen = {key({})}
    best = float((yield [full({})])[0])
    study.runs, study.objective_start = 1, best
    stages = STAGES.get(name, (entries,))
    for k, stage in enumerate(stages):
        # this stage's share of what is left; the last stage has the rest
        cap = study.runs + (budget - study.runs) // (len(stages) - k)
        span, stopped = start_span, ""
        while not stopped:
            study.passes += 1
            before, swept = best, 0
            for p in stage:
                vals = _candidates(value(p), p, n_values, span, start.apply(own))
                new = {key({p: v}) for v in vals} - seen
                if study.runs + len(new) > cap:
                    stopped = "budget"
                    break
                obj = yield [full({p: v}) for v in vals]
                study.runs += len(new)
                seen |= new
                swept += 1
                i = int(np.argmin(obj))
                if obj[i] < best - 1e-12:
                    own[p], best = vals[i], float(obj[i])
                curves.append(Curve(name, study.passes, p, np.array(vals), np.asarray(obj), value(p)))
            if swept:
                history.append(
                    {"controller": name, "pass": study.passes, "objective": best, "span": span, "runs": study.runs}
                )
                if log is not None:
                    log(f"{name} pass {study.passes}: objective {best:.4g} ({study.runs} runs)")
            else:
                study.passes -= 1
            # "not >=": a pass from inf to inf (every run diverged) improves nothing either,
            # where inf - inf < tol * inf is False and the span would never shrink
            if not stopped and not before - best >= tol * abs(before):
                span = math.sqrt(span)
                if span < min_span:
                    stopped = "converged"
    study.objective, study.span, study.stopped = best, span, stopped
    return study, full({}), curves, history


def _before_after(result: TuneResult, run, case, tuned: dict, inner: dict, damper: str) -> list[dict]:
    """RMS of each law the study changed, with the start gains and with the tuned gains (the
    case its study last kept, so no run is repeated), and the reductions against passive;
    ``run`` evaluates cases through the study's run table, ``case(name, changes)`` makes one."""
    names = [
        n
        for n in TUNED_CONTROLLERS
        if n in tuned or (inner and "inner" in GainSet.tables_read(n) and damper not in dampers.IDEAL_NAMES)
    ]
    cases = []
    for n in names:
        cases.append(dataclasses.replace(case(n, {}), gains=()))  # the start gains: the study's base
        cases.append(case(n, tuned.get(n, {})))
    frame = run(cases)
    passive = {r: float(result.passive[r]) for r in RESPONSES}
    rows = []
    for i, n in enumerate(names):
        before, after = frame.iloc[2 * i], frame.iloc[2 * i + 1]
        row: dict[str, Any] = {
            "suspension": n,
            "before": {},
            "after": {},
            "reduction_before_percent": {},
            "reduction_after_percent": {},
        }
        for r in RESPONSES:
            b, a = float(before[f"{r}_rms"]), float(after[f"{r}_rms"])
            row["before"][r], row["after"][r] = b, a
            p = passive[r]  # a zero passive RMS (e.g. roll on a symmetric bump): no reduction
            row["reduction_before_percent"][r] = (p - b) / p * 100.0 if p else None
            row["reduction_after_percent"][r] = (p - a) / p * 100.0 if p else None
        rows.append(row)
    return rows


def tracking_objective(B: float, G: float, damper=DEFAULT_DAMPER, damper_scale: float = 1.0) -> float:
    """The inner loop's objective: normalised RMS tracking error, averaged over the paper's
    sine and sawtooth demands (Fig. 6) at 10 kN x ``damper_scale``, 1 Hz on the damper rig."""
    from railride.secondary import dampers
    from railride.run.rig import track

    model = dampers.preset(damper) if isinstance(damper, str) else damper
    if damper_scale != 1.0:
        model = model.scaled(damper_scale)
    return float(
        np.mean(
            [
                track(model, kind, 10e3 * damper_scale, 1.0, B=B, G=G).metrics().normalised_rms_error
                for kind in ("sine", "sawtooth")
            ]
        )
    )


def _tune_inner(start, changes, n_values, span, tol, result, log, damper, damper_scale=1.0) -> Study:
    """B and G on the rig's force-tracking error (cheap: evaluated here, not on the executor)."""
    params = PARAMETERS["inner"]
    study = Study("inner", params, None, span=float(span))

    def value(p):
        return changes.get(p, start.value(p))

    def objective(**change):
        study.runs += 1
        kw = {"B": value("inner.B"), "G": value("inner.G"), **change}
        return tracking_objective(kw["B"], kw["G"], damper, damper_scale)

    best = study.objective_start = objective()
    for sweep_pass in range(1, INNER_PASSES + 1):
        before = best
        study.passes = sweep_pass
        for p in params:
            vals = _candidates(value(p), p, n_values, span, start)
            obj = np.array([objective(**{p.split(".")[1]: v}) for v in vals])
            k = int(np.argmin(obj))
            if obj[k] < best - 1e-12:
                changes[p], best = vals[k], float(obj[k])
            result.curves.append(Curve("inner", sweep_pass, p, np.array(vals), obj, value(p)))
        result.history.append(
            {"controller": "inner", "pass": sweep_pass, "objective": best, "span": float(span), "runs": study.runs}
        )
        if log is not None:
            log(f"inner pass {sweep_pass}: tracking error {best:.4f}")
        if before - best < tol * abs(before):
            study.stopped = "converged"
            break
    else:
        study.stopped = "passes"
    study.objective = best
    return study
