"""Cost of `railride design` with its defaults: wall time, CPU share and peak memory.

Run:  python benchmarks/bench_design.py [--out DIR] [other railride design options]
      python benchmarks/bench_design.py --profile [--controllers A,B] [--budget N] [--duration S]
                                        [--backend auto|cpu|gpu] [--gpu-kernel BUILD] [--gpu-threads N]
                                        [--gpu-file-cache] [--gpu-min-batch N]
Runs `railride design --out DIR` (default: a new temporary folder) in a child process and
prints a Markdown row for docs/performance.md: the runs it evaluated, its wall time, the CPU
time of the child as a share of one core, and the child's peak resident memory. The default
design takes about 10-30 minutes on a 2-core machine. No test asserts timings.

--profile runs `railride.design` in this process (its defaults, but for the options named, no
files written) and says where its wall time went: by stage (the inner loop, the tuning rounds,
the held-out runs, the probes, the rest), how long some batch was stepping in each, how long
none was, and how long no chunk was being worked on at all: work that more threads do not
overlap as the design runs its chunks today.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _timing import clipped, covered  # benchmarks/_timing.py: run as a script, this folder is on the path


def main():
    args = sys.argv[1:]
    if args and args[0] in ("-h", "--help"):  # the rest go to `railride design` as given
        print(__doc__)
        return None
    if "--profile" in args:
        return profile([a for a in args if a != "--profile"])
    if "--out" in args:
        out = Path(args[args.index("--out") + 1])
    else:
        out = Path(tempfile.mkdtemp(prefix="railride-design-")) / "d"
        args = [*args, "--out", str(out)]
    t0 = time.perf_counter()
    subprocess.run(
        [sys.executable, "-m", "railride.cli", "design", *args, "--format", "json"],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    wall = time.perf_counter() - t0
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    doc = json.loads((out / "design.json").read_text())
    print("| design | runs | wall time | CPU | peak memory |")
    print("|---|---|---|---|---|")
    print(
        f"| {' '.join(args)} | {doc.get('runs_evaluated', '?')} | {wall / 60:.1f} min | "
        f"{(usage.ru_utime + usage.ru_stime) / wall * 100:.0f} % | {usage.ru_maxrss / 1024**2:.2f} GiB |"
    )


def profile(args: list) -> None:
    import argparse
    import signal
    import threading

    import numba

    import railride as rr
    from railride.engine import lanes
    from railride.run import reduced, simulation
    from railride.studies import design as design_module
    from railride.studies import design_probes, sweep, tuning

    from bench_gpu_kernel import KERNELS, use_build  # benchmarks/: run as a script, this folder is on the path

    ap = argparse.ArgumentParser(prog="bench_design.py --profile")
    ap.add_argument("--controllers", default=None)
    ap.add_argument("--budget", type=int, default=design_module.DEFAULT_BUDGET)
    ap.add_argument("--duration", type=float, default=design_module.DEFAULT_DURATION)
    ap.add_argument("--backend", default="auto", choices=["auto", "cpu", "gpu"])
    ap.add_argument(
        "--gpu-kernel", default=None, choices=list(KERNELS),
        help="the GPU kernel's build (bench_gpu_kernel.py --kernels); default: the package's",
    )  # fmt: skip
    ap.add_argument("--gpu-threads", type=int, default=None, help="threads a block (default: gpu.THREADS_PER_BLOCK)")
    ap.add_argument(
        "--gpu-min-batch", type=int, default=None,
        help="--backend auto: the smallest batch the GPU takes (solver.GPU_MIN_BATCH; default: solver.gpu_pays)",
    )  # fmt: skip
    ap.add_argument(
        "--gpu-file-cache", action="store_true",
        help="keep the GPU kernels in numba's file cache (gpu.FILE_CACHE): a second run loads them",
    )  # fmt: skip
    opts = ap.parse_args(args)
    from railride.engine import gpu

    if opts.gpu_kernel is not None:
        use_build(opts.gpu_kernel)
    if opts.gpu_threads is not None:
        gpu.THREADS_PER_BLOCK = opts.gpu_threads
    if opts.gpu_min_batch is not None:
        from railride.run import solver

        solver.GPU_MIN_BATCH = opts.gpu_min_batch
    gpu.FILE_CACHE = opts.gpu_file_cache
    steps: list = []  # (start, end) of every batch's stepping (on the GPU: its call), any thread
    chunks: list = []  # (start, end) of every chunk's whole work (`evaluate`), any thread
    stages: list = []  # (name, start, end)
    sample_steps = [0]
    inside: list = []  # the stage running: a stage called within another is counted in the outer one
    lock = threading.Lock()

    def timed(module, name, into, label=None, count=None):
        original = getattr(module, name)

        def wrapper(*a, **kw):
            if label and inside:
                return original(*a, **kw)
            if count is not None and not count(a[0]):
                return original(*a, **kw)
            inside.extend([label] if label else [])
            start = time.perf_counter()
            try:
                return original(*a, **kw)
            finally:
                if label:
                    inside.pop()
                into.append((label, start, time.perf_counter()) if label else (start, time.perf_counter()))
                if count is not None:
                    with lock:
                        sample_steps[0] += a[0].n * a[0].n_steps

        setattr(module, name, wrapper)

    timed(simulation, "step", steps, count=lambda plan: True)
    # metrics-only batches on the GPU: the call (copies, kernels, sums) counts as stepping
    timed(reduced, "batch_metrics", steps, count=lambda plan: simulation.stepped_on(plan) == "gpu")
    # metrics-only batches summed on the CPU's lanes (`reduced._on_lanes`, which passes ``sums``):
    # their stepping, which `simulation.step` does not see
    make_stepper = lanes.lanes_stepper

    def lanes_stepper(*a, **kw):
        step = make_stepper(*a, **kw)

        def stepping(*args):
            if len(args) < 14:  # no sums: `simulation.step`'s call, timed there
                return step(*args)
            start = time.perf_counter()
            try:
                return step(*args)
            finally:
                steps.append((start, time.perf_counter()))
                with lock:
                    sample_steps[0] += args[0] * args[4]  # runs x steps

        return stepping

    lanes.lanes_stepper = lanes_stepper
    timed(sweep, "evaluate", chunks)
    timed(tuning, "_tune_inner", stages, "inner loop (damper rig)")
    timed(tuning, "run_cases", stages, "tuning rounds")
    timed(design_module, "_judge", stages, "held-out runs")
    timed(design_module, "_run_ahead", stages, "probes' runs")
    timed(design_probes, "references", stages, "probes' scores")
    timed(design_probes, "fault_check", stages, "probes' scores")

    class Cut(BaseException):  # not an Exception: the GPU path takes those for its failures
        pass

    def cut(signum, frame):
        raise Cut

    signal.signal(signal.SIGTERM, cut)  # `timeout` (device_check.sh): report what was done by then
    controllers = opts.controllers.split(",") if opts.controllers else None
    cpu0 = time.process_time()
    t0 = time.perf_counter()
    head = f"design {opts.controllers or 'all laws'}, budget {opts.budget}, {opts.duration:g} s runs"
    head += f", backend {opts.backend}" + (f", GPU kernel {opts.gpu_kernel}" if opts.gpu_kernel else "")
    head += f", {opts.gpu_threads} threads a block" if opts.gpu_threads else ""
    head += f", the GPU for batches of {opts.gpu_min_batch} runs or more" if opts.gpu_min_batch is not None else ""
    head += ", GPU kernels in the file cache" if opts.gpu_file_cache else ""
    try:
        res = rr.design(
            controllers,
            budget=opts.budget,
            duration=opts.duration,
            solver=rr.SolverSettings(backend=opts.backend),
            progress=False,
        )
        head += f": {res.settings['training_runs']} training and {res.settings['judging_runs']} held-out runs"
    except Cut:
        head += ": CUT by SIGTERM before its end; what it had done by then"
        was_cut = True
    else:
        was_cut = False
    t1 = time.perf_counter()
    cpu = time.process_time() - cpu0
    wall = t1 - t0
    by: dict = {}
    for label, a, b in stages:
        by.setdefault(label, []).append((a, b))
    in_stages = covered([(a, b) for spans in by.values() for a, b in spans])
    stepping = covered(clipped(steps, [(t0, t1)]))
    busy = covered(clipped(chunks, [(t0, t1)]))
    print(
        f"{head}; wall {wall:.1f} s, CPU {cpu:.1f} s ({cpu / wall:.2f} cores busy), "
        f"numba threads {numba.get_num_threads()}; "
        f"{sample_steps[0]:.3g} sample-steps, {sample_steps[0] / max(stepping, 1e-9):.3g} a second of stepping"
    )
    print("\n| stage | calls | wall | some batch stepping | none stepping | no chunk at all |")
    print("|---|---|---|---|---|---|")
    for label, spans in by.items():
        w = covered(spans)
        st = covered(clipped(steps, spans))
        c = covered(clipped(chunks, spans))
        print(f"| {label} | {len(spans)} | {w:.1f} s | {st:.1f} s | {w - st:.1f} s | {w - c:.1f} s |")
    rest = wall - in_stages
    print(f"| the rest (checks, start, between rounds, summary) | - | {rest:.1f} s | - | {rest:.1f} s | {rest:.1f} s |")
    print(
        f"| **the whole design** | {len(chunks)} chunks | {wall:.1f} s | {stepping:.1f} s | {wall - stepping:.1f} s "
        f"({(wall - stepping) / wall * 100:.1f} %) | {wall - busy:.1f} s ({(wall - busy) / wall * 100:.1f} %) |"
    )
    print(
        "\nnone stepping: no batch was stepping (a chunk's tables, metrics and rows, and all below); "
        "no chunk at all: no chunk was being worked on (the cases, keys and run table of a round, the searches, "
        "the summary), work that more threads do not overlap"
    )
    if was_cut:  # chunks still stepping in their threads would hold the exit
        sys.stdout.flush()
        os._exit(124)


if __name__ == "__main__":
    main()
