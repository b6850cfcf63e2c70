"""Every law's tuning in one batch a round (railride.studies.lockstep): the laws' searches step
together, each sees what it would see alone, and a law tuned beside others ends with exactly the
gains, objectives and curves it reaches alone."""

from __future__ import annotations

import numpy as np
import pytest

from railride.studies.lockstep import OwnChunks, lockstep
from railride.studies.sweep import CHUNK, GPU_CHUNK, Case, RunTable, _chunks
from railride.studies.tuning import PARAMETERS, tune, tuning_set

#: a robust tuning set of two cases (two seeds) of 1 s runs, and a budget of a few sweeps
SET = tuning_set("fra4", track_seeds=[0, 2], speeds=[40.0], duration=1.0)
SMALL = dict(over=SET, budget=16, n_values=3, before_after=False)


def _search(name, answers, rounds):
    """A fake search: asks ``rounds`` times for two gain sets, records what it is told."""
    for k in range(rounds):
        got = yield [{name: k}, {name: k + 0.5}]
        answers.append((k, list(got)))
    return f"{name} done"


def test_every_round_of_every_live_search_is_one_call_and_answers_go_home():
    calls, answers = [], {"a": [], "b": []}

    def score(asked):
        calls.append({n: [list(g.values())[0] for g in sets] for n, sets in asked.items()})
        return {n: np.array([hash(n) % 7, len(calls)]) for n in asked}

    out = lockstep({"a": _search("a", answers["a"], 3), "b": _search("b", answers["b"], 1)}, score)
    assert out == {"a": "a done", "b": "b done"}
    # round 1 asks both; b is done after it, so rounds 2 and 3 ask a alone
    assert [sorted(c) for c in calls] == [["a", "b"], ["a"], ["a"]]
    assert calls[0] == {"a": [0, 0.5], "b": [0, 0.5]} and calls[2] == {"a": [2, 2.5]}
    assert [k for k, _ in answers["a"]] == [0, 1, 2] and answers["a"][1][1] == [hash("a") % 7, 2]


def test_an_error_closes_every_search():
    closed = []

    def search(name):
        try:
            yield [{name: 1.0}]
            yield [{name: 2.0}]
        finally:
            closed.append(name)

    def score(asked):
        if len(closed) == 0 and any(list(s[0].values())[0] == 2.0 for s in asked.values()):
            raise KeyboardInterrupt
        return {n: np.zeros(1) for n in asked}

    with pytest.raises(KeyboardInterrupt):
        lockstep({"a": search("a"), "b": search("b")}, score)
    assert sorted(closed) == ["a", "b"]


def test_each_law_runs_in_the_chunks_its_own_call_would_make():
    def cases(name, n):
        return [
            Case("fra4", (("seed", s), ("speed", 40.0)), suspension=name, gains=((f"{name}.x", float(k)),))
            for k in range(n)
            for s in (0, 2)
        ]

    parts = [cases("pid", 20), cases("sas-attitude", 9)]
    mixed = _chunks([c for p in parts for c in p], CHUNK)  # what run_cases hands its executor

    class Record:
        def map(self, fn, chunks):
            self.chunks = chunks
            return iter(())

    inner = Record()
    list(OwnChunks(inner, parts).map(None, mixed))
    got = [[c.key for c in ch] for ch in inner.chunks]
    assert sorted(got) == sorted([c.key for c in ch] for p in parts for ch in _chunks(p, CHUNK))
    assert any(len({c.suspension for c in ch}) > 1 for ch in mixed)  # mixing is what it undoes
    # the laws' chunks in the order of the tables they read: both laws' chunks on seed 0, then seed 2
    seeds = [dict(ch[0].scenario_options)["seed"] for ch in inner.chunks]
    assert seeds == [0, 0, 2] and {ch[0].suspension for ch in inner.chunks[:2]} == {"pid", "sas-attitude"}

    # GPU batches: a run is one thread with no batch-mates, so every law's runs go in one batch
    on_gpu = OwnChunks(inner, parts)
    on_gpu.chunk, on_gpu.on_gpu = GPU_CHUNK, True  # as run_cases sets them when the GPU takes the batches
    list(on_gpu.map(None, mixed))
    assert len(inner.chunks) == 1 and sorted(c.key for c in inner.chunks[0]) == sorted(c.key for p in parts for c in p)


def _law(result, name):
    study = next(s for s in result.studies if s.controller == name)
    own = {p: result.gains.value(p) for p in PARAMETERS[name]}
    curves = [
        (c.sweep_pass, c.parameter, c.values.tolist(), c.objective.tolist(), c.chosen)
        for c in result.curves
        if c.controller == name
    ]
    history = [h for h in result.history if h["controller"] == name]
    return study.to_dict(), own, curves, history


def test_a_law_tuned_beside_others_ends_exactly_where_it_ends_alone():
    alone = tune(["pid"], **SMALL)
    together = tune(["pid", "sas-attitude", "skyhook"], **SMALL)
    assert _law(together, "pid") == _law(alone, "pid")
    # every law's runs are the same runs, to the last bit, as in the table of the law alone
    table = RunTable()
    tune(["skyhook"], table=table, **SMALL)
    ours = together.runs.set_index("key")
    theirs = table.frame.set_index("key")
    common = theirs.index.intersection(ours.index)
    assert len(common) == len(theirs)
    cols = [c for c in theirs.columns if c.endswith("_rms") or c.endswith("_ptp")]
    assert (ours.loc[common, cols].to_numpy() == theirs.loc[common, cols].to_numpy()).all()


@pytest.mark.filterwarnings("ignore::railride.errors.TuningWarning")  # the inner loop not tuned
def test_on_the_gpu_every_law_of_a_round_is_one_batch_and_each_law_ends_as_alone(monkeypatch):
    # a run is one GPU thread, so the laws' runs share one batch (each table built once a round)
    # and every law still ends exactly where it ends tuned alone (the CUDA simulator here)
    from railride.run import reduced
    from railride.run.simulation import stepped_on
    from railride.run.solver import SolverSettings

    batches = []
    metrics = reduced.batch_metrics

    def counted(plan, *args, **kw):
        if stepped_on(plan) == "gpu":  # passive's exact steps are the CPU's, summed there too
            batches.append(sorted({s.label for s in plan.suspensions}))
        return metrics(plan, *args, **kw)

    monkeypatch.setattr(reduced, "batch_metrics", counted)
    tiny = dict(
        over=tuning_set("fra4", track_seeds=[0], speeds=[40.0], duration=0.02),
        budget=9,
        n_values=3,
        before_after=False,
        solver=SolverSettings(backend="gpu"),
    )
    together = tune(["pid", "skyhook"], **tiny)
    assert batches and all(b == ["PID", "Skyhook"] for b in batches)
    alone = tune(["skyhook"], **tiny)
    assert _law(together, "skyhook") == _law(alone, "skyhook")
