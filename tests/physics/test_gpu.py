"""The GPU stepper (`railride.engine.gpu`, one thread per sample) against the CPU sample stepper
(`run_batch`) on every kind of batch it serves. In CI the kernel runs in numba's CUDA simulator
(tests/conftest.py), which executes its Python source: these tests check the kernel's logic and
its host side; `test_the_kernel_compiles_for_a_gpu` checks that it compiles for a device."""

import importlib.util
import math
import warnings

import numba
import numpy as np
import pytest

from railride import dampers
from railride.engine import gpu, gpu_kernel
from railride.engine import lanes as engine_lanes
from railride.testing.agreement import histories, worst_difference
from railride.errors import BackendWarning, InputError
from railride.model.params import VehicleParams
from railride.model.track import scenario
from railride.run import solver as solver_module
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
from railride.secondary.control import OUTER_LOOPS, SensorNoise
from railride.secondary.sensing import Accelerometers
from railride.secondary.suspension import Suspension

pytestmark = pytest.mark.skipif(gpu.why_not() is not None, reason=f"no GPU and no simulator: {gpu.why_not()}")

SHORT = scenario("paper-sine", duration=0.012)
GPU = SolverSettings(method="rk4", backend="gpu")
CPU = SolverSettings(method="rk4", backend="cpu")
LAWS = OUTER_LOOPS  # every control law
PAPER = VehicleParams.preset("paper")

CASES = {
    "passive dashpots (in C)": dict(params=[PAPER.replace(c_sz=c) for c in (2e4, 6e4)]),
    "viscous damper model": dict(suspension=Suspension.passive(dampers.Viscous(c=4e4))),
    "Bouc-Wen, open loop": dict(suspension=[Suspension.semi_active("railway", voltage=v) for v in (0.0, 2.25)]),
    "Bouc-Wen, every law and delays": dict(
        suspension=[Suspension.named(n) for n in LAWS] + [Suspension.named("sas-attitude").with_delay(3)]
    ),
    "Spencer, sub-steps": dict(
        suspension=[Suspension.named("skyhook", damper="spencer1997")],
        scenario=scenario("paper-sine", duration=0.004),
    ),
    "ideal actuator": dict(suspension=[Suspension.named(n, damper="ideal") for n in ("sas-attitude", "skyhook")]),
    "ideal semi-active damper": dict(suspension=Suspension.named("hybrid", damper="ideal-damper")),
    "sensor noise": dict(suspension=Suspension.named("skyhook", sensor_noise=SensorNoise(1e-4, 1e-4, 1e-3, 1e-3, 7))),
    "faults": dict(
        suspension=[
            Suspension.named("sas-attitude").with_faults(["1R-off", "2L-on@0.004"]),
            Suspension.named("hybrid").with_faults(["1L-disconnected@0.006"]),
        ]
    ),
    "accelerometers": dict(suspension=Suspension.named("sas-attitude").with_sensing(Accelerometers())),
    "a carbody that bends, random track": dict(
        vehicle="manchester-1", scenario=scenario("fra4", duration=0.012), suspension=Suspension.named("skyhook")
    ),
}


def _runs(monkeypatch, **kw):
    """(GPU run, the same run by run_batch sample after sample)."""
    kw = {"scenario": SHORT, **kw, "on_divergence": "mark"}
    with monkeypatch.context() as m:
        m.setattr(engine_lanes, "lanes_fit", lambda *args: False)
        return simulate(**kw, solver=GPU), simulate(**kw, solver=CPU)


def _worst(a, b) -> float:
    """The largest difference of any history of run a from run b's, over that history's largest value."""
    ha, hb = histories(a), histories(b)
    assert ha.keys() == hb.keys()
    return worst_difference(ha, hb)


@pytest.mark.parametrize("kernel", ["general", "specialised, lean RK4"])
@pytest.mark.parametrize("case", list(CASES))
def test_the_gpu_agrees_with_the_cpu_stepper(case, kernel, monkeypatch):
    # the kernel for any batch, and the one built for the batch (`gpu.kernel_key`: its law,
    # faults, sensing, exponent n = 1 and the matrices' zeros, one stage rate at a time)
    special = kernel != "general"
    monkeypatch.setattr(gpu, "SPECIALISE", special)
    monkeypatch.setattr(gpu, "LEAN_RK4", special)
    on_gpu, on_cpu = _runs(monkeypatch, **CASES[case])
    # the same laws in the same order, the products as plain sums: rounding-level differences
    # (measured <= 1e-15 in the simulator); the bound for laws without switching is 1e-9
    assert _worst(on_gpu, on_cpu) < 1e-9


def test_each_batch_gets_the_kernel_of_its_damper_law_faults_and_sensing(monkeypatch):
    """`gpu.kernel_key`: with SPECIALISE, a batch's kernel fixes its damper law, leaves out faults
    and sensing where no sample has them, and knows a Bouc-Wen exponent of 1 where every damper
    has it; without, every batch gets the general kernel."""
    from railride.engine.layout import LAW_BOUC_WEN, LAW_SPENCER, LAW_VISCOUS_IN_C

    keys = []
    build = gpu._device_functions
    monkeypatch.setattr(gpu, "_device_functions", lambda key: keys.append(key) or build(key))
    sas = Suspension.named("sas-attitude")
    batches = {
        "healthy": [sas],
        "one faulty": [sas, sas.with_faults(["1R-off"])],
        "sensing": [sas.with_sensing(Accelerometers())],
        "passive": [None],
        "n = 2": [Suspension.named("skyhook", damper="spencer1997")],
    }
    for special in (True, False):
        monkeypatch.setattr(gpu, "SPECIALISE", special)
        for suspensions in batches.values():
            kw = {"params": [PAPER.replace(c_sz=3e4)]} if suspensions == [None] else {"suspension": suspensions}
            simulate(scenario=SHORT, solver=GPU, **kw)
    lean = gpu.LEAN_RK4
    special = [(LAW_BOUC_WEN, False, False, True), (LAW_BOUC_WEN, True, False, True), (LAW_BOUC_WEN, False, True, True)]
    special += [(LAW_VISCOUS_IN_C, False, False, False), (LAW_SPENCER, False, False, False)]
    general = (-1, True, True, lean, False, -1)
    assert [k[:5] for k in keys[:5]] == [(*k[:3], lean, k[3]) for k in special]
    assert keys[5:] == [general] * 5
    # the terms of the q'' product, the corner deflections and the forcing: the paper's vehicle
    # has 56 of the 240 coefficients of its matrix A not 0 with dampers, 66 with its dashpots in
    # the matrix, 20 of the 40 of TS (counted from its matrices, ad hoc), and the rails reach the
    # 6 rows of its bogies
    assert [bin(k[5]).count("1") for k in keys[:5]] == [82, 82, 82, 92, 82]


def test_the_sparse_product_leaves_out_only_zeros(monkeypatch):
    """The q'' product, the corner deflections and the rail forcing of only the terms that some
    vehicle has (`gpu.SPARSE_PRODUCT`) give the runs of the whole products to the bit: a bending
    carbody and a rigid one in one batch, on a random track."""
    kw = dict(
        params=[VehicleParams.preset("manchester-1"), PAPER.replace(m_c=4.2e4)],
        scenario=scenario("fra4", duration=0.008),
        suspension=Suspension.named("sas-attitude-ride"),
    )
    runs = []
    for sparse in (False, True):
        monkeypatch.setattr(gpu, "SPARSE_PRODUCT", sparse)
        runs.append(histories(simulate(**kw, solver=GPU)))
    for name in runs[0]:
        np.testing.assert_array_equal(runs[1][name], runs[0][name], err_msg=name)


def test_the_forced_rows_are_the_bogies_unless_a_table_says_otherwise():
    """`gpu.forced_rows`: a flat track's table (all 0) gets the bogies' rows, as any other of
    these vehicles, so no kernel of its own; a table with forcing on a carbody row gets every row."""
    from railride.engine.layout import N_DOF

    flat = np.zeros((5, 4 * N_DOF))
    assert gpu.forced_rows(flat).tolist() == [False] * 3 + [True] * 6 + [False]
    on_carbody = flat.copy()
    on_carbody[2, 2 * N_DOF + 1] = 1e-3  # Bwd w of the carbody's pitch
    assert gpu.forced_rows(on_carbody).all()
    for product in range(4):  # the first and last row outside the bogies, in each product
        for row in (0, 2, 9):
            table = flat.copy()
            table[4, product * N_DOF + row] = -1.0
            assert gpu.forced_rows(table).all(), (product, row)
    on_bogies = flat.copy()
    on_bogies[:, [p * N_DOF + r for p in range(4) for r in range(3, 9)]] = 1.0
    assert gpu.forced_rows(on_bogies).tolist() == [False] * 3 + [True] * 6 + [False]


def test_the_file_cache_setting_reaches_the_compile(monkeypatch):
    """`gpu.FILE_CACHE` is what numba-cuda's ``cuda.jit`` is given as ``cache`` (a stand-in for
    cuda.jit: the simulator compiles nothing)."""
    import types

    given = []
    monkeypatch.setattr(gpu, "simulated", lambda: False)
    monkeypatch.setattr(gpu, "_array_overloads", lambda: None)
    monkeypatch.setattr(gpu, "cuda", types.SimpleNamespace(jit=lambda kernel, **kw: given.append(kw)))
    for keep in (False, True):
        monkeypatch.setattr(gpu, "FILE_CACHE", keep)
        gpu._compile(gpu_kernel.GENERAL)
    assert [kw["cache"] for kw in given] == [False, True]


def test_bump_stops_on_the_gpu(monkeypatch):
    x0 = np.zeros(18)
    x0[0] = 0.06  # the carbody 60 mm up: beyond crh380a's 40 mm clearance at once
    on_gpu, on_cpu = _runs(
        monkeypatch, vehicle="crh380a", suspension=Suspension.named("sas-attitude"), initial_state=x0
    )
    assert on_gpu.travel()["reached_stops"] and _worst(on_gpu, on_cpu) < 1e-9


def test_a_diverging_sample_is_marked_alike_and_the_others_go_on(monkeypatch):
    x0 = np.zeros((3, 18))
    x0[1, 9] = 1e7  # sample 1's carbody leaves +-1000 m within a step or two
    on_gpu, on_cpu = _runs(monkeypatch, suspension=[Suspension.named("skyhook")] * 3, initial_state=x0)
    assert np.isfinite(on_gpu.diverged_at[1]) and on_gpu.diverged_at[1] == on_cpu.diverged_at[1]
    assert np.isnan(on_gpu.diverged_at[[0, 2]]).all()
    assert _worst(on_gpu, on_cpu) < 1e-9


def test_chunks_continue_and_groups_that_fit_memory_give_the_same_run(monkeypatch):
    batch = [Suspension.named(n) for n in LAWS[:3]]
    whole = simulate(SHORT, suspension=batch, solver=GPU)
    # chunks (a progress callback, steps at a time) and groups of one sample (little memory)
    monkeypatch.setattr(gpu, "_free_bytes", lambda: 1)
    monkeypatch.setattr("railride.run.simulation._CHUNK_WORK", 30)
    seen = []
    parts = simulate(SHORT, suspension=batch, solver=GPU, progress=seen.append)
    assert len(seen) > 2
    assert _worst(parts, whole) < 1e-12


def test_batches_from_several_threads_at_once_each_get_their_own_runs(monkeypatch):
    """A study's chunks in flight call the GPU from their threads at once, each on a stream of
    its own: every batch gets the runs it gets alone, and each thread reads its own call's record."""
    from concurrent.futures import ThreadPoolExecutor

    batches = [[Suspension.named(n) for n in LAWS[k : k + 2]] for k in range(0, 6, 2)]
    alone = [simulate(SHORT, suspension=b, solver=GPU) for b in batches]
    monkeypatch.setattr(gpu, "group_size", lambda n, b, free=None: 1)  # several groups each, interleaved

    def run(b):
        result = simulate(SHORT, suspension=b, solver=GPU)
        return result, gpu.last_call()["groups"]

    with ThreadPoolExecutor(len(batches)) as pool:
        together = list(pool.map(run, batches))
    for (result, groups), one in zip(together, alone):
        assert groups == 2  # this thread's call: its two samples, one group each
        assert _worst(result, one) == 0.0


def test_a_gpu_failure_goes_on_on_the_cpu_with_one_warning_and_loses_nothing(monkeypatch):
    batch = [Suspension.named(n) for n in LAWS[:4]]
    reference = simulate(SHORT, suspension=batch, solver=CPU)
    run_group = gpu._run_group
    calls = []

    def failing(kernel, stream, shared, arrays, lo, hi, *args):
        calls.append(lo)
        if len(calls) == 2:  # the second group: the first has finished and reached the host
            raise RuntimeError("CUDA_ERROR_LAUNCH_FAILED (made up)")
        return run_group(kernel, stream, shared, arrays, lo, hi, *args)

    monkeypatch.setattr(gpu, "_run_group", failing)
    monkeypatch.setattr(gpu, "group_size", lambda n, b, free=None: 2)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = simulate(SHORT, suspension=batch, solver=GPU)
    lines = [str(w.message) for w in caught if issubclass(w.category, BackendWarning)]
    assert len(lines) == 1 and "CUDA_ERROR_LAUNCH_FAILED" in lines[0] and "CPU" in lines[0]
    assert calls == [0, 2] and _worst(result, reference) < 1e-9


def test_backend_gpu_without_the_extra_or_a_device_is_an_input_error(monkeypatch):
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None if name == "numba_cuda" else object())
    with pytest.raises(InputError, match=r"backend = 'gpu': numba-cuda is not installed.*railride\[gpu\]"):
        SolverSettings(backend="gpu")
    monkeypatch.undo()
    monkeypatch.setattr(gpu, "why_not", lambda: "no CUDA GPU or driver was found")
    with pytest.raises(InputError, match="backend = 'gpu': no CUDA GPU"):
        SolverSettings(backend="gpu")
    with pytest.raises(InputError, match="backend"):
        SolverSettings(backend="tpu")


def test_auto_takes_the_gpu_for_large_batches_only_and_says_once_when_there_is_none(monkeypatch):
    auto = SolverSettings()
    # in the simulator (a test harness, not a speed) "auto" asks for SIMULATOR_MIN_BATCH runs
    least = solver_module.SIMULATOR_MIN_BATCH
    assert auto.backend == "auto" and auto.backend_for(least - 1, 20.0) == "cpu"
    assert auto.backend_for(least) == "gpu"  # the simulator counts as a GPU
    assert "backend" not in auto.to_dict() and GPU.to_dict()["backend"] == "gpu"
    monkeypatch.setattr(gpu, "why_not", lambda: "no CUDA GPU or driver was found")
    with pytest.warns(BackendWarning, match="no CUDA GPU.*large batches run on the CPU"):
        assert auto.backend_for(least) == "cpu"
    assert SolverSettings(backend="cpu").backend_for(10**6) == "cpu"


def test_auto_weighs_a_gpu_call_against_the_cpu_threads(monkeypatch):
    """The crossover of `gpu_pays` by hand: a GPU call of s steps takes 0.21 s + s 18.9 us
    whatever its runs; n runs take the CPU n s / (threads 2.65e6) s."""
    pays = solver_module.gpu_pays
    # 20-s runs at dt = 1e-4 s on 16 threads: 3.99 s on the GPU, 4.717 ms a run on the CPU: 845.9 runs
    assert not pays(845, 200_000, 16) and pays(846, 200_000, 16)
    assert not pays(105, 200_000, 2) and pays(106, 200_000, 2)  # 37.7 ms a run on 2 threads
    # 1-s runs: the call's host share counts for more (0.399 s against 0.236 ms a run): 1,692 runs
    assert not pays(1691, 10_000, 16) and pays(1692, 10_000, 16)
    # long runs: 18.9 us against one thread's 1 / 2.65e6 s a step, 50.1 runs a thread
    assert not pays(801, None, 16) and pays(802, None, 16)
    # outside the simulator, "auto" asks that of numba's threads; a fixed GPU_MIN_BATCH overrides it
    from numba.core import config

    monkeypatch.setattr(config, "ENABLE_CUDASIM", False, raising=False)
    monkeypatch.setattr(gpu, "why_not", lambda: None)
    threads = numba.get_num_threads()
    auto = SolverSettings()
    assert (
        auto.backend_for(pays_from(threads) - 1, 20.0) == "cpu" and auto.backend_for(pays_from(threads), 20.0) == "gpu"
    )
    monkeypatch.setattr(solver_module, "GPU_MIN_BATCH", 5)
    assert auto.backend_for(4, 20.0) == "cpu" and auto.backend_for(5, 20.0) == "gpu"


def pays_from(threads: int) -> int:
    """The fewest 20-s runs (200,000 steps) that `gpu_pays` gives the GPU on ``threads`` threads."""
    return math.ceil((0.21 + 200_000 * 18.9e-6) * threads * 2.65e6 / 200_000)


def _nvvm() -> bool:
    """Whether numba-cuda can compile to PTX here (its NVVM, from the toolkit of the gpu extra)."""
    if importlib.util.find_spec("numba_cuda") is None or importlib.util.find_spec("nvidia") is None:
        return False
    return any(importlib.util.find_spec(m) is not None for m in ("nvidia.cuda_nvcc", "nvidia.nvvm"))


@pytest.mark.slow
@pytest.mark.skipif(not _nvvm(), reason="no NVVM (install railride[gpu]) to compile the kernel for a GPU")
def test_the_kernel_compiles_for_a_gpu():
    import subprocess
    import sys

    # the general kernel, and the build a healthy Bouc-Wen batch of the paper's vehicle, n = 1, runs (`gpu.kernel_key`)
    code = (
        "import numpy as np; from railride.engine import gpu; from railride.engine.layout import LAW_BOUC_WEN\n"
        "from railride.run.inputs import _system_arrays; from railride.model.vehicle import Vehicle\n"
        "m = _system_arrays(Vehicle('paper'), passive=False)\n"
        "ftab = np.tile(gpu.BOGIE_ROWS, 4)[None, :].astype(float)\n"
        "key = gpu.kernel_key(LAW_BOUC_WEN, np.zeros((1, 8), np.int64), np.zeros((1, 3)), True, np.ones((1, 16)),"
        " m['A'][None], m['TS'][None], ftab)\n"
        "print(key, '.entry' in gpu.ptx((9, 0)), '.entry' in gpu.ptx((9, 0), key))"
    )
    env = {**__import__("os").environ, "NUMBA_ENABLE_CUDASIM": "0"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split()[-2:] == ["True", "True"], done.stdout


@pytest.mark.slow
@pytest.mark.skipif(not _nvvm(), reason="no NVVM (install railride[gpu]) to compile the kernel for a GPU")
def test_the_device_compile_has_the_arithmetic_of_the_inlined_kernel():
    """`gpu_kernel._device_mirror` compiles the engine's functions as device functions of their
    own, for NVVM to inline, in place of numba's copying their IR into the kernel. The build of a
    healthy Bouc-Wen batch of the paper's vehicle gives the same PTX instruction for instruction
    (names, labels and virtual registers aside); the general kernel, whose branches NVVM arranges
    a little differently, the same floating-point instructions by kind and count."""
    import subprocess
    import sys

    code = r"""
import collections, re, types
from unittest import mock
import numpy as np
from numba import cuda
from numba.cuda import dispatcher
from railride.engine import gpu, gpu_kernel
from railride.engine.layout import LAW_BOUC_WEN
from railride.run.inputs import _system_arrays
from railride.model.vehicle import Vehicle

m = _system_arrays(Vehicle('paper'), passive=False)
ftab = np.tile(gpu.BOGIE_ROWS, 4)[None, :].astype(float)
healthy = (np.zeros((1, 8), np.int64), np.zeros((1, 3)))
key = gpu.kernel_key(LAW_BOUC_WEN, *healthy, True, np.ones((1, 16)), m['A'][None], m['TS'][None], ftab)
float_ops = r'\s((?:fma|mul|add|sub|div|neg|abs|max|min)[.a-z]*f64)\s'


def ops(p):
    return sorted(collections.Counter(re.findall(float_ops, p)).items())


def body(p):  # the instructions without names, labels and virtual registers
    lines = [x for x in p.splitlines() if re.match(r'\s+[a-z@]', x)]
    return [re.sub(r'_ZN\w*|\$L__BB\w+|%[a-z]+\d+', '', x).split() for x in lines]


device = types.SimpleNamespace(compute_capability=(9, 0))
for k in (gpu.GENERAL, key):
    gpu._array_overloads()
    with mock.patch.object(dispatcher, 'get_current_device', lambda: device):
        inlined, _ = cuda.compile_ptx(gpu_kernel._kernel_for(*k), gpu_kernel.kernel_signature(), cc=(9, 0))
    mirrored = gpu.ptx((9, 0), k)
    same_ops = len(ops(inlined)) > 5 and ops(inlined) == ops(mirrored)
    print(same_ops, len(body(inlined)) > 1000 and body(inlined) == body(mirrored))
"""
    env = {**__import__("os").environ, "NUMBA_ENABLE_CUDASIM": "0"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=900)
    assert done.returncode == 0, done.stderr[-2000:]
    # the general kernel: the same arithmetic, other branches; the paper's batches: the same PTX
    assert done.stdout.split() == ["True", "False", "True", "True"], done.stdout


@pytest.mark.slow
@pytest.mark.skipif(not _nvvm(), reason="no NVVM (install railride[gpu]) to compile the kernel for a GPU")
def test_the_kernel_compiles_on_a_numpy_without_row_stack():
    """numpy 2.5 removed ``np.row_stack``; numba-cuda 0.30.4 still registers an overload for it,
    which made every kernel compile fail (seen on an H100). Removed here as numpy 2.5 has it
    removed: from the module and from its ``__all__``; the alias used while loading is gone after."""
    import subprocess
    import sys

    code = (
        "import numpy as np; vars(np).pop('row_stack', None)\n"
        "np.__all__ = [n for n in np.__all__ if n != 'row_stack']\n"
        "from railride.engine import gpu; p = gpu.ptx((9, 0)); print('.entry' in p, hasattr(np, 'row_stack'))"
    )
    env = {**__import__("os").environ, "NUMBA_ENABLE_CUDASIM": "0"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["True", "False"]


def test_a_batchs_distinct_vehicles_are_found_once_and_indexed_back():
    """`gpu._vehicles`: each distinct (A, TS) once, and every sample's index gives its own back."""
    rng = np.random.default_rng(3)
    A0, TS0 = rng.standard_normal((3, 24, 10)), rng.standard_normal((3, 10, 4))
    which = rng.integers(0, 3, 500)
    A, TS = A0[which], TS0[which]
    TS[which == 2] = TS0[0]  # a vehicle that differs from another only in A
    A_u, TS_u, vid = gpu._vehicles(A, TS)
    assert len(A_u) == 3 and vid.dtype == np.int64
    assert np.array_equal(A_u[vid], A) and np.array_equal(TS_u[vid], TS)
    A_1, _, vid_1 = gpu._vehicles(A0[[1] * 7], TS0[[1] * 7])
    assert len(A_1) == 1 and not vid_1.any()
