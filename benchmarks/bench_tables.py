"""The rail heights of a random track at the wheelsets, as a study's input tables read them:
railride's compiled spline (`railride.engine.tables`) against scipy's ``CubicSpline``, one
thread and two, the second showing whether the GIL is held.

Run:  python benchmarks/bench_tables.py [--points 400000] [--repeat 5]

Prints a Markdown table for docs/performance.md: per evaluation of both rails' heights and
slopes at ``--points`` positions on fra4 (best of ``--repeat``), the time on one thread, and the
time of two such evaluations on two threads at once. Work that holds the GIL takes twice as
long on two threads; work that does not takes about as long as one. No test asserts timings.
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

    rows = []
    for name, fn in (("scipy `CubicSpline`", scipy_rails), ("railride (`railride.engine.tables`)", compiled_rails)):
        fn()  # compiles or loads
        one = min(_time(fn) for _ in range(args.repeat))
        two = min(_two_threads(fn) for _ in range(args.repeat))
        rows.append((name, one, two))
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, {datetime.date.today().isoformat()}")
    print(f"\n| both rails, heights and slopes, {args.points:,} points | one thread | two at once on two threads |")
    print("|---|---|---|")
    for name, one, two in rows:
        print(f"| {name} | {one * 1e3:.1f} ms | {two * 1e3:.1f} ms ({two / one:.2f}x one) |")


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
