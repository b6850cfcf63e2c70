"""The parts of a study's input tables, railride's compiled ones (`railride.engine.tables`)
against what they replaced, one thread and two, the second showing whether the GIL is held:

* the rail heights of a random track at the wheelsets: against scipy's ``CubicSpline``;
* the rail forcing at the table's nodes (a table of fra4 at 30 and 70 m/s, 20 s, the paper's
  vehicle): against NumPy's ``einsum``, as `railride.run.inputs` built it before.

With ``--round``, instead: the inputs stage (`railride.run.simulation.inputs`) of one round of
the default design's tuning, all its laws in one batch as on the GPU: the 36 training conditions
(fra4 and fra5, seeds 1-3, 30, 50 and 70 m/s, loads 1 and 1.3, 20 s), eight closed loops each,
the input and forcing tables' stores emptied before each try, so that those tables are built
too (the random tracks' realisations are kept: a design's rounds share them).

Run:  python benchmarks/bench_tables.py [--points 400000] [--repeat 5] [--round]

Prints a Markdown table for docs/performance.md: the best of ``--repeat`` times on one thread,
and of two such calls on two threads at once. Work that holds the GIL takes twice as long on two
threads; work that does not takes about as long as one. No test asserts timings.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import threading
import time

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--points", type=int, default=400_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--round", action="store_true", help="the inputs stage of a design's tuning round")
    args = ap.parse_args()
    if args.round:
        _round(args.repeat)
        return

    from railride.model.irregularity import RandomTrack

    track = RandomTrack("fra4", seed=1)
    left, right = track.splines()
    s = np.random.default_rng(0).uniform(0.0, track.end(), args.points)

    def scipy_rails():
        return left(s), right(s), left(s, 1), right(s, 1)

    def compiled_rails():
        return track._evaluate(s)

    cases = [
        (f"both rails, heights and slopes, {args.points:,} points: scipy `CubicSpline`", scipy_rails),
        (f"both rails, heights and slopes, {args.points:,} points: railride", compiled_rails),
    ]
    cases += _forcing_cases()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, {datetime.date.today().isoformat()}")
    print("\n| work | one thread | two at once on two threads |")
    print("|---|---|---|")
    for name, fn in cases:
        fn()  # compiles or loads
        one = min(_time(fn) for _ in range(args.repeat))
        two = min(_two_threads(fn) for _ in range(args.repeat))
        print(f"| {name} | {one * 1e3:.1f} ms | {two * 1e3:.1f} ms ({two / one:.2f}x one) |")


def _forcing_cases() -> list:
    from railride.model.params import VehicleParams
    from railride.model.track import scenario, wheelset_input_table
    from railride.engine.tables import forcing_nodes
    from railride.run.inputs import _system_arrays, _vehicle

    vehicle = _vehicle(VehicleParams.preset("paper"))
    arrays = _system_arrays(vehicle)
    Bw, Bwd = arrays["Bw"], arrays["Bwd"]

    def einsum(utab):  # the forcing table as railride.run.inputs built it before
        w, wd = utab[:, :8], utab[:, 8:]
        return np.hstack([np.einsum("nk,jk->nj", x, B) for B in (Bw, Bwd) for x in (w, wd)])

    cases = []
    for speed in (30.0, 70.0):
        sc = scenario("fra4", seed=1, speed=speed, duration=20.0)
        table, _ = wheelset_input_table(sc, np.asarray(vehicle.wheelset_lag_distance), 1e-4)
        what = f"forcing table, {table.shape[0]:,} nodes ({speed:g} m/s, 20 s)"
        cases.append((f"{what}: NumPy `einsum`", lambda t=table: einsum(t)))
        table.flags.writeable = False  # as the kept tables are
        cases.append((f"{what}: railride", lambda t=table: _compiled(forcing_nodes, t, Bw, Bwd)))
    return cases


def _compiled(forcing_nodes, table, Bw, Bwd):
    """The compiled forcing table on the calling thread alone (`forcing_nodes` over all rows)."""
    out = np.empty((table.shape[0], 4 * Bw.shape[0]))
    forcing_nodes(table, Bw, Bwd, out)
    return out


def _round(repeat: int) -> None:
    """The inputs stage of one tuning round of the default design in one batch (see the module)."""
    import numba

    from railride.model.params import VehicleParams
    from railride.model.track import scenario
    from railride.run import inputs, simulation
    from railride.secondary.suspension import Suspension

    laws = ["pid", "sas-attitude", "sas-attitude-ride", "skyhook", "skyhook-on-off", "groundhook", "hybrid"]
    laws.append("clipped-optimal")
    conditions = [
        (scenario(track, seed=seed, speed=speed, duration=20.0), VehicleParams.preset("paper").loaded(load))
        for track in ("fra4", "fra5")
        for seed in (1, 2, 3)
        for speed in (30.0, 50.0, 70.0)
        for load in (1.0, 1.3)
    ]
    scs = [sc for sc, _ in conditions for _ in laws]
    pars = [p for _, p in conditions for _ in laws]
    plan = simulation.check(scs, pars, [Suspension.named(law) for _ in conditions for law in laws])
    times = []
    for _ in range(repeat + 1):  # the first compiles or loads
        inputs._INPUT_TABLES.clear()
        inputs._FORCING_TABLES.clear()
        t0 = time.perf_counter()
        tables = simulation.inputs(plan)
        times.append(time.perf_counter() - t0)
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, {datetime.date.today().isoformat()}")
    print("\n| work | numba threads | best | median |")
    print("|---|---|---|---|")
    print(
        f"| inputs of one tuning round: {plan.n} runs, 36 conditions, forcing tables "
        f"{tables.ftab.nbytes / 1e6:.0f} MB | {numba.get_num_threads()} | {min(times[1:]):.3f} s "
        f"| {float(np.median(times[1:])):.3f} s |"
    )


def _time(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def _two_threads(fn) -> float:
    threads = [threading.Thread(target=fn) for _ in range(2)]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
