"""A plain NumPy reference of the ride equations, for tests and for reading.

It shares the assembled matrices with the compiled stepper but nothing else: it solves with M
at every stage instead of folding M^-1 in, applies the secondary dampers as external forces
f = -c_sz T^T q' instead of keeping them in C, and evaluates the rail profiles analytically
instead of interpolating the stepper's table. Slow (a Python loop over steps): use short runs.
"""

from __future__ import annotations

import numpy as np

from .params import VehicleParams
from .track import Scenario
from .vehicle import Vehicle


def simulate_reference(scenario: Scenario, params: VehicleParams | None = None,
                       dt: float = 1e-4, output_every: int = 10) -> dict[str, np.ndarray]:
    """RK4 in NumPy. Returns time, q, q' and carbody acceleration every ``output_every`` steps."""
    veh = Vehicle(params)
    M, K, C0, K_w, C_w, T = veh.M, veh.K, veh.C0, veh.K_w, veh.C_w, veh.T
    c_sz = veh.params.c_sz
    lag = veh.wheelset_lag_distance
    V = scenario.speed

    def rails(t):
        s = V * t - lag
        zl, zr, dzl, dzr = scenario.track.evaluate(s)
        w = np.empty(8)
        wd = np.empty(8)
        w[0::2], w[1::2] = zl, zr
        wd[0::2], wd[1::2] = V * dzl, V * dzr
        return w, wd

    def rhs(t, q, v):
        w, wd = rails(t)
        f = -c_sz * (T.T @ v)
        rhs_force = -(K @ q + C0 @ v) - (K_w @ w + C_w @ wd) + T @ f
        return v, np.linalg.solve(M, rhs_force)

    n_steps = int(round(scenario.duration / dt))
    q = np.zeros(9)
    v = np.zeros(9)
    times, qs, vs, accs = [], [], [], []
    for n in range(n_steps + 1):
        t = n * dt
        k1q, k1v = rhs(t, q, v)
        if n % output_every == 0:
            times.append(t)
            qs.append(q.copy())
            vs.append(v.copy())
            accs.append(k1v[0])
        if n == n_steps:
            break
        k2q, k2v = rhs(t + dt / 2, q + dt / 2 * k1q, v + dt / 2 * k1v)
        k3q, k3v = rhs(t + dt / 2, q + dt / 2 * k2q, v + dt / 2 * k2v)
        k4q, k4v = rhs(t + dt, q + dt * k3q, v + dt * k3v)
        q = q + dt / 6 * (k1q + 2 * k2q + 2 * k3q + k4q)
        v = v + dt / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
    return {"time": np.array(times), "q": np.array(qs), "v": np.array(vs),
            "carbody_acceleration": np.array(accs)}
