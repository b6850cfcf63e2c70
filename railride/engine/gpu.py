"""The GPU stepper: `railride.engine.kernels.run_batch`'s work with one CUDA thread per sample
(numba-cuda, the ``gpu`` extra), in float64 throughout.

Each thread advances one sample with the same fixed-step classical RK4, sub-steps, controller
sampling, delays, sensing, inner loop, faults, bump stops and record as the CPU sample stepper.
The laws are not written again: the kernel calls the functions of `railride.engine.laws` and
`railride.engine.sample_parts`, which numba-cuda compiles for the device. What is the GPU's own is
the plumbing: thread-local work arrays, the q'' product as plain loops (the CPU's vector
intrinsics have no device form), and the transfers.

Memory. The vehicles' matrices are stored once per distinct vehicle (a batch of one vehicle
reads one copy, which the device caches), the rail tables once per distinct track (as on the
CPU, `railride.run.inputs`), and the output histories only for the rows a call writes. A batch
whose arrays do not fit the device's free memory is split into sample groups that do.

In numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``, how the tests run this kernel without a
GPU) a kernel runs as Python: there the kernel and every numba function it calls run as their
Python sources (`_python_mirror`), since the simulator's arrays cannot enter compiled code.
"""

from __future__ import annotations

import contextlib
import importlib.util
import threading
import time
import types

import numpy as np
from numba import float64, int64, njit

try:  # numba-cuda (the gpu extra) when installed; numba's own CUDA target otherwise, while it has one
    from numba import cuda
except ImportError:  # pragma: no cover - a numba without a CUDA target and no numba-cuda
    cuda = None  # type: ignore[assignment]

from railride.engine import laws, sample_parts
from railride.engine.laws import (
    _corner_values,
    add_stops,
    damper_law,
    fault_at,
)
from railride.engine.layout import (
    FAULT_DISCONNECTED,
    FAULT_NONE,
    FD_HELD,
    F_MODE,
    I_B,
    I_DELAY,
    I_G,
    I_LAW,
    LAW_BOUC_WEN,
    LAW_IDEAL,
    LAW_VISCOUS_IN_C,
    NS_MAX,
    NY,
    N_CORNER,
    N_DAMPER_STATES,
    N_DOF,
    N_FAULT_COLS,
    N_PACKED,
    N_RAIL,
    P_BETA,
    P_GAMMA,
    P_N,
    S_ON,
    S_W_AA,
    S_W_C,
    STATUS_DIVERGED,
    STATUS_OK,
)
from railride.engine.layout import FASTMATH as _FAST
from railride.engine.sample_parts import (
    N_ACC,
    accelerometer_filters,
    accumulate_metrics,
    controller_sample,
    hold_failed_coils,
    inner_loop,
    record_row,
    rk4_advance,
    rk4_stage_state,
    substep_count,
)

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
# the sizes of the kernel's thread-local arrays: names, since a local array's size must be a
# constant, not an expression
_N_FORCING = 3 * N_DOF  # the rail forcing at a sub-step's start, middle and end
_N_MEAS = 2 * N_DOF  # the controller's sample of (q, q')


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


# -- the kernel -----------------------------------------------------------------------------------
@njit(inline="always", fastmath=_FAST)
def _qdd(s, y, n_cols, R, roff, at, K, koff):
    """K[koff + N_DOF + i] = R[roff + i] + sum_j at[j, i] y_j for the N_DOF rows of q'', with
    y = (s[:2 N_DOF], y[2 N_DOF:n_cols]): (q, q') read from the state, the corner forces from the
    stage vector; at (NY, N_DOF) is the transposed matrix (`kernels.run_batch`)."""
    for i in range(N_DOF):
        acc = R[roff + i]
        for j in range(2 * N_DOF):
            acc += at[j, i] * s[j]
        for j in range(2 * N_DOF, n_cols):
            acc += at[j, i] * y[j]
        K[koff + N_DOF + i] = acc


@njit(inline="always", fastmath=_FAST)
def _derivative(law, s, R, roff, at, tt, pp, vcmd, conn, y, cx, cv, K, koff, zk, fsave):
    """K[koff:koff + NS_MAX] = d/dt of s: `kernels._derivative` with plain loops (see there)."""
    for i in range(N_DOF):
        K[koff + i] = s[N_DOF + i]
    _corner_values(tt, s, 0, cx)
    _corner_values(tt, s, N_DOF, cv)
    if law == LAW_VISCOUS_IN_C:
        if zk[1] > 0.0:
            for c in range(N_CORNER):
                y[2 * N_DOF + c] = 0.0
            if add_stops(zk, cx, y, 2 * N_DOF, fsave):
                _qdd(s, y, NY, R, roff, at, K, koff)
                return
        _qdd(s, y, 2 * N_DOF, R, roff, at, K, koff)
        return
    for c in range(N_CORNER):
        b = 2 * N_DOF + N_DAMPER_STATES * c
        F, dz, dyy, du = damper_law(law, pp, cx[c], cv[c], s[b], s[b + 1], s[b + 2], vcmd[c])
        y[2 * N_DOF + c] = -F * conn[c]
        K[koff + b] = dz
        K[koff + b + 1] = dyy
        K[koff + b + 2] = du
    if zk[1] > 0.0 and add_stops(zk, cx, y, 2 * N_DOF, fsave):
        _qdd(s, y, NY, R, roff, at, K, koff)
        for c in range(N_CORNER):
            y[2 * N_DOF + c] = fsave[c]
        return
    _qdd(s, y, NY, R, roff, at, K, koff)


@njit(inline="always", fastmath=_FAST)
def _forcing(t, ftab, off, n_nodes, interval, R, roff):
    """R[roff:roff + N_DOF] = the rail forcing at t from the forcing table (`kernels._forcing`:
    the Hermite weights on the node values and slopes of Bw w and Bwd w', plain loops)."""
    k, h00, h10, h01, h11, d00, d10, d11 = laws._hermite(t, n_nodes, interval)
    a = off + k
    b = a + 1
    for i in range(N_DOF):
        R[roff + i] = (
            h00 * ftab[a, i]
            + h10 * ftab[a, N_DOF + i]
            + h01 * ftab[b, i]
            + h11 * ftab[b, N_DOF + i]
            + d00 * (ftab[a, 2 * N_DOF + i] - ftab[b, 2 * N_DOF + i])
            + d10 * ftab[a, 3 * N_DOF + i]
            + d11 * ftab[b, 3 * N_DOF + i]
        )


def _kernel_for(fixed_law: int, with_faults: bool, with_sensing: bool, lean: bool):
    """The kernel's Python function for one kind of batch. Its arguments are constants of the
    compile: ``fixed_law`` >= 0 is the damper law of every sample (LAW_*; -1: read from the
    ``law`` argument), ``with_faults`` / ``with_sensing`` False leave the fault checks and the
    accelerometers out (a batch with no faulty sample, no realistic sensing), and ``lean`` steps
    RK4 with one stage rate and a running sum of them instead of the four stage rates side by
    side. A kernel without what it does not need has less thread-local memory (docs/gpu.md)."""
    # local arrays' sizes must be constants of the compile
    n_rates, n_sum = (NS_MAX, NS_MAX) if lean else (4 * NS_MAX, 1)

    # fmt: off
    def _kernel(
        n, law_arg, x, step0, n_steps, final, stride, row0, dt, lam1, vid, A, TS, c_sec, stops, P, vcmd, utab, u_off,
        ftab, f_off, n_nodes, interval, closed_loop, ctrl_stride, Gm, Hm, inner, noise, faults, sensing, snoise, out_q,
        out_v, out_a, out_f, out_w, out_wd, out_d, out_fd, out_vc, status, fail_step, reduce, win, acc,
    ):
        # fmt: on
        """One thread per sample smp < n: `kernels._run_samples`'s loop body for that sample. The
        vehicle's matrices are A[vid[smp]], TS[vid[smp]]; the outputs hold the rows from row0 on.
        With ``reduce``, the outputs hold one row, rewritten at every output step, and the rows
        win[0] <= row <= win[1] go into the sample's metric sums acc[smp] (`sample_parts.accumulate_metrics`)."""
        smp = cuda.grid(1)
        if smp >= n or status[smp] != STATUS_OK:
            return
        law = law_arg if fixed_law < 0 else fixed_law
        has_states = law != LAW_VISCOUS_IN_C and law != LAW_IDEAL
        ns = NS_MAX if has_states else 2 * N_DOF
        xs = x[smp]
        s = cuda.local.array(NS_MAX, float64)
        st = cuda.local.array(NS_MAX, float64)
        K = cuda.local.array(n_rates, float64)
        ksum = cuda.local.array(n_sum, float64)  # lean: the stage rates' weighted sum
        for i in range(NS_MAX):
            s[i] = xs[i]
            st[i] = 0.0  # the states a law without any still reads
        for i in range(n_rates):
            K[i] = 0.0
        y = cuda.local.array(NY, float64)
        cx = cuda.local.array(N_CORNER, float64)
        cv = cuda.local.array(N_CORNER, float64)
        R = cuda.local.array(_N_FORCING, float64)
        w = cuda.local.array(N_RAIL, float64)
        wd = cuda.local.array(N_RAIL, float64)
        fsave = cuda.local.array(N_CORNER, float64)
        vc = cuda.local.array(N_CORNER, float64)
        conn = cuda.local.array(N_CORNER, float64)
        meas = cuda.local.array(_N_MEAS, float64)
        # the small rows the laws read, in thread-local copies
        pp = cuda.local.array(N_PACKED, float64)
        for i in range(N_PACKED):
            pp[i] = P[smp, i]
        tt = cuda.local.array((N_DOF, N_CORNER), float64)
        for i in range(N_DOF):
            for c in range(N_CORNER):
                tt[i, c] = TS[vid[smp], i, c]
        zk = cuda.local.array(2, float64)
        zk[0] = stops[smp, 0]
        zk[1] = stops[smp, 1]
        fm = cuda.local.array(N_FAULT_COLS, int64)
        faulty = False  # a healthy sample skips the fault checks
        for i in range(N_FAULT_COLS):
            fm[i] = faults[smp, i]
        for c in range(N_CORNER):
            vc[c] = vcmd[smp, c]
            conn[c] = 1.0
            faulty = faulty or fm[F_MODE + c] != FAULT_NONE
        faulty = with_faults and faulty
        at = A[vid[smp]]
        cs = c_sec[smp]
        uo, fo, nn, itv = u_off[smp], f_off[smp], n_nodes[smp], interval[smp]
        gm, hm = Gm[smp], Hm[smp]
        delay = int(inner[smp, I_DELAY])
        tc = ctrl_stride * dt
        srow = sensing[smp]
        sens = with_sensing and closed_loop and srow[S_ON] > 0.0
        w_aa = srow[S_W_AA]
        hp = 1.0 / (1.0 + srow[S_W_C] * tc)
        bw1 = law == LAW_BOUC_WEN and pp[P_N] == 1.0
        gb1 = pp[P_N] * (abs(pp[P_GAMMA]) + abs(pp[P_BETA]))
        out4 = (out_q, out_v, out_a, out_f)
        out5 = (out_w, out_wd, out_d, out_fd, out_vc)
        _forcing(step0 * dt, ftab, fo, nn, itv, R, 0)
        last = n_steps + 1 if final else n_steps
        for n_ in range(last):
            step = step0 + n_
            t = step * dt
            if closed_loop and step % ctrl_stride == 0:
                controller_sample(xs, step // ctrl_stride, delay, s, meas, sens, srow, snoise, noise, tc, hp, gm, hm)
            if closed_loop and law == LAW_IDEAL:
                for c in range(N_CORNER):
                    vc[c] = xs[FD_HELD + c]
            if faulty:
                for c in range(N_CORNER):
                    if fault_at(fm, c, step) == FAULT_DISCONNECTED:
                        conn[c] = 0.0
            _derivative(law, s, R, 0, at, tt, pp, vc, conn, y, cx, cv, K, 0, zk, fsave)
            if sens:
                accelerometer_filters(xs, tt, K, dt, w_aa)
            if closed_loop and law != LAW_IDEAL:
                inner_loop(int(inner[smp, I_LAW]), inner[smp, I_B], inner[smp, I_G], y, xs, cv, pp, vc, s, K)
            if faulty:
                hold_failed_coils(fm, step, vc, pp, s, K)
            if step % stride == 0:
                row = 0 if reduce else step // stride - row0
                if record_row(smp, row, t, law, s, K, y, cv, tt, cs, xs, vc, utab, uo, nn, itv, w, wd, out4, out5):
                    status[smp] = STATUS_DIVERGED
                    fail_step[smp] = step
                    break
                if reduce and win[0] <= step // stride <= win[1]:
                    accumulate_metrics(acc, smp, out_q, out_a)
            if n_ == n_steps:
                break
            m = substep_count(law, bw1, gb1, lam1, pp, cv, s, dt)
            h = dt / m
            for sub in range(m):
                ts = t + sub * h
                _forcing(ts + 0.5 * h, ftab, fo, nn, itv, R, N_DOF)
                _forcing(ts + h, ftab, fo, nn, itv, R, 2 * N_DOF)
                if lean:
                    _lean_rk4(law, s, st, K, ksum, h, sub, has_states, R, at, tt, pp, vc, conn, y, cx, cv, zk, fsave)
                else:
                    for stage in range(4):
                        if stage == 0 and sub == 0:
                            continue
                        ch = h * (0.0 if stage == 0 else (0.5 if stage < 3 else 1.0))
                        roff = N_DOF * (0 if stage == 0 else (1 if stage < 3 else 2))
                        prev = NS_MAX * (stage - 1 if stage > 0 else 0)
                        rk4_stage_state(st, s, K, prev, ch, has_states)
                        _derivative(law, st, R, roff, at, tt, pp, vc, conn, y, cx, cv, K, NS_MAX * stage, zk, fsave)
                    rk4_advance(s, K, h, has_states)
                for i in range(N_DOF):
                    R[i] = R[2 * N_DOF + i]
        for i in range(ns):
            xs[i] = s[i]

    return _kernel


@njit(inline="always", fastmath=_FAST)
def _lean_rk4(law, s, st, K, ksum, h, sub, has_states, R, at, tt, pp, vc, conn, y, cx, cv, zk, fsave):
    """One RK4 sub-step of length h with one stage rate K (its first NS_MAX) and the running sum
    ksum = K1 + 2 K2 + 2 K3 (+ K4), summed in the order of `rk4_advance`: the same arithmetic as
    the four stage rates side by side, in half their memory. At sub-step 0, K holds stage 1's
    rate already (the step's start, with the inner loop's coil rates)."""
    n = NS_MAX if has_states else 2 * N_DOF
    if sub > 0:
        _derivative(law, s, R, 0, at, tt, pp, vc, conn, y, cx, cv, K, 0, zk, fsave)
    for i in range(n):
        ksum[i] = K[i]
    for stage in range(1, 4):
        ch = h * (0.5 if stage < 3 else 1.0)
        for i in range(n):
            st[i] = s[i] + ch * K[i]
        _derivative(law, st, R, N_DOF * (1 if stage < 3 else 2), at, tt, pp, vc, conn, y, cx, cv, K, 0, zk, fsave)
        wgt = 2.0 if stage < 3 else 1.0
        for i in range(n):
            ksum[i] += wgt * K[i]
    for i in range(n):
        s[i] += h / 6.0 * ksum[i]


#: the kernel for any batch: every damper law, faults and sensing, the four stage rates
_kernel = _kernel_for(-1, True, True, False)


def _python_mirror(*functions):
    """Copies of ``functions`` (plain Python functions of this module) whose globals are this
    module's, `laws`' and `sample_parts`' with every numba function replaced by its Python source,
    recursively: what the CUDA simulator can run, since its arrays cannot enter compiled code."""
    from numba.core.registry import CPUDispatcher

    space: dict = {}
    for module in (laws, sample_parts, globals()):
        space.update(vars(module) if isinstance(module, types.ModuleType) else module)
    for name, obj in list(space.items()):
        if isinstance(obj, CPUDispatcher):
            obj = obj.py_func
        if isinstance(obj, types.FunctionType) and obj.__module__ in (laws.__name__, sample_parts.__name__, __name__):
            space[name] = types.FunctionType(obj.__code__, space, name, obj.__defaults__, obj.__closure__)
    space["laws"] = types.SimpleNamespace(**{k: space.get(k, v) for k, v in vars(laws).items()})
    # from each function itself, not its name: a kernel of `_kernel_for` keeps its constants
    return [types.FunctionType(f.__code__, space, f.__name__, f.__defaults__, f.__closure__) for f in functions]


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


def kernel_key(law: int, faults: np.ndarray, sensing: np.ndarray, closed_loop: bool) -> tuple:
    """Which kernel a batch runs (`_kernel_for`'s arguments): with SPECIALISE, the batch's damper
    law, and faults and sensing only where some sample has them; else the one for any batch."""
    if not SPECIALISE:
        return (-1, True, True, LEAN_RK4)
    with_faults = bool(np.any(faults[:, F_MODE : F_MODE + N_CORNER] != FAULT_NONE))
    with_sensing = bool(closed_loop and np.any(sensing[:, S_ON] > 0.0))
    return (int(law), with_faults, with_sensing, LEAN_RK4)


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
    return cuda.jit(kernel, **limit)


def last_call() -> dict:
    """What the calling thread's last `run_gpu` took: seconds in the kernels (``kernel_s``) and
    in the transfers (``transfer_s``), its sample groups (``groups``) and the most device memory in
    use while it ran (``device_bytes``). Read by benchmarks/bench_gpu.py."""
    return dict(getattr(_calls, "last", {}))


def kernel_signature() -> tuple:
    """The kernel's argument types as `run_gpu` passes them (numba types)."""
    from numba import types

    i, f, b = types.int64, types.float64, types.boolean

    def a(ndim, dtype=f):
        return types.Array(dtype, ndim, "C")

    return (
        (i, i, a(2), i, i, b, i, i, f, f, a(1, i), a(3), a(3), a(2), a(2), a(2), a(2), a(2), a(1, i), a(2))
        + (a(1, i), a(1, i), a(1), b, i, a(3), a(3), a(2), a(2), a(2, i), a(2), a(2))
        + (a(3),) * 9
        + (a(1, i), a(1, i), b, a(1, i), a(2))
    )


def ptx(cc: tuple[int, int] = (9, 0), key: tuple = (-1, True, True, False)) -> str:
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
        code, _ = cuda.compile_ptx(_kernel_for(*key), kernel_signature(), cc=cc)
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
    try:
        kernel = _device_functions(kernel_key(law, faults[:n], sensing[:n], closed_loop))
    except Exception as exc:
        raise _Failed(exc, 0) from exc
    out_q, out_v, out_a, out_f, out_w, out_wd, out_d, out_fd, out_vc, status, fail_step = outputs
    A_u, TS_u, vid = _vehicles(A, TS)
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
