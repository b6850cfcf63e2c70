"""Cost of each control law in the closed loop, and of a league table.

Run:  python benchmarks/bench_controllers.py [--repeat N]
Prints a Markdown table for docs/performance.md: per law, one 10 s run on `paper-sine` with four
`railway` MR dampers (dt = 1e-4 s, 100 000 steps), its time per step and the ratio to SAS
(attitude+ride); then a league table of five controllers on three scenarios at two speeds, warm.
Wall-clock minima over the repeats; no test asserts timings.
"""

from __future__ import annotations

from _timing import min_time  # benchmarks/_timing.py: run as a script, this folder is on the path

import argparse


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    import numba

    from railride import Suspension, scenario, simulate
    from railride.control import CONTROLLERS
    from railride.league import league

    sc = scenario("paper-sine")
    steps = round(sc.duration / 1e-4)
    laws = [n for n in CONTROLLERS if n != "passive"]
    times = {}
    for name in laws:
        susp = Suspension.named(name)
        simulate(sc, None, susp)  # compile and warm
        times[name] = min_time(lambda: simulate(sc, None, susp).metrics(), args.repeat)
    ref = times["sas-attitude-ride"]
    print(f"numba threads: {numba.get_num_threads()}\n")
    print("| law (MR dampers, 10 s, paper-sine) | time | per step | / SAS (attitude+ride) |")
    print("|---|---|---|---|")
    for name in laws:
        t = times[name]
        print(f"| {name} | {t * 1e3:.1f} ms | {t / steps * 1e6:.3f} us | {t / ref:.2f} |")

    chosen = ["pid", "sas-attitude-ride", "skyhook", "groundhook", "clipped-optimal"]
    run = lambda: league(["paper-sine", "fra4", "german-low"], [30.0, 55.56], controllers=chosen)  # noqa: E731
    run()  # warm
    t = min_time(run, max(1, args.repeat // 2))
    print(f"\nleague table, {len(chosen)} controllers x 3 scenarios x 2 speeds (with both bounds), warm: {t:.2f} s")


if __name__ == "__main__":
    main()
