"""Tuning and sweep benchmarks.

Run:  python benchmarks/bench_tuning.py
Prints a Markdown table for docs/performance.md (single wall-clock runs; the tests assert no
timing). The studies start from the neutral reference gains (scaled from the passive
suspension, GainSet.reference(), railride/data/reference_gains.toml) so that they have the
whole way to go, with the default objective (minimax) and budget: the second row is
`railride tune` as shipped.
"""

from __future__ import annotations

import time

from railride.studies.sweep import Case, run_cases
from railride.studies.tuning import tune


def main():
    run_cases([Case(scenario_options={"duration": 1.0}, suspension="pid")])  # compile
    rows = []
    studies = (
        ("SAS (attitude+ride) alone (14 gains), budget 400, from the reference gains", ("sas-attitude-ride",)),
        ("every law and the inner loop (= `railride tune`), budget 400 per law, from the reference gains", "all"),
    )
    for label, controllers in studies:
        t0 = time.perf_counter()
        res = tune() if controllers == "all" else tune(controllers)
        dt = time.perf_counter() - t0
        n = len(res.runs)
        laws = ", ".join(f"{s.controller} {s.objective:.3f}" for s in res.studies if s.controller != "inner")
        rows.append(
            (
                f"`tune`: {label}, `paper-sine` 10 s runs",
                f"{dt:.1f} s, {n} runs ({n / dt:.0f} runs/s); objective {laws}",
                "<= 120 s per law" if controllers != "all" else "",
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
