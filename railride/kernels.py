"""All compiled code: the closed-loop fixed-step stepper (numba).

The stepper integrates, for each sample of a batch,

    q'' = Aq q + Av q' + Bw w + Bwd w' + Bf f,    f_i = -c_i (Ts q')_i

with classical fourth-order Runge-Kutta at a fixed step. The matrices are the vehicle's
(M^-1 folded in, see `simulate._system_arrays`), stored transposed so that a product runs
down the columns with the nine row sums held in registers; w, w' are the rail heights and velocities at the
four wheelsets, interpolated from a uniform track table with cubic Hermite polynomials. Sizes
are module constants so that LLVM sees fixed trip counts. Nothing is allocated inside the time
loop; samples run in parallel over ``prange``.
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
def _rails(t, speed, lag, table, off, n_nodes, ds, w, wd):
    """Rail heights w and velocities wd at time t for the four wheelsets (L, R each)."""
    inv_ds = 1.0 / ds
    for j in range(N_WHEELSET):
        s = speed * t - lag[j]
        if s <= 0.0:
            w[2 * j] = 0.0
            w[2 * j + 1] = 0.0
            wd[2 * j] = 0.0
            wd[2 * j + 1] = 0.0
            continue
        u = s * inv_ds
        i = int(u)
        if i > n_nodes - 2:
            i = n_nodes - 2
        tau = u - i
        if tau > 1.0:
            tau = 1.0
        om = 1.0 - tau
        h00 = (1.0 + 2.0 * tau) * om * om
        h10 = tau * om * om
        h01 = tau * tau * (3.0 - 2.0 * tau)
        h11 = tau * tau * (tau - 1.0)
        d00 = 6.0 * tau * (tau - 1.0)
        d10 = om * (1.0 - 3.0 * tau)
        d11 = tau * (3.0 * tau - 2.0)
        r0 = off + i
        for r in range(2):
            z0 = table[r0, r]
            z1 = table[r0 + 1, r]
            m0 = table[r0, 2 + r] * ds
            m1 = table[r0 + 1, 2 + r] * ds
            w[2 * j + r] = h00 * z0 + h10 * m0 + h01 * z1 + h11 * m1
            wd[2 * j + r] = speed * inv_ds * (d00 * (z0 - z1) + d10 * m0 + d11 * m1)


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
def run_batch(law, x, step0, n_steps, final, stride, dt, A, TS, B, c_sec,
              speed, lag, table, table_off, table_n, table_ds,
              out_q, out_v, out_a, out_f, out_w, out_wd,
              status, fail_step):
    """Advance every sample's state x[s] = (q, q') by n_steps RK4 steps of dt.

    Per sample s the matrices are stored transposed: A[s] (NY, 9) maps y = (q, q', f) to q''
    (Aq, Av, Bf side by side), TS[s] (9, 4) maps q' to the secondary deflection rates, B[s]
    (16, 9) maps u = (w, w') to q'' (Bw, Bwd). c_sec[s] holds the four damping coefficients.
    ``law`` says how the damper forces enter (LAW_VISCOUS_IN_C or LAW_FORCE_INPUT).

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
        f = np.empty(N_CORNER)  # forces at the step's start, for the record
        rates = np.empty(N_CORNER)
        zero = np.zeros(N_DOF)
        k1v = np.empty(N_DOF)
        k2v = np.empty(N_DOF)
        k3v = np.empty(N_DOF)
        k4v = np.empty(N_DOF)
        k2q = np.empty(N_DOF)
        k3q = np.empty(N_DOF)
        r0 = np.empty(N_DOF)  # rail forcing at t, t + dt/2, t + dt
        rm = np.empty(N_DOF)
        r1 = np.empty(N_DOF)
        u = np.empty(2 * N_RAIL)  # (w, w') at t, for the record
        w = u[:N_RAIL]
        wd = u[N_RAIL:]
        um = np.empty(2 * N_RAIL)  # at t + dt/2
        wm = um[:N_RAIL]
        wdm = um[N_RAIL:]
        u1 = np.empty(2 * N_RAIL)  # at t + dt
        w1 = u1[:N_RAIL]
        wd1 = u1[N_RAIL:]
        at, tt, bt, cs = A[smp], TS[smp], B[smp], c_sec[smp]
        V, lg, off, nn, ds = speed[smp], lag[smp], table_off[smp], table_n[smp], table_ds[smp]
        h = 0.5 * dt
        _rails(step0 * dt, V, lg, table, off, nn, ds, w, wd)
        _mv9(bt, u, 2 * N_RAIL, zero, r0)
        last = n_steps + 1 if final else n_steps
        for n in range(last):
            step = step0 + n
            t = step * dt
            if n < n_steps:
                # the rail inputs do not depend on the state: evaluated first, the CPU can
                # overlap them with the stage computations that do
                _rails(t + h, V, lg, table, off, nn, ds, wm, wdm)
                _mv9(bt, um, 2 * N_RAIL, zero, rm)
                _rails(t + dt, V, lg, table, off, nn, ds, w1, wd1)
                _mv9(bt, u1, 2 * N_RAIL, zero, r1)
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
                for k in range(N_RAIL):
                    out_w[smp, row, k] = w[k]
                    out_wd[smp, row, k] = wd[k]
                if bad:
                    status[smp] = STATUS_DIVERGED
                    fail_step[smp] = step
                    break
            if n == n_steps:
                break
            # stages 2 and 3 share the rail input at t + dt/2
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
            for k in range(2 * N_RAIL):
                u[k] = u1[k]
        for i in range(N_DOF):
            x[smp, i] = q[i]
            x[smp, N_DOF + i] = v[i]
