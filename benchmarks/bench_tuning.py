"""Tuning and sweep benchmarks.

Run:  python benchmarks/bench_tuning.py [--budget 400] [--duration 10]
Prints a Markdown table for docs/performance.md (single wall-clock runs; the tests assert no
timing). The studies start from the neutral reference gains (scaled from the passive
suspension, GainSet.reference(), railride/data/reference_gains.toml) so that they have the
whole way to go, with the default objective (minimax) and budget: the second row is
`railride tune` as shipped.
"""

from __future__ import annotations

import argparse
import platform
import time

from railride.studies.sweep import Case, run_cases
from railride.studies.tuning import tune


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--budget", type=int, default=400, help="vehicle runs per law (default 400, as shipped)")
    ap.add_argument("--duration", type=float, default=10.0, help="each run's length [s] (default 10)")
    args = ap.parse_args()
    print(
        f"machine: {platform.processor() or platform.machine()}, {__import__('os').cpu_count()} cores; "
        f"{time.strftime('%Y-%m-%d')}"
    )
    run_cases([Case(scenario_options={"duration": 1.0}, suspension="pid")])  # compile
    rows = []
    studies = (
        ("SAS (attitude+ride) alone (14 gains), budget 400, from the reference gains", ("sas-attitude-ride",)),
        ("every law and the inner loop (= `railride tune`), budget 400 per law, from the reference gains", "all"),
    )
    for label, controllers in studies:
        t0 = time.perf_counter()
        kw = dict(budget=args.budget, scenario_options={"duration": args.duration})
        res = tune(**kw) if controllers == "all" else tune(controllers, **kw)
        dt = time.perf_counter() - t0
        n = len(res.runs)
        laws = ", ".join(f"{s.controller} {s.objective:.3f}" for s in res.studies if s.controller != "inner")
        rows.append(
            (
                f"`tune`: {label.replace('budget 400', f'budget {args.budget}')}, "
                f"`paper-sine` {args.duration:g} s runs",
                f"{dt:.1f} s, {n} runs ({n / dt:.0f} runs/s); objective {laws}",
                "<= 120 s per law" if controllers != "all" else "",
            )
        )
    cases = [
        Case(scenario_options={"speed": 20.0 + 5 * i, "duration": args.duration}, suspension=s)
        for i in range(13)
        for s in ("passive", "pid", "sas-attitude", "sas-attitude-ride")
    ]
    t0 = time.perf_counter()
    run_cases(cases)
    dt = time.perf_counter() - t0
    rows.append(
        (
            f"`sweep`: 13 speeds x 4 suspensions, {args.duration:g} s runs, local executor",
            f"{len(cases) / dt:.1f} runs/s ({dt:.1f} s)",
            "",
        )
    )
    print("| benchmark | result | target |")
    print("|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    main()
