"""Tuning and sweep benchmarks.

Run:  python benchmarks/bench_tuning.py
Prints a Markdown table for docs/performance.md (single wall-clock runs; the tests assert no
timing). The studies start from the neutral reference gains (scaled from the passive
suspension, GainSet.reference(), railride/data/reference_gains.toml) so that they have the
whole way to go, with the default objective (minimax): the last row is `railride tune` as
shipped.
"""

from __future__ import annotations

import time

from railride.control import GainSet
from railride.sweep import Case, run_cases
from railride.tuning import tune


def reference_gains() -> GainSet:
    return GainSet.reference()


def main():
    run_cases([Case(scenario_options={"duration": 1.0}, suspension="pid")])  # compile
    rows = []
    studies = (
        ("two-phase study (attitude, then ride), from the reference gains", ("attitude", "ride"), reference_gains()),
        ("two-phase study from the shipped gains", ("attitude", "ride"), GainSet.default()),
        (
            "all four phases (inner, pid, attitude, ride) from the reference gains",
            ("inner", "pid", "attitude", "ride"),
            reference_gains(),
        ),
    )
    for label, phases, start in studies:
        t0 = time.perf_counter()
        res = tune(phases, gains=start)
        dt = time.perf_counter() - t0
        n = len(res.runs)
        target = "<= 120 s" if label.startswith("two-phase") and "reference" in label else ""
        rows.append(
            (
                f"`tune`: {label}, `paper-sine` 10 s runs",
                f"{dt:.1f} s, {n} runs ({n / dt:.0f} runs/s), objective {res.history[-1]['objective']:.3f}",
                target,
            )
        )
    cases = [
        Case(scenario_options={"speed": 20.0 + 5 * i}, suspension=s)
        for i in range(13)
        for s in ("passive", "pid", "sas-attitude", "sas-attitude-ride")
    ]
    t0 = time.perf_counter()
    run_cases(cases)
    dt = time.perf_counter() - t0
    rows.append(
        (
            "`sweep`: 13 speeds x 4 suspensions, 10 s runs, local executor",
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
