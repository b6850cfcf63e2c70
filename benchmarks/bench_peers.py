"""railride's passive run against other ways to solve the same linear model, side by side.

Run:  python benchmarks/bench_peers.py [--rounds N] [--repeat N] [--scenario paper-sine|fra4]
Every peer integrates the same equations, x' = A x + Bw w(t) + Bwd w'(t) of the passive
vehicle (railride.model.vehicle), with the same rail inputs (the cubic Hermite interpolation of
railride's input table, `railride.engine.discrete.hermite_at`), for 10 s, output at 1 kHz, and reports
its largest difference from railride's exact discretisation (relative to the largest carbody
bounce) and whether that is below 1e-4 (it reproduces the trajectory). Peers: railride's RK4
stepper (dt = 1e-4 s), SciPy's solve_ivp with LSODA and RK45 (rtol 1e-6, atol 1e-9), a NumPy
RK4 loop at dt = 1e-4 s, and, where the `bench` extra installs them, python-control's
forced_response (inputs sampled at 1 kHz and interpolated linearly, so it solves a slightly
different input) and PathSim (an ODE block with the SciPy peers' right-hand side, Dormand-Prince
5(4) `RKDP54` at the same tolerances as RK45, a Scope sampling at 1 kHz). A peer that is not
installed is skipped with a printed line.

Timing: paired rounds. Each round times every method once (the fast ones, railride and
python-control, as the best of --repeat calls); a method's ratio is its time over railride's
exact path in the same round, and the table prints the medians over the rounds, so a burst of
other work on the machine moves both sides of a ratio. No test asserts timings.
Also: an outer loop on the ideal actuator, exact against RK4, and `ride_spectrum` beside a 60 s
random run (best of --repeat).
"""

from __future__ import annotations

from _timing import min_time  # benchmarks/_timing.py: run as a script, this folder is on the path

import argparse
import statistics
import time

REPRODUCES = 1e-4  # largest difference / largest bounce below which a peer reproduces the trajectory


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--scenario", default="paper-sine")
    args = ap.parse_args()

    import numpy as np
    from scipy.integrate import solve_ivp

    import railride as rr
    from railride.engine.discrete import hermite_at
    from railride.run.simulation import _system_arrays
    from railride.model.track import wheelset_input_table

    sc = rr.scenario(args.scenario, duration=10.0)
    vehicle = rr.Vehicle()
    A = vehicle.state_matrix
    arrays = _system_arrays(vehicle)
    n = vehicle.n_dof  # the engine pads its arrays to the flexible car's 10 DOF: this rigid car's rows
    Bw, Bwd = arrays["Bw"][:n], arrays["Bwd"][:n]
    utab, interval = wheelset_input_table(sc, vehicle.wheelset_lag_distance, 1e-4)
    t_out = np.arange(10001) * 1e-3

    def forcing(t):
        w, wd = hermite_at(utab, np.atleast_1d(t), interval)
        r = np.zeros((w.shape[0], 18))
        r[:, 9:] = w @ Bw.T + wd @ Bwd.T
        return r

    def rhs(t, x):
        return A @ x + forcing(t)[0]

    def bounce(result):
        return result.dataset["carbody_bounce"].values

    rk4 = rr.SolverSettings(method="rk4")
    rr.simulate(sc, solver=rk4)  # compile and warm

    def scipy(method):
        def run():
            sol = solve_ivp(rhs, (0.0, 10.0), np.zeros(18), method=method, t_eval=t_out, rtol=1e-6, atol=1e-9)
            return sol.y[0]

        return run

    def numpy_rk4():
        dt, x = 1e-4, np.zeros(18)
        out = np.zeros(10001)
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
                out[(k + 1) // 10] = x[0]
        return out

    # name -> (run returning the bounce at t_out, fast: best of --repeat within a round)
    methods = {
        "railride, exact discretisation (default)": (lambda: bounce(rr.simulate(sc)), True),
        "railride, RK4 stepper, dt = 1e-4 s": (lambda: bounce(rr.simulate(sc, solver=rk4)), True),
        "SciPy solve_ivp LSODA, rtol 1e-6": (scipy("LSODA"), False),
        "SciPy solve_ivp RK45, rtol 1e-6": (scipy("RK45"), False),
        "NumPy RK4 loop, dt = 1e-4 s": (numpy_rk4, False),
    }
    skipped = []
    try:
        import control
    except ImportError:
        skipped.append("python-control: not installed (pip install 'railride[bench]'), skipped")
    else:
        w, wd = hermite_at(utab, t_out, interval)
        B = np.zeros((18, 16))
        B[9:, :8], B[9:, 8:] = Bw, Bwd
        lti = control.ss(A, B, np.eye(18)[:1], np.zeros((1, 16)))
        U = np.hstack([w, wd]).T
        methods["python-control forced_response, inputs at 1 kHz"] = (
            lambda: np.asarray(control.forced_response(lti, t_out, U).outputs).ravel(),
            True,
        )
    try:
        import pathsim
        from pathsim import Connection, Simulation
        from pathsim.blocks import ODE, Scope
        from pathsim.solvers import RKDP54
    except ImportError:
        skipped.append("PathSim: not installed (pip install 'railride[bench]'), skipped")
    else:

        def pathsim_run():
            # the same right-hand side as the SciPy peers; the Scope's sampling events end a
            # step at every output sample (PathSim has no dense output), so steps are <= 1 ms
            ode = ODE(lambda x, u, t: rhs(t, x), np.zeros(18))
            scope = Scope(sampling_period=1e-3)
            sim = Simulation(
                [ode, scope],
                [Connection(ode[0], scope[0])],
                dt=1e-3,
                Solver=RKDP54,
                tolerance_lte_rel=1e-6,
                tolerance_lte_abs=1e-9,
                log=False,
            )
            sim.run(10.0)
            t, y = scope.read()
            if len(t) != len(t_out) or not np.allclose(t, t_out, atol=1e-9):
                raise RuntimeError(f"PathSim sampled {len(t)} points, expected the 1 kHz grid of {len(t_out)}")
            return np.asarray(y).ravel()

        methods[f"PathSim {pathsim.__version__} RKDP54, rtol 1e-6, Scope at 1 kHz"] = (pathsim_run, False)

    times = {name: [] for name in methods}
    ratios = {name: [] for name in methods}
    outputs = {}
    for _ in range(args.rounds):
        for name, (run, fast) in methods.items():
            seconds, outputs[name] = _timed(run)
            if fast:
                seconds = min(seconds, min_time(run, args.repeat - 1) if args.repeat > 1 else seconds)
            times[name].append(seconds)
        exact = times["railride, exact discretisation (default)"][-1]
        for name in methods:
            ratios[name].append(times[name][-1] / exact)

    reference = outputs["railride, exact discretisation (default)"]
    scale = np.max(np.abs(reference))

    # the other linear case: an outer loop on the ideal actuator (exact steps against RK4), and the
    # frequency-domain ride of four laws beside a 60 s random run in the time domain
    sas = rr.Suspension.named("sas-attitude-ride", damper="ideal")
    rr.simulate(sc, suspension=sas)
    closed = {
        m: min_time(lambda m=m: rr.simulate(sc, suspension=sas, solver=rr.SolverSettings(method=m)), args.repeat)
        for m in ("auto", "rk4")
    }
    from railride.frequency.ride_spectrum import ride_spectrum

    ride_spectrum("fra4", points=100)
    spectrum = min_time(lambda: ride_spectrum("fra4"), args.repeat)
    long_run = rr.scenario("fra4", duration=60.0)
    rr.simulate(long_run, suspension=sas)
    random_run = min_time(lambda: rr.simulate(long_run, suspension=sas), args.repeat)

    print(f"scenario {args.scenario}, 10 s, passive vehicle, output at 1 kHz; medians of {args.rounds} paired rounds\n")
    for line in skipped:
        print(line)
    print("| method | time | x railride exact | largest difference / largest bounce | reproduces |")
    print("|---|---|---|---|---|")
    for name in methods:
        error = float(np.max(np.abs(outputs[name] - reference)) / scale)
        ok = "yes" if error < REPRODUCES else "NO"
        seconds, ratio = statistics.median(times[name]), statistics.median(ratios[name])
        print(f"| {name} | {seconds * 1e3:.1f} ms | {ratio:.1f} | {error:.1e} | {ok} |")
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
