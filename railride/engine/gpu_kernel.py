"""The GPU kernel (numba-cuda): `railride.engine.kernels.run_batch`'s loop body for one sample,
one CUDA thread per sample, in float64 throughout; `railride.engine.gpu` compiles and launches it.

Each thread advances one sample with the same fixed-step classical RK4, sub-steps, controller
sampling, delays, sensing, inner loop, faults, bump stops and record as the CPU sample stepper.
The laws are not written again: the kernel calls the functions of `railride.engine.laws` and
`railride.engine.sample_parts`, which numba-cuda compiles for the device. What is the GPU's own is
the plumbing: thread-local work arrays, the q'' product and the rail forcing as plain loops (the
CPU's vector intrinsics have no device form), and the builds of the kernel (`_kernel_for`): one
per kind of batch, with one RK4 stage rate at a time (`_lean_rk4`), for less thread-local memory.

In numba's CUDA simulator (``NUMBA_ENABLE_CUDASIM=1``, how the tests run the kernel without a
GPU) a kernel runs as Python: there the kernel and every numba function it calls run as their
Python sources (`_python_mirror`), since the simulator's arrays cannot enter compiled code.
"""

from __future__ import annotations

import functools
import types

import numpy as np
from numba import float64, int64, njit

try:  # numba-cuda (the gpu extra) when installed; numba's own CUDA target otherwise, while it has one
    from numba import cuda
except ImportError:  # pragma: no cover - a numba without a CUDA target and no numba-cuda
    cuda = None  # type: ignore[assignment]

from railride.engine import laws, sample_parts
from railride.engine.laws import (
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

# the sizes of the kernel's thread-local arrays: names, since a local array's size must be a
# constant, not an expression
_N_FORCING = 3 * N_DOF  # the rail forcing at a sub-step's start, middle and end
_N_MEAS = 2 * N_DOF  # the controller's sample of (q, q')


@njit(inline="always", fastmath=_FAST)
def _qdd(s, y, n_cols, R, roff, at, nz, K, koff):
    """K[koff + N_DOF + i] = R[roff + i] + sum_j at[j, i] y_j for the N_DOF rows of q'', with
    y = (s[:2 N_DOF], y[2 N_DOF:n_cols]): (q, q') read from the state, the corner forces from the
    stage vector; at (NY, N_DOF) is the transposed matrix (`kernels.run_batch`). Only the terms
    where nz[j, i] (a constant of the compile: `_kernel_for`'s ``pattern``) are summed, in the
    order of j: a term left out is one whose coefficient is 0 in every vehicle of the batch."""
    for i in range(N_DOF):
        acc = R[roff + i]
        for j in range(2 * N_DOF):
            if nz[j, i]:
                acc += at[j, i] * s[j]
        for j in range(2 * N_DOF, n_cols):
            if nz[j, i]:
                acc += at[j, i] * y[j]
        K[koff + N_DOF + i] = acc


@njit(inline="always", fastmath=_FAST)
def _corners(tt, tnz, s, offset, out):
    """out[c] = sum_j tt[j, c] s[offset + j], `laws._corner_values` over the terms where tnz[j, c]
    (a constant of the compile: `_kernel_for`'s ``pattern``), in the same order."""
    for c in range(N_CORNER):
        acc = 0.0
        for j in range(N_DOF):
            if tnz[j, c]:
                acc += tt[j, c] * s[offset + j]
        out[c] = acc


@njit(inline="always", fastmath=_FAST)
def _derivative(law, s, R, roff, at, nz, tt, tnz, pp, vcmd, conn, y, cx, cv, K, koff, zk, fsave):
    """K[koff:koff + NS_MAX] = d/dt of s: `kernels._derivative` with plain loops (see there)."""
    for i in range(N_DOF):
        K[koff + i] = s[N_DOF + i]
    _corners(tt, tnz, s, 0, cx)
    _corners(tt, tnz, s, N_DOF, cv)
    if law == LAW_VISCOUS_IN_C:
        if zk[1] > 0.0:
            for c in range(N_CORNER):
                y[2 * N_DOF + c] = 0.0
            if add_stops(zk, cx, y, 2 * N_DOF, fsave):
                _qdd(s, y, NY, R, roff, at, nz, K, koff)
                return
        _qdd(s, y, 2 * N_DOF, R, roff, at, nz, K, koff)
        return
    for c in range(N_CORNER):
        b = 2 * N_DOF + N_DAMPER_STATES * c
        F, dz, dyy, du = damper_law(law, pp, cx[c], cv[c], s[b], s[b + 1], s[b + 2], vcmd[c])
        y[2 * N_DOF + c] = -F * conn[c]
        K[koff + b] = dz
        K[koff + b + 1] = dyy
        K[koff + b + 2] = du
    if zk[1] > 0.0 and add_stops(zk, cx, y, 2 * N_DOF, fsave):
        _qdd(s, y, NY, R, roff, at, nz, K, koff)
        for c in range(N_CORNER):
            y[2 * N_DOF + c] = fsave[c]
        return
    _qdd(s, y, NY, R, roff, at, nz, K, koff)


@njit(inline="always", fastmath=_FAST)
def _forcing(t, ftab, off, n_nodes, interval, R, roff, fnz):
    """R[roff:roff + N_DOF] = the rail forcing at t from the forcing table (`kernels._forcing`:
    the Hermite weights on the node values and slopes of Bw w and Bwd w', plain loops); 0 in the
    rows that no rail input reaches (not fnz[i], a constant of the compile: their columns of the
    table are 0)."""
    k, h00, h10, h01, h11, d00, d10, d11 = laws._hermite(t, n_nodes, interval)
    a = off + k
    b = a + 1
    for i in range(N_DOF):
        if not fnz[i]:
            R[roff + i] = 0.0
            continue
        R[roff + i] = (
            h00 * ftab[a, i]
            + h10 * ftab[a, N_DOF + i]
            + h01 * ftab[b, i]
            + h11 * ftab[b, N_DOF + i]
            + d00 * (ftab[a, 2 * N_DOF + i] - ftab[b, 2 * N_DOF + i])
            + d10 * ftab[a, 3 * N_DOF + i]
            + d11 * ftab[b, 3 * N_DOF + i]
        )


#: `_kernel_for`'s arguments for the kernel of any batch: every damper law, faults and sensing,
#: the four stage rates side by side, any Bouc-Wen exponent, every term of every product
GENERAL = (-1, True, True, False, False, -1)


def pattern_of(A, TS, forced) -> int:
    """`_kernel_for`'s ``pattern`` for the vehicles' matrices A (vehicles, NY, N_DOF) and TS
    (vehicles, N_DOF, N_CORNER) and the rows of q'' that rail inputs reach (``forced``, N_DOF
    bools): bit j N_DOF + i set where A[:, j, i] is not 0 in some vehicle, bit NY N_DOF +
    j N_CORNER + c where TS[:, j, c] is not 0 in some vehicle, bit NY N_DOF + N_DOF N_CORNER + i
    where forced[i]."""
    nonzero = np.concatenate([np.any(M != 0.0, axis=0).ravel() for M in (A, TS)] + [np.asarray(forced, bool)])
    return sum(1 << k for k, nz in enumerate(nonzero) if nz)


def _kernel_for(
    fixed_law: int, with_faults: bool, with_sensing: bool, lean: bool, unit_n: bool = False, pattern: int = -1
):
    """The kernel's Python function for one kind of batch. Its arguments are constants of the
    compile: ``fixed_law`` >= 0 is the damper law of every sample (LAW_*; -1: read from the
    ``law`` argument), ``with_faults`` / ``with_sensing`` False leave the fault checks and the
    accelerometers out (a batch with no faulty sample, no realistic sensing), and ``lean`` steps
    RK4 with one stage rate and a running sum of them instead of the four stage rates side by
    side. A kernel without what it does not need has less thread-local memory (docs/gpu.md).
    ``unit_n``: every sample's Bouc-Wen exponent n is 1 (the paper's damper), which the kernel
    then knows when it compiles, so the laws' powers |z|^(n-1) and their branches are compiled
    out (`laws._bouc_wen_rate`, `laws.damper_stiffness`). ``pattern`` (`pattern_of`; -1: every
    term): the terms of the q'' product and of the corner deflections that some vehicle of the
    batch has, and the rows of q'' that the rails reach; the others, zeros in every vehicle, are
    compiled out (the paper's vehicle with dampers has 56 of A's 240 and 20 of T's 40)."""
    # local arrays' sizes must be constants of the compile
    n_rates, n_sum = (NS_MAX, NS_MAX) if lean else (4 * NS_MAX, 1)
    # a constant array of the compile: the product's tests on it fold
    n_a, n_t = NY * N_DOF, N_DOF * N_CORNER
    bits = np.array([pattern < 0 or (pattern >> k) & 1 == 1 for k in range(n_a + n_t + N_DOF)])
    nz, tnz, fnz = bits[:n_a].reshape(NY, N_DOF), bits[n_a : n_a + n_t].reshape(N_DOF, N_CORNER), bits[n_a + n_t :]

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
        if unit_n:  # the value it holds, now a constant of the compile: the laws' branches on n fold
            pp[P_N] = 1.0
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
        _forcing(step0 * dt, ftab, fo, nn, itv, R, 0, fnz)
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
            _derivative(law, s, R, 0, at, nz, tt, tnz, pp, vc, conn, y, cx, cv, K, 0, zk, fsave)
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
                _forcing(ts + 0.5 * h, ftab, fo, nn, itv, R, N_DOF, fnz)
                _forcing(ts + h, ftab, fo, nn, itv, R, 2 * N_DOF, fnz)
                if lean:
                    _lean_rk4(
                        law, s, st, K, ksum, h, sub, has_states, R, at, nz, tt, tnz, pp, vc, conn, y, cx, cv, zk, fsave
                    )  # fmt: skip
                else:
                    for stage in range(4):
                        if stage == 0 and sub == 0:
                            continue
                        ch = h * (0.0 if stage == 0 else (0.5 if stage < 3 else 1.0))
                        roff = N_DOF * (0 if stage == 0 else (1 if stage < 3 else 2))
                        prev = NS_MAX * (stage - 1 if stage > 0 else 0)
                        rk4_stage_state(st, s, K, prev, ch, has_states)
                        kk = NS_MAX * stage
                        _derivative(law, st, R, roff, at, nz, tt, tnz, pp, vc, conn, y, cx, cv, K, kk, zk, fsave)
                    rk4_advance(s, K, h, has_states)
                for i in range(N_DOF):
                    R[i] = R[2 * N_DOF + i]
        for i in range(ns):
            xs[i] = s[i]

    return _kernel


@njit(inline="always", fastmath=_FAST)
def _lean_rk4(law, s, st, K, ksum, h, sub, has_states, R, at, nz, tt, tnz, pp, vc, conn, y, cx, cv, zk, fsave):
    """One RK4 sub-step of length h with one stage rate K (its first NS_MAX) and the running sum
    ksum = K1 + 2 K2 + 2 K3 (+ K4), summed in the order of `rk4_advance`: the same arithmetic as
    the four stage rates side by side, in half their memory. At sub-step 0, K holds stage 1's
    rate already (the step's start, with the inner loop's coil rates)."""
    n = NS_MAX if has_states else 2 * N_DOF
    if sub > 0:
        _derivative(law, s, R, 0, at, nz, tt, tnz, pp, vc, conn, y, cx, cv, K, 0, zk, fsave)
    for i in range(n):
        ksum[i] = K[i]
    for stage in range(1, 4):
        ch = h * (0.5 if stage < 3 else 1.0)
        for i in range(n):
            st[i] = s[i] + ch * K[i]
        roff = N_DOF * (1 if stage < 3 else 2)
        _derivative(law, st, R, roff, at, nz, tt, tnz, pp, vc, conn, y, cx, cv, K, 0, zk, fsave)
        wgt = 2.0 if stage < 3 else 1.0
        for i in range(n):
            ksum[i] += wgt * K[i]
    for i in range(n):
        s[i] += h / 6.0 * ksum[i]


def _python_mirror(*functions):
    """Copies of ``functions`` (plain Python functions of this module) whose globals are this
    module's, `laws`' and `sample_parts`' with every numba function replaced by its Python source,
    recursively: what the CUDA simulator can run, since its arrays cannot enter compiled code."""
    return _copies(functions, _mirror_space(lambda f: f))


def _device_mirror(*functions):
    """Copies of ``functions`` as `_python_mirror` makes them, with every numba function of this
    module, `laws` and `sample_parts` compiled for the device as a function of its own (numba's
    ``inline="never"``), which NVVM then inlines: what the device compiles. With the engine's
    ``inline="always"``, numba-cuda copied each callee's IR into the kernel at every call: most
    of a kernel's compile, for the same PTX in the build of the paper's batches (docs/gpu.md).
    numba-cuda gives the engine's fastmath flags to neither."""
    return _copies(functions, _device_space())


@functools.cache
def _device_space() -> dict:
    """`_device_mirror`'s globals, made once a process: their device functions, compiled for the
    first kernel, serve every later one (docs/gpu.md). Two threads asking first at once may each
    make one; their kernels then share fewer device functions, nothing else."""
    return _mirror_space(lambda f: njit(inline="never")(f))


def _copies(functions, space: dict) -> list:
    # from each function itself, not its name: a kernel of `_kernel_for` keeps its constants
    return [types.FunctionType(f.__code__, space, f.__name__, f.__defaults__, f.__closure__) for f in functions]


def _mirror_space(wrap) -> dict:
    """Globals for copies of this module's functions: this module's, `laws`' and `sample_parts`'
    with every function of those modules replaced by a copy of its Python source that reads these
    globals, recursively; a numba function's copy by ``wrap`` of it."""
    from numba.core.registry import CPUDispatcher

    space: dict = {}
    for module in (laws, sample_parts, globals()):
        space.update(vars(module) if isinstance(module, types.ModuleType) else module)
    ours = (laws.__name__, sample_parts.__name__, __name__)
    for name, obj in list(space.items()):
        compiled = isinstance(obj, CPUDispatcher)
        f = obj.py_func if compiled else obj
        if isinstance(f, types.FunctionType) and f.__module__ in ours:
            copy = types.FunctionType(f.__code__, space, name, f.__defaults__, f.__closure__)
            space[name] = wrap(copy) if compiled else copy
    mirror = types.ModuleType(laws.__name__)  # `laws.name` in the kernel's helpers reads the copies
    mirror.__dict__.update({k: space.get(k, v) for k, v in vars(laws).items() if k != "__name__"})
    space["laws"] = mirror
    return space


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
