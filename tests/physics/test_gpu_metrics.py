"""Runs that keep only their metrics (`railride.run.reduced`): the GPU kernel's sums on the device
against `RideResult.metrics` of the CPU stepper's histories, and the studies that use them. In CI
the kernel runs in numba's CUDA simulator (tests/conftest.py)."""

import warnings

import numpy as np
import pytest

from railride import limits
from railride.engine import gpu
from railride.engine import lanes as engine_lanes
from railride.errors import BackendWarning, InputError
from railride.model.track import scenario
from railride.run.checks import check
from railride.run.reduced import batch_metrics, window_rows
from railride.run import reduced, simulation
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
from railride.secondary.control import OUTER_LOOPS
from railride.secondary.suspension import Suspension
from railride.studies import sweep
from railride.studies.case import Case

pytestmark = pytest.mark.skipif(gpu.why_not() is not None, reason=f"no GPU and no simulator: {gpu.why_not()}")

SHORT = scenario("paper-sine", duration=0.02)
GPU = SolverSettings(method="rk4", backend="gpu")
CPU = SolverSettings(method="rk4", backend="cpu")
LAWS = [Suspension.named(n) for n in OUTER_LOOPS]


def _cpu_metrics(sc, suspensions, window, **kw):
    """The CPU stepper's histories, sample after sample (run_batch), and their metrics."""
    res = simulate(sc, suspension=suspensions, solver=CPU, on_divergence="mark", **kw)
    return res.metrics(window).values, res.diverged_at


def _relative(a, b) -> float:
    """The largest difference of a from b, over the largest |b| of each (response, statistic)."""
    return float(np.nanmax(np.abs(a - b) / np.nanmax(np.abs(b), axis=0)))


@pytest.mark.parametrize("window", [None, (0.005, 0.02), (0.0101, 0.0149)])
def test_the_device_sums_give_the_metrics_of_the_histories(window, monkeypatch):
    monkeypatch.setattr(engine_lanes, "lanes_fit", lambda *args: False)
    on_gpu, when = batch_metrics(check(SHORT, None, LAWS, GPU, "mark", histories=False), window)
    on_cpu, _ = _cpu_metrics(SHORT, LAWS, window)
    assert on_gpu.shape == (len(LAWS), 4, 2) and np.isnan(when).all()
    assert np.all(on_cpu[:, :, 1] > 0)  # every response moved: the comparison can fail
    # the same rows (window_rows against the histories' times) and the same sums to rounding
    assert _relative(on_gpu, on_cpu) < 1e-9


def test_a_diverging_run_has_nan_metrics_and_its_time_and_the_others_stand(monkeypatch):
    monkeypatch.setattr(engine_lanes, "lanes_fit", lambda *args: False)
    x0 = np.zeros((3, 18))
    x0[1, 9] = 1e7  # sample 1's carbody leaves +-1000 m within a step or two
    batch = [Suspension.named("skyhook")] * 3
    on_gpu, when = batch_metrics(check(SHORT, None, batch, GPU, "mark", x0, histories=False))
    on_cpu, cpu_when = _cpu_metrics(SHORT, batch, None, initial_state=x0)
    assert np.isnan(on_gpu[1]).all() and when[1] == cpu_when[1] and np.isfinite(when[1])
    assert np.isnan(when[[0, 2]]).all() and _relative(on_gpu[[0, 2]], on_cpu[[0, 2]]) < 1e-9


def test_a_gpu_failure_runs_the_batch_on_the_cpu_with_one_warning(monkeypatch):
    reference, _ = _cpu_metrics(SHORT, LAWS[:3], None)

    def failing(*args):
        raise RuntimeError("CUDA_ERROR_LAUNCH_FAILED (made up)")

    monkeypatch.setattr(gpu, "_run_group", failing)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got, _ = batch_metrics(check(SHORT, None, LAWS[:3], GPU, "mark", histories=False))
    lines = [str(w.message) for w in caught if issubclass(w.category, BackendWarning)]
    assert len(lines) == 1 and "CUDA_ERROR_LAUNCH_FAILED" in lines[0]
    assert _relative(got, reference) < 1e-9


def test_a_metrics_only_gpu_batch_is_checked_for_its_own_memory():
    # 64 runs of 2 s on one track: their histories need about 60 MB, their sums a few kB
    sc = scenario("paper-sine", duration=2.0)
    batch = [Suspension.named("skyhook")] * 64
    before = limits.max_memory()
    limits.set_max_memory(20e6)
    try:
        with pytest.raises(InputError, match="memory"):
            check(sc, None, batch, GPU, "mark")
        check(sc, None, batch, GPU, "mark", histories=False)  # the same runs, without histories
        with pytest.raises(InputError, match="memory"):  # where the CPU runs them, histories it is
            check(sc, None, batch, CPU, "mark", histories=False)
    finally:
        limits.set_max_memory(before)


def test_the_window_rows_are_those_the_histories_select():
    t = np.arange(21) / 1000.0
    for window in [(0.005, 0.02), (0.0101, 0.0149), (0.0, np.inf)]:
        w0, w1 = window_rows(21, 1000.0, window)
        end = t[-1] if np.isinf(window[1]) else window[1]
        keep = np.flatnonzero((t >= window[0] - 1e-12) & (t <= end + 1e-12))
        assert (w0, w1) == (keep[0], keep[-1])
    with pytest.raises(InputError, match="fewer than two"):
        window_rows(21, 1000.0, (0.0101, 0.0105))


def test_a_study_on_the_gpu_takes_large_batches_and_gives_the_cpu_rows(monkeypatch):
    cases = [
        Case("paper-sine", (("duration", 0.02), ("speed", v)), suspension=n)
        for v in (30.0, 45.0)
        for n in ("skyhook", "sas-attitude", "pid")
    ]
    batches = []
    run_gpu = gpu.run_gpu

    def counted(n, *args, **kw):
        batches.append((n, kw.get("reduce") is not None))
        return run_gpu(n, *args, **kw)

    monkeypatch.setattr(gpu, "run_gpu", counted)
    monkeypatch.setattr(sweep, "CHUNK", 2)  # CPU batches of two; the GPU's take a group whole
    on_gpu = sweep.run_cases(cases, solver=GPU)
    assert batches == [(6, True)]  # one group (the laws differ in their outer loops), metrics only
    monkeypatch.setattr(engine_lanes, "lanes_fit", lambda *args: False)
    on_cpu = sweep.run_cases(cases, solver=CPU)
    columns = [c for c in on_cpu.columns if c.endswith(("_rms", "_ptp"))]
    assert len(columns) == 8 and list(on_gpu["key"]) == list(on_cpu["key"])
    a, b = on_gpu[columns].to_numpy(), on_cpu[columns].to_numpy()
    assert np.all(b > 0) and np.max(np.abs(a - b) / np.abs(b).max(axis=0)) < 1e-9
    batches.clear()
    sweep.run_cases(cases, solver=GPU, comfort=True)  # comfort reads histories: CPU-sized batches, kept
    assert batches and all(n <= 2 and not reduced for n, reduced in batches)


def test_auto_sends_a_study_to_the_gpu_only_from_the_smallest_gpu_batch(monkeypatch):
    auto = SolverSettings()
    assert not sweep.gpu_batches(auto, 10) and sweep.gpu_batches(auto, 10**5)  # the simulator is a GPU
    assert sweep.gpu_batches(GPU, 1) and not sweep.gpu_batches(CPU, 10**5)
    monkeypatch.setattr(gpu, "why_not", lambda: "no CUDA GPU or driver was found")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no GPU: "auto" studies run as they always did, silently
        assert not sweep.gpu_batches(auto, 10**5)
    idx = list(range(sweep.GPU_CHUNK + 40))
    parts = sweep._batches(idx, GPU, metrics_only=True)
    assert [len(p) for p in parts] == [sweep.GPU_CHUNK, 40]
    assert [len(p) for p in sweep._batches(idx, GPU, metrics_only=False)][:2] == [sweep.CHUNK] * 2


def test_runs_the_gpu_does_not_take_go_in_cpu_sized_batches(monkeypatch):
    # passive runs take the exact steps on the CPU whatever the backend: not one batch of the
    # whole group (its histories), but the CPU's batches of CHUNK
    cases = [Case("paper-sine", (("duration", 0.02), ("speed", v))) for v in (30.0, 35.0, 40.0, 45.0, 50.0)]
    sizes = []
    run = simulation.run

    def counted(plan, *args, **kw):
        sizes.append(plan.n)
        return run(plan, *args, **kw)

    monkeypatch.setattr(simulation, "run", counted)
    monkeypatch.setattr(reduced, "run", counted)  # a metrics-only batch the lanes do not take
    monkeypatch.setattr(sweep, "CHUNK", 2)
    auto_gpu = SolverSettings(backend="gpu")  # method auto: the exact steps for passive runs
    rows = sweep.run_cases(cases, solver=auto_gpu)
    assert sizes == [2, 2, 1] and len(rows) == 5
    assert np.all(rows["acceleration_m_s2_rms"] > 0)


def test_a_gpu_failure_reruns_a_large_batch_on_the_cpu_in_small_batches(monkeypatch):

    reference, _ = _cpu_metrics(SHORT, LAWS[:5], None)
    monkeypatch.setattr(gpu, "_run_group", lambda *args: (_ for _ in ()).throw(RuntimeError("made up")))
    monkeypatch.setattr(reduced, "CPU_BATCH", 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendWarning)
        got, when = batch_metrics(check(SHORT, None, LAWS[:5], GPU, "mark", histories=False))
    assert got.shape == (5, 4, 2) and np.isnan(when).all() and _relative(got, reference) < 1e-9
