"""railride's passive run against other ways to solve the same linear model, side by side.

Run:  python benchmarks/bench_peers.py [--repeat N] [--scenario paper-sine|fra4]
Every peer integrates the same equations, x' = A x + Bw w(t) + Bwd w'(t) of the passive
vehicle (railride.vehicle), with the same rail inputs (the cubic Hermite interpolation of
railride's input table, `railride.discrete.hermite_at`), for 10 s, and reports its largest
difference from railride's exact discretisation (relative to the largest carbody bounce) and
its time; the ratio is each time over railride's exact path. Peers: railride's RK4 stepper
(dt = 1e-4 s), SciPy's solve_ivp with LSODA and RK45 (rtol 1e-6, atol 1e-9, output at 1 kHz),
a NumPy RK4 loop at dt = 1e-4 s, and python-control's forced_response (when installed; inputs
sampled at 1 kHz and interpolated linearly, so it solves a slightly different input).
Also: an outer loop on the ideal actuator, exact against RK4, and `ride_spectrum` beside a 60 s
random run. Wall-clock minima over the repeats (the slow peers run once); no test asserts timings.
"""

from __future__ import annotations

from _timing import min_time  # benchmarks/_timing.py: run as a script, this folder is on the path

import argparse
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--scenario", default="paper-sine")
    args = ap.parse_args()

    import numpy as np
    from scipy.integrate import solve_ivp

    import railride as rr
    from railride.discrete import hermite_at
    from railride.simulation import _system_arrays
    from railride.track import wheelset_input_table

    sc = rr.scenario(args.scenario, duration=10.0)
    vehicle = rr.Vehicle()
    A = vehicle.state_matrix
    arrays = _system_arrays(vehicle)
    Bw, Bwd = arrays["Bw"], arrays["Bwd"]
    utab, interval = wheelset_input_table(sc, vehicle.wheelset_lag_distance, 1e-4)
    t_out = np.arange(10001) * 1e-3

    def forcing(t):
        w, wd = hermite_at(utab, np.atleast_1d(t), interval)
        r = np.zeros((w.shape[0], 18))
        r[:, 9:] = w @ Bw.T + wd @ Bwd.T
        return r

    reference = rr.simulate(sc).dataset["carbody_bounce"].values
    scale = np.max(np.abs(reference))
    rows = []

    def record(name, seconds, bounce):
        rows.append((name, seconds, float(np.max(np.abs(bounce - reference)) / scale)))

    rr.simulate(sc, solver=rr.SolverSettings(method="rk4"))  # compile and warm
    exact = min_time(lambda: rr.simulate(sc), args.repeat)
    record("railride, exact discretisation (default)", exact, reference)
    rk4 = rr.SolverSettings(method="rk4")
    seconds = min_time(lambda: rr.simulate(sc, solver=rk4), args.repeat)
    record("railride, RK4 stepper, dt = 1e-4 s", seconds, rr.simulate(sc, solver=rk4).dataset["carbody_bounce"].values)

    def rhs(t, x):
        return A @ x + forcing(t)[0]

    for method in ("LSODA", "RK45"):
        t0 = time.perf_counter()
        sol = solve_ivp(rhs, (0.0, 10.0), np.zeros(18), method=method, t_eval=t_out, rtol=1e-6, atol=1e-9)
        record(f"SciPy solve_ivp {method}, rtol 1e-6", time.perf_counter() - t0, sol.y[0])

    t0 = time.perf_counter()
    dt, x = 1e-4, np.zeros(18)
    bounce = np.empty(10001)
    bounce[0] = 0.0
    grid = np.arange(100001) * dt
    r_all = forcing(grid)
    r_mid = forcing(grid[:-1] + dt / 2)
    for k in range(100000):
        r0, rm, r1 = r_all[k], r_mid[k], r_all[k + 1]
        k1 = A @ x + r0
        k2 = A @ (x + dt / 2 * k1) + rm
        k3 = A @ (x + dt / 2 * k2) + rm
        k4 = A @ (x + dt * k3) + r1
        x = x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        if (k + 1) % 10 == 0:
            bounce[(k + 1) // 10] = x[0]
    record("NumPy RK4 loop, dt = 1e-4 s", time.perf_counter() - t0, bounce)

    try:
        import control
    except ImportError:
        control = None
    if control is not None:
        w, wd = hermite_at(utab, t_out, interval)
        B = np.zeros((18, 16))
        B[9:, :8], B[9:, 8:] = Bw, Bwd
        sys = control.ss(A, B, np.eye(18)[:1], np.zeros((1, 16)))
        U = np.hstack([w, wd]).T
        seconds = min_time(lambda: control.forced_response(sys, t_out, U), args.repeat)
        response = control.forced_response(sys, t_out, U)
        record("python-control forced_response, inputs at 1 kHz", seconds, np.asarray(response.outputs).ravel())

    # the other linear case: an outer loop on the ideal actuator (exact steps against RK4), and the
    # frequency-domain ride of four laws beside a 60 s random run in the time domain
    sas = rr.Suspension.named("sas-attitude-ride", damper="ideal")
    rr.simulate(sc, suspension=sas)
    closed = {
        m: min_time(lambda m=m: rr.simulate(sc, suspension=sas, solver=rr.SolverSettings(method=m)), args.repeat)
        for m in ("auto", "rk4")
    }
    from railride.ride_spectrum import ride_spectrum

    ride_spectrum("fra4", points=100)
    spectrum = min_time(lambda: ride_spectrum("fra4"), args.repeat)
    long_run = rr.scenario("fra4", duration=60.0)
    rr.simulate(long_run, suspension=sas)
    random_run = min_time(lambda: rr.simulate(long_run, suspension=sas), args.repeat)

    print(f"scenario {args.scenario}, 10 s, passive vehicle, output at 1 kHz\n")
    print("| method | time | x railride exact | largest difference / largest bounce |")
    print("|---|---|---|---|")
    for name, seconds, error in rows:
        print(f"| {name} | {seconds * 1e3:.1f} ms | {seconds / exact:.1f} | {error:.1e} |")
    print(
        f"\nSAS (attitude+ride) on the ideal actuator, 10 s {args.scenario}: exact {closed['auto'] * 1e3:.1f} ms, "
        f"RK4 {closed['rk4'] * 1e3:.1f} ms"
    )
    print(
        f"ride_spectrum('fra4'), four laws, 2000 frequencies: {spectrum * 1e3:.0f} ms; "
        f"one 60 s fra4 run of the same SAS in the time domain: {random_run * 1e3:.0f} ms"
    )


if __name__ == "__main__":
    main()
