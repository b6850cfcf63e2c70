"""Cost of a study over many tracks (railride.study): wall time and peak memory.

Run:  python benchmarks/bench_study.py [--seeds N]
Prints a Markdown row for docs/performance.md: one study of 1000 closed-loop and passive runs
of 10 s (fra4, N = 20 track seeds x 5 speeds x 2 loads x (passive + 4 controllers)), on this
machine's cores, with its wall time (compilation excluded: a warm-up study runs first) and the
process's peak resident memory. No test asserts timings.
"""

from __future__ import annotations

import argparse
import resource
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=20)
    args = ap.parse_args()

    from railride.study import study

    controllers = ["pid", "sas-attitude", "sas-attitude-ride", "clipped-optimal"]
    study(controllers, track_seeds=[0], speeds=[40.0], duration=1.0)  # compile
    seeds = list(range(args.seeds))
    speeds = [30.0, 37.5, 45.0, 52.5, 60.0]
    t0 = time.perf_counter()
    res = study(controllers, track_seeds=seeds, speeds=speeds, loads=[1.0, 1.3], faults=["none"])
    wall = time.perf_counter() - t0
    peak_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    n = len(res.cases)
    print("| study | runs | wall time | runs/s | peak memory (process) |")
    print("|---|---|---|---|---|")
    print(
        f"| fra4, {args.seeds} seeds x 5 speeds x 2 loads x (passive + 4 controllers), 10 s runs | {n} | "
        f"{wall:.1f} s | {n / wall:.1f} | {peak_mib:.0f} MiB |"
    )


if __name__ == "__main__":
    main()
