"""The lane stepper: RK4 for groups of `LANES` samples with every per-sample array lane-innermost
(docs/performance.md). Each lane keeps its own sub-steps, delay, voltage law, faults and
divergence, so that a sample's history is the same whatever its batch-mates; the damper law and
the products are vector intrinsics (`railride.engine._simd_lanes`).
"""

from __future__ import annotations


import numpy as np
from numba import njit

from railride.engine._simd_lanes import LANES, lanes_axpy, lanes_move, lanes_mr_damper, lanes_rk4, lanes_spmv
from railride.engine.kernels import run_parallel
from railride.engine.laws import (  # the scalar laws and helpers, inlined here too
    _hermite,
    stop_force,
    _one_step_limit,
    _rail_inputs,
    coil_rate,
    damper_law,
    damper_stiffness,
    fault_at,
    fault_command,
    substeps,
    voltage_law,
)
from railride.engine.layout import (  # sizes, codes and slots: compile-time constants to numba
    DIVERGED,
    FAULT_DISCONNECTED,
    FAULT_NONE,
    FD_HELD,
    FD_NEXT,
    F_MODE,
    I_B,
    I_DELAY,
    I_G,
    I_LAW,
    LAW_BOUC_WEN,
    LAW_IDEAL,
    LAW_SPENCER,
    LAW_VISCOUS_IN_C,
    NS_MAX,
    NY,
    N_CORNER,
    N_DAMPER_STATES,
    N_DOF,
    N_DS,
    N_RAIL,
    NOISE_Q,
    NOISE_V,
    P_ALPHA_A,
    P_BETA,
    P_ETA,
    P_GAMMA,
    P_N,
    S_ON,
    SENS,
    STATUS_DIVERGED,
    STATUS_OK,
)
from railride.engine.layout import FASTMATH as _FAST, NO_PARFORS as _NO_PARFORS
from railride.engine.sample_parts import N_ACC, accumulate_metrics


#: rows of a lane state: q, q', the corner forces f (the stage vector y = (q, q', f), so the
#: q'' product reads its columns in place) and the damper states; the rates use the same rows
ROW_F = 2 * N_DOF
ROW_D = NY
NL = NY + N_DS


@njit(cache=True, inline="always", fastmath=_FAST)
def _lane_forcing(ts, lanes, act, smp, ftab, f_off, n_nodes, interval, RR, roff):
    """RR[roff + i, l] = the rail forcing of lane l's sample at time ts[l] (see `_forcing`), for
    the lanes where act[l] != 0."""
    for l in range(lanes):
        if act[l] == 0.0:
            continue
        s = smp[l]
        if l > 0 and act[l - 1] != 0.0 and f_off[smp[l - 1]] == f_off[s] and ts[l - 1] == ts[l]:
            for i in range(N_DOF):  # the lane before reads the same table at the same time
                RR[roff + i, l] = RR[roff + i, l - 1]
            continue
        k, h00, h10, h01, h11, d00, d10, d11 = _hermite(ts[l], n_nodes[s], interval[s])
        a = f_off[s] + k
        b = a + 1
        for i in range(N_DOF):
            RR[roff + i, l] = (
                h00 * ftab[a, i]
                + h10 * ftab[a, N_DOF + i]
                + h01 * ftab[b, i]
                + h11 * ftab[b, N_DOF + i]
                + d00 * (ftab[a, 2 * N_DOF + i] - ftab[b, 2 * N_DOF + i])
                + d10 * ftab[a, 3 * N_DOF + i]
                + d11 * ftab[b, 3 * N_DOF + i]
            )


@njit(cache=True, inline="always", fastmath=_FAST)
def _lane_derivative(
    law,
    ST,
    RR,
    roff,
    a_ptr,
    a_col,
    aval,
    a_uni,
    t_ptr,
    t_col,
    tval,
    t_uni,
    P,
    VC,
    CONN,
    CC,
    ZL,
    ONE,
    K,
    kb,
    ZK,
    FS,
    stops,
):
    """K[kb:kb + NL] = d/dt of the lane states ST (rows as `NL`), with the rail forcing
    RR[roff:roff + N_DOF]; as `_derivative`, every lane at once. ST's force rows receive f; CC the
    corner deflections (rows 0-3) and rates (4-7). Bump stops where ZK (clearance, stiffness
    per lane) has a stiffness (``stops``: in any lane of the group): their forces join f for the
    product only (FS keeps f), and only at a step where a lane is beyond its clearance."""
    lanes_move(K, kb, ST, N_DOF, N_DOF, ONE)
    if law != LAW_VISCOUS_IN_C or stops:
        lanes_spmv(t_ptr, t_col, tval, t_uni, ST, ZL, 0, CC, 0)
    if law == LAW_BOUC_WEN or law == LAW_SPENCER:
        lanes_mr_damper(law == LAW_SPENCER, P, CC, ST, ROW_F, ROW_D, VC, CONN, K, kb)
    elif law != LAW_VISCOUS_IN_C:  # the ideal devices and the viscous model: lane by lane
        for c in range(N_CORNER):
            b = ROW_D + N_DAMPER_STATES * c
            for l in range(LANES):
                F, dz, dyy, du = damper_law(
                    law, P, CC[c, l], CC[N_CORNER + c, l], ST[b, l], ST[b + 1, l], ST[b + 2, l], VC[c, l]
                )
                ST[ROW_F + c, l] = -F * CONN[c, l]
                K[kb + b, l] = dz
                K[kb + b + 1, l] = dyy
                K[kb + b + 2, l] = du
    if law == LAW_VISCOUS_IN_C:  # force columns only for the stops (here or in another group)
        for c in range(N_CORNER):
            for l in range(LANES):
                ST[ROW_F + c, l] = 0.0
    n_over = 0
    if stops:  # branch-free, so that it vectorises: a lane without stops has an infinite clearance
        for c in range(N_CORNER):
            for l in range(LANES):
                n_over += abs(CC[c, l]) > ZK[0, l]
    touched = n_over > 0
    if touched:
        for c in range(N_CORNER):
            for l in range(LANES):
                FS[c, l] = ST[ROW_F + c, l]
                ST[ROW_F + c, l] = FS[c, l] + stop_force(ZK[0, l], ZK[1, l], CC[c, l])
    lanes_spmv(a_ptr, a_col, aval, a_uni, ST, RR, roff, K, kb + N_DOF)
    if touched:
        for c in range(N_CORNER):
            for l in range(LANES):
                ST[ROW_F + c, l] = FS[c, l]


@njit(cache=True, nogil=True, fastmath=_FAST, parallel=_NO_PARFORS)
def run_lanes(
    lo, hi, lane_smp, lane_own, law, x, step0, n_steps, final, stride, dt, vehicle, dampers, inputs, control, outputs,
    sums,
):  # fmt: skip
    """`run_batch` for the groups lo <= g < hi of LANES samples: lane l of group g is sample
    lane_smp[g, l], and writes its state, outputs and status only where lane_own[g, l] (a
    padding lane repeats a sample of its group and discards what it computes). The arguments
    are run_batch's groups but for realistic sensing, which this kernel leaves out (run_batch has
    it; control's sensing and snoise go unread); dampers = (P, vcmd) with P the batch's one
    damper (N_PACKED,), and vehicle = (a_ptr, a_col, a_val, a_uni, t_ptr, t_col, t_val, t_uni,
    c_sec, stops): the products run on their non-zero structure
    over every lane of a group, compressed rows shared by all groups: q'' = r + A y over
    (a_ptr, a_col, a_val[g]) (rows of q'', columns of y = (q, q', f)), the corner deflections
    and rates over (t_ptr, t_col, t_val[g]) (rows cx then cv, columns of q, q'); a_val[g, k, l]
    is lane l's entry k, and a_uni[g] (t_uni[g]) says that every lane of group g has the same
    entries (one vehicle), which are then read once and broadcast.

    sums = (reduce, win, acc): with reduce, a run that keeps no history, as on the GPU: the
    outputs hold one row a sample (two where that history is recorded: the records read which
    from the shapes), rewritten at every output step, and the rows win[0]..win[1] (both
    included) go into the sample's metric sums acc[i] (`sample_parts.accumulate_metrics`).

    Every lane runs exactly its own sample's arithmetic: its own sub-step count (the group
    loops to the largest, the lanes that are done masked), its delay, voltage law, faults and
    divergence (a diverged lane stops where it was and counts no more sub-steps), so a sample's
    history does not depend, bit for bit, on the samples beside it. Vector form: the products,
    the stage states, the RK4 update and the MR damper laws (`railride.engine._simd_lanes`); the
    controller, the voltage laws, the sub-step choice, the rail forcing (computed once for
    lanes that read the same table at the same time) and the records run lane by lane.
    """
    a_ptr, a_col, a_val, a_uni, t_ptr, t_col, t_val, t_uni, c_sec, stops = vehicle
    P, vcmd = dampers
    utab, u_off, ftab, f_off, n_nodes, interval = inputs
    closed_loop, ctrl_stride, Gm, Hm, inner, noise, faults, _sensing, _snoise = control
    out_q, out_v, out_a, out_f, out_w, out_wd, out_d, out_fd, out_vc, status, fail_step = outputs
    reduce, win, acc = sums
    has_states = law != LAW_VISCOUS_IN_C and law != LAW_IDEAL
    record_d = out_d.shape[1] > 1
    record_c = out_fd.shape[1] > 1
    n_noise = noise.shape[0]
    tc = ctrl_stride * dt
    bw1 = law == LAW_BOUC_WEN and P[P_N] == 1.0
    gb1 = P[P_N] * (abs(P[P_GAMMA]) + abs(P[P_BETA]))
    lam1 = _one_step_limit(dt)
    n_ctrl = SENS - NS_MAX  # the controller's states: integrals, held demands, the delay ring
    for g in range(lo, hi):
        smp = lane_smp[g]
        own = lane_own[g]
        aval, au = a_val[g], a_uni[g]  # the q'' entries; alike in every lane?
        tval, tu = t_val[g], t_uni[g]
        S = np.zeros((NL, LANES))
        ST = np.zeros((NL, LANES))
        K = np.zeros((4 * NL, LANES))
        RR = np.zeros((3 * N_DOF, LANES))
        CC = np.zeros((2 * N_CORNER, LANES))
        ZL = np.zeros((2 * N_CORNER, LANES))  # a zero start for the corner products
        ONE = np.ones(LANES)
        VC = np.empty((N_CORNER, LANES))
        CONN = np.ones((N_CORNER, LANES))
        ZK = np.empty((2, LANES))  # each lane's bump stops: clearance, stiffness
        FS = np.empty((N_CORNER, LANES))
        XC = np.empty((n_ctrl, LANES))  # controller states, lane-local: padding lanes share x rows
        ch = np.empty(LANES)
        h = np.empty(LANES)
        h6 = np.empty(LANES)
        ts = np.empty(LANES)
        ts2 = np.empty(LANES)
        act = np.zeros(LANES)
        alive = np.zeros(LANES)
        m = np.ones(LANES, dtype=np.int64)
        meas = np.empty(2 * N_DOF)
        w = np.empty(N_RAIL)
        wd = np.empty(N_RAIL)
        faulty = False
        has_stops = False
        for l in range(LANES):
            i = smp[l]
            alive[l] = 1.0 if status[i] == STATUS_OK else 0.0
            for j in range(2 * N_DOF):
                S[j, l] = x[i, j]
            if has_states:
                for j in range(N_DS):
                    S[ROW_D + j, l] = x[i, 2 * N_DOF + j]
            for j in range(n_ctrl):
                XC[j, l] = x[i, NS_MAX + j]
            for c in range(N_CORNER):
                VC[c, l] = vcmd[i, c]
                faulty = faulty or faults[i, F_MODE + c] != FAULT_NONE
            act[l] = 1.0
            ts[l] = step0 * dt
            ZK[0, l], ZK[1, l] = stops[i, 0], stops[i, 1]
            has_stops = has_stops or stops[i, 1] > 0.0
        _lane_forcing(ts, LANES, act, smp, ftab, f_off, n_nodes, interval, RR, 0)
        last = n_steps + 1 if final else n_steps
        for n in range(last):
            step = step0 + n
            t = step * dt
            if closed_loop and step % ctrl_stride == 0:
                k = step // ctrl_stride
                for l in range(LANES):
                    i = smp[l]
                    # the demand computed `delay` periods ago takes effect; its slot the new one
                    slot = FD_NEXT - NS_MAX + N_CORNER * (k % int(inner[i, I_DELAY]))
                    for c in range(N_CORNER):
                        XC[FD_HELD - NS_MAX + c, l] = XC[slot + c, l]
                    for j in range(2 * N_DOF):
                        meas[j] = S[j, l]
                    if k < n_noise:
                        for j in range(3):
                            meas[j] += noise[k, NOISE_Q + j]
                            meas[N_DOF + j] += noise[k, NOISE_V + j]
                    for j in range(3):
                        XC[j, l] += tc * meas[j]
                    for c in range(N_CORNER):
                        acc_fd = 0.0
                        for j in range(2 * N_DOF):
                            acc_fd += Gm[i, c, j] * meas[j]
                        for j in range(3):
                            acc_fd += Hm[i, c, j] * XC[j, l]
                        XC[slot + c, l] = acc_fd
            if closed_loop and law == LAW_IDEAL:
                for c in range(N_CORNER):
                    for l in range(LANES):
                        VC[c, l] = XC[FD_HELD - NS_MAX + c, l]
            if faulty:
                for l in range(LANES):
                    i = smp[l]
                    for c in range(N_CORNER):
                        if fault_at(faults[i], c, step) == FAULT_DISCONNECTED:
                            CONN[c, l] = 0.0
            _lane_derivative(
                law,
                S,
                RR,
                0,
                a_ptr,
                a_col,
                aval,
                au,
                t_ptr,
                t_col,
                tval,
                tu,
                P,
                VC,
                CONN,
                CC,
                ZL,
                ONE,
                K,
                0,
                ZK,
                FS,
                has_stops,
            )
            if closed_loop and law != LAW_IDEAL:
                for l in range(LANES):
                    i = smp[l]
                    mode = int(inner[i, I_LAW])
                    B_in, G_in = inner[i, I_B], inner[i, I_G]
                    for c in range(N_CORNER):
                        f = S[ROW_F + c, l]
                        fd = XC[FD_HELD - NS_MAX + c, l]
                        VC[c, l] = voltage_law(mode, B_in, G_in, f, fd, CC[N_CORNER + c, l], P)
                        b = ROW_D + N_DAMPER_STATES * c + 2
                        K[b, l] = coil_rate(P, S[b, l], VC[c, l])
            if faulty:
                for l in range(LANES):
                    i = smp[l]
                    for c in range(N_CORNER):
                        v, held = fault_command(fault_at(faults[i], c, step), VC[c, l], P)
                        if held:
                            VC[c, l] = v
                            b = ROW_D + N_DAMPER_STATES * c + 2
                            K[b, l] = coil_rate(P, S[b, l], v)
            if step % stride == 0:
                row = 0 if reduce else step // stride
                summed = reduce and win[0] <= step // stride <= win[1]
                if law == LAW_VISCOUS_IN_C:  # the dashpots' forces, for the record
                    lanes_spmv(t_ptr, t_col, tval, tu, S, ZL, 0, CC, 0)
                    for c in range(N_CORNER):
                        for l in range(LANES):
                            S[ROW_F + c, l] = -c_sec[smp[l], c] * CC[N_CORNER + c, l]
                for l in range(LANES):
                    if alive[l] == 0.0:
                        continue
                    i = smp[l]
                    bad = False
                    for j in range(N_DOF):
                        if not (abs(S[j, l]) < DIVERGED and abs(S[N_DOF + j, l]) < 1e3 * DIVERGED):
                            bad = True
                    if record_d:
                        for j in range(N_DS):
                            if not abs(S[ROW_D + j, l]) < DIVERGED:
                                bad = True
                    if own[l]:
                        for j in range(N_DOF):
                            out_q[i, row, j] = S[j, l]
                            out_v[i, row, j] = S[N_DOF + j, l]
                            out_a[i, row, j] = K[N_DOF + j, l]
                        for c in range(N_CORNER):
                            out_f[i, row, c] = S[ROW_F + c, l]
                        if record_d:
                            for j in range(N_DS):
                                out_d[i, row, j] = S[ROW_D + j, l]
                        _rail_inputs(t, utab, u_off[i], n_nodes[i], interval[i], w, wd)
                        for c in range(N_RAIL):
                            out_w[i, row, c] = w[c]
                            out_wd[i, row, c] = wd[c]
                        if record_c:
                            for c in range(N_CORNER):
                                out_fd[i, row, c] = XC[FD_HELD - NS_MAX + c, l]
                                out_vc[i, row, c] = VC[c, l]
                        if bad:
                            status[i] = STATUS_DIVERGED
                            fail_step[i] = step
                        elif summed:
                            accumulate_metrics(acc, i, out_q, out_a)
                    if bad:
                        alive[l] = 0.0
            if n == n_steps:
                break
            n_sub = 0
            for l in range(LANES):
                ml = 0  # a diverged lane stays where it stopped
                if alive[l] != 0.0:
                    ml = 1
                    if bw1:
                        vmax = 0.0
                        for c in range(N_CORNER):
                            vmax = max(vmax, abs(CC[N_CORNER + c, l]))
                        lam = gb1 * vmax + P[P_ETA]
                        if lam > lam1:
                            ml = substeps(lam, dt)
                    elif law != LAW_VISCOUS_IN_C:
                        lam = 0.0
                        for c in range(N_CORNER):
                            b = ROW_D + N_DAMPER_STATES * c
                            lam = max(lam, damper_stiffness(law, P, CC[N_CORNER + c, l], S[b, l], S[b + 2, l]))
                        ml = substeps(lam, dt)
                m[l] = ml
                n_sub = max(n_sub, ml)
                h[l] = dt / ml if ml > 0 else 0.0
                h6[l] = h[l] / 6.0
            if n_sub == 0:  # every lane has diverged
                break
            for sub in range(n_sub):
                for l in range(LANES):
                    act[l] = 1.0 if sub < m[l] else 0.0
                    start = t + sub * h[l]
                    ts[l] = start + 0.5 * h[l]
                    ts2[l] = start + h[l]
                _lane_forcing(ts, LANES, act, smp, ftab, f_off, n_nodes, interval, RR, N_DOF)
                _lane_forcing(ts2, LANES, act, smp, ftab, f_off, n_nodes, interval, RR, 2 * N_DOF)
                for stage in range(4):
                    if stage == 0 and sub == 0:
                        continue
                    c_st = 0.0 if stage == 0 else (0.5 if stage < 3 else 1.0)
                    for l in range(LANES):
                        ch[l] = h[l] * c_st
                    roff = N_DOF * (0 if stage == 0 else (1 if stage < 3 else 2))
                    prev = NL * (stage - 1 if stage > 0 else 0)
                    lanes_axpy(ST, 0, S, 0, ch, K, prev, 2 * N_DOF)
                    if has_states:
                        lanes_axpy(ST, ROW_D, S, ROW_D, ch, K, prev + ROW_D, N_DS)
                    _lane_derivative(
                        law,
                        ST,
                        RR,
                        roff,
                        a_ptr,
                        a_col,
                        aval,
                        au,
                        t_ptr,
                        t_col,
                        tval,
                        tu,
                        P,
                        VC,
                        CONN,
                        CC,
                        ZL,
                        ONE,
                        K,
                        NL * stage,
                        ZK,
                        FS,
                        has_stops,
                    )
                lanes_rk4(S, 0, K, NL, 2 * N_DOF, h6, act)
                if has_states:
                    lanes_rk4(S, ROW_D, K, NL, N_DS, h6, act)
                lanes_move(RR, 0, RR, 2 * N_DOF, N_DOF, act)
        for l in range(LANES):
            if not own[l]:
                continue
            i = smp[l]
            for j in range(2 * N_DOF):
                x[i, j] = S[j, l]
            if has_states:
                for j in range(N_DS):
                    x[i, 2 * N_DOF + j] = S[ROW_D + j, l]
            for j in range(n_ctrl):
                x[i, NS_MAX + j] = XC[j, l]


#: `run_lanes`' sums where a run keeps its histories whole
_NO_SUMS = (False, np.zeros(2, dtype=np.int64), np.zeros((1, N_ACC)))


def lane_groups(n: int):
    """Groups of LANES samples covering 0..n: (sample of each lane, whether the lane owns it);
    the last group is padded with copies of the last sample, which write nothing."""
    idx = np.arange(-(-n // LANES) * LANES)
    own = idx < n
    return np.where(own, idx, n - 1).reshape(-1, LANES), own.reshape(-1, LANES)


def _compressed(M, smp):
    """Compressed rows of the entries of M (n, rows, cols) that are non-zero in any sample:
    (ptr, col, val) with val[g, k, l] sample smp[g, l]'s entry k."""
    rows, cols = np.nonzero(np.any(M != 0.0, axis=0))  # row-major: sorted by row
    ptr = np.searchsorted(rows, np.arange(M.shape[1] + 1)).astype(np.int64)
    val = M[:, rows, cols][smp]  # (groups, LANES, nnz)
    return ptr, cols.astype(np.int64), np.ascontiguousarray(val.transpose(0, 2, 1))


def lanes_fit(n: int, P, sensing) -> bool:
    """Whether `lanes_stepper` can run this batch: LANES samples or more, one damper (the
    packed parameters of every sample alike) and no realistic sensing."""
    return n >= LANES and bool(np.all(P == P[P_ALPHA_A])) and not bool(np.any(sensing[:, S_ON] > 0.0))


def lanes_stepper(n, law, A, TS, P, stops):
    """`run_batch`'s work for the n samples of a batch (sensing off, see `lanes_fit`) in groups
    of LANES samples by `run_lanes`, the groups on threads (`run_parallel`). The lane groups and
    the products' compressed rows are built here, once per run; the function returned takes
    run_batch's arguments after lo, hi, chunk after chunk (it reads A, TS and P from here; the
    vehicle and damper groups it is given supply c_sec and vcmd)."""
    smp, own = lane_groups(n)
    # dashpots inside Av: no force columns, unless bump stops act through them
    n_cols = 2 * N_DOF if law == LAW_VISCOUS_IN_C and not np.any(stops[:, 1] > 0.0) else NY
    a_ptr, a_col, a_val = _compressed(A[:, :n_cols, :].transpose(0, 2, 1), smp)
    T = np.zeros((n, 2 * N_CORNER, 2 * N_DOF))  # (cx, cv) = T^T (q, q')
    T[:, :N_CORNER, :N_DOF] = T[:, N_CORNER:, N_DOF:] = TS.transpose(0, 2, 1)
    t_ptr, t_col, t_val = _compressed(T, smp)
    a_uni, t_uni = (np.all(v == v[:, :, :1], axis=(1, 2)) for v in (a_val, t_val))  # groups of one vehicle
    products = (a_ptr, a_col, a_val, a_uni, t_ptr, t_col, t_val, t_uni)
    damper = np.ascontiguousarray(P[P_ALPHA_A])

    def step(_n, _law, x, step0, n_steps, final, stride, dt, vehicle, dampers, inputs, control, outputs, sums=None):
        # run_batch's groups: the products and run_batch's c_sec and stops, the one damper and vcmd,
        # the rest as they are; sums: `run_lanes`' (default: the histories whole, no sums)
        run_parallel(
            run_lanes, len(smp), smp, own, law, x, step0, n_steps, final, stride, dt, products + vehicle[2:4],
            (damper, dampers[1]), inputs, control, outputs, _NO_SUMS if sums is None else sums,
        )  # fmt: skip

    return step
