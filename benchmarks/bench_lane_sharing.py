"""The lane stepper on batches whose lane groups share, or do not share, their rail inputs and vehicle.

Run:  python benchmarks/bench_lane_sharing.py [--repeat 5] [--duration 10]
Three 32-run batches of pid on MR dampers (`railride.studies.sweep.evaluate`, one compiled
batch each, given in this order): 32 track cases (fra4 and fra5, 3 seeds, 3 speeds, loads 1
and 1.3) with one gain set; 4 cases with 8 gain sets each (a lane group of 8 is one case);
4.6 cases with 7 gain sets each (groups straddle two cases, as in a tuning round whose current
gain set is already in its table). Prints the lane stepper's rate in sample-steps per second,
the best of --repeat rounds, the batches alternating in each round. A study's chunks are
sorted by vehicle, track and speed (`railride.studies.sweep._chunks`), so its batches are of
the second or third kind. No test asserts timings.
"""

from __future__ import annotations

import argparse

import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--duration", type=float, default=10.0)
    args = ap.parse_args()

    from railride.model.params import VehicleParams
    from railride.studies.case import Case
    from railride.studies.sweep import evaluate

    paper = VehicleParams.of("paper")

    def case(track, seed, speed, load, kp):
        options = (("duration", args.duration), ("seed", seed), ("speed", speed))
        return Case(track, options, suspension="pid", gains=(("pid.kp", kp),), vehicle=paper.load_changes(load))

    speeds = (30.0, 50.0, 70.0)
    tracks = [(t, s, v, ld) for t in ("fra4", "fra5") for ld in (1.0, 1.3) for s in (1, 2, 3) for v in speeds]
    gains = [1e3 * 2**k for k in range(8)]
    batches = {
        "32 cases x 1 gain set": [case(*c, kp) for kp in gains for c in tracks][:32],
        "4 cases x 8 gain sets": [case(*c, kp) for c in tracks for kp in gains][:32],
        "4.6 cases x 7 gain sets": [case(*c, kp) for c in tracks for kp in gains[:7]][:32],
    }
    intervals = _watch_lane_steps()  # (start, end) of every call of the lane stepper
    for cases in batches.values():
        evaluate(cases[:8])  # compile and warm
    best = dict.fromkeys(batches, float("inf"))
    for _ in range(args.repeat):
        for name, cases in batches.items():
            intervals.clear()
            evaluate(cases)
            best[name] = min(best[name], sum(end - start for start, end in intervals))
    steps = round(args.duration / 1e-4)
    print(f"| batch of 32 runs of {args.duration:g} s | step stage | sample-steps/s |")
    print("|---|---|---|")
    for name, s in best.items():
        print(f"| {name} | {s:.3f} s | {32 * steps / s / 1e6:.1f} M |")


def _watch_lane_steps() -> list:
    """Record the (start, end) of every call of a lane stepper, in any thread: the stepping of
    a batch with histories (`railride.run.simulation`) and of a metrics-only batch
    (`railride.run.reduced`, which a sweep without comfort takes) alike."""
    from railride.engine import lanes

    intervals: list = []
    make = lanes.lanes_stepper

    def timed_maker(*args, **kwargs):
        step = make(*args, **kwargs)

        def timed(*a, **k):
            start = time.perf_counter()
            try:
                return step(*a, **k)
            finally:
                intervals.append((start, time.perf_counter()))

        return timed

    lanes.lanes_stepper = timed_maker
    return intervals


if __name__ == "__main__":
    main()
