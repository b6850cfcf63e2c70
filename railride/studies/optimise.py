"""Beyond the paper's sensitivity study: a global optimiser over all gains at once, and global
sensitivity indices.

Both search the gains in log10 space between REFERENCE / 1000 and REFERENCE x 100 (a gain of
exactly 0 is not reachable there; the one-at-a-time study of `railride.studies.tuning` includes 0).
Every generation of the optimiser and every block of the sensitivity sample is one call of
`railride.studies.sweep.run_cases`, so it runs as compiled batches, on a Dask cluster if asked, and
lands in the run table.

* `optimise`: SciPy's differential evolution (Storn and Price 1997) with ``vectorized=True``.
* `sensitivity`: first-order and total Sobol indices by SciPy's `scipy.stats.sobol_indices`
  (Saltelli 2010 sampling, Jansen / Saltelli estimators), with the gains uniform in log10.

Both minimise or analyse a named `railride.studies.tuning.Objective` (default `DEFAULT_OBJECTIVE`); the
results carry it (``objective_definition``) so its statement can be printed with them, and
follow the result protocol (``to_dict``, ``to_pandas``, ``plot(ax=None)``, ``save(folder)``):
`OptimiseResult` with the convergence of the search, `SensitivityResult` with the indices.
`railride.studies.pareto` samples the same search box.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import scipy.optimize

from railride.errors import InputError
from railride.secondary.control import GainSet
from railride.defaults import DEFAULT_DAMPER
from railride.run.solver import SolverSettings
from railride.studies.sweep import Case, RunTable, run_cases
from railride.studies.objectives import DEFAULT_OBJECTIVE, RMS_COLUMNS, Objective
from railride.plots import PNG_DPI, FigureOptions
from railride.studies.evolution import log_gain_bounds  # noqa: F401 (re-exported: its home before)
from railride.studies.tuning import PARAMETERS, _rms
from railride.secondary.suspension import damper_record

#: the paper's fourteen SAS parameters
SAS_PARAMETERS = PARAMETERS["sas-attitude-ride"]
#: the schemas of the documents of `OptimiseResult.to_dict` and `SensitivityResult.to_dict`
SCHEMA_OPTIMISE = "railride.optimise/1"
SCHEMA_SENSITIVITY = "railride.sensitivity/1"
#: the files `OptimiseResult.save` and `SensitivityResult.save` write, in this order
OPTIMISE_FILES = ("optimise.png", "optimise.csv", "optimise.json")
SENSITIVITY_FILES = ("sobol.png", "sobol.csv", "sobol.json")


class GainEvaluator:
    """objective(log10 gains) for a batch of points, through run_cases; `rms` gives the RMS
    of the four responses instead (the Pareto view). ``batches`` records, per call of the
    objective, the runs done so far and the lowest objective of the batch (the optimiser calls
    it once per generation)."""

    def __init__(
        self,
        parameters,
        suspension,
        scenario,
        scenario_options,
        gains,
        objective,
        damper,
        executor,
        table,
        progress,
        params=None,
        solver=None,
        vehicle_columns=None,
        costs: bool = False,
    ):
        self.parameters = tuple(parameters)
        self.suspension = suspension
        self.scenario = scenario
        self.opts = tuple(sorted((scenario_options or {}).items()))
        self.gains = GainSet.of(gains, scenario)
        self.objective = DEFAULT_OBJECTIVE if objective is None else objective
        if self.objective.columns != RMS_COLUMNS or self.objective.needs_costs:
            raise InputError(
                f"objective {self.objective.kind!r} with its bounds: the global optimiser scores the four RMS "
                "ratios only; tune these with the sensitivity study (railride.tune)"
            )
        self.damper = damper
        self.executor = executor
        self.table = RunTable() if table is None else table
        self.params = params
        self.solver = SolverSettings.of(solver)
        self.progress = progress
        self.vehicle_columns = vehicle_columns  # the vehicle's name and load in the run table (run_cases)
        # with ``costs``, every run also keeps what it asks of its dampers (its travel: `rms_travel`)
        self.costs = bool(costs)
        self.n_runs = 0
        self.batches: list[tuple[int, float]] = []
        passive = self._run([Case(scenario, self.opts)])
        self.passive = _rms(passive)[0]
        self.passive_travel = float(passive["travel_max_m"].iloc[0]) if self.costs else None

    def _run(self, cases):
        self.n_runs += len(cases)
        return run_cases(
            cases,
            executor=self.executor,
            table=self.table,
            base_gains=self.gains,
            params=self.params,
            solver=self.solver,
            progress=self.progress,
            vehicle_columns=self.vehicle_columns,
            costs=self.costs,
        )

    def cases(self, points: np.ndarray) -> list[Case]:
        """points (n, d) of log10 gains."""
        return [
            Case(
                self.scenario,
                self.opts,
                suspension=self.suspension,
                damper=self.damper,
                gains=tuple(zip(self.parameters, (10.0**p).tolist())),
            )
            for p in np.atleast_2d(points)
        ]

    def rms(self, cases: list[Case]) -> np.ndarray:
        """(n, 4) RMS of acceleration, displacement, pitch, roll of ``cases``."""
        return _rms(self._run(cases))

    def rms_travel(self, cases: list[Case]) -> tuple[np.ndarray, np.ndarray]:
        """((n, 4) RMS as `rms`, (n,) largest secondary travel [m]) of ``cases`` (needs ``costs``)."""
        frame = self._run(cases)
        return _rms(frame), frame["travel_max_m"].to_numpy(dtype=float)

    def __call__(self, points: np.ndarray) -> np.ndarray:
        values = self.objective(self.rms(self.cases(points)), self.passive)
        self.batches.append((self.n_runs, float(np.min(values))))
        return values

    def record(self, **settings) -> tuple[dict, dict]:
        """(the scenario's record, the study's settings with ``settings`` first): among them the
        base gains' record (``gains``, ``gains_provenance``, ``gains_values``: `GainSet.record`
        of the suspension; ``base_gains`` as ``gains``) and ``gains_varied``, the parameters
        the search sets instead."""
        from railride.model.params import VehicleParams
        from railride.studies.sweep import other_settings
        from railride.model.track import scenario as make_scenario

        scenario = make_scenario(self.scenario, **dict(self.opts)).describe()
        vehicle = (
            self.params if isinstance(self.params, VehicleParams) else VehicleParams.preset(self.params or "paper")
        )
        ran = self.gains.record([self.suspension])
        return scenario, {
            **settings,
            "damper": damper_record(self.damper),
            "dt_s": self.solver.dt,
            **self.solver.backend_record(),
            "base_gains": ran["source"],
            "gains": ran["source"],
            "gains_provenance": ran["provenance"],
            "gains_values": ran["values"],
            "gains_varied": list(self.parameters),
            **other_settings(vehicle, self.solver),
        }


def _parameter_rows(parameters) -> list[dict]:
    """Each parameter with its unit and the search box in SI."""
    from railride.analysis.labels import gain_unit

    return [
        {"name": p, "unit": gain_unit(p), "low": float(10.0**lo), "high": float(10.0**hi)}
        for p, (lo, hi) in zip(parameters, log_gain_bounds(parameters))
    ]


def _save(result, folder, files, figure_formats=("png",), dpi: float = PNG_DPI) -> list:
    """The ``files`` (png, csv, json) of a result into ``folder``, all or nothing
    (`railride.output.files.write_folder`): ``plot()`` (in each of ``figure_formats``, PNG at
    ``dpi``), ``to_pandas()`` and ``to_dict()``."""
    from railride.output.files import figure_files, json_text, write_folder

    figures = FigureOptions(figure_formats, dpi)
    text = json_text(result.to_dict())  # refuse NaN before any file is written
    frame = result.to_pandas()
    png, csv, doc = files
    return write_folder(
        folder,
        [
            *figure_files(png.rsplit(".", 1)[0], result.plot, figures),
            (csv, lambda path: frame.to_csv(path, index=False)),
            (doc, lambda path: path.write_text(text, encoding="utf-8")),
        ],
    )


@dataclass(frozen=True, eq=False)
class OptimiseResult:
    """The result of `optimise`: the tuned ``gains`` (the base gains with ``parameters`` at
    10 ** ``log10_gains``), the ``objective`` they reach (of ``objective_definition``), the
    ``n_runs`` evaluated (with the passive run), the ``generations`` and SciPy's ``message``.
    ``convergence`` (generations + 1, 2): per generation (0 the initial population) the runs
    done by its end and the lowest objective in it. ``suspension``, ``scenario`` (the
    `Scenario.describe` record) and ``settings``: what it ran with.

    The result protocol: `to_dict` (the ``railride.optimise/1`` document), `to_pandas` (the
    convergence table), `plot` (the convergence), `save` (optimise.png, optimise.csv,
    optimise.json).
    """

    gains: GainSet
    objective: float
    n_runs: int
    generations: int
    parameters: tuple
    log10_gains: np.ndarray
    message: str
    objective_definition: Objective | None = None  # what ``objective`` is the value of
    convergence: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    suspension: str | None = None
    scenario: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)

    def to_pandas(self) -> pd.DataFrame:
        """One row per generation (0 the initial population): ``generation``, ``runs`` done by
        its end, ``objective`` the lowest in it and ``best`` the lowest so far."""
        c = np.asarray(self.convergence, dtype=float).reshape(-1, 2)
        return pd.DataFrame(
            {
                "generation": np.arange(len(c)),
                "runs": c[:, 0].astype(int),
                "objective": c[:, 1],
                "best": np.minimum.accumulate(c[:, 1]),
            }
        )

    def to_dict(self) -> dict:
        """The ``railride.optimise/1`` document: the settings, the objective, each parameter with
        its search box and tuned value, the gains and the convergence (None for an objective
        that is not finite: a generation whose runs all diverged)."""
        from railride._version import __version__, versions
        from railride.secondary.provenance import stated_source

        rows = _parameter_rows(self.parameters)
        for row, lg in zip(rows, np.asarray(self.log10_gains, dtype=float)):
            row.update(value=float(10.0**lg), log10_value=float(lg))
        g = self.gains
        return {
            "schema": SCHEMA_OPTIMISE,
            "railride_version": __version__,
            "versions": versions(),
            "suspension": self.suspension,
            "scenario": self.scenario,
            "settings": self.settings,
            "objective": None if self.objective_definition is None else self.objective_definition.to_dict(),
            "objective_value": _finite(self.objective),
            "parameters": rows,
            "generations": int(self.generations),
            "runs": int(self.n_runs),
            "message": self.message,
            "gains": {
                # the base gains' source with the entries the search changed
                "source": stated_source(g),
                **{t: g.table(t).to_dict() for t in GainSet.TABLES},
            },
            "convergence": [
                {
                    "generation": int(r.generation),
                    "runs": int(r.runs),
                    "objective": _finite(r.objective),
                    "best": _finite(r.best),
                }
                for r in self.to_pandas().itertuples()
            ],
        }

    def plot(self, ax=None):
        """The objective against generation (`railride.plots.optimise.plot_convergence`); ``ax``
        None for a new figure, or one Axes. Returns the figure."""
        from railride.plots.optimise import plot_convergence

        return plot_convergence(self, ax=ax)

    def save(self, folder, *, figure_formats=("png",), dpi: float = PNG_DPI) -> list:
        """optimise.png, optimise.csv and optimise.json into ``folder``, all or nothing (other
        files stay); the figure in each of ``figure_formats`` (png, pdf, svg), PNG at ``dpi``.
        Returns the paths."""
        return _save(self, folder, OPTIMISE_FILES, figure_formats, dpi)


def optimise(
    parameters=SAS_PARAMETERS,
    *,
    suspension: str = "sas-attitude-ride",
    scenario: str = "paper-sine",
    scenario_options=None,
    gains: GainSet | None = None,
    objective: Objective | None = None,
    damper: str = DEFAULT_DAMPER,
    executor=None,
    table: RunTable | None = None,
    popsize: int = 8,
    maxiter: int = 30,
    seed: int = 0,
    params=None,
    solver=None,
    progress=None,
) -> OptimiseResult:
    """Differential evolution over ``parameters`` (names as in `railride.studies.tuning.PARAMETERS`)
    at once. ``popsize`` times the number of parameters runs per generation; ``seed`` makes the
    search repeatable. ``params``: the vehicle (`VehicleParams` or a preset name, default
    "paper"); ``solver``: the `SolverSettings` of every run."""
    ev = GainEvaluator(
        parameters,
        suspension,
        scenario,
        scenario_options,
        gains,
        objective,
        damper,
        executor,
        table,
        progress,
        params,
        solver,
    )
    res = scipy.optimize.differential_evolution(
        lambda x: ev(x.T),
        log_gain_bounds(parameters),
        vectorized=True,
        updating="deferred",
        popsize=popsize,
        maxiter=maxiter,
        seed=seed,
        polish=False,
        tol=1e-4,
    )
    tuned = ev.gains.apply(tuple(zip(parameters, (10.0**res.x).tolist())))
    record, settings = ev.record(popsize=popsize, maxiter=maxiter, seed=seed)
    return OptimiseResult(
        tuned,
        float(res.fun),
        ev.n_runs,
        int(res.nit),
        tuple(parameters),
        res.x,
        str(res.message),
        ev.objective,
        np.array(ev.batches, dtype=float),
        suspension,
        record,
        settings,
    )


@dataclass(frozen=True, eq=False)
class SensitivityResult:
    """The result of `sensitivity`: per parameter the ``first_order`` and ``total`` Sobol
    indices of the objective (``objective_definition``), from ``n_runs`` runs (with the passive
    run). ``suspension``, ``scenario`` (the `Scenario.describe` record) and ``settings``: what
    it ran with.

    The result protocol: `to_dict` (the ``railride.sensitivity/1`` document), `to_pandas` (the
    indices), `plot` (the indices as bars), `save` (sobol.png, sobol.csv, sobol.json).
    """

    parameters: tuple
    first_order: np.ndarray
    total: np.ndarray
    n_runs: int
    objective_definition: Objective | None = None  # the function the indices decompose
    suspension: str | None = None
    scenario: dict = field(default_factory=dict)
    settings: dict = field(default_factory=dict)

    def table(self) -> list[dict]:
        return [
            {"parameter": p, "first_order": float(s), "total": float(t)}
            for p, s, t in zip(self.parameters, self.first_order, self.total)
        ]

    def to_pandas(self) -> pd.DataFrame:
        """One row per parameter: ``parameter``, ``first_order``, ``total``."""
        return pd.DataFrame(self.table(), columns=["parameter", "first_order", "total"])

    def to_dict(self) -> dict:
        """The ``railride.sensitivity/1`` document: the settings, the objective and each
        parameter with its search box and indices (None for a NaN)."""
        from railride._version import __version__, versions

        rows = _parameter_rows(self.parameters)
        for row, s, t in zip(rows, self.first_order, self.total):
            row.update(first_order=_finite(s), total=_finite(t))
        return {
            "schema": SCHEMA_SENSITIVITY,
            "railride_version": __version__,
            "versions": versions(),
            "suspension": self.suspension,
            "scenario": self.scenario,
            "settings": self.settings,
            "objective": None if self.objective_definition is None else self.objective_definition.to_dict(),
            "runs": int(self.n_runs),
            "parameters": rows,
        }

    def plot(self, ax=None):
        """The first-order and total indices of each parameter as bars
        (`railride.plots.optimise.plot_indices`); ``ax`` None for a new figure, or one Axes.
        Returns the figure."""
        from railride.plots.optimise import plot_indices

        return plot_indices(self, ax=ax)

    def save(self, folder, *, figure_formats=("png",), dpi: float = PNG_DPI) -> list:
        """sobol.png, sobol.csv and sobol.json into ``folder``, all or nothing (other files
        stay); the figure in each of ``figure_formats`` (png, pdf, svg), PNG at ``dpi``.
        Returns the paths."""
        return _save(self, folder, SENSITIVITY_FILES, figure_formats, dpi)


def _finite(value) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


def sensitivity(
    parameters=SAS_PARAMETERS,
    *,
    suspension: str = "sas-attitude-ride",
    scenario: str = "paper-sine",
    scenario_options=None,
    gains: GainSet | None = None,
    objective: Objective | None = None,
    damper: str = DEFAULT_DAMPER,
    executor=None,
    table: RunTable | None = None,
    n: int = 64,
    seed: int = 0,
    params=None,
    solver=None,
    progress=None,
) -> SensitivityResult:
    """Sobol indices of the objective with every parameter uniform in log10 over the search
    bounds: n (d + 2) runs for d parameters (``n`` a power of two). ``params`` and ``solver``
    as for `optimise`."""
    if n < 2 or n & (n - 1):
        raise InputError(f"n = {n!r}: a power of two >= 2")
    ev = GainEvaluator(
        parameters,
        suspension,
        scenario,
        scenario_options,
        gains,
        objective,
        damper,
        executor,
        table,
        progress,
        params,
        solver,
    )
    import scipy.stats  # here, not at import: scipy.stats costs half a second to load

    dists = [scipy.stats.uniform(lo, hi - lo) for lo, hi in log_gain_bounds(parameters)]
    res = scipy.stats.sobol_indices(func=lambda x: ev(x.T), n=n, dists=dists, rng=np.random.default_rng(seed))
    record, settings = ev.record(n=n, seed=seed)
    return SensitivityResult(
        tuple(parameters),
        np.asarray(res.first_order),
        np.asarray(res.total_order),
        ev.n_runs,
        ev.objective,
        suspension,
        record,
        settings,
    )
