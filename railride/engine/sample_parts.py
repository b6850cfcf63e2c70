"""The parts of one sample's step that the CPU sample stepper (`railride.engine.kernels.run_batch`)
and the GPU kernel (`railride.engine.gpu`) share, each written once: the controller's sample (the
accelerometers' integration, sensor noise, the demand and its delay), the accelerometers'
anti-alias filters, the inner loop and the failed coil drivers, the sub-step count, the RK4
combinations, the record of a step, and the metric sums of a run that keeps no history (the lane
stepper's and the kernel's, `railride.run.reduced`). Plain numba, no allocation: the steppers hand in their
own work arrays (numpy on the CPU, thread-local arrays on the GPU).

``xs`` is one sample's row of the state array x (`railride.engine.layout`: q, q', damper states,
then the controller's integrator, held and pending demands, and the sensors' states).
"""

from __future__ import annotations

from numba import njit

from railride.engine.laws import (
    _corner_values,
    _rail_inputs,
    coil_rate,
    damper_stiffness,
    fault_at,
    fault_command,
    substeps,
    voltage_law,
)
from railride.engine.layout import (  # sizes and slots: compile-time constants to numba
    DIVERGED,
    FD_HELD,
    FD_NEXT,
    LAW_VISCOUS_IN_C,
    NOISE_Q,
    NOISE_V,
    NS_MAX,
    N_CORNER,
    N_DAMPER_STATES,
    N_DOF,
    N_DS,
    N_RAIL,
    N_SENS_STATES,
    P_ETA,
    ROW_BENDING,
    S_BIAS,
    S_MAP,
    SENS,
    SS_DISP,
    SS_FILTERED,
    SS_HP1,
    SS_HP2,
    SS_LAST,
    SS_VEL,
    SS_VEL_LAST,
    XI,
)
from railride.engine.layout import FASTMATH as _FAST


@njit(cache=True, inline="always", fastmath=_FAST)
def controller_sample(xs, k, delay, s, meas, sens, srow, snoise, noise, tc, hp, gm, hm):
    """The controller's sample k: the demand computed ``delay`` periods ago takes effect (held
    in xs[FD_HELD:]) and its ring slot takes the new demand f_d = gm m + hm xi from the measured
    state m (meas): the exact (q, q') of s, or with ``sens`` the accelerometers' estimate
    (sensing row srow, sample noise snoise[k]), plus the sensor noise noise[k] where it has rows;
    xi integrates the carbody's (z, phi, theta) by the rectangle rule (period tc). hp is the
    backward-Euler factor 1 / (1 + w_c tc) of the integration stages."""
    slot = FD_NEXT + N_CORNER * (k % delay)
    for c in range(N_CORNER):
        xs[FD_HELD + c] = xs[slot + c]
    for j in range(2 * N_DOF):
        meas[j] = 0.0 if sens else s[j]
    if sens:  # the accelerometers, sampled, and the band-limited integration
        for c in range(N_CORNER):
            b = SENS + N_SENS_STATES * c
            a_m = xs[b + SS_FILTERED] + srow[S_BIAS + c]
            a_m += snoise[k, c] if k < snoise.shape[0] else 0.0
            xs[b + SS_HP1] = hp * (xs[b + SS_HP1] + a_m - xs[b + SS_LAST])
            xs[b + SS_LAST] = a_m
            v_new = hp * (xs[b + SS_VEL] + tc * xs[b + SS_HP1])
            xs[b + SS_HP2] = hp * (xs[b + SS_HP2] + v_new - xs[b + SS_VEL_LAST])
            xs[b + SS_VEL_LAST] = v_new
            xs[b + SS_VEL] = v_new
            xs[b + SS_DISP] = hp * (xs[b + SS_DISP] + tc * xs[b + SS_HP2])
        for j in range(3):
            for c in range(N_CORNER):
                pm = srow[S_MAP + N_CORNER * j + c]
                meas[j] += pm * xs[SENS + N_SENS_STATES * c + SS_DISP]
                meas[N_DOF + j] += pm * xs[SENS + N_SENS_STATES * c + SS_VEL]
    if k < noise.shape[0]:  # sensor noise on the carbody's (z, phi, theta) and their rates
        for j in range(3):
            meas[j] += noise[k, NOISE_Q + j]
            meas[N_DOF + j] += noise[k, NOISE_V + j]
    for j in range(3):
        xs[XI + j] += tc * meas[j]
    for c in range(N_CORNER):
        acc_fd = 0.0
        for j in range(2 * N_DOF):
            acc_fd += gm[c, j] * meas[j]
        for j in range(3):
            acc_fd += hm[c, j] * xs[XI + j]
        xs[slot + c] = acc_fd


@njit(cache=True, inline="always", fastmath=_FAST)
def accelerometer_filters(xs, tt, K, dt, w_aa):
    """Each accelerometer's anti-alias filter follows its corner's floor acceleration (bending
    included) from the step-start rates K, over one step dt (forward Euler, rate w_aa)."""
    for c in range(N_CORNER):
        a_c = tt[ROW_BENDING, c] * K[N_DOF + ROW_BENDING]
        for j in range(3):
            a_c += tt[j, c] * K[N_DOF + j]
        b = SENS + N_SENS_STATES * c
        xs[b + SS_FILTERED] += dt * w_aa * (a_c - xs[b + SS_FILTERED])


@njit(cache=True, inline="always", fastmath=_FAST)
def inner_loop(mode, B, G, y, xs, cv, pp, vc, s, K):
    """The inner loop at the step's start: each corner's command voltage vc from its damper force
    on the carbody y[2 N_DOF + c], the held demand and the deflection rate cv (`voltage_law`),
    and stage 1's coil rate corrected for it (the forces do not depend on the command, only on
    the coil state)."""
    for c in range(N_CORNER):
        vc[c] = voltage_law(mode, B, G, y[2 * N_DOF + c], xs[FD_HELD + c], cv[c], pp)
        b = 2 * N_DOF + N_DAMPER_STATES * c + 2
        K[b] = coil_rate(pp, s[b], vc[c])


@njit(cache=True, inline="always", fastmath=_FAST)
def hold_failed_coils(fm, step, vc, pp, s, K):
    """A failed coil driver holds its command whatever the law asks (`fault_command`); stage 1's
    coil rate follows the held command."""
    for c in range(N_CORNER):
        v, held = fault_command(fault_at(fm, c, step), vc[c], pp)
        if held:
            vc[c] = v
            b = 2 * N_DOF + N_DAMPER_STATES * c + 2
            K[b] = coil_rate(pp, s[b], v)


@njit(cache=True, inline="always", fastmath=_FAST)
def substep_count(law, bw1, gb1, lam1, pp, cv, s, dt):
    """RK4 sub-steps for this step (`substeps`) from the corner rates cv and damper states of s.
    Bouc-Wen with n = 1 (bw1, the railway dampers): the rate bound n gb |x'| + eta of
    `damper_stiffness` grows with |x'| alone, so the fastest corner decides, and one comparison
    with the one-step limit lam1 skips `substeps` at almost every step."""
    if bw1:
        vmax = 0.0
        for c in range(N_CORNER):
            vmax = max(vmax, abs(cv[c]))
        lam = gb1 * vmax + pp[P_ETA]
        return substeps(lam, dt) if lam > lam1 else 1
    if law == LAW_VISCOUS_IN_C:
        return 1
    lam = 0.0
    for c in range(N_CORNER):
        b = 2 * N_DOF + N_DAMPER_STATES * c
        lam = max(lam, damper_stiffness(law, pp, cv[c], s[b], s[b + 2]))
    return substeps(lam, dt)


@njit(cache=True, inline="always", fastmath=_FAST)
def rk4_stage_state(st, s, K, prev, ch, has_states):
    """st = s + ch K[prev:]: the state at an RK4 stage (the damper states only if it has any)."""
    for i in range(2 * N_DOF):  # constant trip counts: LLVM unrolls them
        st[i] = s[i] + ch * K[prev + i]
    if has_states:
        for i in range(2 * N_DOF, NS_MAX):
            st[i] = s[i] + ch * K[prev + i]


@njit(cache=True, inline="always", fastmath=_FAST)
def rk4_advance(s, K, h, has_states):
    """s += h/6 (K1 + 2 K2 + 2 K3 + K4), the four stage rates one after another in K."""
    for i in range(2 * N_DOF):
        s[i] += h / 6.0 * (K[i] + 2.0 * K[NS_MAX + i] + 2.0 * K[2 * NS_MAX + i] + K[3 * NS_MAX + i])
    if has_states:
        for i in range(2 * N_DOF, NS_MAX):
            s[i] += h / 6.0 * (K[i] + 2.0 * K[NS_MAX + i] + 2.0 * K[2 * NS_MAX + i] + K[3 * NS_MAX + i])


@njit(cache=True, inline="always", fastmath=_FAST)
def record_row(smp, row, t, law, s, K, y, cv, tt, cs, xs, vc, utab, uo, nn, itv, w, wd, outputs4, outputs5):
    """Write a step's row of sample smp's histories: state, acceleration (K's step-start rates),
    damper forces, rail inputs, damper states, held demands and command voltages (the last three
    only where their outputs have rows). Returns whether the state has left +-DIVERGED (or is
    not finite). outputs4 = (out_q, out_v, out_a, out_f), outputs5 = (out_w, out_wd, out_d,
    out_fd, out_vc)."""
    out_q, out_v, out_a, out_f = outputs4
    out_w, out_wd, out_d, out_fd, out_vc = outputs5
    bad = False
    for i in range(N_DOF):
        out_q[smp, row, i] = s[i]
        out_v[smp, row, i] = s[N_DOF + i]
        out_a[smp, row, i] = K[N_DOF + i]
        if not (abs(s[i]) < DIVERGED and abs(s[N_DOF + i]) < 1e3 * DIVERGED):
            bad = True
    if law == LAW_VISCOUS_IN_C:
        _corner_values(tt, s, N_DOF, cv)
        for c in range(N_CORNER):
            y[2 * N_DOF + c] = -cs[c] * cv[c]
    for c in range(N_CORNER):
        out_f[smp, row, c] = y[2 * N_DOF + c]
    if out_d.shape[1] > 1:
        for i in range(N_DS):
            out_d[smp, row, i] = s[2 * N_DOF + i]
            if not abs(s[2 * N_DOF + i]) < DIVERGED:
                bad = True
    _rail_inputs(t, utab, uo, nn, itv, w, wd)
    for c in range(N_RAIL):
        out_w[smp, row, c] = w[c]
        out_wd[smp, row, c] = wd[c]
    if out_fd.shape[1] > 1:
        for c in range(N_CORNER):
            out_fd[smp, row, c] = xs[FD_HELD + c]
            out_vc[smp, row, c] = vc[c]
    return bad


#: the columns of a sample's metric sums where a run keeps no history: the sums of squares, the
#: least and the largest values of the metric channels (`METRIC_CHANNELS`), and the rows summed
ACC_SQUARES, ACC_MIN, ACC_MAX, ACC_ROWS = 0, 4, 8, 12
N_ACC = 13
#: the channels of `railride.analysis.metrics.RESPONSES` as (history, column): the carbody's
#: vertical acceleration (out_a), bounce, pitch and roll (out_q), in that order
METRIC_CHANNELS = (("a", 0), ("q", 0), ("q", 1), ("q", 2))


@njit(cache=True, inline="always", fastmath=_FAST)
def accumulate_metrics(acc, smp, out_q, out_a):
    """Add the row just written (row 0 of out_q, out_a) to sample smp's metric sums."""
    for k in range(4):
        v = out_a[smp, 0, 0] if k == 0 else out_q[smp, 0, k - 1]
        acc[smp, ACC_SQUARES + k] += v * v
        acc[smp, ACC_MIN + k] = min(acc[smp, ACC_MIN + k], v)
        acc[smp, ACC_MAX + k] = max(acc[smp, ACC_MAX + k], v)
    acc[smp, ACC_ROWS] += 1.0
