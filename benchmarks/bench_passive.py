"""Passive ride benchmarks: single run, batch throughput, CLI cold start.

Run:  python benchmarks/bench_passive.py [--repeat N] [--json FILE]
Prints a Markdown table for docs/performance.md. Timings are wall-clock minima over repeats;
nothing here is asserted by the tests.
"""

from __future__ import annotations

from _timing import min_time  # benchmarks/_timing.py: run as a script, this folder is on the path

import argparse
import json
import os
import platform
import shutil
import subprocess
import sys
import time
from datetime import date
from pathlib import Path

import numpy as np


def bench_single(repeat):
    from railride.run.simulation import simulate
    from railride.model.track import scenario

    sc = scenario("paper-sine")  # 10 s at dt = 1e-4 s: 100 000 RK4 steps
    simulate(sc)  # compile or load the cache
    run = min_time(lambda: simulate(sc), repeat)
    with_dataset = min_time(lambda: simulate(sc).dataset, repeat)
    with_metrics = min_time(lambda: simulate(sc).metrics(), repeat)
    return run, with_dataset, with_metrics


def bench_kernel_only(repeat):
    """The compiled RK4 stepper alone (`method="rk4"`), without tables or the Dataset: the
    thread's CPU time around the kernel call, with one numba thread."""
    import time

    import numba

    from railride.engine import kernels
    from railride.run.simulation import simulate
    from railride.run.solver import SolverSettings
    from railride.model.track import scenario

    sc, solver = scenario("paper-sine"), SolverSettings(method="rk4")
    took: list[float] = []
    run_parallel = kernels.run_parallel

    def timed(kernel, n, *args):
        t0 = time.thread_time()
        run_parallel(kernel, n, *args)
        took.append(time.thread_time() - t0)

    threads = numba.get_num_threads()
    numba.set_num_threads(1)
    kernels.run_parallel = timed
    try:
        simulate(sc, solver=solver)
        best = float("inf")
        for _ in range(repeat):
            took.clear()
            simulate(sc, solver=solver)
            best = min(best, sum(took))
    finally:
        kernels.run_parallel = run_parallel
        numba.set_num_threads(threads)
    return best


def bench_batch(n_samples, repeat, method="auto"):
    """A c_sz sweep: n_samples different vehicles in one batch ("auto" runs it by RK4 on the
    lane stepper; "exact" needs one matrix exponential per vehicle)."""
    from railride.model.params import VehicleParams
    from railride.run.simulation import simulate
    from railride.run.solver import SolverSettings
    from railride.model.track import scenario

    base = VehicleParams.preset("paper")
    params = [base.replace(c_sz=c) for c in np.linspace(2e4, 1.2e5, n_samples)]
    sc = scenario("paper-sine", duration=2.0)  # 20 000 steps per sample
    solver = SolverSettings(method=method)
    simulate(sc, params[: max(2, n_samples // 8)], solver=solver)
    t = min_time(lambda: simulate(sc, params, solver=solver), repeat)
    return n_samples * 20_000 / t, t


def bench_exact_tracks(repeat):
    """32 passive runs of one vehicle on 32 fra4 realisations, 10 s at 40 m/s, by the exact
    steps ("auto" takes them for passive): a study's passive chunk, its samples on numba's
    threads (NUMBA_NUM_THREADS sets how many)."""
    from railride.model.params import VehicleParams
    from railride.run.simulation import simulate
    from railride.model.track import scenario

    scs = [scenario("fra4", seed=s, speed=40.0, duration=10.0) for s in range(32)]
    params = [VehicleParams.preset("paper")] * 32
    simulate(scs, params)  # the matrix exponentials, the tables and the kernel's cache
    return min_time(lambda: simulate(scs, params), repeat)


def bench_cli(repeat):
    """Cold start of `railride simulate`: first call with an empty numba cache, then warm."""

    exe = shutil.which("railride")
    cmd = (
        [exe, "simulate", "--format", "json"]
        if exe
        else [sys.executable, "-m", "railride.cli", "simulate", "--format", "json"]
    )
    from railride.engine.cache_guard import cache_dir

    cache = Path(cache_dir())  # the engine's __pycache__, or its folder under NUMBA_CACHE_DIR
    for f in list(cache.glob("*.nbi")) + list(cache.glob("*.nbc")):
        f.unlink()
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    cold = time.perf_counter() - t0
    warm = min_time(lambda: subprocess.run(cmd, check=True, capture_output=True), repeat)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import railride.run.simulation, railride.cli"], check=True)
    imports = time.perf_counter() - t0
    return cold, warm, imports


def _cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown cpu"


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", type=Path)
    ap.add_argument("--no-cli", action="store_true", help="skip the CLI cold start (it empties the numba cache)")
    args = ap.parse_args()
    import numba

    res = {
        "date": date.today().isoformat(),
        "machine": f"{platform.machine()}, {os.cpu_count()} cores, {_cpu_name()}",
        "python": platform.python_version(),
        "numba": numba.__version__,
        "numpy": np.__version__,
        "threads": numba.config.NUMBA_NUM_THREADS,
    }
    res["single_run_s"], res["single_dataset_s"], res["single_metrics_s"] = bench_single(args.repeat)
    res["kernel_only_s"] = bench_kernel_only(args.repeat)
    for n in (64, 512):
        res[f"batch_{n}_sample_steps_per_s"], res[f"batch_{n}_s"] = bench_batch(n, max(2, args.repeat // 2))
    res["batch_64_exact_s"] = bench_batch(64, max(2, args.repeat // 2), "exact")[1]
    res["exact_32_tracks_s"] = bench_exact_tracks(args.repeat)
    if not args.no_cli:
        res["cli_cold_s"], res["cli_warm_s"], res["import_s"] = bench_cli(max(2, args.repeat // 2))

    print(f"{res['date']}, {res['machine']}, Python {res['python']}, numba {res['numba']}, {res['threads']} threads\n")
    print("| benchmark | result | target |")
    print("|---|---|---|")
    print(
        f"| one 10 s passive run, dt = 1e-4 s, `simulate()` after compilation | "
        f"{res['single_run_s'] * 1e3:.1f} ms | <= 20 ms |"
    )
    alone = res["kernel_only_s"] * 1e3
    print(f'| the same by RK4 (`method="rk4"`), compiled stepper alone, one core | {alone:.1f} ms | |')
    print(f"| the same, `simulate().dataset` (xarray Dataset assembled) | {res['single_dataset_s'] * 1e3:.1f} ms | |")
    print(f"| the same, `simulate().metrics()` | {res['single_metrics_s'] * 1e3:.1f} ms | |")
    for n in (64, 512):
        print(
            f"| batch of {n} samples x 20 000 steps | {res[f'batch_{n}_sample_steps_per_s'] / 1e6:.2f} M "
            f"sample-steps/s ({res[f'batch_{n}_s']:.2f} s) | >= 2 M/s |"
        )
    exact = res["batch_64_exact_s"]
    print(f'| batch of 64 x 20 000 steps, `method="exact"` (64 matrix exponentials) | {exact:.2f} s | |')
    tracks = res["exact_32_tracks_s"]
    print(
        f"| 32 passive runs, one vehicle, 32 fra4 tracks, 10 s, exact steps ({res['threads']} threads) "
        f"| {tracks:.3f} s | |"
    )
    if not args.no_cli:
        cold = res["cli_cold_s"]
        print(f"| `railride simulate`, first call (empty numba cache, compile included) | {cold:.1f} s | |")
        print(f"| `railride simulate`, second call (numba cache) | {res['cli_warm_s']:.2f} s | |")
        print(f"| of which Python imports | {res['import_s']:.2f} s | |")
    if args.json:
        args.json.write_text(json.dumps(res, indent=2) + "\n")


if __name__ == "__main__":
    main()
