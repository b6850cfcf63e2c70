"""What a tuning study returns (`railride.studies.tuning.tune`): `TuneResult`, its sensitivity curves
(`Curve`) and the gains file it writes, with the provenance of every law's gains.

`TuneResult` follows the result protocol: `to_dict` (tune.json, schema ``railride.tune/3``),
`to_pandas` (curves.csv), `plot` (sensitivity.png, and `plot_pages` its further pages,
sensitivity_2.png, ...), `save` (the four files, all or nothing);
`gains_toml` is gains.toml with its provenance.
"""

from __future__ import annotations

import json
import textwrap
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from railride.secondary.control import GainSet
from railride.analysis.metrics import RESPONSES
from railride.studies.objectives import DEFAULT_OBJECTIVE, Objective
from railride.plots import PNG_DPI, FigureOptions

#: the schema of `TuneResult.to_dict` (tune.json)
SCHEMA = "railride.tune/3"


@dataclass
class Curve:
    """The sensitivity curve of one gain in one pass of one study: objective against value.
    ``controller``: the law whose study it belongs to, or "inner" (the inner loop on the rig)."""

    controller: str
    sweep_pass: int
    parameter: str
    values: np.ndarray
    objective: np.ndarray
    chosen: float


@dataclass
class Study:
    """How one law's gains were tuned: the gains varied (``entries``), the vehicle runs it
    used of its ``budget`` (``runs``: distinct gain sets scored, the start included), the
    ``passes`` begun, the objective at the start and at the end, the sweep's span factor at
    the end, and why it stopped (``stopped``: "budget", the next sweep would not fit, or
    "converged", the span narrowed below the study's floor). For "inner" (the force-tracking
    loop on the damper rig) ``runs`` counts rig evaluations and ``budget`` is None.

    ``optimiser``: "sensitivity" (the study above) or "evolution" (differential evolution,
    `railride.studies.evolution`): then ``passes`` counts generations, ``population`` is the
    gain sets of one, ``seed`` its seed, ``convergence`` per generation the runs done by its
    end and the best objective so far, ``span`` is NaN, and ``stopped`` is "budget"."""

    controller: str
    entries: tuple
    budget: int | None
    runs: int = 0
    passes: int = 0
    objective_start: float = float("nan")
    objective: float = float("nan")
    span: float = float("nan")
    stopped: str = ""
    optimiser: str = "sensitivity"
    population: int | None = None
    seed: int | None = None
    convergence: list = field(default_factory=list)

    def to_dict(self) -> dict:
        """The study's record; an evolution's also has ``optimiser``, ``population``, ``seed``
        and ``convergence`` (per generation: ``generation``, ``runs``, ``objective``)."""
        out = {
            "controller": self.controller,
            "entries": list(self.entries),
            "budget": self.budget,
            "runs": self.runs,
            "passes": self.passes,
            "objective_start": _finite(self.objective_start),
            "objective": _finite(self.objective),
            "span": _finite(self.span),
            "stopped": self.stopped,
        }
        if self.optimiser != "sensitivity":
            out.update(
                optimiser=self.optimiser,
                population=self.population,
                seed=self.seed,
                convergence=[
                    {"generation": i + 1, "runs": int(runs), "objective": _finite(best)}
                    for i, (runs, best) in enumerate(self.convergence)
                ],
            )
        return out


@dataclass(frozen=True, eq=False)
class TuneResult:
    """The result of `railride.studies.tuning.tune`: the tuned ``gains`` (the start gains ``start``
    with the changes the studies kept), one `Study` per law tuned (``studies``, in order), the
    sensitivity ``curves`` in the order they ran, the objective after each pass (``history``),
    the passive RMS by response (``passive``), the ``objective`` the vehicle studies minimised
    and the run table at the end (``runs``). The settings it ran with: ``controllers``,
    ``scenario`` (the `Scenario.describe` record) and ``settings`` (damper, damper_scale, dt_s,
    budget, values, span, tolerance, min_span, start_gains: the source of the start gains).
    ``before_after``: per law tuned, the RMS with the start and with the tuned gains and their
    reductions against passive. ``date``: when the study ended (UTC, ISO 8601)."""

    gains: GainSet
    curves: list[Curve] = field(default_factory=list)
    history: list[dict] = field(default_factory=list)
    studies: list[Study] = field(default_factory=list)
    runs: pd.DataFrame | None = None
    passive: dict = field(default_factory=dict)
    objective: Objective = DEFAULT_OBJECTIVE
    start: GainSet | None = None  # None: the gains are the start
    controllers: tuple = ()
    scenario: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    before_after: list[dict] = field(default_factory=list)
    date: str | None = None

    @property
    def n_runs(self) -> int:
        """Rows of the run table at the end (the studies' runs and the before/after runs)."""
        return 0 if self.runs is None else len(self.runs)

    def report_contents(self):
        """What this result shows in its HTML report (`railride.output.report.write_report`)."""
        from railride.output.report import tune_contents

        return tune_contents(self)

    def to_dict(self) -> dict:
        """The ``railride.tune/3`` document (docs/cli.md) without the facts of a command line
        (``runs_evaluated``, ``runs_per_second``, ``wall_time_s``, ``executor``, ``command``,
        which `railride tune` adds after ``runs``)."""
        from railride._version import __version__, versions

        start = self.gains if self.start is None else self.start
        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            "date": self.date,
            "controllers": list(self.controllers),
            "scenario": self.scenario,
            "settings": self.settings,
            "objective": self.objective.to_dict(),
            "passive_rms": {r: float(self.passive[r]) for r in RESPONSES},
            "studies": [s.to_dict() for s in self.studies],
            "history": [
                {
                    "controller": h["controller"],
                    "pass": int(h["pass"]),
                    "objective": _finite(h["objective"]),
                    "span": float(h["span"]),
                    "runs": int(h["runs"]),
                }
                for h in self.history
            ],
            "gains": {
                "source": start.source,
                **{t: self.gains.table(t).to_dict() for t in GainSet.TABLES},
            },
            "before_after": self.before_after,
            "runs": self.n_runs,
        }

    def gains_toml(self, command: str | None = None) -> str:
        """The gains file of the tuned gains with its provenance: a header of comments and a
        [provenance] table (scenario and its record, damper, step, objective, the vehicle's
        name, the load factor or factors, the scenarios and speeds, the laws tuned, the budget,
        start gains, date; ``command``, the command line that ran the study, when given), the
        vehicle's values ([provenance.vehicle_values]) and one [provenance.studies.NAME] table
        per law (`Study`), which `GainSet.load` keeps as ``provenance`` (`GainSet.mismatch`
        reads the vehicle, loads and tracks)."""
        from railride.analysis.labels import describe_dampers
        from railride.model.params import vehicle_text

        s = self.settings
        doc = self.to_dict()
        run_text = f"{self._scenario_text()}, {self.scenario.get('duration_s', 0):g} s"
        statement = self.objective.describe()
        tool = "railride tune" if command is not None else "railride.studies.tuning.tune"
        laws = [st for st in self.studies if st.controller != "inner"]
        evolution = s.get("optimiser", {}).get("name") == "evolution"
        how = (
            ["# differential evolution (Storn and Price 1997; SciPy), objective and budget of vehicle runs"]
            if evolution
            else [
                "# one-at-a-time",
                "# sensitivity study (the paper's section V), objective and budget of vehicle runs",
            ]
        )
        lines = [
            f"# railride controller gains, tuned by `{tool}`: every law by the same{how[0][1:]}",
            *how[1:],
            "# (docs/tuning.md). Read by `railride compare --gains FILE`.",
            *([f"# command: {command}"] if command is not None else []),
            f"# date: {doc['date']}; railride {doc['railride_version']}",
            f"# {'first run of the tuning set' if 'tuning_set' in s else 'scenario'}: {run_text}, dt {s['dt_s']:g} s, "
            f"{describe_dampers(s, detail=True)}",
            *([f"# {vehicle_text(s['vehicle'])}"] if s.get("vehicle") else []),
            f"# objective: {statement}",
            *(
                [
                    f"# tuning set: {len(s['tuning_set'])} runs per gain set ({_set_text(s['tuning_set'])}), "
                    f"objective: the {s['aggregate']} over them"
                ]
                if "tuning_set" in s
                else []
            ),
            *textwrap.wrap(
                f"study: each law from the start values, with at most {s['budget']} "
                + (f"gain sets ({len(s['tuning_set'])} runs each)" if "tuning_set" in s else "vehicle runs")
                + (self._evolution_text() if evolution else self._sensitivity_text()),
                98,
                initial_indent="# ",
                subsequent_indent="#   ",
            ),
            *(
                ["# inner loop: B and G on the damper rig's force tracking, shared by every law that tracks a force"]
                if "inner" in self.controllers
                else []
            ),
            *[
                f"#   {st.controller}: {len(st.entries)} gain{'s' * (len(st.entries) != 1)}, {st.runs} runs, "
                + (
                    f"{st.passes} generation{'s' * (st.passes != 1)} of {st.population}, "
                    if st.optimiser == "evolution"
                    else f"{st.passes} pass{'es' * (st.passes != 1)}, "
                )
                + f"objective {st.objective_start:.4g} -> {st.objective:.4g} ({st.stopped})"
                for st in laws
            ],
            f"# start values: {s['start_gains']}",
            "# Units: SI. Forces are desired forces on the carbody (up +) at corners 1R, 1L, 2R, 2L.",
            "",
            "[provenance]",
            f"method = {json.dumps(f'{tool} ({self._method()}, equal budget per law)')}",
            *([f"optimiser = {_toml_inline(s['optimiser'])}"] if evolution else []),
            f"date = {json.dumps(doc['date'])}",
            f"railride_version = {json.dumps(doc['railride_version'])}",
            f"scenario = {json.dumps(run_text)}",
            # a preset by its name; a damper object by its parameters (JSON's null is no TOML)
            f"damper = {_toml_inline(s['damper']) if isinstance(s['damper'], dict) else json.dumps(s['damper'])}",
            f"damper_scale = {s.get('damper_scale', 1.0)!r}",
            f"dt_s = {s['dt_s']!r}",
            *([f"command = {json.dumps(command)}"] if command is not None else []),
            f"objective = {json.dumps(statement)}",
            # the exact track, so a study judging these gains can tell whether it is the same one
            f"scenario_record = {_toml_inline(doc['scenario'])}",
            *(
                [
                    "tuning_set = [" + ", ".join(_toml_inline(r) for r in s["tuning_set"]) + "]",
                    f"aggregate = {json.dumps(s['aggregate'])}",
                ]
                if "tuning_set" in s
                else []
            ),
            # the vehicle, loads, scenarios and speeds it ran (`GainSet.mismatch` reads them)
            *self._case_lines(),
            # the laws whose gains these are (`GainSet.untuned` names the others)
            f"controllers = {json.dumps([c for c in self.controllers if c != 'inner'])}",
            f"inner_loop_tuned = {json.dumps('inner' in self.controllers)}",
            f"budget = {int(s['budget'])}",
            f"runs = {int(doc['runs'])}",
            f"start_gains = {json.dumps(s['start_gains'])}",
            "",
        ]
        values = (s.get("vehicle") or {}).get("values")
        if values:
            lines.append("[provenance.vehicle_values]")
            lines += [f"{k} = {_toml_value(v)}" for k, v in values.items() if v is not None]
            lines.append("")
        for st in self.studies:
            d = st.to_dict()
            lines.append(f"[provenance.studies.{st.controller}]")
            lines += [
                f"{k} = {_toml_value(v)}"
                for k, v in d.items()
                if k not in ("controller", "convergence") and v is not None
            ]
            lines.append("")
        lines.append(self.gains.to_toml(provenance=False))
        return "\n".join(lines)

    def to_pandas(self) -> pd.DataFrame:
        """The sensitivity curves as one long table, one row per value tried (curves.csv):
        ``controller``, ``pass``, ``parameter``, ``value``, ``objective``, ``chosen``
        (`railride.output.tables.curves_frame`)."""
        from railride.output.tables import curves_frame

        return curves_frame(self.curves)

    def plot(self, ax=None, *, page: int = 1):
        """The sensitivity figure (`railride.plots.tuning.plot_sensitivity`): one panel per gain,
        the objective against its value, one line per pass. ``ax``: one Axes per gain, in the
        order tuned, or None for a new figure (titled with the scenario and the objective) of
        page ``page`` (at most 12 panels a page; `plot_pages` draws them all). Returns the
        figure."""
        from railride.plots.tuning import plot_sensitivity

        return plot_sensitivity(self.curves, title=self._title(), ax=ax, page=page)

    def plot_pages(self) -> list:
        """Every page of the sensitivity figure, in order: what `save` writes as
        sensitivity.png, sensitivity_2.png, ... (`railride.plots.tuning.plot_sensitivity_pages`)."""
        from railride.plots.tuning import plot_sensitivity_pages

        return plot_sensitivity_pages(self.curves, title=self._title())

    def save(
        self,
        folder,
        command: str | None = None,
        *,
        extra: dict | None = None,
        figure_formats=("png",),
        dpi: float = PNG_DPI,
    ) -> list:
        """gains.toml (`gains_toml` with ``command``), sensitivity.png (`plot`; sensitivity_2.png,
        ... for the further pages of `plot_pages`; in each of
        ``figure_formats``, png, pdf, svg, PNG at ``dpi``), curves.csv (`to_pandas`) and
        tune.json (`to_dict`, then the entries of ``extra``, such as a command line's facts)
        into ``folder``, all or nothing (each file replaced atomically; other files, such as
        the run table runs.csv, stay). Returns the paths."""
        from railride.output.files import write_tune_outputs

        figures = FigureOptions(figure_formats, dpi)
        doc = {**self.to_dict(), **(extra or {})}
        gains = self.gains_toml(command)
        return write_tune_outputs(self.curves, folder, doc, gains, title=self._title(), figures=figures)

    def _method(self) -> str:
        if self.settings.get("optimiser", {}).get("name") == "evolution":
            return "differential evolution over each law's gains at once"
        return "one-at-a-time sensitivity study"

    def _sensitivity_text(self) -> str:
        s = self.settings
        return (
            f"; per gain and pass {s['values']} values from 1/{s['span']:g} to {s['span']:g} x the current value "
            f"(and 0); a pass that improves by less than {s['tolerance'] * 100:g} % narrows the span to "
            f"its square root; a study ends when its next sweep would not fit the budget "
            f"(budget) or the span falls below {s['min_span']:g} (converged)"
        )

    def _evolution_text(self) -> str:
        o = self.settings["optimiser"]
        return (
            f"; the start, then SciPy's differential evolution ({o['strategy']}, mutation "
            f"{o['mutation'][0]:g}-{o['mutation'][1]:g}, recombination {o['recombination']:g}, seed {o['seed']}) "
            f"over all of a law's gains at once, each in log10 from 1/1000 to 100 x its reference value; a "
            f"population of {o['population']}; generations: {o['generations']}; the best gain set scored is kept"
        )

    def _case_lines(self) -> list[str]:
        """The [provenance] lines of the case it tuned for: ``vehicle`` (the name of its record),
        ``load`` (a list for a robust tuning over several), ``scenarios`` and ``speeds_m_s``
        (those of the scenario, or of every run of the tuning set)."""
        vehicle = self.settings.get("vehicle") or {"name": "paper", "load": 1.0}
        records = self.settings.get("tuning_set") or [self.scenario]
        names = list(dict.fromkeys(r["name"] for r in records if "name" in r))
        speeds = list(dict.fromkeys(float(r["speed_m_s"]) for r in records if "speed_m_s" in r))
        return [
            f"vehicle = {json.dumps(str(vehicle['name']))}",
            f"load = {_toml_value(vehicle['load'])}",
            f"scenarios = {json.dumps(names)}",
            f"speeds_m_s = {json.dumps(speeds)}",
        ]

    def _scenario_text(self) -> str:
        from railride.analysis.labels import describe_scenario

        return describe_scenario(self.scenario)

    def _title(self) -> str:
        """The figure's title; the objective's statement is long: wrapped to fit the narrowest
        figure."""
        budget = self.settings.get("budget")
        return "\n".join(
            [
                (
                    f"Sensitivity of the tuning objective - {self._scenario_text()}, "
                    f"{self.scenario.get('duration_s', 0):g} s, {self.settings.get('damper')} dampers"
                ),
                # one line: the figure's title fits it to the page at spaces (a wrap here split
                # "clipped-optimal" at its hyphen)
                f"{', '.join(self.controllers)}; at most {budget} runs per law; {self.objective.describe()}",
            ]
        )


def _set_text(records) -> str:
    """A tuning set in a few words: its scenarios, seeds, speeds and loads."""
    parts = []
    keys = (
        ("name", ""),
        ("seed", "seeds "),
        ("start_m", "sections from s = "),
        ("speed_m_s", "speeds "),
        ("load", "loads "),
    )
    for key, label in keys:
        values = list(dict.fromkeys(r.get(key) for r in records if r.get(key) is not None))
        if values:
            unit = " m" if key == "start_m" else ""
            parts.append(label + ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in values) + unit)
    return "; ".join(parts)


def _finite(value) -> float | None:
    """A float for the JSON document, None for inf and NaN (a run that diverged scores J = inf)."""
    value = float(value)
    return value if np.isfinite(value) else None


def _toml_value(value) -> str:
    """A number, string, boolean or list of strings as TOML spells it (as JSON does, but
    TOML's inf and nan are bare words)."""
    if isinstance(value, float) and not np.isfinite(value):
        return "nan" if np.isnan(value) else ("inf" if value > 0 else "-inf")
    return json.dumps(value)


def _toml_inline(record: dict) -> str:
    """A flat record of strings, numbers and booleans as a TOML inline table (JSON spells those
    values as TOML does; None has no TOML form and is left out)."""
    items = [f"{k} = {json.dumps(v)}" for k, v in record.items() if v is not None and not isinstance(v, (dict, list))]
    return "{" + ", ".join(items) + "}"
