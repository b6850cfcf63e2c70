"""All compiled code: the closed-loop fixed-step stepper (numba).

The stepper integrates, for each sample of a batch,

    q'' = Aq q + Av q' + Bw w + Bwd w' + Bf f,    f_i = -c_i (Ts q')_i

with classical fourth-order Runge-Kutta at a fixed step. The matrices are the vehicle's
(M^-1 folded in, see `simulate._system_arrays`), stored transposed so that a product runs
down the columns with the nine row sums held in registers. The rail inputs w, w' and the
forcing Bw w + Bwd w' come from tables on a time grid whose nodes fall on step boundaries,
interpolated with cubic Hermite polynomials (see `railride.track.wheelset_input_table`).
Sizes are module constants so that LLVM sees fixed trip counts. Nothing is allocated inside
the time loop; samples run in parallel over ``prange``.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

N_DOF = 9
N_CORNER = 4
N_WHEELSET = 4
N_RAIL = 8
NY = 2 * N_DOF + N_CORNER  # length of the stage vector (q, q', f)
#: a displacement or rotation beyond this (m or rad) is taken as divergence
DIVERGED = 1.0e3

#: reassociation lets LLVM vectorise the dot products; NaN/inf semantics stay IEEE so the
#: divergence check still sees them
_FAST = {"reassoc", "contract", "nsz", "arcp"}

#: how the secondary damper forces enter the equations (see `_acceleration`)
LAW_VISCOUS_IN_C = 0
LAW_FORCE_INPUT = 1

STATUS_OK = 0
STATUS_DIVERGED = 1


@njit(cache=True, inline="always", fastmath=_FAST)
def _hermite(t, n_nodes, interval):
    """Node index k of time t on the input grid and the cubic Hermite weights there.

    Returns (k, h00, h10, h01, h11, d00, d10, d11): a quantity with node values y, slopes y'
    is y(t) = h00 y_k + h10 y'_k + h01 y_k+1 + h11 y'_k+1 and its rate is
    y'(t) = d00 (y_k - y_k+1) + d10 y'_k + d11 y'_k+1 (the interval is folded in).
    """
    u = t / interval
    k = int(u)
    if k > n_nodes - 2:
        k = n_nodes - 2
    tau = u - k
    if tau > 1.0:
        tau = 1.0
    om = 1.0 - tau
    return (k,
            (1.0 + 2.0 * tau) * om * om,
            tau * om * om * interval,
            tau * tau * (3.0 - 2.0 * tau),
            tau * tau * (tau - 1.0) * interval,
            6.0 * tau * (tau - 1.0) / interval,
            om * (1.0 - 3.0 * tau),
            tau * (3.0 * tau - 2.0))


@njit(cache=True, inline="always", fastmath=_FAST)
def _forcing(t, ftab, off, n_nodes, interval, out):
    """Rail forcing r = Bw w + Bwd w' at time t, from the forcing table.

    Hermite interpolation is linear in the node data, so interpolating the node values
    P = Bw w_k, Q = Bw w'_k, R = Bwd w_k, S = Bwd w'_k (columns 0-8, 9-17, 18-26, 27-35)
    gives exactly Bw w(t) + Bwd w'(t) of the interpolated rail inputs, in 9 x 8 operations
    instead of interpolating 16 inputs and multiplying by a 9 x 16 matrix.
    """
    k, h00, h10, h01, h11, d00, d10, d11 = _hermite(t, n_nodes, interval)
    a = off + k
    b = a + 1
    for i in range(N_DOF):
        out[i] = (h00 * ftab[a, i] + h10 * ftab[a, 9 + i] + h01 * ftab[b, i] + h11 * ftab[b, 9 + i]
                  + d00 * (ftab[a, 18 + i] - ftab[b, 18 + i]) + d10 * ftab[a, 27 + i]
                  + d11 * ftab[b, 27 + i])


@njit(cache=True, inline="always", fastmath=_FAST)
def _rail_inputs(t, utab, off, n_nodes, interval, w, wd):
    """Rail heights w and velocities w' at the wheelsets at time t, from the input table."""
    k, h00, h10, h01, h11, d00, d10, d11 = _hermite(t, n_nodes, interval)
    a = off + k
    b = a + 1
    for c in range(N_RAIL):
        w[c] = h00 * utab[a, c] + h10 * utab[a, 8 + c] + h01 * utab[b, c] + h11 * utab[b, 8 + c]
        wd[c] = d00 * (utab[a, c] - utab[b, c]) + d10 * utab[a, 8 + c] + d11 * utab[b, 8 + c]


@njit(cache=True, inline="always", fastmath=_FAST)
def _mv9(AT, x, n_cols, r, out):
    """out = r + A x for the 9 rows of q'', with A stored transposed (n_cols, 9).

    The nine sums live in named locals on purpose: numba cannot tell LLVM that ``out`` does
    not alias the inputs, so an array accumulator is reloaded and stored at every column and
    the product becomes load-bound (about 3x slower, see docs/performance.md).
    """
    a0 = r[0]
    a1 = r[1]
    a2 = r[2]
    a3 = r[3]
    a4 = r[4]
    a5 = r[5]
    a6 = r[6]
    a7 = r[7]
    a8 = r[8]
    for j in range(n_cols):
        xj = x[j]
        a0 += AT[j, 0] * xj
        a1 += AT[j, 1] * xj
        a2 += AT[j, 2] * xj
        a3 += AT[j, 3] * xj
        a4 += AT[j, 4] * xj
        a5 += AT[j, 5] * xj
        a6 += AT[j, 6] * xj
        a7 += AT[j, 7] * xj
        a8 += AT[j, 8] * xj
    out[0] = a0
    out[1] = a1
    out[2] = a2
    out[3] = a3
    out[4] = a4
    out[5] = a5
    out[6] = a6
    out[7] = a7
    out[8] = a8


@njit(cache=True, inline="always", fastmath=_FAST)
def _secondary_rates(TT, y, out):
    """out = deflection rates of the four secondary corners, Ts q' (TT = Ts^T, (9, 4))."""
    b0 = 0.0
    b1 = 0.0
    b2 = 0.0
    b3 = 0.0
    for j in range(N_DOF):
        vj = y[N_DOF + j]
        b0 += TT[j, 0] * vj
        b1 += TT[j, 1] * vj
        b2 += TT[j, 2] * vj
        b3 += TT[j, 3] * vj
    out[0] = b0
    out[1] = b1
    out[2] = b2
    out[3] = b3


@njit(cache=True, inline="always", fastmath=_FAST)
def _damper_forces(y, TT, c_sec, rates):
    """Secondary damper forces f = -c (Ts q') into y[18:22]."""
    _secondary_rates(TT, y, rates)
    for c in range(N_CORNER):
        y[2 * N_DOF + c] = -c_sec[c] * rates[c]


@njit(cache=True, inline="always", fastmath=_FAST)
def _acceleration(law, y, r, AT, TT, c_sec, rates, out):
    """out = q'' for y = (q, q', f) with rail forcing r.

    LAW_VISCOUS_IN_C: the viscous dampers are part of Av, so q'' = r + [Aq Av] (q, q') and f is
    only computed when recorded. LAW_FORCE_INPUT: f = -c (Ts q') goes into y[18:22] first and
    q'' = r + [Aq Av Bf] y (Av without the dampers).
    """
    if law == LAW_VISCOUS_IN_C:
        _mv9(AT, y, 2 * N_DOF, r, out)
    else:
        _damper_forces(y, TT, c_sec, rates)
        _mv9(AT, y, NY, r, out)


@njit(cache=True, parallel=True, fastmath=_FAST)
def run_batch(law, x, step0, n_steps, final, stride, dt, A, TS, c_sec,
              utab, u_off, ftab, f_off, n_nodes, interval,
              out_q, out_v, out_a, out_f, out_w, out_wd,
              status, fail_step):
    """Advance every sample's state x[s] = (q, q') by n_steps RK4 steps of dt.

    Per sample s: A[s] (NY, 9) maps y = (q, q', f) to q'' (Aq, Av, Bf side by side, stored
    transposed), TS[s] (9, 4) maps q' to the secondary deflection rates, c_sec[s] holds the four
    damping coefficients, and ``law`` says how the damper forces enter (LAW_VISCOUS_IN_C or
    LAW_FORCE_INPUT). The rail inputs come as tables on the time grid k * interval[s] with
    n_nodes[s] rows: utab rows from u_off[s] (w, w', for the record) and ftab rows from
    f_off[s] (the forcing, see `_forcing`).

    Steps are numbered globally from step0 (t = step * dt). At every step whose number is a
    multiple of ``stride`` the state, acceleration, damper forces and rail inputs at that time
    are written to row step // stride of the outputs; with ``final`` the state after the last
    step is written too. A sample whose state leaves +-DIVERGED or stops being finite gets
    status STATUS_DIVERGED and the step number in fail_step, and stops.
    """
    n_samples = x.shape[0]
    for smp in prange(n_samples):
        if status[smp] != STATUS_OK:
            continue
        q = x[smp, :N_DOF].copy()
        v = x[smp, N_DOF:].copy()
        y = np.empty(NY)  # stage state (q, q', f)
        rates = np.empty(N_CORNER)
        k1v = np.empty(N_DOF)
        k2v = np.empty(N_DOF)
        k3v = np.empty(N_DOF)
        k4v = np.empty(N_DOF)
        k2q = np.empty(N_DOF)
        k3q = np.empty(N_DOF)
        r0 = np.empty(N_DOF)  # rail forcing at t, t + dt/2, t + dt
        rm = np.empty(N_DOF)
        r1 = np.empty(N_DOF)
        w = np.empty(N_RAIL)
        wd = np.empty(N_RAIL)
        at, tt, cs = A[smp], TS[smp], c_sec[smp]
        uo, fo, nn, itv = u_off[smp], f_off[smp], n_nodes[smp], interval[smp]
        h = 0.5 * dt
        _forcing(step0 * dt, ftab, fo, nn, itv, r0)
        last = n_steps + 1 if final else n_steps
        for n in range(last):
            step = step0 + n
            t = step * dt
            for i in range(N_DOF):
                y[i] = q[i]
                y[N_DOF + i] = v[i]
            _acceleration(law, y, r0, at, tt, cs, rates, k1v)
            if step % stride == 0:
                row = step // stride
                bad = False
                for i in range(N_DOF):
                    out_q[smp, row, i] = q[i]
                    out_v[smp, row, i] = v[i]
                    out_a[smp, row, i] = k1v[i]
                    if not (abs(q[i]) < DIVERGED and abs(v[i]) < 1e3 * DIVERGED):
                        bad = True
                if law == LAW_VISCOUS_IN_C:
                    _damper_forces(y, tt, cs, rates)
                for c in range(N_CORNER):
                    out_f[smp, row, c] = y[2 * N_DOF + c]
                _rail_inputs(t, utab, uo, nn, itv, w, wd)
                for c in range(N_RAIL):
                    out_w[smp, row, c] = w[c]
                    out_wd[smp, row, c] = wd[c]
                if bad:
                    status[smp] = STATUS_DIVERGED
                    fail_step[smp] = step
                    break
            if n == n_steps:
                break
            _forcing(t + h, ftab, fo, nn, itv, rm)  # stages 2 and 3 share t + dt/2
            _forcing(t + dt, ftab, fo, nn, itv, r1)
            for i in range(N_DOF):
                y[i] = q[i] + h * v[i]
                k2q[i] = v[i] + h * k1v[i]
                y[N_DOF + i] = k2q[i]
            _acceleration(law, y, rm, at, tt, cs, rates, k2v)
            for i in range(N_DOF):
                y[i] = q[i] + h * k2q[i]
                k3q[i] = v[i] + h * k2v[i]
                y[N_DOF + i] = k3q[i]
            _acceleration(law, y, rm, at, tt, cs, rates, k3v)
            for i in range(N_DOF):
                y[i] = q[i] + dt * k3q[i]
                y[N_DOF + i] = v[i] + dt * k3v[i]
            _acceleration(law, y, r1, at, tt, cs, rates, k4v)
            for i in range(N_DOF):
                q[i] += dt / 6.0 * (v[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + y[N_DOF + i])
                v[i] += dt / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i])
                r0[i] = r1[i]
        for i in range(N_DOF):
            x[smp, i] = q[i]
            x[smp, N_DOF + i] = v[i]
