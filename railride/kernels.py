"""All compiled code: the closed-loop fixed-step stepper (numba).

The stepper integrates, for each sample of a batch,

    q'' = Aq q + Av q' + Bw w + Bwd w' + Bf f,    f_i = -c_i (Ts q')_i

with classical fourth-order Runge-Kutta at a fixed step. The matrices are the vehicle's
(M^-1 folded in, see `simulate._system_arrays`), passed in compressed-row form because they are
mostly zeros (about a third of the entries are not); w, w' are the rail heights and velocities at the
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
#: a displacement or rotation beyond this (m or rad) is taken as divergence
DIVERGED = 1.0e3

#: reassociation lets LLVM vectorise the dot products; NaN/inf semantics stay IEEE so the
#: divergence check still sees them
_FAST = {"reassoc", "contract", "nsz", "arcp"}

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
def _csr_matvec(ptr, col, val, x, out, n_rows):
    """out[:n_rows] = A x for A in compressed-row form."""
    for i in range(n_rows):
        acc = 0.0
        for k in range(ptr[i], ptr[i + 1]):
            acc += val[k] * x[col[k]]
        out[i] = acc


@njit(cache=True, inline="always", fastmath=_FAST)
def _acceleration(y, r, a_ptr, a_col, a_val, t_ptr, t_col, t_val, c_sec, out):
    """out = q'' for y = (q, q', f) with rail forcing r.

    First the secondary damper forces f = -c (Ts q') go into y[18:22], then
    q'' = r + [Aq Av Bf] y.
    """
    for c in range(N_CORNER):
        rate = 0.0
        for k in range(t_ptr[c], t_ptr[c + 1]):
            rate += t_val[k] * y[t_col[k]]
        y[2 * N_DOF + c] = -c_sec[c] * rate
    for i in range(N_DOF):
        acc = r[i]
        for k in range(a_ptr[i], a_ptr[i + 1]):
            acc += a_val[k] * y[a_col[k]]
        out[i] = acc


@njit(cache=True, parallel=True, fastmath=_FAST)
def run_batch(x, step0, n_steps, final, stride, dt,
              a_ptr, a_col, a_val, t_ptr, t_col, t_val, b_ptr, b_col, b_val, c_sec,
              speed, lag, table, table_off, table_n, table_ds,
              out_q, out_v, out_a, out_f, out_w, out_wd,
              status, fail_step):
    """Advance every sample's state x[s] = (q, q') by n_steps RK4 steps of dt.

    Per sample s the matrices are in compressed-row form (ptr[s], col[s], val[s]):
    ``a`` maps y = (q, q', f) to q'' (Aq, Av, Bf side by side), ``t`` maps y to the secondary
    deflection rates (Ts acting on q'), ``b`` maps u = (w, w') to q'' (Bw, Bwd).

    Steps are numbered globally from step0 (t = step * dt). At every step whose number is a
    multiple of ``stride`` the state, acceleration, damper forces and rail inputs at that time
    are written to row step // stride of the outputs; with ``final`` the state after the last
    step is written too. A sample whose state leaves +-DIVERGED or stops being finite gets
    status STATUS_DIVERGED and the step number in fail_step, and stops.
    """
    n_samples = x.shape[0]
    NY = 2 * N_DOF + N_CORNER
    for smp in prange(n_samples):
        if status[smp] != STATUS_OK:
            continue
        q = x[smp, :N_DOF].copy()
        v = x[smp, N_DOF:].copy()
        y = np.empty(NY)  # stage state (q, q', f)
        f = np.empty(N_CORNER)  # forces at the step's start, for the record
        k1v = np.empty(N_DOF)
        k2v = np.empty(N_DOF)
        k3v = np.empty(N_DOF)
        k4v = np.empty(N_DOF)
        k2q = np.empty(N_DOF)
        k3q = np.empty(N_DOF)
        r0 = np.empty(N_DOF)
        rm = np.empty(N_DOF)
        r1 = np.empty(N_DOF)
        u = np.empty(2 * N_RAIL)
        w = u[:N_RAIL]
        wd = u[N_RAIL:]
        ap, ac, avl = a_ptr[smp], a_col[smp], a_val[smp]
        tp, tc, tv = t_ptr[smp], t_col[smp], t_val[smp]
        bp, bc, bv = b_ptr[smp], b_col[smp], b_val[smp]
        cs = c_sec[smp]
        V, lg, off, nn, ds = speed[smp], lag[smp], table_off[smp], table_n[smp], table_ds[smp]
        h = 0.5 * dt
        _rails(step0 * dt, V, lg, table, off, nn, ds, w, wd)
        _csr_matvec(bp, bc, bv, u, r0, N_DOF)
        last = n_steps + 1 if final else n_steps
        for n in range(last):
            step = step0 + n
            t = step * dt
            for i in range(N_DOF):
                y[i] = q[i]
                y[N_DOF + i] = v[i]
            _acceleration(y, r0, ap, ac, avl, tp, tc, tv, cs, k1v)
            for c in range(N_CORNER):
                f[c] = y[2 * N_DOF + c]
            if step % stride == 0:
                row = step // stride
                bad = False
                for i in range(N_DOF):
                    out_q[smp, row, i] = q[i]
                    out_v[smp, row, i] = v[i]
                    out_a[smp, row, i] = k1v[i]
                    if not (abs(q[i]) < DIVERGED and abs(v[i]) < 1e3 * DIVERGED):
                        bad = True
                for c in range(N_CORNER):
                    out_f[smp, row, c] = f[c]
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
            _rails(t + h, V, lg, table, off, nn, ds, w, wd)
            _csr_matvec(bp, bc, bv, u, rm, N_DOF)
            for i in range(N_DOF):
                y[i] = q[i] + h * v[i]
                k2q[i] = v[i] + h * k1v[i]
                y[N_DOF + i] = k2q[i]
            _acceleration(y, rm, ap, ac, avl, tp, tc, tv, cs, k2v)
            for i in range(N_DOF):
                y[i] = q[i] + h * k2q[i]
                k3q[i] = v[i] + h * k2v[i]
                y[N_DOF + i] = k3q[i]
            _acceleration(y, rm, ap, ac, avl, tp, tc, tv, cs, k3v)
            _rails(t + dt, V, lg, table, off, nn, ds, w, wd)
            _csr_matvec(bp, bc, bv, u, r1, N_DOF)
            for i in range(N_DOF):
                y[i] = q[i] + dt * k3q[i]
                y[N_DOF + i] = v[i] + dt * k3v[i]
            _acceleration(y, r1, ap, ac, avl, tp, tc, tv, cs, k4v)
            for i in range(N_DOF):
                q[i] += dt / 6.0 * (v[i] + 2.0 * k2q[i] + 2.0 * k3q[i] + y[N_DOF + i])
                v[i] += dt / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i])
                r0[i] = r1[i]
        for i in range(N_DOF):
            x[smp, i] = q[i]
            x[smp, N_DOF + i] = v[i]
