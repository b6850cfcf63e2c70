"""Controller tuning by the paper's sensitivity study (its section V).

One parameter at a time is swept over a logarithmic range (and 0) while the others stay fixed;
the best value is kept; passes repeat until a whole pass improves the objective by less than a
tolerance. Phases follow the paper: PID's three gains; the six SAS attitude gains with the ride
loop off, then the eight ride gains with the attitude loop fixed, starting from zero ride gains
(the paper's phase 2); the inner loop's B and G on the force-tracking error of the damper rig.

A vehicle run is scored by a named `Objective` over the four RMS ratios to passive, r_k =
RMS_k / RMS_k(passive) (acceleration, displacement, pitch, roll): ``sum``, ``weighted``,
``minimax`` or ``constrained``, plus an optional penalty on ratios above 1. `DEFAULT_OBJECTIVE`
is the one home of the default; `Objective.describe` states an objective in full, and every
output of a study prints that statement.

Every vehicle evaluation goes through `railride.sweep.run_cases`, so it can run on a Dask
cluster and lands in the run table; the study itself is deterministic given the results, so a
resumed study replays its path from the table and only evaluates what is missing.

`tune` returns a `TuneResult`, which holds what `railride tune` writes: `to_dict` (tune.json,
schema ``railride.tune/2``), `to_pandas` (curves.csv), `plot` (sensitivity.png), `gains_toml`
(gains.toml with its provenance) and `save` (the four files, all or nothing).
"""

from __future__ import annotations

import json
import math
from typing import Any
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .control import PAPER_CONTROLLERS, GainSet
from .defaults import DEFAULT_DAMPER
from .metrics import RESPONSES
from .params import VehicleParams
from .objectives import (  # noqa: F401 (re-exported: the objectives' old home)
    DEFAULT_OBJECTIVE,
    INFEASIBLE_OFFSET,
    INFEASIBLE_SCALE,
    OBJECTIVE_KINDS,
    RATIO_NAMES,
    Objective,
)
from . import validation
from .solver import SolverSettings, check_resolution
from .sweep import Case, RunTable, run_cases

#: one phase per gain table of the paper's controllers, in the paper's order
PHASES = GainSet.PAPER_TABLES
#: the gains each phase tunes, by "table.entry"
PARAMETERS = {phase: GainSet.entry_names(phase) for phase in PHASES}
#: the controllers whose response a phase changes (the before/after rows of `TuneResult`)
PHASE_CONTROLLERS = {
    phase: tuple(n for n in PAPER_CONTROLLERS[1:] if phase in GainSet.tables_read(n)) for phase in PHASES
}
#: the suspension a vehicle phase is scored with: the first controller that reads its table
SUSPENSION = {phase: names[0] for phase, names in PHASE_CONTROLLERS.items() if phase != "inner"}
#: the gain tables each controller reads
CONTROLLER_TABLES = {n: GainSet.tables_read(n) for n in PAPER_CONTROLLERS[1:]}
#: the schema of `TuneResult.to_dict` (tune.json)
SCHEMA = "railride.tune/2"


#: the neutral gains of railride/data/reference_gains.toml (`GainSet.reference`), by
#: "table.entry": where the sweep of a gain that is 0 is centred, and the centre of the search
#: box of the global methods
REFERENCE = GainSet.reference().entries()


@dataclass
class Curve:
    """The sensitivity curve of one parameter in one pass: objective against value."""

    phase: str
    sweep_pass: int
    parameter: str
    values: np.ndarray
    objective: np.ndarray
    chosen: float


@dataclass
class TuneResult:
    """The result of `tune`: the tuned ``gains`` (the start gains ``start`` with the changes the
    study kept), the sensitivity ``curves`` in the order they ran, the objective after each pass
    (``history``), the passive RMS by response (``passive``), the ``objective`` the vehicle
    phases minimised and the run table at the end (``runs``). The settings it ran with:
    ``phases``, ``scenario`` (the `Scenario.describe` record) and ``settings`` (damper,
    damper_scale, dt_s, values, span, max_passes, tolerance, start_gains: the source of the
    start gains). ``before_after``: per controller the phases change, the RMS with the start and
    with the tuned gains and their reductions against passive. ``date``: when the study ended
    (UTC, ISO 8601).

    The result protocol: `to_dict` (the ``railride.tune/2`` document), `to_pandas` (the curves
    as one long table), `plot` (the sensitivity figure), `save` (gains.toml, sensitivity.png,
    curves.csv, tune.json); `gains_toml` is the gains file with its provenance.
    """

    gains: GainSet
    curves: list[Curve] = field(default_factory=list)
    history: list[dict] = field(default_factory=list)  # objective after each pass of each phase
    runs: pd.DataFrame | None = None
    passive: dict = field(default_factory=dict)  # RMS of the passive run, by response
    objective: Objective = DEFAULT_OBJECTIVE  # what the vehicle phases minimised
    start: GainSet | None = None  # None: the gains are the start
    phases: tuple = ()
    scenario: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    before_after: list[dict] = field(default_factory=list)
    date: str | None = None

    @property
    def n_runs(self) -> int:
        """Rows of the run table at the end (the study's runs and the before/after runs)."""
        return 0 if self.runs is None else len(self.runs)

    def to_dict(self) -> dict:
        """The ``railride.tune/2`` document (docs/cli.md) without the facts of a command line
        (``runs_evaluated``, ``runs_per_second``, ``wall_time_s``, ``executor``, ``command``,
        which `railride tune` adds after ``runs``)."""
        from . import __version__

        start = self.gains if self.start is None else self.start
        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "date": self.date,
            "phases": list(self.phases),
            "scenario": self.scenario,
            "settings": self.settings,
            "objective": self.objective.to_dict(),
            "passive_rms": {r: float(self.passive[r]) for r in RESPONSES},
            "history": [
                {"phase": h["phase"], "pass": int(h["pass"]), "objective": float(h["objective"])} for h in self.history
            ],
            "gains": {
                "source": start.source,
                "inner": self.gains.inner.to_dict(),
                "pid": self.gains.pid.to_dict(),
                "attitude": self.gains.attitude.to_dict(),
                "ride": self.gains.ride.to_dict(),
            },
            "before_after": self.before_after,
            "runs": self.n_runs,
        }

    def gains_toml(self, command: str | None = None) -> str:
        """The gains file of the tuned gains with its provenance: a header of comments and a
        [provenance] table (scenario and its record, damper, step, objective, phases, runs,
        start gains, date; ``command``, the command line that ran the study, when given), which
        `GainSet.load` keeps as ``provenance``."""
        from .labels import describe_dampers

        s = self.settings
        last = {}
        for h in self.history:
            last[h["phase"]] = h
        finals = "; ".join(f"{p} {h['objective']:.4g} after pass {h['pass']}" for p, h in last.items())
        doc = self.to_dict()
        run_text = f"{self._scenario_text()}, {self.scenario.get('duration_s', 0):g} s"
        statement = self.objective.describe()
        tool = "railride tune" if command is not None else "railride.tuning.tune"
        lines = [
            f"# railride controller gains, tuned by `{tool}` (the paper's sensitivity study,",
            "# its section V; docs/tuning.md). Read by `railride compare --gains FILE`.",
            *([f"# command: {command}"] if command is not None else []),
            f"# date: {doc['date']}; railride {doc['railride_version']}",
            f"# scenario: {run_text}, dt {s['dt_s']:g} s, {describe_dampers(s, detail=True)}",
            f"# objective: {statement}",
            f"# phases: {', '.join(doc['phases'])}; {s['values']} values from 1/{s['span']:g} to "
            f"{s['span']:g} x the current value (and 0) per gain, passes: at most "
            f"{s['max_passes']}" + ("; the ride phase starts from zero ride gains" if "ride" in doc["phases"] else ""),
            f"# start values: {s['start_gains']}",
            f"# runs: {doc['runs']}; final objective: {finals}",
            "# Units: SI. Forces are desired forces on the carbody (up +) at corners 1R, 1L, 2R, 2L.",
            "",
            "[provenance]",
            f"method = {json.dumps(f'{tool} (one-at-a-time sensitivity study)')}",
            f"date = {json.dumps(doc['date'])}",
            f"railride_version = {json.dumps(doc['railride_version'])}",
            f"scenario = {json.dumps(run_text)}",
            f"damper = {json.dumps(s['damper'])}",
            f"damper_scale = {s.get('damper_scale', 1.0)!r}",
            f"dt_s = {s['dt_s']!r}",
            *([f"command = {json.dumps(command)}"] if command is not None else []),
            f"objective = {json.dumps(statement)}",
            # the exact track, so a study judging these gains can tell whether it is the same one
            f"scenario_record = {_toml_inline(doc['scenario'])}",
            f"phases = {json.dumps(doc['phases'])}",
            f"runs = {int(doc['runs'])}",
            f"start_gains = {json.dumps(s['start_gains'])}",
            "",
            self.gains.to_toml(),
        ]
        return "\n".join(lines)

    def to_pandas(self) -> pd.DataFrame:
        """The sensitivity curves as one long table, one row per value tried (curves.csv):
        ``phase``, ``pass``, ``parameter``, ``value``, ``objective``, ``chosen``
        (`railride.tables.curves_frame`)."""
        from .tables import curves_frame

        return curves_frame(self.curves)

    def plot(self, ax=None):
        """The sensitivity figure (`railride.plots.tuning.plot_sensitivity`): one panel per parameter,
        the objective against its value, one line per pass. ``ax``: one Axes per parameter, in
        the order tuned, or None for a new figure (titled with the scenario and the objective).
        Returns the figure."""
        from .plots.tuning import plot_sensitivity

        return plot_sensitivity(self.curves, title=self._title(), ax=ax)

    def save(self, folder, command: str | None = None, *, extra: dict | None = None) -> list:
        """gains.toml (`gains_toml` with ``command``), sensitivity.png (`plot`), curves.csv
        (`to_pandas`) and tune.json (`to_dict`, then the entries of ``extra``, such as a command
        line's facts) into ``folder``, all or nothing (each file replaced atomically; other
        files, such as the run table runs.csv, stay). Returns the paths."""
        from .files import write_tune_outputs

        doc = {**self.to_dict(), **(extra or {})}
        return write_tune_outputs(self.curves, folder, doc, self.gains_toml(command), title=self._title())

    def _scenario_text(self) -> str:
        from .labels import describe_scenario

        return describe_scenario(self.scenario)

    def _title(self) -> str:
        """The figure's title; the objective's statement is long: wrapped to fit the narrowest
        figure."""
        import textwrap

        return "\n".join(
            [
                (
                    f"Sensitivity of the tuning objective - {self._scenario_text()}, "
                    f"{self.scenario.get('duration_s', 0):g} s, {self.settings.get('damper')} dampers"
                ),
                *textwrap.wrap(f"phases {', '.join(self.phases)}; {self.objective.describe()}", 100),
            ]
        )


def _toml_inline(record: dict) -> str:
    """A flat record of strings, numbers and booleans as a TOML inline table (JSON spells those
    values as TOML does; None has no TOML form and is left out)."""
    items = [f"{k} = {json.dumps(v)}" for k, v in record.items() if v is not None and not isinstance(v, (dict, list))]
    return "{" + ", ".join(items) + "}"


def _utc_now() -> str:
    from datetime import datetime, timezone

    return datetime.now(timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")


def _rms(rows: pd.DataFrame) -> np.ndarray:
    return rows[[f"{r}_rms" for r in RESPONSES]].to_numpy()


def _candidates(current: float, parameter: str, n_values: int, span: float) -> list[float]:
    ref = current if current > 0 else REFERENCE[parameter]
    values = ref * np.logspace(-math.log10(span), math.log10(span), n_values)
    # four significant digits: gains a person can read and type, nothing lost to the study
    vals = sorted({0.0, float(current), *[float(f"{v:.4g}") for v in values]})
    if parameter == "inner.B":
        vals = [v for v in vals if v > 0]  # B = 0 ignores the measured force
    return vals


def tune(
    phases=PHASES,
    *,
    scenario: str = "paper-sine",
    scenario_options=None,
    gains: GainSet | None = None,
    objective: Objective | None = None,
    damper: str = DEFAULT_DAMPER,
    executor=None,
    table: RunTable | None = None,
    n_values: int = 13,
    span: float = 30.0,
    max_passes: int = 5,
    tol: float = 1e-3,
    params=None,
    solver=None,
    window=None,
    progress=None,
    log=None,
    damper_scale: float = 1.0,
    before_after: bool = True,
) -> TuneResult:
    """The sensitivity study: the phases in order (from PHASES; default all four, so PID and SAS
    are tuned by the same procedure and budget), each to convergence, from ``gains`` (default
    the neutral `GainSet.reference`), minimising ``objective`` (default `DEFAULT_OBJECTIVE`).

    ``n_values`` log-spaced values from 1/span to span times the current value (and 0) per
    parameter; a pass ends when every parameter of the phase was swept; a phase ends when a pass
    improves the objective by less than ``tol`` (relative) or after ``max_passes``. The ride
    phase starts from zero ride gains, as the paper's phase 2 (the ride loop is added to a tuned
    attitude loop), whatever ``gains`` holds for them. ``damper_scale`` scales the MR dampers'
    force capacity (`railride.dampers.BoucWen.scaled`); the inner phase then tracks demands
    scaled alike, so a damper k times larger is tuned on the same relative task. ``params``:
    the vehicle (`VehicleParams` or a preset name, default "paper"); ``solver``: the
    `SolverSettings` of every vehicle run; both are recorded in ``settings`` where they differ
    from the defaults. Every setting is checked before the first run.
    ``progress(done, total, runs_per_second)`` after each chunk; ``log(text)`` after each pass.

    ``before_after``: at the end, run each controller the phases change with the start and with
    the tuned gains (`TuneResult.before_after`; through the run table, where most of these runs
    already are). Returns a `TuneResult` (``to_dict``, ``to_pandas``, ``plot``, ``save``).
    """
    from .suspension import damper_model
    from .sweep import other_settings
    from .track import scenario as make_scenario

    solver = SolverSettings.of(solver)
    vehicle = VehicleParams.of(params)
    gains = GainSet.reference() if gains is None else gains
    objective = DEFAULT_OBJECTIVE if objective is None else objective
    opts = tuple(sorted((scenario_options or {}).items()))
    table = RunTable() if table is None else table
    unknown = [p for p in phases if p not in PHASES]
    if unknown:
        raise ValueError(f"unknown phase {unknown[0]!r}; allowed: {', '.join(PHASES)}, all")
    from . import dampers

    damper_model(damper, damper_scale)  # a known name, and a scale it has
    if "inner" in phases and damper in dampers.IDEAL_NAMES:
        raise ValueError(
            f"damper = {damper!r} with phase 'inner': the ideal actuator has no force "
            "tracking loop to tune; leave out the inner phase"
        )
    damper_scale = dampers.check_scale("damper_scale", damper_scale)
    validation.integer("n_values", n_values, 3)
    validation.integer("max_passes", max_passes, 1)
    if not validation.number("span", span, "finite", allowed="a finite number > 1") > 1:
        raise ValueError(f"span = {validation.shown(span)}: must be a finite number > 1")
    scen = make_scenario(scenario, **dict(scenario_options or {}))
    check_resolution(scen, solver.output_rate)
    record = scen.describe()
    base = gains
    result = TuneResult(
        gains,
        objective=objective,
        start=gains,
        phases=tuple(phases),
        scenario=record,
        settings={
            "damper": damper,
            "damper_scale": damper_scale,
            "dt_s": solver.dt,
            "values": n_values,
            "span": float(span),
            "max_passes": max_passes,
            "tolerance": tol,
            "start_gains": gains.source,
            **other_settings(vehicle, solver),
        },
    )

    def run(cases):
        return run_cases(
            cases,
            executor=executor,
            table=table,
            base_gains=base,
            params=vehicle,
            solver=solver,
            window=window,
            progress=progress,
        )

    passive = _rms(run([Case(scenario, opts)]))[0]
    result.passive = dict(zip(RESPONSES, passive))
    changes: dict[str, float] = {}

    def current_value(p):
        return changes.get(p, base.value(p))

    for phase in phases:
        params = PARAMETERS[phase]
        if phase == "inner":
            _tune_inner(base, changes, params, n_values, span, max_passes, tol, result, log, damper, damper_scale)
            continue
        suspension = SUSPENSION[phase]
        if phase == "ride":  # the paper's phase 2: the ride loop joins with zero gains
            changes.update(dict.fromkeys(params, 0.0))

        def score(change_sets, suspension=suspension):
            cases = [
                Case(
                    scenario,
                    opts,
                    suspension=suspension,
                    damper=damper,
                    damper_scale=damper_scale,
                    gains=tuple(sorted({**changes, **cs}.items())),
                )
                for cs in change_sets
            ]
            return objective(_rms(run(cases)), passive)

        best = float(score([{}])[0])
        for sweep_pass in range(1, max_passes + 1):
            start = best
            for p in params:
                vals = _candidates(current_value(p), p, n_values, span)
                obj = score([{p: v} for v in vals])
                k = int(np.argmin(obj))
                if obj[k] < best - 1e-12:
                    changes[p], best = vals[k], float(obj[k])
                result.curves.append(Curve(phase, sweep_pass, p, np.array(vals), np.asarray(obj), current_value(p)))
            result.history.append({"phase": phase, "pass": sweep_pass, "objective": best})
            if log is not None:
                log(f"{phase} pass {sweep_pass}: objective {best:.4f}")
            if start - best < tol * abs(start):
                break
    result.gains = base.apply(tuple(changes.items()))
    if before_after:
        result.before_after = _before_after(result, run, scenario, opts, damper, damper_scale)
    result.runs = table.frame
    result.date = _utc_now()
    return result


def _gain_changes(start: GainSet, tuned: GainSet, tables) -> tuple:
    """The ("table.entry", value) pairs of ``tuned`` that differ from ``start``, in ``tables``."""
    out = []
    for table in tables:
        a, b = start.table(table).to_dict(), tuned.table(table).to_dict()
        out += [(f"{table}.{k}", float(b[k])) for k in a if b[k] != a[k]]
    return tuple(sorted(out))


def _before_after(result: TuneResult, run, scenario, opts, damper, damper_scale) -> list[dict]:
    """RMS of each controller the phases change, with the start and with the tuned gains, and
    the reductions against passive; ``run`` evaluates cases through the study's run table."""
    names = [n for n in PAPER_CONTROLLERS if any(n in PHASE_CONTROLLERS[p] for p in result.phases)]
    cases = []
    for n in names:
        cases.append(Case(scenario, opts, suspension=n, damper=damper, damper_scale=damper_scale))
        cases.append(
            Case(
                scenario,
                opts,
                suspension=n,
                damper=damper,
                damper_scale=damper_scale,
                gains=_gain_changes(result.start or result.gains, result.gains, CONTROLLER_TABLES[n]),
            )
        )
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
    from . import dampers
    from .rig import track

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


def _tune_inner(base, changes, params, n_values, span, max_passes, tol, result, log, damper, damper_scale=1.0):
    """B and G on the rig's force-tracking error (cheap: evaluated here, not on the executor)."""

    def value(p):
        return changes.get(p, base.value(p))

    best = tracking_objective(value("inner.B"), value("inner.G"), damper, damper_scale)
    for sweep_pass in range(1, max_passes + 1):
        start = best
        for p in params:
            vals = _candidates(value(p), p, n_values, span)
            obj = np.array(
                [
                    tracking_objective(
                        **{"B": value("inner.B"), "G": value("inner.G"), p.split(".")[1]: v},
                        damper=damper,
                        damper_scale=damper_scale,
                    )
                    for v in vals
                ]
            )
            k = int(np.argmin(obj))
            if obj[k] < best - 1e-12:
                changes[p], best = vals[k], float(obj[k])
            result.curves.append(Curve("inner", sweep_pass, p, np.array(vals), obj, value(p)))
        result.history.append({"phase": "inner", "pass": sweep_pass, "objective": best})
        if log is not None:
            log(f"inner pass {sweep_pass}: tracking error {best:.4f}")
        if start - best < tol * abs(start):
            break
    return best
