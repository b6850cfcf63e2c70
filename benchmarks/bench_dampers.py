"""MR damper benchmarks: the vehicle with four MR dampers, the damper rig.

Run:  python benchmarks/bench_dampers.py [--repeat N] [--batches]
      python benchmarks/bench_dampers.py --lane-sizes [--threads 1,2,4,8,16] [--sizes 8,16,...]
Prints a Markdown table for docs/performance.md (wall-clock minima; no test asserts timings).
"""

from __future__ import annotations

from _timing import min_time  # benchmarks/_timing.py: run as a script, this folder is on the path

import argparse
import time

import numpy as np


def batch_rows(repeat: int) -> list[tuple[str, str, str]]:
    """Batch throughput, the lane stepper (`lanes.run_lanes`, the default for batches of
    lanes.LANES samples or more) against the sample-by-sample stepper (`run_batch`), timed in
    alternating rounds (paired: the machine is shared), 20 000 steps per sample, both cores."""
    from railride.engine import lanes
    from railride.model.params import VehicleParams
    from railride.run.simulation import simulate
    from railride.run.solver import SolverSettings
    from railride.secondary.suspension import Suspension
    from railride.model.track import scenario

    sc = scenario("paper-sine", duration=2.0)
    sas = Suspension.named("sas-attitude-ride")
    paper = VehicleParams.preset("paper")
    batches = [
        (
            "batch of 64 voltages, `railway` dampers",
            dict(suspension=[Suspension.semi_active("railway", voltage=float(v)) for v in np.linspace(0.0, 2.25, 64)]),
        ),
        ("batch of 64 SAS (attitude+ride) closed loops, `railway`", dict(suspension=[sas] * 64)),
        ("batch of 512 SAS (attitude+ride) closed loops, `railway`", dict(suspension=[sas] * 512)),
        (
            'batch of 64 passive vehicles (c_sz swept), `method="rk4"`',
            dict(
                params=[paper.replace(c_sz=c) for c in np.linspace(2e4, 1.2e5, 64)],
                solver=SolverSettings(method="rk4"),
            ),
        ),
    ]
    fit = lanes.lanes_fit
    rows = []
    for label, kw in batches:
        n = len(kw.get("suspension", kw.get("params")))
        # best wall-clock and CPU time (both threads) of each stepper
        best = {name: [float("inf"), float("inf")] for name in ("run_batch", "run_lanes")}
        for r in range(repeat + 1):  # round 0 compiles or loads each stepper
            for name in best:
                lanes.lanes_fit = fit if name == "run_lanes" else (lambda *a: False)
                try:
                    wall, cpu = time.perf_counter(), time.process_time()
                    simulate(sc, **kw)
                    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
                finally:
                    lanes.lanes_fit = fit
                if r > 0:
                    best[name] = [min(best[name][0], wall), min(best[name][1], cpu)]
        rate = {k: [n * 20_000 / t / 1e6 for t in v] for k, v in best.items()}
        rows.append(
            (
                f"{label} x 20 000 steps, both cores: `run_batch` -> `run_lanes`",
                f"{rate['run_batch'][0]:.2f} -> **{rate['run_lanes'][0]:.2f}** M sample-steps/s "
                f"(per CPU-second: {rate['run_batch'][1]:.2f} -> {rate['run_lanes'][1]:.2f} M)",
                ">= 10 M/s" if "SAS" in label else "",
            )
        )
    return rows


def lane_size_rows(threads, sizes, repeat: int) -> list[tuple[str, str, str]]:
    """`run_batch` against the lane stepper by batch size and numba thread count: where the lane
    groups (`lanes.LANES` samples each) are fewer than the threads, the lane stepper leaves
    threads idle, and the question is from which size it still wins. SAS (attitude+ride) closed
    loops and MR dampers at spread voltages, 1 s (10 000 steps) each, best of ``repeat``."""
    import numba

    from railride.engine import lanes
    from railride.run.simulation import simulate
    from railride.secondary.suspension import Suspension
    from railride.model.track import scenario

    sc = scenario("paper-sine", duration=1.0)
    fit = lanes.lanes_fit

    def rate(n: int, stepper: str, kind: str) -> float:
        if kind == "SAS (attitude+ride)":
            sus = [Suspension.named("sas-attitude-ride")] * n
        else:
            sus = [Suspension.semi_active("railway", voltage=float(v)) for v in np.linspace(0.0, 2.25, n)]
        lanes.lanes_fit = fit if stepper == "lanes" else (lambda *a: False)
        try:
            simulate(sc, suspension=sus)  # compiles or loads the stepper
            t = min_time(lambda: simulate(sc, suspension=sus), repeat)
        finally:
            lanes.lanes_fit = fit
        return n * 10_000 / t / 1e6

    rows = []
    for k in threads:
        numba.set_num_threads(k)
        for kind in ("SAS (attitude+ride)", "voltages"):
            for n in sizes:
                b, ln = rate(n, "batch", kind), rate(n, "lanes", kind)
                groups = -(-n // lanes.LANES)
                rows.append(
                    (
                        f"{k} thread(s), {n} {kind} ({groups} lane group(s)): `run_batch` -> `run_lanes`",
                        f"{b:.2f} -> {ln:.2f} M sample-steps/s ({ln / b:.2f}x)",
                        "",
                    )
                )
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--batches", action="store_true", help="only the batch rows (run_batch against run_lanes)")
    ap.add_argument("--lane-sizes", action="store_true", help="run_batch against run_lanes by batch size and threads")
    ap.add_argument("--threads", default="1,2", help="numba thread counts for --lane-sizes (default 1,2)")
    ap.add_argument("--sizes", default="8,16,24,32,64", help="batch sizes for --lane-sizes")
    args = ap.parse_args()
    if args.lane_sizes:
        threads = [int(v) for v in args.threads.split(",")]
        sizes = [int(v) for v in args.sizes.split(",")]
        _print(lane_size_rows(threads, sizes, args.repeat))
        return
    if args.batches:
        _print(batch_rows(args.repeat))
        return

    from railride.run import rig
    from railride.run.simulation import simulate
    from railride.secondary.suspension import Suspension
    from railride.model.track import scenario

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
    rows += batch_rows(max(2, args.repeat // 2))
    for name in ("railway", "spencer1997"):
        rig.cycles(name, 0.015, 2.5, [0.0])
        t = min_time(lambda: rig.cycles(name, 0.015, 2.5, [0.0, 0.75, 1.5, 2.25]), args.repeat)
        rows.append((f"rig: `{name}`, 4 voltages x 4 cycles at 2.5 Hz, dt = 1e-4 s", f"{t * 1e3:.1f} ms", ""))
    rig.track("railway")
    t = min_time(lambda: rig.track("railway"), args.repeat)
    rows.append(("rig: force tracking, 3 cycles at 1 Hz", f"{t * 1e3:.1f} ms", ""))

    _print(rows)


def _print(rows) -> None:
    print("| benchmark | result | target |")
    print("|---|---|---|")
    for r in rows:
        print("| " + " | ".join(r) + " |")


if __name__ == "__main__":
    main()
