"""MR damper benchmarks: the vehicle with four MR dampers, the damper rig.

Run:  python benchmarks/bench_dampers.py [--repeat N]
Prints a Markdown table for docs/performance.md (wall-clock minima; no test asserts timings).
"""

from __future__ import annotations

from _timing import min_time  # benchmarks/_timing.py: run as a script, this folder is on the path

import argparse

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()

    from railride import rig
    from railride.simulation import simulate
    from railride.suspension import Suspension
    from railride.track import scenario

    sc = scenario("paper-sine")  # 10 s at dt = 1e-4 s
    rows = []
    for damper, voltage, note in (
        ("railway", 0.0, "passive-off"),
        ("railway", 2.25, "passive-on"),
        ("dyke1996", 2.25, "small-scale damper"),
    ):
        mr = Suspension.semi_active(damper, voltage=voltage)
        simulate(sc, suspension=mr)
        t = min_time(lambda: simulate(sc, suspension=mr), args.repeat)
        rows.append(
            (
                f"vehicle, four `{damper}` MR dampers at {voltage:g} V ({note}), 10 s, dt = 1e-4 s",
                f"{t * 1e3:.1f} ms",
                "<= 50 ms" if damper == "railway" else "",
            )
        )
    # the closed loop: SAS (attitude+ride) with the shipped gains on each device
    for damper in ("railway", "ideal-damper", "ideal"):
        sas = Suspension.named("sas-attitude-ride", damper=damper)
        simulate(sc, suspension=sas)
        t = min_time(lambda: simulate(sc, suspension=sas), args.repeat)
        rows.append((f"vehicle, SAS (attitude+ride) closed loop, `{damper}`, 10 s", f"{t * 1e3:.1f} ms", ""))
    spencer = Suspension.semi_active("spencer1997", voltage=1.0)
    simulate(scenario("paper-sine", duration=1.0), suspension=spencer)
    t = min_time(lambda: simulate(scenario("paper-sine", duration=1.0), suspension=spencer), max(1, args.repeat // 2))
    rows.append(("vehicle, four `spencer1997` dampers at 1 V, 1 s (stiff: sub-stepped)", f"{t * 1e3:.1f} ms", ""))
    sc_batch = scenario("paper-sine", duration=2.0)
    batch = [Suspension.semi_active("railway", voltage=float(v)) for v in np.linspace(0.0, 2.25, 64)]
    simulate(sc_batch, suspension=batch)
    t = min_time(lambda: simulate(sc_batch, suspension=batch), max(1, args.repeat // 2))
    rows.append(
        (
            "batch of 64 voltages x 20 000 steps, `railway` dampers, both cores",
            f"{64 * 20_000 / t / 1e6:.2f} M sample-steps/s",
            "",
        )
    )
    for name in ("railway", "spencer1997"):
        rig.cycles(name, 0.015, 2.5, [0.0])
        t = min_time(lambda: rig.cycles(name, 0.015, 2.5, [0.0, 0.75, 1.5, 2.25]), args.repeat)
        rows.append((f"rig: `{name}`, 4 voltages x 4 cycles at 2.5 Hz, dt = 1e-4 s", f"{t * 1e3:.1f} ms", ""))
    rig.track("railway")
    t = min_time(lambda: rig.track("railway"), args.repeat)
    rows.append(("rig: force tracking, 3 cycles at 1 Hz", f"{t * 1e3:.1f} ms", ""))

    print("| benchmark | result | target |")
    print("|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    main()
