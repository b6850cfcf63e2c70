"""A plain NumPy reference of the ride equations, for tests and for reading.

It shares the assembled matrices and the damper laws' NumPy form (`railride.secondary.dampers`) with the
compiled stepper but nothing else: it solves with M at every stage instead of folding M^-1 in,
applies the secondary dampers as external forces instead of keeping them in C, evaluates the
rail profiles and the rig motion analytically instead of interpolating tables, and restates the
sub-step rule. Slow (a Python loop over steps): use short runs.
"""

from __future__ import annotations

import numpy as np

from railride.secondary import dampers
from railride.model.params import VehicleParams
from railride.model.track import Scenario
from railride.model.vehicle import Vehicle


def _substeps(lam: float, dt: float) -> int:
    """The stepper's sub-step rule, restated: 2^k sub-steps with lam 1e-4 / m <= 0.5 and
    lam dt / m <= 1."""
    m = 1
    while (lam * 1e-4 > 0.5 * m or lam * dt > 1.0 * m) and m < 1024:
        m *= 2
    return m


def simulate_reference(
    scenario: Scenario,
    params: VehicleParams | None = None,
    dt: float = 1e-4,
    output_every: int = 10,
    damper=None,
    voltage: float | None = None,
) -> dict[str, np.ndarray]:
    """RK4 in NumPy. Returns time, q, q' (the vehicle's DOFs: nine, or ten where the carbody
    bends) and carbody acceleration every ``output_every`` steps.

    Without ``damper`` the secondary dashpots are c_sz; with a model from railride.secondary.dampers its
    law (`rates`) acts at the four corners at the constant command ``voltage``.
    """
    veh = Vehicle(params)
    M, K, C0, K_w, C_w, T = veh.M, veh.K, veh.C0, veh.K_w, veh.C_w, veh.T
    nd = veh.n_dof  # 9, or 10 where the carbody bends
    c_sz = veh.params.c_sz
    lag = veh.wheelset_lag_distance
    V = scenario.speed
    v_cmd = 0.0 if damper is None else (damper.v_min if voltage is None else voltage)

    def rails(t):
        s = V * t - lag
        zl, zr, dzl, dzr = scenario.track.evaluate(s)
        w = np.empty(8)
        wd = np.empty(8)
        w[0::2], w[1::2] = zl, zr
        wd[0::2], wd[1::2] = V * dzl, V * dzr
        return w, wd

    def rhs(t, state):
        q, v, d = state[:nd], state[nd : 2 * nd], state[2 * nd :].reshape(4, 3)
        w, wd = rails(t)
        if damper is None:
            f = -c_sz * (T.T @ v)
            dd = np.zeros_like(d)
        else:
            F, dz, dy, du = damper.rates(T.T @ q, T.T @ v, d[:, 0], d[:, 1], d[:, 2], v_cmd)
            f = -F
            dd = np.column_stack([dz, dy, du])
        force = -(K @ q + C0 @ v) - (K_w @ w + C_w @ wd) + T @ f
        return np.concatenate([v, np.linalg.solve(M, force), dd.ravel()])

    n_steps = int(round(scenario.duration / dt))
    state = np.zeros(2 * nd + 12)
    state[2 * nd + 2 :: 3] = v_cmd  # coils settled at the command
    times, qs, vs, accs = [], [], [], []
    for n in range(n_steps + 1):
        t = n * dt
        k1 = rhs(t, state)
        if n % output_every == 0:
            times.append(t)
            qs.append(state[:nd].copy())
            vs.append(state[nd : 2 * nd].copy())
            accs.append(k1[nd])
        if n == n_steps:
            break
        m = 1
        if damper is not None:
            rates = T.T @ state[nd : 2 * nd]
            lam = max(
                dampers.stiffness_estimate(damper, rates[c], state[2 * nd + 3 * c], state[2 * nd + 2 + 3 * c])
                for c in range(4)
            )
            m = _substeps(lam, dt)
        h = dt / m
        for sub in range(m):
            ts = t + sub * h
            if sub > 0:
                k1 = rhs(ts, state)
            k2 = rhs(ts + h / 2, state + h / 2 * k1)
            k3 = rhs(ts + h / 2, state + h / 2 * k2)
            k4 = rhs(ts + h, state + h * k3)
            state = state + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return {"time": np.array(times), "q": np.array(qs), "v": np.array(vs), "carbody_acceleration": np.array(accs)}


def rig_reference(
    damper, amplitude: float, frequency: float, voltage: float, duration: float, dt: float = 1e-4
) -> dict[str, np.ndarray]:
    """A damper driven by x = amplitude sin(2 pi frequency t) at a constant voltage: RK4 in
    NumPy on (z, y, u, E) with the stepper's sub-step rule. Returns t, x, F, z, u, E per step."""
    w = 2 * np.pi * frequency

    def motion(t):
        return amplitude * np.sin(w * t), amplitude * w * np.cos(w * t)

    def rhs(t, s):
        x, xd = motion(t)
        F, dz, dy, du = damper.rates(x, xd, s[0], s[1], s[2], voltage)
        return np.array([dz, dy, du, F * xd], dtype=float), F

    n_steps = int(round(duration / dt))
    s = np.array([0.0, 0.0, voltage, 0.0])
    rows = []
    for n in range(n_steps + 1):
        t = n * dt
        k1, F = rhs(t, s)
        rows.append((t, motion(t)[0], F, s[0], s[2], s[3]))
        if n == n_steps:
            break
        m = _substeps(dampers.stiffness_estimate(damper, motion(t)[1], s[0], s[2]), dt)
        h = dt / m
        for sub in range(m):
            ts = t + sub * h
            if sub > 0:
                k1, _ = rhs(ts, s)
            k2, _ = rhs(ts + h / 2, s + h / 2 * k1)
            k3, _ = rhs(ts + h / 2, s + h / 2 * k2)
            k4, _ = rhs(ts + h, s + h * k3)
            s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    out = np.array(rows)
    return {k: out[:, i] for i, k in enumerate(("t", "x", "F", "z", "u", "E"))}
