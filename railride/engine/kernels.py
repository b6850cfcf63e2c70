"""All compiled code: the closed-loop fixed-step stepper (numba).

The stepper integrates, for each sample of a batch,

    q'' = Aq q + Av q' + Bw w + Bwd w' + Bf f,    f_i = -c_i (Ts q')_i

with classical fourth-order Runge-Kutta at a fixed step. The matrices are the vehicle's
(M^-1 folded in, see `simulation._system_arrays`), stored transposed so that a product runs
down the columns with the nine row sums held in registers. The rail inputs w, w' and the
forcing Bw w + Bwd w' come from tables on a time grid whose nodes fall on step boundaries,
interpolated with cubic Hermite polynomials (see `railride.model.track.wheelset_input_table`).
Sizes are module constants so that LLVM sees fixed trip counts. The three products of every
stage (q'', the corner deflections and rates, the rail forcing) are vector intrinsics
(`railride.engine._simd`); the damper laws are inlined. Nothing is allocated inside the time loop.
Batches run in parallel on threads (`run_parallel`): the kernels release the GIL. numba's
``prange`` would do the same, but it doubled the compile time of the stepper (12 s against
6 s), which every fresh install pays once.
"""

from __future__ import annotations

import warnings

import numpy as np
from numba import njit
from numba.core.errors import NumbaPerformanceWarning

from railride.engine.cache_guard import guard as _guard_cache
from railride.engine._simd import bouc_wen1_corners, corner_pairs, forcing_rows, mv9_simd
from railride.engine.laws import (
    _hermite,
    _one_step_limit,
    add_stops,
    damper_law,
    damper_stiffness,
    fault_at,
    substeps,
    voltage_law,
)
from railride.engine.sample_parts import (
    accelerometer_filters,
    controller_sample,
    hold_failed_coils,
    inner_loop,
    record_row,
    rk4_advance,
    rk4_stage_state,
    substep_count,
)
from railride.engine.layout import (  # sizes, codes and slots: compile-time constants to numba
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
    ROW_BENDING,
    N_RAIL,
    P_BETA,
    P_GAMMA,
    P_N,
    P_V_MAX,
    P_V_MIN,
    RIG_COMMANDED,
    RIG_CONSTANT,
    RIG_TRACKING,
    S_ON,
    S_W_AA,
    S_W_C,
    STATUS_DIVERGED,
    STATUS_OK,
    VOLTAGE_TRACKING,
)
from railride.engine.layout import FASTMATH as _FAST, NO_PARFORS as _NO_PARFORS
from railride.engine.layout import R_E, R_F, R_T, R_U, R_V, R_X, R_XD, R_Y, R_Z  # the rig's output columns

# numba's cache keys each file's kernels by that file alone: clear it when any engine source
# changed (an inlined function of another file), before any kernel is compiled or loaded
_guard_cache()

# numba reports the parallel pipeline without parfors as a missed opportunity: that is the intent
# here (`layout.NO_PARFORS`)
warnings.filterwarnings(
    "ignore", message=r"(?s).*keyword argument 'parallel=True' was specified", category=NumbaPerformanceWarning
)


@njit(cache=True, inline="always", fastmath=_FAST)
def _forcing(t, ftab, off, n_nodes, interval, out, ooff):
    """Rail forcing r = Bw w + Bwd w' at time t, from the forcing table.

    Hermite interpolation is linear in the node data, so interpolating the node values
    P = Bw w_k, Q = Bw w'_k, R = Bwd w_k, S = Bwd w'_k (N_DOF columns each, one after another)
    gives exactly Bw w(t) + Bwd w'(t) of the interpolated rail inputs, in N_DOF x 8 operations
    instead of interpolating 16 inputs and multiplying by an N_DOF x 16 matrix (in vector form,
    `railride.engine._simd.forcing_rows`).
    """
    k, h00, h10, h01, h11, d00, d10, d11 = _hermite(t, n_nodes, interval)
    forcing_rows(ftab, off + k, h00, h10, h01, h11, d00, d10, d11, out, ooff)


@njit(cache=True, inline="always", fastmath=_FAST)
def _mv9(AT, x, xf, n_cols, r, roff, out, ooff, idx8, val8, idx9, val9, n8, which):
    """out[ooff:ooff+N_DOF] = r[roff:roff+N_DOF] + A y for the rows of q'', A stored transposed
    (n_cols, N_DOF), y = (x[:2N], xf[2N:n_cols]): the state's (q, q') read in place, the corner
    forces from the stage vector. Rows 0-8 in vector form (`railride.engine._simd`), row 8 from
    its non-zero entries (idx8, val8, n8[0, which]); row 9, the carbody's bending, from its own
    (idx9, val9, n8[1, which]): none for a rigid carbody, whose bending stays 0.
    ``which``: 0 counts the entries on (q, q'), 1 those on (q, q', f). Offsets instead of
    slices: a slice made in the loop costs reference counting. As plain numba, nine named
    scalar sums were the fastest form and stayed scalar."""
    mv9_simd(AT, x, xf, n_cols, r, roff, out, ooff, idx8, val8, n8[0, which])
    acc = r[roff + ROW_BENDING]
    for k in range(n8[1, which]):
        j = idx9[k]
        acc += val9[k] * (x[j] if j < 2 * N_DOF else xf[j])
    out[ooff + ROW_BENDING] = acc


@njit(cache=True, inline="always", fastmath=_FAST)
def _derivative(law, s, R, roff, AT, TT, P, vcmd, conn, y, cx, cv, K, koff, i8, v8, i9, v9, n8, bw1, zk, fsave):
    """K[koff:koff+NS_MAX] = d/dt of the state s = (q, q', damper states), with the rail forcing
    R[roff:roff+N_DOF].

    y receives the stage vector (q, q', f). LAW_VISCOUS_IN_C: the dampers are in Av,
    q'' = r + [Aq Av] (q, q'). Otherwise every corner's damper law gives its force F from the
    corner deflection and rate, f = -F conn[c] enters through Bf (conn[c] = 0: the damper is
    disconnected), and the damper states (z, y, u) advance.

    Bump stops (zk = (clearance, stiffness), off where the stiffness is 0): their forces join
    the corner forces for the product only (`add_stops`); with LAW_VISCOUS_IN_C the force
    columns then carry the stops' forces alone.
    """
    for i in range(N_DOF):
        K[koff + i] = s[N_DOF + i]
    if law == LAW_VISCOUS_IN_C:
        if zk[1] > 0.0:
            corner_pairs(TT, s, cx, cv)
            for c in range(N_CORNER):
                y[2 * N_DOF + c] = 0.0
            if add_stops(zk, cx, y, 2 * N_DOF, fsave):
                _mv9(AT, s, y, NY, R, roff, K, koff + N_DOF, i8, v8, i9, v9, n8, 1)
                return
        _mv9(AT, s, y, 2 * N_DOF, R, roff, K, koff + N_DOF, i8, v8, i9, v9, n8, 0)
        return
    corner_pairs(TT, s, cx, cv)
    if bw1:  # Bouc-Wen with n = 1 (the railway dampers): the four corners as one vector
        # the product repeated in this branch on purpose: one call after an if/else made the
        # SAS closed loop 20-25 % slower (A/B, alternating processes)
        bouc_wen1_corners(P, s, cx, cv, vcmd, conn, y, K, koff)
        if zk[1] > 0.0 and add_stops(zk, cx, y, 2 * N_DOF, fsave):
            _mv9(AT, s, y, NY, R, roff, K, koff + N_DOF, i8, v8, i9, v9, n8, 1)
            for c in range(N_CORNER):
                y[2 * N_DOF + c] = fsave[c]
            return
        _mv9(AT, s, y, NY, R, roff, K, koff + N_DOF, i8, v8, i9, v9, n8, 1)
        return
    for c in range(N_CORNER):
        b = 2 * N_DOF + N_DAMPER_STATES * c
        F, dz, dyy, du = damper_law(law, P, cx[c], cv[c], s[b], s[b + 1], s[b + 2], vcmd[c])
        y[2 * N_DOF + c] = -F * conn[c]
        K[koff + b] = dz
        K[koff + b + 1] = dyy
        K[koff + b + 2] = du
    if zk[1] > 0.0 and add_stops(zk, cx, y, 2 * N_DOF, fsave):
        _mv9(AT, s, y, NY, R, roff, K, koff + N_DOF, i8, v8, i9, v9, n8, 1)
        for c in range(N_CORNER):
            y[2 * N_DOF + c] = fsave[c]
        return
    _mv9(AT, s, y, NY, R, roff, K, koff + N_DOF, i8, v8, i9, v9, n8, 1)


@njit(cache=True, nogil=True, fastmath=_FAST, parallel=_NO_PARFORS)
def run_batch(lo, hi, law, x, step0, n_steps, final, stride, dt, vehicle, dampers, inputs, control, outputs):
    """Advance the state x[s] = (q, q', damper states) of samples lo <= s < hi by n_steps
    steps of dt. Compiled without the GIL: `railride.run.simulation` runs sample ranges on threads.

    The arrays come in five groups (tuples, unpacked once at the top; `layout` names the columns
    of the packed ones): vehicle = (A, TS, c_sec, stops), dampers = (P, vcmd), inputs = (utab, u_off,
    ftab, f_off, n_nodes, interval), control = (closed_loop, ctrl_stride, Gm, Hm, inner, noise,
    faults, sensing, snoise) and outputs = (out_q, out_v, out_a, out_f, out_w, out_wd, out_d,
    out_fd, out_vc, status, fail_step).

    Per sample s: A[s] (NY, N_DOF) maps y = (q, q', f) to q'' (Aq, Av, Bf side by side, stored
    transposed), TS[s] (N_DOF, 4) is T (corner deflections T^T q). ``law`` is LAW_VISCOUS_IN_C
    (passive dashpots inside Av; c_sec[s] only for recording their forces) or a damper law
    (railride.secondary.dampers) with packed parameters P[s] (slots P_*) and command voltages
    vcmd[s] (4 corners). The rail inputs come as tables on the time grid k * interval[s] with
    n_nodes[s] rows: utab rows from u_off[s] (w, w', for the record) and ftab rows from f_off[s]
    (see `_forcing`). stops[s] = (clearance, stiffness) of the secondary bump stops (stiffness
    0: none; `stop_force`).

    Each step is one classical RK4 step, or 2^k equal RK4 sub-steps when the dampers' internal
    states are stiff (`substeps`).

    Open loop, each corner's command voltage is vcmd[s]. With ``closed_loop`` the controller
    samples the state m = (q, q') (noise[k] added to the carbody's six at sample k, if noise has
    rows) every ctrl_stride steps, integrates the carbody's (z, phi, theta) by the rectangle rule,
    and computes the desired corner forces f_d = Gm[s] m + Hm[s] xi (Gm 4 x 2 N_DOF), which take effect
    inner[s, I_DELAY] controller periods later (the computation and communication delay, 1 to
    MAX_DELAY; zero demand until the first arrives) and are held. The voltage
    law inner[s, I_LAW] (`voltage_law`) runs at every step from the damper force f on the carbody
    and the deflection rates x' at the step's start, with the gains B, G = inner[s, I_B],
    inner[s, I_G] of the tracking law. With LAW_IDEAL there is no inner loop: the command of
    each corner is the held demand itself, which the ideal actuator applies (out_vc then
    records the demand, not a voltage). The controller's integrator and demands are states
    x[s, NS_MAX:], so a run can continue across calls.

    Realistic sensing (sensing[s, S_ON] = 1; layout `SENSING_COLS`): the controller does not see
    the state. A vertical accelerometer at each carbody corner measures the corner's
    acceleration through a first-order anti-alias filter (rate sensing[s, S_W_AA], integrated at
    every step), sampled at the controller rate with a bias (sensing[s, S_BIAS + c]) and white
    noise (snoise[k, c]); at each sample two band-limited integration stages, each a high-pass
    then a leaky integral (s / (s + w)^2, w = sensing[s, S_W_C], backward Euler), give each
    corner's velocity and displacement, which the map sensing[s, S_MAP:] turns into the carbody's
    heave, pitch and roll; the bogie states read as 0.

    Damper faults: corner c of sample s fails with mode faults[s, F_MODE + c] (FAULT_*) from step
    faults[s, F_STEP + c] on (`fault_at`). FAULT_OFF and FAULT_ON hold its command at v_min and
    v_max whatever the voltage law asks (`fault_command`; the coil follows with its time
    constant); FAULT_DISCONNECTED removes its force from the vehicle.

    Steps are numbered globally from step0 (t = step * dt). At every step whose number is a
    multiple of ``stride`` the state, acceleration, damper forces, rail inputs, damper states,
    demanded forces and command voltages at that time are written to row step // stride of the
    outputs (out_d, out_fd, out_vc only if they have rows);
    with ``final`` the state after the last step is written too. A sample whose state leaves
    +-DIVERGED or stops being finite gets status STATUS_DIVERGED and the step number in
    fail_step, and stops.
    """
    A, TS, c_sec, stops = vehicle
    P, vcmd = dampers
    utab, u_off, ftab, f_off, n_nodes, interval = inputs
    closed_loop, ctrl_stride, Gm, Hm, inner, noise, faults, sensing, snoise = control
    out_q, out_v, out_a, out_f, out_w, out_wd, out_d, out_fd, out_vc, status, fail_step = outputs
    # the loops in a function of their own, the arrays its arguments: with the loops on the arrays
    # unpacked here, the stepper measured 3-4 % slower (docs/performance.md, "Engine refactor")
    _run_samples(
        lo, hi, law, x, step0, n_steps, final, stride, dt, A, TS, c_sec, stops, P, vcmd, utab, u_off, ftab, f_off,
        n_nodes, interval, closed_loop, ctrl_stride, Gm, Hm, inner, noise, faults, sensing, snoise, out_q, out_v, out_a,
        out_f, out_w, out_wd, out_d, out_fd, out_vc, status, fail_step,
    )  # fmt: skip


# fmt: off
@njit(cache=True, nogil=True, fastmath=_FAST, parallel=_NO_PARFORS)
def _run_samples(
    lo, hi, law, x, step0, n_steps, final, stride, dt, A, TS, c_sec, stops, P, vcmd, utab, u_off, ftab, f_off,
    n_nodes, interval, closed_loop, ctrl_stride, Gm, Hm, inner, noise, faults, sensing, snoise, out_q, out_v, out_a,
    out_f, out_w, out_wd, out_d, out_fd, out_vc, status, fail_step,
):
    # fmt: on
    """`run_batch`'s loops, on its groups unpacked."""
    # damper states to integrate (the ideal actuator has none: its law ignores them)
    has_states = law != LAW_VISCOUS_IN_C and law != LAW_IDEAL
    ns = NS_MAX if has_states else 2 * N_DOF
    out4 = (out_q, out_v, out_a, out_f)
    out5 = (out_w, out_wd, out_d, out_fd, out_vc)
    for smp in range(lo, hi):
        if status[smp] != STATUS_OK:
            continue
        xs = x[smp]  # the sample's row: its controller and sensor states are updated in place
        s = x[smp].copy()
        st = np.zeros(NS_MAX)  # stage state (zeros: the states a law without any still reads)
        y = np.empty(NY)  # stage vector (q, q', f)
        cx = np.empty(N_CORNER)
        cv = np.empty(N_CORNER)
        K = np.zeros(4 * NS_MAX)  # the four stage rates, one after another
        R = np.empty(3 * N_DOF)  # rail forcing at the sub-step's start, middle and end
        w = np.empty(N_RAIL)
        wd = np.empty(N_RAIL)
        at, tt, cs, pp, zk = A[smp], TS[smp], c_sec[smp], P[smp], stops[smp]
        fsave = np.empty(N_CORNER)  # the damper forces while the bump stops' join them
        uo, fo, nn, itv = u_off[smp], f_off[smp], n_nodes[smp], interval[smp]
        vc = vcmd[smp].copy()  # command voltages, held over each step
        fm = faults[smp]
        conn = np.ones(N_CORNER)  # 0 where a damper is disconnected
        faulty = False  # a healthy sample skips the fault checks
        for c in range(N_CORNER):
            faulty = faulty or fm[F_MODE + c] != FAULT_NONE
        meas = np.empty(2 * N_DOF)  # the controller's sample of the state (q, q')
        gm, hm = Gm[smp], Hm[smp]
        delay = int(inner[smp, I_DELAY])  # controller periods from a sample to its demand taking effect
        tc = ctrl_stride * dt
        srow = sensing[smp]
        sens = closed_loop and srow[S_ON] > 0.0
        w_aa, w_c = srow[S_W_AA], srow[S_W_C]
        hp = 1.0 / (1.0 + w_c * tc)  # backward Euler of s / (s + w) and of 1 / (s + w)
        bw1 = law == LAW_BOUC_WEN and pp[P_N] == 1.0
        gb1 = pp[P_N] * (abs(pp[P_GAMMA]) + abs(pp[P_BETA]))
        lam1 = _one_step_limit(dt)  # the largest rate bound that needs no sub-steps
        # rows 8 (the rear bogie's roll) and 9 (the carbody's bending) of q'' are sparse: their
        # non-zero columns, in order
        i8 = np.empty(NY, np.int64)
        v8 = np.empty(NY)
        i9 = np.empty(NY, np.int64)
        v9 = np.empty(NY)
        n8 = np.zeros((2, 2), np.int64)  # per row, how many act on (q, q'), and on (q, q', f)
        for j in range(NY):
            for r in range(2):
                a_j = at[j, 8 + r]
                if a_j != 0.0:
                    k = n8[r, 1]
                    if r == 0:
                        i8[k], v8[k] = j, a_j
                    else:
                        i9[k], v9[k] = j, a_j
                    n8[r, 1] += 1
                    if j < 2 * N_DOF:
                        n8[r, 0] += 1
        _forcing(step0 * dt, ftab, fo, nn, itv, R, 0)
        last = n_steps + 1 if final else n_steps
        for n in range(last):
            step = step0 + n
            t = step * dt
            if closed_loop and step % ctrl_stride == 0:
                controller_sample(xs, step // ctrl_stride, delay, s, meas, sens, srow, snoise, noise, tc, hp, gm, hm)
            if closed_loop and law == LAW_IDEAL:
                # the ideal actuator applies the held demand itself (no inner loop); its force
                # is the command, so it is set before the step-start rates use it
                for c in range(N_CORNER):
                    vc[c] = xs[FD_HELD + c]
            if faulty:  # a fault takes effect at its step
                for c in range(N_CORNER):
                    if fault_at(fm, c, step) == FAULT_DISCONNECTED:
                        conn[c] = 0.0
            # rates at the step's start: for the record, the sub-step choice and stage 1
            _derivative(law, s, R, 0, at, tt, pp, vc, conn, y, cx, cv, K, 0, i8, v8, i9, v9, n8, bw1, zk, fsave)
            if sens:
                accelerometer_filters(xs, tt, K, dt, w_aa)
            if closed_loop and law != LAW_IDEAL:  # cv: the deflection rates at the step's start
                inner_loop(int(inner[smp, I_LAW]), inner[smp, I_B], inner[smp, I_G], y, xs, cv, pp, vc, s, K)
            if faulty:
                hold_failed_coils(fm, step, vc, pp, s, K)
            if step % stride == 0:
                row = step // stride
                if record_row(smp, row, t, law, s, K, y, cv, tt, cs, xs, vc, utab, uo, nn, itv, w, wd, out4, out5):
                    status[smp] = STATUS_DIVERGED
                    fail_step[smp] = step
                    break
            if n == n_steps:
                break
            m = substep_count(law, bw1, gb1, lam1, pp, cv, s, dt)
            h = dt / m
            for sub in range(m):
                ts = t + sub * h
                _forcing(ts + 0.5 * h, ftab, fo, nn, itv, R, N_DOF)
                _forcing(ts + h, ftab, fo, nn, itv, R, 2 * N_DOF)
                # classical RK4: stage j at s + c_j h K_(j-1), c = (0, 1/2, 1/2, 1), with the
                # forcing at the sub-step's start, middle, middle and end
                for stage in range(4):
                    if stage == 0 and sub == 0:
                        continue  # K_0 is the step-start rate computed above
                    ch = h * (0.0 if stage == 0 else (0.5 if stage < 3 else 1.0))
                    roff = N_DOF * (0 if stage == 0 else (1 if stage < 3 else 2))
                    prev = NS_MAX * (stage - 1 if stage > 0 else 0)  # stage 0 adds 0 * K_0
                    rk4_stage_state(st, s, K, prev, ch, has_states)
                    kb = NS_MAX * stage
                    _derivative(
                        law, st, R, roff, at, tt, pp, vc, conn, y, cx, cv, K, kb, i8, v8, i9, v9, n8, bw1, zk, fsave
                    )
                rk4_advance(s, K, h, has_states)
                for i in range(N_DOF):
                    R[i] = R[2 * N_DOF + i]
        for i in range(ns):
            x[smp, i] = s[i]


@njit(cache=True, nogil=True, fastmath=_FAST, parallel=_NO_PARFORS)
def rig_batch(lo, hi, law, P, n_steps, stride, dt, xtab, x_interval, mode, vconst, series, B, G, out):
    """A damper on a test rig: every sample lo <= s < hi drives one damper (parameters P[s])
    through the extension x(t) of the table xtab (rows (x, x') on the grid k * x_interval, cubic
    Hermite). Compiled without the GIL: `railride.run.rig` runs sample ranges on threads
    (`run_parallel`).

    The command voltage, held over each step, is vconst[s] (``mode`` RIG_CONSTANT), the series
    series[s, step] (RIG_COMMANDED, clipped to [v_min, v_max]), or the force-tracking law of
    paper eq. 12-14 (RIG_TRACKING), v = clip(G[s] (f_d - B[s] F) sgn(F), v_min, v_max), from the
    force F at the step's start and the desired force f_d = series[s, step] (`voltage_law`).
    States: z, y, u and the dissipated energy E (E' = F x'). Row step // stride of out[s]
    receives (t, x, x', F, z, y, u, v, E) (columns `layout.RIG_COLUMNS`, slots R_*) at every
    step that is a multiple of stride, and after the last step.
    """
    n_rows = xtab.shape[0]
    for smp in range(lo, hi):
        pp = P[smp]
        z = 0.0
        yy = 0.0
        u = vconst[smp] if mode == RIG_CONSTANT else pp[P_V_MIN]
        E = 0.0
        kz = np.empty(4)  # stage rates of z, y, u, E
        ky = np.empty(4)
        ku = np.empty(4)
        ke = np.empty(4)
        for n in range(n_steps + 1):
            t = n * dt
            k, h00, h10, h01, h11, d00, d10, d11 = _hermite(t, n_rows, x_interval)
            x = h00 * xtab[k, 0] + h10 * xtab[k, 1] + h01 * xtab[k + 1, 0] + h11 * xtab[k + 1, 1]
            xd = d00 * (xtab[k, 0] - xtab[k + 1, 0]) + d10 * xtab[k, 1] + d11 * xtab[k + 1, 1]
            F, dz, dy, du = damper_law(law, pp, x, xd, z, yy, u, 0.0)
            if mode == RIG_TRACKING:  # the vehicle's tracking law on the damper's own force
                v = voltage_law(VOLTAGE_TRACKING, B[smp], G[smp], F, series[smp, n], 0.0, pp)
            elif mode == RIG_COMMANDED:
                v = min(max(series[smp, n], pp[P_V_MIN]), pp[P_V_MAX])
            else:
                v = vconst[smp]
            if n % stride == 0 or n == n_steps:
                row = n // stride if n % stride == 0 else out.shape[1] - 1
                out[smp, row, R_T] = t
                out[smp, row, R_X] = x
                out[smp, row, R_XD] = xd
                out[smp, row, R_F] = F
                out[smp, row, R_Z] = z
                out[smp, row, R_Y] = yy
                out[smp, row, R_U] = u
                out[smp, row, R_V] = v
                out[smp, row, R_E] = E
            if n == n_steps:
                break
            m = substeps(damper_stiffness(law, pp, xd, z, u), dt)
            h = dt / m
            for sub in range(m):
                tk = t + sub * h
                # RK4 on (z, y, u, E) with the prescribed motion at the stage times
                for stage in range(4):
                    c = 0.0 if stage == 0 else (0.5 if stage < 3 else 1.0)
                    zs = z if stage == 0 else z + c * h * kz[stage - 1]
                    ys = yy if stage == 0 else yy + c * h * ky[stage - 1]
                    us = u if stage == 0 else u + c * h * ku[stage - 1]
                    k, h00, h10, h01, h11, d00, d10, d11 = _hermite(tk + c * h, n_rows, x_interval)
                    xs = h00 * xtab[k, 0] + h10 * xtab[k, 1] + h01 * xtab[k + 1, 0] + h11 * xtab[k + 1, 1]
                    xds = d00 * (xtab[k, 0] - xtab[k + 1, 0]) + d10 * xtab[k, 1] + d11 * xtab[k + 1, 1]
                    Fs, kz[stage], ky[stage], ku[stage] = damper_law(law, pp, xs, xds, zs, ys, us, v)
                    ke[stage] = Fs * xds
                z += h / 6.0 * (kz[0] + 2.0 * kz[1] + 2.0 * kz[2] + kz[3])
                yy += h / 6.0 * (ky[0] + 2.0 * ky[1] + 2.0 * ky[2] + ky[3])
                u += h / 6.0 * (ku[0] + 2.0 * ku[1] + 2.0 * ku[2] + ku[3])
                E += h / 6.0 * (ke[0] + 2.0 * ke[1] + 2.0 * ke[2] + ke[3])


def threads_for(units: int, threads: int | None = None) -> int:
    """The threads `run_parallel` runs ``units`` independent pieces of work on: ``threads``
    (default numba's thread count, `numba.set_num_threads`), at most one per piece, at least one."""
    import numba

    return max(1, min(int(units), numba.get_num_threads() if threads is None else int(threads)))


def run_each(work, n: int) -> None:
    """``work(i)`` for i < n on numba's threads (`threads_for`), each i taken by the next thread
    that comes free: for pieces of unequal cost (a batch's exact runs, the pieces of its forcing
    tables) that release the GIL. An error in one is raised here."""
    threads = threads_for(n)
    if threads == 1:
        for i in range(n):
            work(i)
        return
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(threads, thread_name_prefix="railride-work") as pool:
        for job in [pool.submit(work, i) for i in range(n)]:
            job.result()


def run_parallel(kernel, n_samples: int, *args, start: int = 0) -> None:
    """Call ``kernel(lo, hi, *args)`` on sample ranges that cover start..n_samples, one range per
    thread (numba's thread count as set by `numba.set_num_threads`, at most one per sample)."""
    from concurrent.futures import ThreadPoolExecutor

    n_threads = threads_for(n_samples - start)
    if n_threads == 1:
        kernel(start, n_samples, *args)
        return
    bounds = np.linspace(start, n_samples, n_threads + 1).round().astype(int)
    with ThreadPoolExecutor(n_threads) as pool:
        jobs = [pool.submit(kernel, int(bounds[i]), int(bounds[i + 1]), *args) for i in range(n_threads)]
        for job in jobs:
            job.result()
