"""What a sweep holds and where its time goes: peak memory against the number of runs, and a
profile of a fra4 sweep split into the stepper, the track tables and the metrics and comfort.

Run:  python benchmarks/bench_sweep_cost.py [--runs 512] [--profile-runs 128]
Memory: sweeps of 10 s fra4 runs (passive and three controllers on MR dampers, track seeds x
speeds, comfort indices on), --runs / 8, --runs / 4 and --runs runs, each in a fresh child
process after a warm-up sweep that compiles; the peak resident memory of the sweep itself
(Linux: the peak is reset after the warm-up through /proc/self/clear_refs) and above the
warm process. If memory is bounded by the chunk (32 runs), the peaks are about the same.
Time: cProfile of one sweep of about --profile-runs runs in this process, warm, its chunks one
after another in the main thread (`LocalExecutor(ahead=0)`: cProfile sees the main thread only;
the compiled kernels' own threads show as the stepper's call). The run counts printed are the
grids' own (a grid holds whole seeds: at least 32 runs). No test asserts either.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import subprocess
import sys
import time

SUSPENSIONS = ["passive", "pid", "sas-attitude", "sas-attitude-ride"]


def _grid(runs: int):
    from railride.studies.sweep import grid

    n_speeds = 8
    seeds = list(range(max(1, runs // (len(SUSPENSIONS) * n_speeds))))
    speeds = [30.0 + 5.0 * i for i in range(n_speeds)]
    return grid(SUSPENSIONS, scenario="fra4", speed=speeds, track_seed=seeds, duration=10.0)


def _status(field: str) -> float:
    """A field of /proc/self/status [MiB]."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError(f"no {field} in /proc/self/status")


def child(runs: int) -> None:
    """One sweep in this process, its peak memory as JSON on stdout."""
    import gc

    from railride.studies.sweep import run_sweep

    run_sweep(_grid(32))  # compile and warm: the same kernels, one chunk
    gc.collect()
    warm = _status("VmRSS")
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")  # resets VmHWM, the peak resident memory, to the current one
    g = _grid(runs)
    t0 = time.perf_counter()
    res = run_sweep(g)
    wall = time.perf_counter() - t0
    peak, after = _status("VmHWM"), _status("VmRSS")
    # what stays after the sweep is the shared tracks and tables (each store bounded by bytes)
    from railride.run import simulation
    from railride.model import track

    stores = (track._TRACKS, simulation._INPUT_TABLES, simulation._FORCING_TABLES)
    held = sum(s.nbytes for s in stores) / 2**20
    for s in stores:
        s.clear()
    gc.collect()
    try:  # glibc keeps freed heap pages: give them back, so the column shows what is still live
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass
    out = {
        "runs": len(res.to_pandas()),
        "warm": warm,
        "peak": peak,
        "after": after,
        "held": held,
        "cleared": _status("VmRSS"),
    }
    print(json.dumps({**out, "wall": wall}))


def profile(runs: int) -> None:
    from railride.studies.sweep import run_sweep

    from railride.studies.executors import LocalExecutor

    run_sweep(_grid(32))
    g = _grid(runs)
    runs = len(g.cases)
    prof = cProfile.Profile()
    t0 = time.perf_counter()
    prof.enable()
    run_sweep(g, executor=LocalExecutor(ahead=0))  # every chunk in this thread, where cProfile looks
    prof.disable()
    wall = time.perf_counter() - t0
    stats = pstats.Stats(prof).stats  # (file, line, name) -> (cc, nc, tottime, cumtime, callers)

    def cumulative(module: str, name: str) -> float:
        return sum(v[3] for (f, _, n), v in stats.items() if f.endswith(module) and n == name)

    def called_from(caller_module: str, caller: str) -> float:
        """The cumulative time of every call made directly by ``caller``."""
        return sum(
            ct
            for v in stats.values()
            for (f, _, n), (_, _, _, ct) in v[4].items()
            if f.endswith(caller_module) and n == caller
        )

    def own(module: str, name: str) -> float:
        return sum(v[2] for (f, _, n), v in stats.items() if f.endswith(module) and n == name)

    # each part by its outermost functions (cumulative times of nested calls would count twice)
    parts = {
        "stepper (compiled kernels; the exact steps with their exponentials)": cumulative("kernels.py", "run_parallel")
        + cumulative("discrete.py", "run_exact")
        + cumulative("discrete.py", "run_exact_closed"),
        "track tables: random-track synthesis and wheelset input tables (shared, kept by bytes)": cumulative(
            "simulation.py", "_input_table"
        ),
        "track tables: the rail forcing tables of the RK4 stepper (shared, kept by bytes)": cumulative(
            "simulation.py", "_forcing_table"
        ),
        "metrics (RMS, peak-to-peak)": cumulative("ride.py", "metrics"),
        "the result's Dataset (assembled for the comfort indices)": cumulative("ride.py", "dataset"),
        "comfort (floor accelerations, ISO 2631-1 / EN 12299 filters)": cumulative("comfort.py", "ride_comfort"),
        "each row built: its comfort indices picked by xarray isel/sel, its settings (sweep.evaluate)": called_from(
            "sweep.py", "evaluate"
        )
        - cumulative("simulation.py", "simulate")
        - cumulative("ride.py", "metrics")
        - cumulative("ride.py", "dataset")
        - cumulative("comfort.py", "ride_comfort"),
        "simulate's own lines (output arrays allocated and first touched, batch set-up)": own(
            "simulation.py", "simulate"
        ),
    }
    print(f"fra4 sweep, {runs} runs of 10 s ({', '.join(SUSPENSIONS)}), warm, cProfile: {wall:.2f} s\n")
    print("| part | time | share |")
    print("|---|---|---|")
    for name, seconds in parts.items():
        print(f"| {name} | {seconds:.2f} s | {100 * seconds / wall:.0f} % |")
    rest = wall - sum(parts.values())
    print(f"| the rest (cases, suspensions, run table, other set-up) | {rest:.2f} s | {100 * rest / wall:.0f} % |")
    print("\nlargest own times:")
    pstats.Stats(prof).sort_stats("tottime").print_stats(12)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--runs", type=int, default=512)
    ap.add_argument("--profile-runs", type=int, default=128)
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--skip-memory", action="store_true")
    ap.add_argument("--skip-profile", action="store_true")
    args = ap.parse_args()
    if args.child:
        child(args.child)
        return
    if not args.skip_memory:
        print(
            "| sweep (fra4, 10 s runs, comfort on) | runs | wall | warm process | peak during the sweep "
            "| after it | of it, tracks and tables kept | after clearing them |"
        )
        print("|---|---|---|---|---|---|---|---|")
        for runs in (args.runs // 8, args.runs // 4, args.runs):
            out = subprocess.run(
                [sys.executable, __file__, "--child", str(runs)], check=True, capture_output=True, text=True
            ).stdout
            r = json.loads(out.strip().splitlines()[-1])
            print(
                f"| {', '.join(SUSPENSIONS)} | {r['runs']} | {r['wall']:.1f} s | {r['warm']:.0f} MiB | "
                f"{r['peak']:.0f} MiB (+{r['peak'] - r['warm']:.0f}) | {r['after']:.0f} MiB | {r['held']:.0f} MiB | "
                f"{r['cleared']:.0f} MiB |"
            )
        print()
    if not args.skip_profile:
        profile(args.profile_runs)


if __name__ == "__main__":
    main()
