"""The GPU stepper: `railride.engine.kernels.run_batch`'s work with one CUDA thread per sample
(numba-cuda, the ``gpu`` extra), in float64 throughout. The kernel itself, and its builds for
each kind of batch, are `railride.engine.gpu_kernel`; this module chooses the build
(`kernel_key`), compiles it once a process, and moves the batch to and from the device.

Memory. The vehicles' matrices are stored once per distinct vehicle (a batch of one vehicle
reads one copy, which the device caches), the rail tables once per distinct track (as on the
CPU, `railride.run.inputs`), and the output histories only for the rows a call writes. A batch
whose arrays do not fit the device's free memory is split into sample groups that do.

In numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``, how the tests run the kernel without a
GPU) the kernel runs as its Python source (`gpu_kernel._python_mirror`).
"""

from __future__ import annotations

import contextlib
import importlib.util
import threading
import time
import types

import numpy as np

try:  # numba-cuda (the gpu extra) when installed; numba's own CUDA target otherwise, while it has one
    from numba import cuda
except ImportError:  # pragma: no cover - a numba without a CUDA target and no numba-cuda
    cuda = None  # type: ignore[assignment]

from railride.engine.gpu_kernel import (
    GENERAL,
    _device_mirror,
    _kernel_for,
    _python_mirror,
    kernel_signature,
    pattern_of,
)
from railride.engine.layout import F_MODE, FAULT_NONE, LAW_BOUC_WEN, LAW_SPENCER, N_CORNER, N_DOF, P_N, ROW_BOGIES, S_ON
from railride.engine.sample_parts import N_ACC

#: threads per block on a GPU (a multiple of the warp, 32)
THREADS_PER_BLOCK = 128
#: the most registers a thread of the kernel may use (None: the compiler's choice, 255 at most);
#: set before the first compile. Fewer registers let more threads share a multiprocessor, at the
#: cost of more spills to local memory (`benchmarks/bench_gpu_kernel.py --resources`, docs/gpu.md)
MAX_REGISTERS: int | None = None
#: compile a kernel for each kind of batch (`kernel_key`): its damper law fixed, and faults and
#: realistic sensing left out where no sample has them, for less thread-local memory; False:
#: one kernel for every batch (one compile a process). With LEAN_RK4, twice the general
#: kernel's rate on an H100 (docs/gpu.md, "The kernel built for its batch")
SPECIALISE = True
#: RK4 with one stage rate and a running sum in place of the four stage rates (`_lean_rk4`):
#: faster with SPECIALISE, slower without it (measured on an H100, docs/gpu.md)
LEAN_RK4 = True
#: with SPECIALISE, a batch whose dampers all have the Bouc-Wen exponent n = 1 gets a kernel that
#: knows it (`_kernel_for`'s ``unit_n``): 19 % fewer instructions and less stack for ptxas
#: (docs/gpu.md); the same arithmetic but for where the compiler fuses a multiply and an add
UNIT_N = True
#: with SPECIALISE, the q'' product and the corner deflections sum only the terms whose
#: coefficient is not 0 in some vehicle of the batch (56 of 240 and 20 of 40 for the paper's
#: vehicle with dampers), and the rail forcing only in the rows the rails reach (`forced_rows`):
#: `_kernel_for`'s ``pattern``
SPARSE_PRODUCT = True
#: keep each compiled kernel in numba's file cache beside the engine's CPU kernels
#: (``cuda.jit(cache=True)``; cleared with them when an engine source changes,
#: `railride.engine.cache_guard`), so that a later process loads it instead of compiling it
#: again (19-43 s a kind of batch on an H100 before `gpu_kernel._device_mirror`). Off until a
#: device has shown that a second process loads it and gets the same results
#: (`benchmarks/bench_gpu_cache.py`, docs/gpu.md)
FILE_CACHE = False
#: the share of the device's free memory one group of samples may take
MEMORY_SHARE = 0.6
# what the calling thread's last `run_gpu` took (`last_call`)
_calls = threading.local()
# held while a group of samples is sized against the free memory and given its device arrays:
# calls from several threads (a study's chunks in flight) then never size their groups on the
# same free memory
_ALLOCATING = threading.Lock()
_COMPILING = threading.Lock()
_SIMULATOR = threading.Lock()


def why_not() -> str | None:
    """None when a GPU can run the stepper; otherwise what is missing, in words: the extra
    (numba-cuda) or a usable CUDA device and driver. The simulator counts as a device."""
    if importlib.util.find_spec("numba_cuda") is None:
        return "numba-cuda is not installed (pip install 'railride[gpu]')"
    if cuda is None:
        return "numba has no CUDA target here (pip install 'railride[gpu]')"
    try:
        if cuda.is_available():
            return None
        return "no CUDA GPU or driver was found"
    except Exception as exc:  # a broken driver or toolkit: its own words
        return f"CUDA is not usable here: {exc}"


def simulated() -> bool:
    """Whether numba runs CUDA kernels in its simulator (NUMBA_ENABLE_CUDASIM=1)."""
    from numba.core import config

    return bool(getattr(config, "ENABLE_CUDASIM", False))


def device_name() -> str:
    """The GPU the stepper runs on, in words (the simulator says so)."""
    if simulated():
        return "numba CUDA simulator"
    name = cuda.get_current_device().name
    return name.decode() if isinstance(name, bytes) else str(name)


_compiled: dict = {}


def _array_overloads() -> None:
    """Loads numba-cuda's numpy overloads on a numpy without ``np.row_stack`` (removed in numpy
    2.5): numba-cuda 0.30.4 registers one for it on every numpy 2, so its first compile fails with
    an AttributeError. The alias of ``np.vstack`` lives only while that module loads."""
    if simulated() or hasattr(np, "row_stack"):
        return
    setattr(np, "row_stack", np.vstack)  # setattr: numpy 2.5 and its stubs have no such name
    try:
        import numba.cuda.np.arrayobj  # noqa: F401
    except ImportError:  # numba's own CUDA target: nothing of numba-cuda to load
        pass
    finally:
        delattr(np, "row_stack")


def kernel_key(
    law: int,
    faults: np.ndarray,
    sensing: np.ndarray,
    closed_loop: bool,
    P: np.ndarray,
    A: np.ndarray,
    TS: np.ndarray,
    ftab: np.ndarray,
) -> tuple:
    """Which kernel a batch runs (`_kernel_for`'s arguments): with SPECIALISE, the batch's damper
    law, faults and sensing only where some sample has them, a Bouc-Wen exponent of 1 where
    every sample's damper (P, as `Damper.pack()`) has it, and the terms of the q'' product, of
    the corner deflections and of the rail forcing that its vehicles' matrices A and TS and its
    forcing table ftab have (`forced_rows`); else the one for any batch."""
    if not SPECIALISE:
        return (*GENERAL[:3], LEAN_RK4, False, -1)
    with_faults = bool(np.any(faults[:, F_MODE : F_MODE + N_CORNER] != FAULT_NONE))
    with_sensing = bool(closed_loop and np.any(sensing[:, S_ON] > 0.0))
    unit_n = UNIT_N and law in (LAW_BOUC_WEN, LAW_SPENCER) and bool(np.all(P[:, P_N] == 1.0))
    pattern = pattern_of(A, TS, forced_rows(ftab)) if SPARSE_PRODUCT else -1
    return (int(law), with_faults, with_sensing, LEAN_RK4, unit_n, pattern)


#: the rows of q'' that the rail inputs reach in every vehicle here (`forced_rows`)
BOGIE_ROWS = np.isin(np.arange(N_DOF), np.arange(ROW_BOGIES, ROW_BOGIES + 6))


def forced_rows(ftab: np.ndarray) -> np.ndarray:
    """The rows of q'' (N_DOF bools) that a kernel computes the rail forcing of, for the forcing
    table ftab (nodes, 4 N_DOF: Bw w, Bw w', Bwd w, Bwd w' side by side): the bogies' rows where
    the table has nothing in the others (every vehicle here: the rails act on the bogies through
    the primary suspension), else every row. Never the table's own zeros, so that a flat track
    needs no kernel of its own."""
    # the others as two slices of each of the four products: views, not a gathered copy of
    # columns of a round's tables (168 MB for the default design), which every GPU call made
    table = ftab.reshape(ftab.shape[0], 4, N_DOF)
    forced = np.any(table[:, :, :ROW_BOGIES]) or np.any(table[:, :, ROW_BOGIES + 6 :])
    return BOGIE_ROWS if not forced else np.ones(N_DOF, bool)


def _device_functions(key: tuple):
    """The kernel of ``key`` (`kernel_key`), compiled for the device on first use (or mirrored
    for the simulator), once though several threads ask at once."""
    with _COMPILING:
        if key not in _compiled:
            _compiled[key] = _compile(key)
        return _compiled[key]


def _compile(key: tuple):
    kernel = _kernel_for(*key)
    if simulated():
        return cuda.jit(_python_mirror(kernel)[0])
    _array_overloads()
    limit = {} if MAX_REGISTERS is None else {"max_registers": MAX_REGISTERS}
    return cuda.jit(_device_mirror(kernel)[0], cache=FILE_CACHE, **limit)


def last_call() -> dict:
    """What the calling thread's last `run_gpu` took: seconds in the kernels (``kernel_s``) and
    in the transfers (``transfer_s``), its sample groups (``groups``) and the most device memory in
    use while it ran (``device_bytes``). Read by benchmarks/bench_gpu.py."""
    return dict(getattr(_calls, "last", {}))


def ptx(cc: tuple[int, int] = (9, 0), key: tuple = GENERAL) -> str:
    """The kernel of ``key`` (`kernel_key`; default: the one for any batch) compiled to PTX for
    compute capability ``cc``, with no device present (needs numba-cuda's NVVM, the toolkit of
    the gpu extra): the check that every law the kernel calls compiles for a GPU, where no GPU
    is at hand."""
    from unittest import mock

    from numba.cuda import dispatcher

    # a device function the kernel calls (not inlined) asks the current device for its compute
    # capability: with no device, the one asked for here
    device = types.SimpleNamespace(compute_capability=cc)
    _array_overloads()
    with mock.patch.object(dispatcher, "get_current_device", lambda: device):
        code, _ = cuda.compile_ptx(_device_mirror(_kernel_for(*key))[0], kernel_signature(), cc=cc)
    return code


def _vehicles(A: np.ndarray, TS: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distinct vehicles of a batch: (A, TS) once each, in the order they first come, and
    every sample's index into them. Keyed by the matrices' bytes: NumPy's ``unique`` over rows
    sorted them, the largest part of a 32,768-run batch's host work (docs/gpu.md)."""
    n = len(A)
    a, ts = np.ascontiguousarray(A).reshape(n, -1), np.ascontiguousarray(TS).reshape(n, -1)
    seen: dict[tuple[bytes, bytes], int] = {}
    first: list[int] = []
    vid = np.empty(n, np.int64)
    for i in range(n):
        key = (a[i].tobytes(), ts[i].tobytes())
        j = seen.get(key)
        if j is None:
            j = seen[key] = len(first)
            first.append(i)
        vid[i] = j
    return np.ascontiguousarray(A[first]), np.ascontiguousarray(TS[first]), vid


def _rows(step0: int, n_steps: int, final: bool, stride: int) -> tuple[int, int]:
    """(first, last + 1) of the output rows a call writes: the multiples of stride among its
    steps, the one after its last step only with ``final``."""
    end = step0 + n_steps + (1 if final else 0)
    return -(-step0 // stride), -(-end // stride)


def _free_bytes() -> int:
    """The device's free memory (the simulator's: plenty)."""
    if simulated():
        return 1 << 40
    return int(cuda.current_context().get_memory_info()[0])


def group_size(n: int, bytes_per_sample: int, free: int | None = None) -> int:
    """Samples per group so that one group's arrays take at most MEMORY_SHARE of the free memory."""
    free = _free_bytes() if free is None else free
    return max(1, min(n, int(MEMORY_SHARE * free // max(bytes_per_sample, 1))))


def stepper(on_failure):
    """The GPU stepper as the step stage calls a stepper, ``(n, law, x, step0, ...)`` as
    `kernels.run_parallel(kernels.run_batch, ...)` takes them. Where the GPU fails (a driver error,
    its memory, a compile), ``on_failure(exc)`` is told and the samples it had not finished run
    on the CPU, so nothing is lost."""

    def step(n, *args):
        try:
            done = run_gpu(n, *args)
        except _Failed as failed:
            on_failure(failed.cause)
            done = failed.done
        if done < n:
            from railride.engine.kernels import run_batch, run_parallel

            run_parallel(run_batch, n, *args, start=done)

    return step


class _Failed(Exception):
    """The GPU failed after the first ``done`` samples had finished (and reached the host)."""

    def __init__(self, cause: BaseException, done: int):
        super().__init__(str(cause))
        self.cause = cause
        self.done = done


def run_gpu(
    n, law, x, step0, n_steps, final, stride, dt, vehicle, dampers, inputs, control, outputs, reduce=None
) -> int:
    """`kernels.run_parallel(kernels.run_batch, ...)`'s work on the GPU, with the same arguments:
    samples 0..n advance n_steps steps from step0; x, the outputs' rows of these steps, status
    and fail_step are written back. The samples go in groups that fit the device's memory; a
    group's results reach the host arrays only when the group has finished. Returns n; a
    failure raises `_Failed` with the samples finished before it.

    ``reduce`` = (win, acc): no histories leave the device. The outputs hold one row per sample
    (two where the run records that history, one where it does not: the stepper reads which from
    their shapes), rewritten at each output step, and the output rows win[0]..win[1] (both
    included) are added to acc (n, `N_ACC`), whose sums go on from what acc holds."""
    from railride.engine.laws import _one_step_limit

    A, TS, c_sec, stops = vehicle
    P, vcmd = dampers
    utab, u_off, ftab, f_off, n_nodes, interval = inputs
    closed_loop, ctrl_stride, Gm, Hm, inner, noise, faults, sensing, snoise = control
    A_u, TS_u, vid = _vehicles(A, TS)
    try:
        kernel = _device_functions(kernel_key(law, faults[:n], sensing[:n], closed_loop, P[:n], A_u, TS_u, ftab))
    except Exception as exc:
        raise _Failed(exc, 0) from exc
    out_q, out_v, out_a, out_f, out_w, out_wd, out_d, out_fd, out_vc, status, fail_step = outputs
    r0, r1 = _rows(step0, n_steps, final, stride)
    n_rows = max(r1 - r0, 2)  # two at least: a history of one row is one the batch does not record
    histories = (out_q, out_v, out_a, out_f, out_w, out_wd, out_d, out_fd, out_vc)
    per_sample = [x, c_sec, stops, P, vcmd, Gm, Hm, inner, faults, sensing]
    row_bytes = sum(h.shape[2] * 8 for h in histories if h.shape[1] > 1)
    if reduce is not None:
        per_sample.append(reduce[1])
        n_rows, row_bytes = 1, sum(h.shape[1] * h.shape[2] * 8 for h in histories)
    bytes_per_sample = sum(a[0].nbytes for a in per_sample) + n_rows * row_bytes
    lam1 = _one_step_limit(dt)
    lo = 0
    record = _calls.last = {"kernel_s": 0.0, "transfer_s": 0.0, "groups": 0, "device_bytes": 0}
    try:
        # a stream of this call's own: the kernels and copies of calls from other threads (a
        # study's chunks in flight) overlap on the device, where the default stream would queue them
        stream = cuda.stream()
        win = np.zeros(2, dtype=np.int64) if reduce is None else np.asarray(reduce[0], dtype=np.int64)
        with _ALLOCATING:
            shared = [_to_device(a, stream) for a in (A_u, TS_u, utab, ftab, noise, snoise, win)]
    except Exception as exc:
        raise _Failed(exc, 0) from exc
    while lo < n:
        try:
            started = time.perf_counter()
            with _ALLOCATING:  # sized on the memory that the other threads' groups have left
                hi = lo + group_size(n - lo, bytes_per_sample)
                arrays = _group_arrays(stream, lo, hi, n_rows, vid, per_sample, histories, inputs, status, fail_step,
                                       reduce is not None)  # fmt: skip
            record["transfer_s"] += time.perf_counter() - started
            _run_group(kernel, stream, shared, arrays, lo, hi, law, step0, n_steps, final, stride, r0, r1, dt, lam1,
                       per_sample, histories, control, status, fail_step, reduce is not None, record)  # fmt: skip
        except Exception as exc:
            raise _Failed(exc, lo) from exc
        lo = hi
    return n


def _to_device(a: np.ndarray, stream):
    return cuda.to_device(np.ascontiguousarray(a), stream=stream)


def _group_arrays(stream, lo, hi, n_rows, vid, per_sample, histories, inputs, status, fail_step, reduce):  # fmt: skip
    """The device arrays of samples lo..hi: their rows of the per-sample arrays and tables'
    offsets, status, and the outputs (with ``reduce``, one row each and the metric sums)."""
    _, u_off, _, f_off, n_nodes, interval = inputs
    m = hi - lo
    dev = [_to_device(a[lo:hi], stream) for a in per_sample]
    small = [_to_device(a[lo:hi], stream) for a in (vid, u_off, f_off, n_nodes, interval)]
    st, fs = _to_device(status[lo:hi], stream), _to_device(fail_step[lo:hi], stream)
    if reduce:  # the host's one or two rows: the stepper writes row 0
        outs = [cuda.device_array((m, h.shape[1], h.shape[2]), stream=stream) for h in histories]
        acd = dev.pop()
    else:
        outs = [cuda.device_array((m, n_rows if h.shape[1] > 1 else 1, h.shape[2]), stream=stream) for h in histories]
        acd = cuda.device_array((1, N_ACC), stream=stream)  # not read
    return dev, small, st, fs, outs, acd


def _run_group(kernel, stream, shared, arrays, lo, hi, law, step0, n_steps, final, stride, r0, r1, dt, lam1,
               per_sample, histories, control, status, fail_step, reduce, record):  # fmt: skip
    """Samples lo..hi on the device (their ``arrays``, `_group_arrays`), their results into the
    host arrays once they finished (with ``reduce``, the metric sums: per_sample's last array)."""
    x = per_sample[0]
    closed_loop, ctrl_stride = control[0], control[1]
    m = hi - lo
    dev, small, st, fs, outs, acd = arrays
    xd, cs, sp, pd, vd, gd, hd, ind, fd, sd = dev
    vidd, uod, fod, nnd, itd = small
    Ad, TSd, ud, fdd, nod, snd, wind = shared
    launched = time.perf_counter()
    blocks = -(-m // THREADS_PER_BLOCK) if not simulated() else -(-m // 8)
    threads = THREADS_PER_BLOCK if not simulated() else 8
    # the simulator runs one kernel at a time: it swaps the kernel's `cuda` for its own per launch
    with _SIMULATOR if simulated() else contextlib.nullcontext():
        kernel[blocks, threads, stream](
            m, law, xd, step0, n_steps, final, stride, r0, dt, lam1, vidd, Ad, TSd, cs, sp, pd, vd, ud, uod, fdd,
            fod, nnd, itd, closed_loop, ctrl_stride, gd, hd, ind, nod, fd, sd, snd, *outs, st, fs, reduce, wind, acd,
        )  # fmt: skip
        stream.synchronize()
    finished = time.perf_counter()
    if not simulated():
        free, total = cuda.current_context().get_memory_info()
        record["device_bytes"] = max(record["device_bytes"], int(total - free))
    # all back from the device before any host array changes: a failure up to here leaves the
    # group as it was, for the CPU to run
    back = [xd.copy_to_host(stream=stream), st.copy_to_host(stream=stream), fs.copy_to_host(stream=stream)]
    rows = [
        o.copy_to_host(stream=stream)[:, : r1 - r0] if h.shape[1] > 1 and not reduce else None
        for h, o in zip(histories, outs)
    ]
    sums = acd.copy_to_host(stream=stream) if reduce else None
    stream.synchronize()
    x[lo:hi], status[lo:hi], fail_step[lo:hi] = back
    if sums is not None:
        per_sample[-1][lo:hi] = sums
    for h, r in zip(histories, rows):
        if r is not None:
            h[lo:hi, r0:r1] = r
    record["kernel_s"] += finished - launched
    record["transfer_s"] += time.perf_counter() - finished
    record["groups"] += 1
