"""What one chunk of a study costs beside its stepping: time and memory of each stage.

Run:  python benchmarks/bench_chunk.py [--runs 32] [--duration 20] [--repeat 5] [--comfort]
One chunk as `railride design` makes them (`railride.studies.sweep.evaluate` with the damper
costs): --runs runs of --duration s, pid on MR dampers with --runs / 4 gain sets on four tracks
(fra4 and fra5 at 30 and 50 m/s), histories at 1 kHz. Each stage is timed by wrapping the
function the chunk calls (best of --repeat, after a warm-up chunk) and, in a separate round,
its peak Python-traced memory above what was held when it started (tracemalloc, which NumPy
reports its arrays to): the step, the metrics, the damper costs and, with --comfort, the
comfort indices. No test asserts either.
"""

from __future__ import annotations

import argparse
import time
import tracemalloc


def _cases(runs: int, duration: float):
    from railride.studies.case import Case

    tracks = [("fra4", 30.0), ("fra4", 50.0), ("fra5", 30.0), ("fra5", 50.0)]
    per = max(1, runs // len(tracks))
    gains = [(("pid.kp", 1e5 * (k + 1)),) for k in range(per)]
    return [
        Case(t, (("duration", duration), ("seed", 1), ("speed", v)), suspension="pid", gains=g)
        for t, v in tracks
        for g in gains
    ][:runs]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=32)
    ap.add_argument("--duration", type=float, default=20.0)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--comfort", action="store_true")
    args = ap.parse_args()

    from railride.run import ride, simulation
    from railride.studies import sweep

    stages = {
        "step": (simulation, "step"),
        "metrics": (ride.RideResult, "metrics"),
        "damper costs": (sweep, "_costs"),
    }
    if args.comfort:
        from railride.analysis import comfort

        stages["comfort indices"] = (comfort, "ride_comfort")
    seconds: dict[str, float] = {}
    peak: dict[str, float] = {}
    trace = [False]

    def wrap(name, fn):
        def timed(*a, **k):
            t0 = time.perf_counter()
            if trace[0]:
                held = tracemalloc.get_traced_memory()[0]
                tracemalloc.reset_peak()
            try:
                return fn(*a, **k)
            finally:
                seconds[name] = seconds.get(name, 0.0) + time.perf_counter() - t0
                if trace[0]:
                    peak[name] = max(peak.get(name, 0.0), (tracemalloc.get_traced_memory()[1] - held) / 2**20)

        return timed

    for name, (owner, attr) in stages.items():
        setattr(owner, attr, wrap(name, getattr(owner, attr)))
    cases = _cases(args.runs, args.duration)
    sweep.evaluate(_cases(8, 1.0), costs=True, comfort=args.comfort)  # compile and warm
    best: dict[str, float] = {}
    for _ in range(args.repeat):
        seconds.clear()
        t0 = time.perf_counter()
        sweep.evaluate(cases, costs=True, comfort=args.comfort)
        seconds["whole chunk"] = time.perf_counter() - t0
        for k, v in seconds.items():
            best[k] = min(best.get(k, float("inf")), v)
    trace[0] = True
    tracemalloc.start()
    tracemalloc.reset_peak()
    sweep.evaluate(cases, costs=True, comfort=args.comfort)
    peak["whole chunk"] = tracemalloc.get_traced_memory()[1] / 2**20
    tracemalloc.stop()
    print(f"{len(cases)} runs of {args.duration:g} s, best of {args.repeat}")
    print("| stage | time | peak memory above |")
    print("|---|---|---|")
    for name in ("whole chunk", *stages):
        print(f"| {name} | {best.get(name, float('nan')):.3f} s | {peak.get(name, float('nan')):.0f} MiB |")


if __name__ == "__main__":
    main()
