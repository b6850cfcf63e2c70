"""Batches in threads of one process share numba's threads (`railride.run.cores`): those that
fill them step one at a time, smaller ones beside each other; a study's chunks step on the
caller's thread count and give the same rows as one after another."""

import threading

import numba
import numpy as np
import pandas as pd
import pytest

from railride.engine.lanes import LANES
from railride.model.params import VehicleParams
from railride.model.track import scenario
from railride.run import simulation
from railride.secondary.suspension import Suspension
from railride.studies.executors import LocalExecutor
from railride.studies.study import study


def _batch(seed: int, n: int | None = None):
    """n runs (default: enough to fill numba's threads, one per run below `lanes.LANES` runs, one
    per group of LANES above)."""
    if n is None:
        threads = max(2, numba.get_num_threads())
        n = threads if threads < LANES else threads * LANES
    susp = Suspension.named("sas-attitude")
    scs = [scenario("fra4", seed=seed + k, speed=40.0, duration=0.5) for k in range(n)]
    return simulation.simulate(scs, [VehicleParams.of("paper")] * n, [susp] * n)


def _watch(monkeypatch) -> list:
    """[how many batches were stepping when it began, ended] of every step stage; the first
    waits up to 1 s for another to begin beside it."""
    intervals, step = [], simulation.step
    beside = threading.Event()

    def watched(*args, **kwargs):
        me = [sum(1 for _, end in intervals if end is None), None]  # how many were stepping
        intervals.append(me)
        if me[0]:
            beside.set()
        if len(intervals) == 1:  # the first waits for another to step beside it: none may
            beside.wait(timeout=1.0)
        try:
            return step(*args, **kwargs)
        finally:
            me[1] = True

    monkeypatch.setattr(simulation, "step", watched)
    return intervals


def test_batches_that_fill_the_threads_step_one_after_another(monkeypatch):
    _batch(0)  # compiled before the threads start
    intervals = _watch(monkeypatch)
    results: dict = {}
    threads = [threading.Thread(target=lambda k=k: results.setdefault(k, _batch(10 * k))) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(intervals) == 4
    # each batch found no other stepping when it began
    assert [entered for entered, _ in intervals] == [0, 0, 0, 0]
    # and the results are those of the batches run alone
    for k in range(4):
        alone = _batch(10 * k)
        np.testing.assert_array_equal(results[k]._raw["q"], alone._raw["q"])


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="one thread: no room beside a batch")
def test_batches_that_leave_threads_free_step_beside_each_other(monkeypatch):
    _batch(0, 1)
    intervals = _watch(monkeypatch)
    threads = [threading.Thread(target=lambda k=k: _batch(10 * k, 1)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(entered for entered, _ in intervals) == [0, 1]
    assert simulation.CPU_THREADS.used == 0


def test_the_chunks_step_on_the_callers_thread_count():
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        seen = list(LocalExecutor(ahead=1).map(lambda chunk: numba.get_num_threads(), range(3)))
    finally:
        numba.set_num_threads(threads)
    assert seen == [(0, 1), (1, 1), (2, 1)]


def test_a_progress_callback_may_run_a_batch_itself():
    inner = []

    def progress(fraction):
        if not inner:  # in the stepping of the outer batch: the gate lets its own thread in
            inner.append(_batch(5))

    susp = Suspension.named("pid")
    res = simulation.simulate(scenario("fra4", seed=1, speed=40.0, duration=0.5), "paper", susp, progress=progress)
    assert inner and np.all(np.isfinite(res._raw["q"]))


def test_a_study_in_threads_equals_one_chunk_after_another():
    options = dict(track_seeds=[0, 1, 2], speeds=[40.0], loads=[1.0, 1.3], duration=1.0, progress=False)
    laws = ["pid", "sas-attitude"]
    threaded = study(laws, executor=LocalExecutor(ahead=2), **options)
    serial = study(laws, executor=LocalExecutor(ahead=0), **options)
    pd.testing.assert_frame_equal(threaded.cases, serial.cases)
    pd.testing.assert_frame_equal(threaded.summary, serial.summary)


def test_the_exact_steps_on_threads_equal_them_one_after_another():
    """The exact steps run a batch's samples on numba's threads: the same arrays as on one
    thread, a diverging sample (the shipped groundhook on the ideal actuator) marked as there."""
    import numba

    scs = [scenario("fra4", seed=s, speed=40.0, duration=1.0) for s in range(4)]
    params = [VehicleParams.of("paper")] * 4
    names = ("pid", "groundhook", "sas-attitude", "skyhook")
    closed = [Suspension.named(n, damper="ideal") for n in names]

    def both():
        return (
            simulation.simulate(scs, params),
            simulation.simulate(scs, params, closed, on_divergence="mark"),
        )

    threaded = both()
    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        alone = both()
    finally:
        numba.set_num_threads(threads)
    for many, one in zip(threaded, alone):
        assert many.dataset.attrs["integrator"].startswith("exact discretisation")
        for key in ("q", "a"):
            np.testing.assert_array_equal(many._raw[key], one._raw[key])
        np.testing.assert_array_equal(many.diverged_at, one.diverged_at)
    assert np.isfinite(threaded[1].diverged_at[1]) and np.isnan(threaded[1].diverged_at[[0, 2, 3]]).all()


def test_enough_chunks_ahead_to_fill_the_threads():
    # a 32-run chunk on the lane stepper steps on one thread per group of 8 runs: 4 threads, so
    # 16 threads want four chunks stepping beside the one whose rows are made; one chunk ahead
    # would hold at most 8. Never fewer than one: a chunk's rows overlap the next one's stepping
    from railride.studies.executors import chunks_ahead

    assert [chunks_ahead(t) for t in (1, 2, 4, 8, 16, 64)] == [1, 1, 1, 2, 4, 16]
    # without a chunk whose rows are made beside the stepping ones (a design's): one less
    assert [chunks_ahead(t, rows_beside=False) for t in (1, 2, 4, 8, 16, 64)] == [0, 0, 0, 1, 3, 15]
    assert LocalExecutor().ahead == chunks_ahead(numba.get_num_threads())
    assert LocalExecutor(rows_beside=False).ahead == chunks_ahead(numba.get_num_threads(), rows_beside=False)
    assert LocalExecutor(0).ahead == 0 and LocalExecutor(3).ahead == 3


def test_the_chunks_in_flight_fit_the_memory_limit(monkeypatch):
    # each chunk in flight holds its runs' histories: no more of them than the memory limit
    # holds, and at least one (whose own size each run checks)
    from railride.limits import memory_limit
    from railride.studies.sweep import grid, run_sweep

    with memory_limit("100M"):
        assert LocalExecutor(4).bounded(30 * 2**20).ahead == 2  # three chunks of 30 MiB
        assert LocalExecutor(4).bounded(60 * 2**20).ahead == 0  # one
        assert LocalExecutor(1).bounded(2**20).ahead == 1  # never more than asked
    used = []
    map_ = LocalExecutor.map

    def recorded(self, fn, chunks):
        used.append(self.ahead)
        return map_(self, fn, chunks)

    monkeypatch.setattr(LocalExecutor, "map", recorded)
    # 40 runs of 1 s: chunks of 32 runs hold 32 x 1,001 rows x 70 channels, 18 MB each
    g = grid(["pid"], speed=[30.0 + k for k in range(40)], duration=1.0)
    rows = {}
    for limit in ("30M", "64M"):
        with memory_limit(limit):
            rows[limit] = run_sweep(g, executor=LocalExecutor(3), progress=False, comfort=False).to_pandas()
    assert used == [0, 2]  # one chunk fits 30 MB, three fit 64 MB
    pd.testing.assert_frame_equal(rows["30M"], rows["64M"])
