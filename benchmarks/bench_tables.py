"""The parts of a study's input tables, railride's compiled ones (`railride.engine.tables`)
against what they replaced, one thread and two, the second showing whether the GIL is held:

* the rail heights of a random track at the wheelsets: against scipy's ``CubicSpline``;
* the rail forcing at the table's nodes (a table of fra4 at 30 and 70 m/s, 20 s, the paper's
  vehicle): against NumPy's ``einsum``, as `railride.run.inputs` built it before.

Run:  python benchmarks/bench_tables.py [--points 400000] [--repeat 5]

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
    args = ap.parse_args()

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
    from railride.run.inputs import _forcing_table, _system_arrays, _vehicle

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
        cases.append((f"{what}: railride", lambda t=table: _forcing_table(t, Bw, Bwd)))
    return cases


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
