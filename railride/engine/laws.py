"""The laws of the engine, each written once: scalar functions that every stepper inlines (the
CPU sample stepper `railride.engine.kernels.run_batch`, the lane stepper `railride.engine.lanes`,
the damper rig and the GPU kernel `railride.engine.gpu`).

The damper force laws and their states' rates, the coil lag, the inner loop's voltage laws, the
damper faults, the bump stops, the sub-step rule for stiff damper states, and the cubic Hermite
interpolation of the rail input tables. Plain numba (`njit`, no vector intrinsics, no
allocation), so numba-cuda compiles the same functions for the GPU.
"""

from __future__ import annotations

from numba import njit

from railride.engine.layout import (  # sizes, codes and slots: compile-time constants to numba
    FAULT_NONE,
    FAULT_OFF,
    FAULT_ON,
    F_MODE,
    F_STEP,
    LAW_BOUC_WEN,
    LAW_IDEAL,
    LAW_SPENCER,
    LAW_VISCOUS,
    LAW_VISCOUS_IN_C,
    MAX_SUBSTEPS,
    N_CORNER,
    N_DOF,
    N_RAIL,
    P_A,
    P_ALPHA_A,
    P_ALPHA_B,
    P_BETA,
    P_C0A,
    P_C0B,
    P_C1A,
    P_C1B,
    P_DISSIPATIVE,
    P_ETA,
    P_GAMMA,
    P_K0,
    P_K1,
    P_N,
    P_V_MAX,
    P_V_MIN,
    P_Z_BOUND,
    SUBSTEP_DT_REF,
    SUBSTEP_LIMIT,
    VOLTAGE_CLIPPED,
    VOLTAGE_ON_OFF,
)
from railride.engine.layout import FASTMATH as _FAST


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
    return (
        k,
        (1.0 + 2.0 * tau) * om * om,
        tau * om * om * interval,
        tau * tau * (3.0 - 2.0 * tau),
        tau * tau * (tau - 1.0) * interval,
        6.0 * tau * (tau - 1.0) / interval,
        om * (1.0 - 3.0 * tau),
        tau * (3.0 * tau - 2.0),
    )


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
def _corner_values(TT, s, offset, out):
    """out[c] = sum_j TT[j, c] s[offset + j]: the secondary deflections (offset 0, from q) or
    their rates (offset N_DOF, from q') at the four corners (TT = T, (N_DOF, 4))."""
    b0 = 0.0
    b1 = 0.0
    b2 = 0.0
    b3 = 0.0
    for j in range(N_DOF):
        sj = s[offset + j]
        b0 += TT[j, 0] * sj
        b1 += TT[j, 1] * sj
        b2 += TT[j, 2] * sj
        b3 += TT[j, 3] * sj
    out[0] = b0
    out[1] = b1
    out[2] = b2
    out[3] = b3


@njit(cache=True, inline="always", fastmath=_FAST)
def _bouc_wen_rate(z, w, A, n, gamma, beta):
    """z' = -gamma |w| z |z|^(n-1) - beta w |z|^n + A w (see railride.secondary.dampers)."""
    az = abs(z)
    if n == 1.0:
        zn1 = 1.0
    elif n == 2.0:
        zn1 = az
    else:
        zn1 = az ** (n - 1.0)
    return -gamma * abs(w) * z * zn1 - beta * w * zn1 * az + A * w


@njit(cache=True, inline="always", fastmath=_FAST)
def damper_law(law, P, x, xd, z, y, u, v):
    """Force F (tension +) and the rates (z', y', u') of one damper; P as `Damper.pack()`.
    LAW_IDEAL: v is the held demand on the carbody, so F = -v and the carbody gets f = v."""
    if law == LAW_VISCOUS:
        return P[P_C0A] * xd, 0.0, 0.0, 0.0
    if law == LAW_IDEAL:  # P[P_DISSIPATIVE] > 0: dissipative only, no force where it would push energy in
        if P[P_DISSIPATIVE] > 0.0 and v * xd > 0.0:
            return 0.0, 0.0, 0.0, 0.0
        return -v, 0.0, 0.0, 0.0
    alpha = P[P_ALPHA_A] + P[P_ALPHA_B] * u
    c0 = P[P_C0A] + P[P_C0B] * u
    du = coil_rate(P, u, v)
    if law == LAW_BOUC_WEN:
        dz = _bouc_wen_rate(z, xd, P[P_A], P[P_N], P[P_GAMMA], P[P_BETA])
        return c0 * xd + P[P_K0] * x + alpha * z, dz, 0.0, du
    c1 = P[P_C1A] + P[P_C1B] * u
    dy = (alpha * z + c0 * xd + P[P_K0] * (x - y)) / (c0 + c1)
    dz = _bouc_wen_rate(z, xd - dy, P[P_A], P[P_N], P[P_GAMMA], P[P_BETA])
    return c1 * dy + P[P_K1] * x, dz, dy, du


@njit(cache=True, inline="always", fastmath=_FAST)
def coil_rate(P, u, v):
    """u' of an MR damper's coil voltage u lagging the command v (rate P[P_ETA])."""
    return -P[P_ETA] * (u - v)


@njit(cache=True, inline="always", fastmath=_FAST)
def voltage_law(mode, B, G, f, fd, xd, P):
    """The command voltage the closed loop's inner loop gives an MR damper (voltage law ``mode``,
    `layout.VOLTAGE_LAWS`; both steppers call this) from the damper force f on the carbody, the
    demand fd there and the corner's deflection rate xd, within P's v_min..v_max: tracking,
    v = clip(G (fd - B f) sgn(f), v_min, v_max); on-off, v_max where fd xd < 0; clipped, v_max
    where (fd - f) f > 0; else v_min."""
    if mode == VOLTAGE_ON_OFF:
        return P[P_V_MAX] if fd * xd < 0.0 else P[P_V_MIN]
    if mode == VOLTAGE_CLIPPED:
        return P[P_V_MAX] if (fd - f) * f > 0.0 else P[P_V_MIN]
    sgn = 1.0 if f > 0.0 else (-1.0 if f < 0.0 else 0.0)
    return min(max(G * (fd - B * f) * sgn, P[P_V_MIN]), P[P_V_MAX])


@njit(cache=True, inline="always")
def fault_at(fm, c, step):
    """The fault of corner c at ``step`` (FAULT_*) from a sample's row fm of the fault table
    (columns `layout.F_MODE`, `layout.F_STEP`): its mode from its step on, FAULT_NONE before."""
    return fm[F_MODE + c] if step >= fm[F_STEP + c] else FAULT_NONE


@njit(cache=True, inline="always", fastmath=_FAST)
def fault_command(fault, v, P):
    """(command, held) of a corner with ``fault`` whose voltage law asked v: a failed coil driver
    holds v_min (FAULT_OFF) or v_max (FAULT_ON) whatever the law asks (held True); otherwise v.
    (FAULT_DISCONNECTED leaves the command and removes the force: the steppers' ``conn``.)"""
    if fault == FAULT_OFF:
        return P[P_V_MIN], True
    if fault == FAULT_ON:
        return P[P_V_MAX], True
    return v, False


@njit(cache=True, fastmath=_FAST)
def damper_stiffness(law, P, xd, z, u):
    """A bound on the fastest rate of the damper's internal states [1/s]
    (same as railride.secondary.dampers.stiffness_estimate). |z| is taken at least at the bound of the
    hysteretic variable (P[P_Z_BOUND]): starting from z = 0 the rate grows within the step."""
    if law == LAW_VISCOUS or law == LAW_VISCOUS_IN_C or law == LAW_IDEAL:
        return 0.0
    gb = abs(P[P_GAMMA]) + abs(P[P_BETA])
    n = P[P_N]
    az = max(abs(z), P[P_Z_BOUND])
    lam = n * gb * abs(xd) * (1.0 if n == 1.0 else az ** (n - 1.0)) + P[P_ETA]
    if law == LAW_SPENCER:
        cs = P[P_C0A] + P[P_C0B] * u + P[P_C1A] + P[P_C1B] * u
        lam += ((P[P_A] + gb * az**n) * (P[P_ALPHA_A] + P[P_ALPHA_B] * u) + P[P_K0]) / cs
    return lam


@njit(cache=True)
def substeps(lam, dt):
    """Sub-steps per step (a power of two) for a fastest damper rate lam [1/s].

    The count depends on lam alone, lam * SUBSTEP_DT_REF / m <= SUBSTEP_LIMIT, so a smaller dt
    gives proportionally smaller sub-steps and step halving refines the whole scheme; a floor
    keeps lam * dt / m <= 2 * SUBSTEP_LIMIT for stability when dt is large.
    """
    m = 1
    while (lam * SUBSTEP_DT_REF > SUBSTEP_LIMIT * m or lam * dt > 2.0 * SUBSTEP_LIMIT * m) and m < MAX_SUBSTEPS:
        m *= 2
    return m


@njit(cache=True)
def _one_step_limit(dt):
    """The largest rate bound lam for which `substeps` gives one step (by bisection on its own
    test, so that lam <= this is exactly substeps(lam, dt) == 1)."""
    lo = 0.0
    hi = 1.0
    while substeps(hi, dt) == 1:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if substeps(mid, dt) == 1:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True, inline="always", fastmath=_FAST)
def stop_force(z_stop, k_stop, x):
    """The force of a corner's bump stop on the carbody (up +) at the secondary deflection x
    (extension +): none within the clearance +-z_stop, k_stop times the travel beyond it,
    against it (`railride.model.params.VehicleParams`, z_stop and k_stop)."""
    if x > z_stop:
        return -k_stop * (x - z_stop)
    if x < -z_stop:
        return -k_stop * (x + z_stop)
    return 0.0


@njit(cache=True, inline="always", fastmath=_FAST)
def add_stops(zk, cx, f, foff, fsave):
    """Add the bump stops' forces (clearance zk[0], stiffness zk[1]) at the corner deflections
    cx to the corner forces f[foff:foff + 4], the forces before in fsave, where any corner is
    beyond the clearance; whether one is. The damper forces go back in place after the
    product: what the record and the inner loop read is the damper's force alone, as a load
    cell on the damper measures it. Off the stops (almost every step) this is four comparisons."""
    z = zk[0]
    if not (abs(cx[0]) > z or abs(cx[1]) > z or abs(cx[2]) > z or abs(cx[3]) > z):
        return False
    for c in range(N_CORNER):
        fsave[c] = f[foff + c]
        f[foff + c] = fsave[c] + stop_force(z, zk[1], cx[c])
    return True
