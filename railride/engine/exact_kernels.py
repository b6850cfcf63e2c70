"""The compiled steps of the exact discretisation (`railride.engine.discrete`): the passive
vehicle, and an outer loop on the ideal actuator with exact states, each one sample at a time
from its step maps; the outputs are those the RK4 stepper records (`railride.engine.kernels`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from railride.engine.laws import _rail_inputs
from railride.engine.layout import DIVERGED, N_CORNER, N_DOF, N_RAIL, STATUS_DIVERGED, STATUS_OK
from railride.engine.layout import FASTMATH as _FAST


@njit(cache=True, nogil=True, fastmath=_FAST)
def exact_run(Phi, maps, used, stride, m, utab, interval, x0, A, Bw, Bwd, TS, c_sec, q, v, a, f, w, wd):
    """The exact discretisation of the passive vehicle (`railride.engine.discrete`), one sample: the
    state (q, q') at every output row from x0 by x_(k+1) = Phi x_k + maps[k % period] (the
    first used[k % period] input-table rows from the step's start), and the outputs the RK4 stepper records there:
    q, q', q'' = A x + Bw w + Bwd w', the secondary forces -c T^T q' and the rail inputs w, w'
    (cubic Hermite on the table, rates its derivative). ``utab`` holds enough rows for the last
    step's span (padded by the caller)."""
    period, n, width = maps.shape
    rows = q.shape[0]
    x = np.empty(n)
    g = np.empty(n)
    for i in range(n):
        x[i] = x0[i]
    nn = utab.shape[0]
    for k in range(rows):
        # the outputs at t_k
        _rail_inputs(k * stride * (interval / m), utab, 0, nn, interval, w[k], wd[k])
        for i in range(N_DOF):
            q[k, i] = x[i]
            v[k, i] = x[N_DOF + i]
            acc = 0.0
            for j in range(n):
                acc += A[N_DOF + i, j] * x[j]
            for j in range(N_RAIL):
                acc += Bw[i, j] * w[k, j] + Bwd[i, j] * wd[k, j]
            a[k, i] = acc
        for c in range(N_CORNER):
            acc = 0.0
            for i in range(N_DOF):
                acc += TS[i, c] * x[N_DOF + i]
            f[k, c] = -c_sec[c] * acc
        if k == rows - 1:
            break
        # one output step
        p = k % period
        base = (k * stride) // m
        for i in range(n):
            acc = 0.0
            for r in range(used[p]):  # the table rows this kind of step touches
                for j in range(16):
                    acc += maps[p, i, 16 * r + j] * utab[base + r, j]
            g[i] = acc
        for i in range(n):
            acc = g[i]
            for j in range(n):
                acc += Phi[i, j] * x[j]
            g[i] = acc
        for i in range(n):
            x[i] = g[i]


@njit(cache=True, nogil=True, fastmath=_FAST)
def exact_closed_run(
    phi,
    rail,
    force,
    start,
    period,
    m,
    stride,
    ctrl,
    tc,
    utab,
    interval,
    x0,
    A,
    Bw,
    Bwd,
    Bf,
    G,
    H,
    delay,
    n_out,
    q,
    v,
    a,
    f,
    w,
    wd,
    out_fd,
    out_vc,
):
    """The exact steps of an outer loop on the ideal actuator (`railride.engine.discrete.ClosedStepper`),
    one sample, with the RK4 stepper's controller: at every ``ctrl``-th step the demand computed
    ``delay`` samples before takes hold, the integrals xi gain tc times the carbody displacements,
    and the new demand G x + H xi is stored; the held demand is the corner force until the next
    sample. Records at every ``stride``-th step what the stepper records there. Returns (status,
    the step it diverged at or -1)."""
    n = phi.shape[1]
    n_seg = start.shape[0]
    n_steps = n_out * stride
    x = np.empty(n)
    y = np.empty(n)
    xi = np.zeros(3)
    ring = np.zeros((delay, N_CORNER))
    held = np.zeros(N_CORNER)
    nn = utab.shape[0]
    for i in range(n):
        x[i] = x0[i]
    rep = 0
    while True:
        for s in range(n_seg):
            step = rep * period + start[s]
            if step > n_steps:
                return STATUS_OK, -1
            if step % ctrl == 0:
                k = step // ctrl
                slot = k % delay
                for c in range(N_CORNER):
                    held[c] = ring[slot, c]
                for j in range(3):
                    xi[j] += tc * x[j]
                for c in range(N_CORNER):
                    acc = 0.0
                    for j in range(n):
                        acc += G[c, j] * x[j]
                    for j in range(3):
                        acc += H[c, j] * xi[j]
                    ring[slot, c] = acc
            if step % stride == 0:
                row = step // stride
                _rail_inputs(step * (interval / m), utab, 0, nn, interval, w[row], wd[row])
                bad = False
                for i in range(N_DOF):
                    q[row, i] = x[i]
                    v[row, i] = x[N_DOF + i]
                    if not (abs(x[i]) < DIVERGED and abs(x[N_DOF + i]) < 1e3 * DIVERGED):
                        bad = True
                    acc = 0.0
                    for j in range(n):
                        acc += A[N_DOF + i, j] * x[j]
                    for j in range(N_RAIL):
                        acc += Bw[i, j] * w[row, j] + Bwd[i, j] * wd[row, j]
                    for c in range(N_CORNER):
                        acc += Bf[i, c] * held[c]
                    a[row, i] = acc
                for c in range(N_CORNER):
                    f[row, c] = held[c]
                    out_fd[row, c] = held[c]
                    out_vc[row, c] = held[c]
                if bad:
                    return STATUS_DIVERGED, step
            if step == n_steps:
                return STATUS_OK, -1
            node = step // m
            for i in range(n):
                acc = 0.0
                for j in range(n):
                    acc += phi[s, i, j] * x[j]
                for j in range(16):
                    acc += rail[s, i, j] * utab[node, j] + rail[s, i, 16 + j] * utab[node + 1, j]
                for c in range(N_CORNER):
                    acc += force[s, i, c] * held[c]
                y[i] = acc
            for i in range(n):
                x[i] = y[i]
        rep += 1


# ---------------------------------------------------------------------------------------------
# The lane stepper: run_batch's arithmetic for LANES samples at once. Every per-sample array of
# the time loop holds one row of LANES doubles per quantity (lane-innermost), so that one vector
# instruction advances every sample of a group (docs/architecture.md, docs/performance.md).
