"""Beyond the paper's sensitivity study: a global optimiser over all gains at once, and global
sensitivity indices.

Both search the gains in log10 space between REFERENCE / 1000 and REFERENCE x 100 (a gain of
exactly 0 is not reachable there; the one-at-a-time study of `railride.tuning` includes 0).
Every generation of the optimiser and every block of the sensitivity sample is one call of
`railride.sweep.run_cases`, so it runs as compiled batches, on a Dask cluster if asked, and
lands in the run table.

* `optimise`: SciPy's differential evolution (Storn and Price 1997) with ``vectorized=True``.
* `sensitivity`: first-order and total Sobol indices by SciPy's `scipy.stats.sobol_indices`
  (Saltelli 2010 sampling, Jansen / Saltelli estimators), with the gains uniform in log10.

Both minimise or analyse a named `railride.tuning.Objective` (default `DEFAULT_OBJECTIVE`); the
results carry it (``objective_definition``) so its statement can be printed with them.
`railride.pareto` samples the same search box.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.optimize

from .control import GainSet
from .defaults import DEFAULT_DAMPER
from .solver import SolverSettings
from .sweep import Case, RunTable, run_cases
from .objectives import DEFAULT_OBJECTIVE, Objective
from .tuning import PARAMETERS, REFERENCE, _rms

#: the paper's fourteen SAS parameters
SAS_PARAMETERS = PARAMETERS["attitude"] + PARAMETERS["ride"]


def _bounds(parameters):
    """(low, high) log10 of each parameter: REFERENCE / 1000 to REFERENCE x 100."""
    return [(math.log10(REFERENCE[p] / 1e3), math.log10(REFERENCE[p] * 1e2)) for p in parameters]


class _Evaluator:
    """objective(log10 gains) for a batch of points, through run_cases; `rms` gives the RMS
    of the four responses instead (the Pareto view)."""

    def __init__(self, parameters, suspension, scenario, scenario_options, gains, objective,
                 damper, executor, table, progress, params=None, solver=None):
        self.parameters = tuple(parameters)
        self.suspension = suspension
        self.scenario = scenario
        self.opts = tuple(sorted((scenario_options or {}).items()))
        self.gains = GainSet.default() if gains is None else gains
        self.objective = DEFAULT_OBJECTIVE if objective is None else objective
        self.damper = damper
        self.executor = executor
        self.table = RunTable() if table is None else table
        self.params = params
        self.solver = SolverSettings.of(solver)
        self.progress = progress
        self.n_runs = 0
        self.passive = _rms(self._run([Case(scenario, self.opts)]))[0]

    def _run(self, cases):
        self.n_runs += len(cases)
        return run_cases(cases, executor=self.executor, table=self.table, base_gains=self.gains,
                         params=self.params, solver=self.solver, progress=self.progress)

    def cases(self, points: np.ndarray) -> list[Case]:
        """points (n, d) of log10 gains."""
        return [Case(self.scenario, self.opts, suspension=self.suspension, damper=self.damper,
                     gains=tuple(zip(self.parameters, (10.0 ** p).tolist())))
                for p in np.atleast_2d(points)]

    def rms(self, cases: list[Case]) -> np.ndarray:
        """(n, 4) RMS of acceleration, displacement, pitch, roll of ``cases``."""
        return _rms(self._run(cases))

    def __call__(self, points: np.ndarray) -> np.ndarray:
        return self.objective(self.rms(self.cases(points)), self.passive)


@dataclass
class OptimiseResult:
    gains: GainSet
    objective: float
    n_runs: int
    generations: int
    parameters: tuple
    log10_gains: np.ndarray
    message: str
    objective_definition: Objective | None = None  # what ``objective`` is the value of


def optimise(parameters=SAS_PARAMETERS, *, suspension: str = "sas-attitude-ride",
             scenario: str = "paper-sine", scenario_options=None, gains: GainSet | None = None,
             objective: Objective | None = None, damper: str = DEFAULT_DAMPER, executor=None,
             table: RunTable | None = None, popsize: int = 8, maxiter: int = 30, seed: int = 0,
             params=None, solver=None, progress=None) -> OptimiseResult:
    """Differential evolution over ``parameters`` (names as in `railride.tuning.PARAMETERS`)
    at once. ``popsize`` times the number of parameters runs per generation; ``seed`` makes the
    search repeatable. ``params``: the vehicle (`VehicleParams` or a preset name, default
    "paper"); ``solver``: the `SolverSettings` of every run."""
    ev = _Evaluator(parameters, suspension, scenario, scenario_options, gains, objective, damper,
                    executor, table, progress, params, solver)
    res = scipy.optimize.differential_evolution(
        lambda x: ev(x.T), _bounds(parameters), vectorized=True, updating="deferred",
        popsize=popsize, maxiter=maxiter, seed=seed, polish=False, tol=1e-4)
    tuned = ev.gains.apply(tuple(zip(parameters, (10.0 ** res.x).tolist())))
    return OptimiseResult(tuned, float(res.fun), ev.n_runs, int(res.nit), tuple(parameters),
                          res.x, str(res.message), ev.objective)


@dataclass
class SensitivityResult:
    parameters: tuple
    first_order: np.ndarray
    total: np.ndarray
    n_runs: int
    objective_definition: Objective | None = None  # the function the indices decompose

    def table(self) -> list[dict]:
        return [{"parameter": p, "first_order": float(s), "total": float(t)}
                for p, s, t in zip(self.parameters, self.first_order, self.total)]


def sensitivity(parameters=SAS_PARAMETERS, *, suspension: str = "sas-attitude-ride",
                scenario: str = "paper-sine", scenario_options=None, gains: GainSet | None = None,
                objective: Objective | None = None, damper: str = DEFAULT_DAMPER, executor=None,
                table: RunTable | None = None, n: int = 64, seed: int = 0, params=None, solver=None,
                progress=None) -> SensitivityResult:
    """Sobol indices of the objective with every parameter uniform in log10 over the search
    bounds: n (d + 2) runs for d parameters (``n`` a power of two). ``params`` and ``solver``
    as for `optimise`."""
    if n < 2 or n & (n - 1):
        raise ValueError(f"n = {n!r}: a power of two >= 2")
    ev = _Evaluator(parameters, suspension, scenario, scenario_options, gains, objective, damper,
                    executor, table, progress, params, solver)
    import scipy.stats  # here, not at import: scipy.stats costs half a second to load

    dists = [scipy.stats.uniform(lo, hi - lo) for lo, hi in _bounds(parameters)]
    res = scipy.stats.sobol_indices(func=lambda x: ev(x.T), n=n, dists=dists,
                                    rng=np.random.default_rng(seed))
    return SensitivityResult(tuple(parameters), np.asarray(res.first_order),
                             np.asarray(res.total_order), ev.n_runs, ev.objective)
