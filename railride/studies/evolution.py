"""A population optimiser beside the paper's sensitivity study: SciPy's differential evolution
(Storn and Price 1997; `scipy.optimize.differential_evolution`, ``vectorized=True``,
``updating="deferred"``) over all of one law's gains at once, with the same objective, runs and
budget of gain sets as the study (`railride.studies.tuning.tune` with ``optimiser="evolution"``).

The search box is that of `railride.studies.optimise`: every gain in log10 space from 1/1000 to
100 times its reference value (`log_gain_bounds`), the top lowered to the largest value its
table allows (a blend's 1). A gain of exactly 0 is out of reach. Each candidate is rounded to four
significant digits, as the study's are, so the gains it reports are the ones it ran.

The budget is spent as the study spends it: the start gain set first (one gain set, the study's
start), then a population of `sizes` members, generation after generation (the first one a
seeded Latin hypercube), as many whole generations as the rest of the budget holds. SciPy's own
convergence test is off (``tol = 0``), so the search runs to its budget; the result is the best
gain set scored, the start included.

`search` is a generator, as the study's sweeps are (`railride.studies.tuning`): it yields each
generation's gain sets and receives their objectives, so that `tune` runs the generations of
every law as one batch. SciPy's optimiser calls its objective; it runs in a thread of its own
that waits for each batch's scores, so the search is SciPy's, step for step, and repeatable for
a seed.
"""

from __future__ import annotations

import math
import queue
import threading
from collections.abc import Generator

import numpy as np

from railride.errors import InputError
from railride.secondary.control import GainSet
from railride.studies.tune_result import Study

#: the tuning methods of `railride.studies.tuning.tune` and `railride.studies.design.design`: the
#: paper's one-at-a-time sensitivity study, or differential evolution
OPTIMISERS = ("sensitivity", "evolution")
#: members of the population per gain (SciPy's ``popsize``) while the budget allows it
POPSIZE = 5
#: the fewest generations (the first, random one included) the budget must hold: the population
#: is at most (budget - 1) / MIN_GENERATIONS members
MIN_GENERATIONS = 10
#: SciPy's smallest population
MIN_POPULATION = 5
#: the smallest budget the search takes: the start and two generations of the smallest population
MIN_BUDGET = 1 + 2 * MIN_POPULATION
#: SciPy's settings of the search, as SciPy names them (its defaults but ``tol``, which is off)
SETTINGS = {"strategy": "best1bin", "mutation": [0.5, 1.0], "recombination": 0.7, "tol": 0.0, "polish": False}
#: what a gain set whose runs diverged scores inside the search (SciPy's convergence measure
#: needs finite values); the study records inf
DIVERGED = 1e9

_REFERENCE = GainSet.reference()


def _allowed(parameter: str, value: float) -> bool:
    table, _, entry = parameter.partition(".")
    try:
        _REFERENCE.table(table).replace(**{entry: value})
    except (ValueError, InputError):
        return False
    return True


def log_gain_bounds(parameters) -> list[tuple[float, float]]:
    """(low, high) log10 of each parameter: its reference value (`GainSet.reference`) / 1000 to
    x 100, the top lowered to the largest value its table allows (a blend's 1)."""
    reference = _REFERENCE.entries()
    out = []
    for p in parameters:
        low, high = math.log10(reference[p] / 1e3), math.log10(reference[p] * 1e2)
        if not _allowed(p, 10.0**high):
            ok = math.log10(reference[p])  # allowed: the reference itself
            for _ in range(60):  # bisect for the largest allowed value
                mid = 0.5 * (ok + high)
                ok, high = (mid, high) if _allowed(p, 10.0**mid) else (ok, mid)
            high = ok
        out.append((low, high))
    return out


def sizes(n_gains: int, budget: int) -> tuple[int, int]:
    """(population, generations) of a law with ``n_gains`` gains and ``budget`` gain sets: the
    population is `POPSIZE` per gain, at most (budget - 1) / `MIN_GENERATIONS` and at least
    `MIN_POPULATION`; the generations (the first included) are as many as budget - 1 holds
    whole (the one is the start)."""
    population = max(MIN_POPULATION, min(POPSIZE * n_gains, (budget - 1) // MIN_GENERATIONS))
    return population, (budget - 1) // population


#: why a budget below `MIN_BUDGET` is refused
BUDGET_RULE = f"with optimiser = 'evolution': the start and two generations of {MIN_POPULATION} gain sets"


def record(seed: int) -> dict:
    """The search's settings, for a result's record: the name, the seed, how the population and
    the generations follow from the budget, and SciPy's settings."""
    return {
        "name": "evolution",
        "method": "scipy.optimize.differential_evolution (vectorized, updating='deferred')",
        "seed": seed,
        "population": (
            f"{POPSIZE} gain sets per gain, at most (budget - 1) / {MIN_GENERATIONS}, at least {MIN_POPULATION}"
        ),
        "generations": "as many whole ones as budget - 1 holds, the first a Latin hypercube",
        "box": "log10, reference / 1000 to reference x 100",
        **SETTINGS,
    }


class _Cancelled(Exception):
    """Sent to SciPy's thread when the search is closed before its end."""


def _rounded(parameters, box, point) -> dict:
    """The gains of a point of log10 values, to four significant digits, within the box."""
    out = {}
    for p, (_, high), x in zip(parameters, box, point):
        v = float(f"{10.0 ** float(x):.4g}")
        out[p] = v if _allowed(p, v) else float(10.0**high)
    return out


def search(
    name: str, parameters, start: dict, budget: int, seed: int, log=None
) -> Generator[list[dict], np.ndarray, tuple[Study, dict]]:
    """Differential evolution over ``parameters`` (the law ``name``'s gains, by "table.entry") as
    a generator: yields gain sets (every gain of the law, by "table.entry") and receives their
    objectives (an array, inf where a run diverged): first ``start``, then each generation.
    Returns the `Study` (``passes``: the generations; ``convergence``: per generation the runs
    done and the best objective so far) and the best gain set scored; ``log(text)`` after each
    generation."""
    import scipy.optimize
    import scipy.stats.qmc

    parameters = tuple(parameters)
    box = log_gain_bounds(parameters)
    population, generations = sizes(len(parameters), budget)
    study = Study(name, parameters, budget, optimiser="evolution", population=population, seed=seed)
    start = {**start}
    score = float(np.asarray((yield [start]))[0])
    seen = {tuple(sorted(start.items()))}  # the distinct gain sets scored: the study's runs
    study.runs, study.objective_start = 1, score
    best, best_gains = score, start
    lows, highs = np.array(box).T
    init = lows + (highs - lows) * scipy.stats.qmc.LatinHypercube(len(parameters), seed=seed).random(population)

    asks: queue.Queue = queue.Queue()
    replies: queue.Queue = queue.Queue()

    def objective(x: np.ndarray) -> np.ndarray:  # SciPy's thread: (gains, members) -> (members,)
        asks.put(("ask", [_rounded(parameters, box, col) for col in np.atleast_2d(x).T]))
        reply = replies.get()
        if isinstance(reply, BaseException):
            raise reply
        return reply

    def run() -> None:
        try:
            scipy.optimize.differential_evolution(
                objective,
                box,
                vectorized=True,
                updating="deferred",
                seed=seed,
                init=init,
                maxiter=generations - 1,
                atol=0.0,
                **SETTINGS,
            )
            asks.put(("done", None))
        except _Cancelled:
            pass
        except BaseException as e:  # pragma: no cover - SciPy's own failure, raised in the caller
            asks.put(("error", e))

    thread = threading.Thread(target=run, name=f"evolution {name}", daemon=True)
    thread.start()
    finished = False
    try:
        while True:
            kind, payload = asks.get()
            if kind == "error":
                raise payload
            if kind == "done":
                finished = True
                break
            scores = np.asarray((yield payload), dtype=float)
            seen.update(tuple(sorted(g.items())) for g in payload)
            study.runs = len(seen)
            study.passes += 1
            for gains, value in zip(payload, scores):
                if value < best - 1e-12:
                    best, best_gains = float(value), gains
            study.convergence.append((study.runs, best))
            if log is not None:
                log(f"{name} generation {study.passes}: objective {best:.4g} ({study.runs} runs)")
            replies.put(np.where(np.isfinite(scores), scores, DIVERGED))
    finally:
        if not finished:
            replies.put(_Cancelled())
        thread.join()
    study.objective, study.stopped = best, "budget"
    return study, best_gains
