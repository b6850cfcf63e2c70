"""The GPU stepper (railride.engine.gpu): throughput, memory and agreement with the CPU.

Run:  python benchmarks/bench_gpu.py [--samples 32768] [--duration 1] [--law sas-attitude-ride]
                                     [--output-rate 200] [--check 64] [--cpu] [--design]
Needs a CUDA GPU and the gpu extra (pip install 'railride[gpu]'); NUMBA_ENABLE_CUDASIM=1 runs it
in numba's CUDA simulator with tiny sizes (a smoke test of the script, no figure).

Prints Markdown rows for docs/gpu.md, each with the device, the machine's cores and the date:
* a batch of ``--samples`` closed loops of ``--law`` (MR dampers, Bouc-Wen n = 1, the law's
  voltage law) on fra4 (8 track seeds x 8 speeds 30-70 m/s, shared tables), ``--duration`` s at
  dt = 1e-4 s, stepped once to compile and once timed: sample-steps per second of the kernels
  alone and of the whole `simulate` call (transfers, tables and results included), peak device
  memory, host peak memory;
* with ``--check N``, the largest difference of the first N samples from the CPU stepper, over
  each history's largest value (the issue's bound: 1e-9 for laws without switching);
* with ``--cpu``, the same batch on this machine's CPU cores, for the GPU's factor over them;
* with ``--metrics-only``, the same batch as the studies run it when they keep only the metrics
  (`railride.run.reduced.batch_metrics`: sums on the device, no histories), and its largest
  difference from the metrics of the histories above; with ``--only-metrics``, that batch alone,
  with no batch of histories first (1e5 runs of 60 s in one GPU's memory: ``--samples 100000
  --duration 60 --only-metrics``), its device and host peaks and how many runs ended with every
  metric finite;
* with ``--design``, `railride design --backend gpu` with its defaults (wall time, runs);
* with ``--host-only`` (in the simulator: NUMBA_ENABLE_CUDASIM=1; ``--controllers`` to pick laws),
  the default design with its GPU kernel replaced by a stand-in that returns at once: the host's
  share of the design, which no GPU takes away (wall time, runs, host peak), and the kinds of
  batch it sends the GPU (kernel keys, each a compile on a device), for ``bench_gpu_kernel.py
  --resources --keys``;
* with ``--host-batch`` (in the simulator), the ``--samples``-run metrics-only batch above with
  its kernel a stand-in: the host's share of one such call (checking the runs, then
  `batch_metrics`: tables, packing, the simulator's copies in place of transfers), best of 3;
* with ``--memory-plan`` (no GPU needed: the simulator does), the bytes a metrics-only run of 60 s
  takes on the device, from the sizes of the arrays a 64-run batch packs (computed, not measured):
  a run's own arrays, and the tables each distinct track and vehicle adds.
No test asserts timings.
"""

from __future__ import annotations

import argparse
import datetime
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _batch(n: int, duration: float, law: str):
    from railride.model.track import scenario
    from railride.secondary.suspension import Suspension

    tracks = [
        scenario("fra4", seed=seed, speed=float(v), duration=duration)
        for seed in range(8)
        for v in np.linspace(30.0, 70.0, 8)
    ]
    return [tracks[i % len(tracks)] for i in range(n)], Suspension.named(law)


def _worst(a, b) -> float:
    worst = 0.0
    for k in b.dataset.data_vars:
        x, y = a.dataset[k].values, b.dataset[k].values
        if y.dtype.kind != "f":
            continue
        scale = np.nanmax(np.abs(y)) if np.any(np.isfinite(y)) else 0.0
        if scale > 0.0:
            worst = max(worst, float(np.nanmax(np.abs(x - y))) / scale)
    return worst


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=32768)
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--law", default="sas-attitude-ride")
    ap.add_argument("--output-rate", type=float, default=200.0)
    ap.add_argument("--check", type=int, default=64)
    ap.add_argument("--cpu", action="store_true")
    ap.add_argument("--design", action="store_true")
    ap.add_argument("--metrics-only", action="store_true")
    ap.add_argument("--only-metrics", action="store_true", help="the metrics-only batch alone, no histories")
    ap.add_argument("--memory-plan", action="store_true")
    ap.add_argument("--host-only", action="store_true")
    ap.add_argument("--host-batch", action="store_true")
    ap.add_argument("--controllers", default=None, help="--host-only: the design's laws (comma-separated; default all)")
    args = ap.parse_args()
    if args.memory_plan:
        _memory_plan()
        return
    if args.host_only:
        _host_only(args.controllers)
        return
    if args.host_batch:
        _host_batch(args.samples, args.duration, args.law, args.output_rate)
        return

    import numba

    from railride.engine import gpu
    from railride.run.simulation import simulate
    from railride.run.solver import SolverSettings

    missing = gpu.why_not()
    if missing is not None:
        sys.exit(f"bench_gpu: {missing}")
    device = gpu.device_name()
    where = f"{device}; {os.cpu_count()} CPU cores; {datetime.date.today().isoformat()}"
    on_gpu = SolverSettings(output_rate=args.output_rate, backend="gpu")
    scs, susp = _batch(min(args.samples, 256), args.duration if args.duration < 0.1 else 0.1, args.law)
    t0 = time.perf_counter()
    simulate(scs, suspension=susp, solver=on_gpu)  # compiles the kernel (and the CPU's, for the tables)
    print(f"The first call, which compiles the kernel: {time.perf_counter() - t0:.1f} s")

    scs, susp = _batch(args.samples, args.duration, args.law)
    work = args.samples * round(args.duration / on_gpu.dt)
    if args.only_metrics:
        _only_metrics(scs, susp, on_gpu, work, where, args)
        return
    t0 = time.perf_counter()
    result = simulate(scs, suspension=susp, solver=on_gpu)
    wall = time.perf_counter() - t0
    call = gpu.last_call()
    host = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2
    print(f"Device: {where}; {result.dataset.attrs['integrator']}")
    print()
    columns = ("batch", "kernels", "sample-steps/s (kernels)", "whole call", "sample-steps/s (call)", "groups")
    print("| " + " | ".join(columns + ("device memory", "host peak")) + " |")
    print("|---|---|---|---|---|---|---|---|")
    print(
        f"| {args.samples} x {args.law}, fra4, {args.duration:g} s at dt 1e-4 s, output {args.output_rate:g} Hz "
        f"| {call['kernel_s']:.2f} s | {work / max(call['kernel_s'], 1e-9):.3g} | {wall:.2f} s | {work / wall:.3g} "
        f"| {call['groups']} | {call['device_bytes'] / 1024**3:.2f} GiB | {host:.2f} GiB |"
    )
    if args.check:
        k = min(args.check, args.samples)
        cpu = simulate(scs[:k], suspension=susp, solver=SolverSettings(output_rate=args.output_rate, backend="cpu"))
        gpu_part = simulate(scs[:k], suspension=susp, solver=on_gpu)
        print(f"\nFirst {k} samples against the CPU stepper: largest difference / history's largest value = "
              f"{_worst(gpu_part, cpu):.2e}")  # fmt: skip
    if args.metrics_only:
        from railride.run.checks import check
        from railride.run.reduced import batch_metrics

        t0 = time.perf_counter()
        sums, _ = batch_metrics(check(scs, None, susp, on_gpu, "mark", histories=False))
        reduced = time.perf_counter() - t0
        call = gpu.last_call()
        full = result.metrics().values
        diff = float(np.nanmax(np.abs(sums - full) / np.nanmax(np.abs(full), axis=0)))
        print(f"\nMetrics only (sums on the device): kernels {call['kernel_s']:.2f} s, whole call {reduced:.2f} s, "
              f"{work / reduced:.3g} sample-steps/s, device memory {call['device_bytes'] / 1024**3:.2f} GiB; "
              f"largest difference from the histories' metrics / largest metric: {diff:.2e}")  # fmt: skip
    if args.cpu:
        on_cpu = SolverSettings(output_rate=args.output_rate, backend="cpu")
        simulate(scs[:16], suspension=susp, solver=on_cpu)  # compiles the CPU steppers
        t0 = time.perf_counter()
        simulate(scs, suspension=susp, solver=on_cpu)
        cpu_wall = time.perf_counter() - t0
        print(f"\nThe same batch on the CPU ({numba.get_num_threads()} threads): {cpu_wall:.2f} s, "
              f"{work / cpu_wall:.3g} sample-steps/s; GPU call / CPU call: {cpu_wall / wall:.1f}x")  # fmt: skip
    if args.design:
        out = Path(tempfile.mkdtemp(prefix="railride-design-gpu-")) / "d"
        t0 = time.perf_counter()
        cmd = [sys.executable, "-m", "railride.cli", "design", "--backend", "gpu", "--out", str(out)]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        print(f"\nrailride design --backend gpu (defaults): {(time.perf_counter() - t0) / 60:.1f} min ({where})")


def _only_metrics(scs, susp, on_gpu, work, where, args):
    """The batch as a study that keeps only the metrics runs it (`batch_metrics`: sums on the
    device, no histories on either side), with no batch of histories before it: the size a GPU's
    memory holds, measured (1e5 runs of 60 s: ``--samples 100000 --duration 60``)."""
    from railride.engine import gpu
    from railride.run.checks import check
    from railride.run.reduced import batch_metrics

    t0 = time.perf_counter()
    sums, _ = batch_metrics(check(scs, None, susp, on_gpu, "mark", histories=False))
    wall = time.perf_counter() - t0
    call = gpu.last_call()
    host = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2
    finite = int(np.isfinite(sums.reshape(len(sums), -1)).all(axis=1).sum())
    print(f"Device: {where}; metrics only, no histories")
    print()
    print("| batch | kernels | sample-steps/s (kernels) | whole call | sample-steps/s (call) | groups | device memory "
          "| host peak | runs with every metric finite |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|---|")
    print(
        f"| {args.samples} x {args.law}, fra4, {args.duration:g} s at dt 1e-4 s "
        f"| {call['kernel_s']:.2f} s | {work / max(call['kernel_s'], 1e-9):.3g} | {wall:.2f} s | {work / wall:.3g} "
        f"| {call['groups']} | {call['device_bytes'] / 1024**3:.2f} GiB | {host:.2f} GiB | {finite} of {len(sums)} |"
    )


def _memory_plan():
    """The device bytes of metrics-only runs of 60 s (`railride.run.reduced`), from the arrays a
    64-run batch of SAS (attitude) loops on fra4 at 30 and 70 m/s packs: computed, not measured."""
    from railride.engine import gpu, sample_parts
    from railride.model.track import scenario
    from railride.run.checks import check
    from railride.run.simulation import inputs, pack, stepper_arguments
    from railride.run.solver import SolverSettings
    from railride.secondary.suspension import Suspension

    if gpu.why_not() is not None:
        sys.exit(f"bench_gpu: {gpu.why_not()} (NUMBA_ENABLE_CUDASIM=1 is enough for --memory-plan)")
    n, duration = 64, 60.0
    speeds = (30.0, 70.0)
    scs = [scenario("fra4", seed=1, speed=v, duration=duration) for v in speeds] * (n // 2)
    loops = [Suspension.named("sas-attitude")] * n
    plan = check(scs, None, loops, SolverSettings(backend="gpu"), "mark", histories=False)
    tables = inputs(plan)
    packed = pack(plan, tables, rows=2)
    vehicle, dampers, rails, control, outputs = stepper_arguments(plan, tables, packed)
    own = [packed.x, vehicle[2], vehicle[3], dampers[0], dampers[1], *control[2:5], control[6], control[7]]
    per_run = sum(a[0].nbytes for a in own) + sum(h[0].nbytes for h in outputs[:9]) + (sample_parts.N_ACC + 5) * 8
    rows = {float(v): int(k) for v, k in zip(speeds, rails[4][:2])}  # nodes of each speed's table
    per_track = {v: k * (rails[0].shape[1] + rails[2].shape[1]) * 8 for v, k in rows.items()}
    full = 8 * (plan.n_out + 1) * sum(h.shape[2] for h in outputs[:9] if h.shape[1] > 1)
    print(f"Metrics-only runs of {duration:g} s, SAS (attitude), fra4, dt 1e-4 s (computed from the arrays' sizes):")
    print(f"- a run's own arrays on the device: {per_run} bytes; 1e5 runs: {per_run * 1e5 / 2**30:.2f} GiB")
    for v, b in per_track.items():
        print(f"- one distinct track and vehicle at {v:g} m/s: {b / 2**20:.1f} MiB of input and forcing tables")
    print(f"- one such run's histories at 1 kHz: {full / 2**20:.1f} MiB; 1e5 runs: {full * 1e5 / 2**40:.1f} TiB")


def _host_only(controllers) -> None:
    """The default design with ``backend="gpu"`` in numba's CUDA simulator, its kernel replaced by
    a stand-in that returns at once (`_StandIn`): the wall time of everything but the GPU's
    stepping, which no GPU takes away (cases, scenarios, tables, packing, the CPU's damper rig,
    comfort, rows, the design's own work): the wall time less the time in the GPU calls
    (`railride.engine.gpu.run_gpu`: the simulator's copies of the arrays a GPU would be sent and
    send back, its device arrays in host memory, and the stand-in), which a real device's
    transfers and kernels replace (not measured here; the simulator's device arrays also count
    in the host peak). Its metrics are arbitrary, so its tuning takes other paths than a real
    design's and may make another number of runs: both are printed, and the kinds of batch
    (kernel keys) it sent the GPU, each a compile on a device, with their calls."""
    from railride.engine import gpu
    from railride.run.solver import SolverSettings
    from railride.studies.design import design

    if not gpu.simulated():
        sys.exit("bench_gpu: --host-only runs in the simulator: set NUMBA_ENABLE_CUDASIM=1")
    kinds: dict = {}  # kernel key (`gpu.kernel_key`) -> GPU calls

    def stand_in(key):
        kinds[key] = kinds.get(key, 0) + 1
        return _StandIn()

    gpu._device_functions = stand_in
    inside = [0.0]  # in the GPU calls: the simulator's copies and device arrays, the stand-in
    run_gpu = gpu.run_gpu

    def counted(*args, **kw):
        t = time.perf_counter()
        try:
            return run_gpu(*args, **kw)
        finally:
            inside[0] += time.perf_counter() - t

    gpu.run_gpu = counted
    laws = None if controllers is None else controllers.split(",")
    t0 = time.perf_counter()
    cpu0 = time.process_time()
    result = design(laws, solver=SolverSettings(backend="gpu"), progress=False)
    wall, cpu = time.perf_counter() - t0, time.process_time() - cpu0
    s = result.settings
    runs = s["training_runs"] + s["judging_runs"]
    host = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024**2
    print(f"{os.cpu_count()} CPU cores; {datetime.date.today().isoformat()}")
    host_s = wall - inside[0]
    print("\n| design (defaults, backend gpu), the kernel a stand-in | runs | wall time | in the GPU calls "
          "| the host's work | per run | CPU time | host peak |")  # fmt: skip
    print("|---|---|---|---|---|---|---|---|")
    print(f"| {'all laws' if laws is None else ', '.join(laws)} | {runs:,} ({s['training_runs']:,} training, "
          f"{s['judging_runs']:,} held out) | {wall:.1f} s | {inside[0]:.1f} s | **{host_s:.1f} s** "
          f"| {host_s / runs * 1e3:.2f} ms | {cpu:.1f} s | {host:.2f} GiB |")  # fmt: skip
    print("\nkinds of batch (kernel keys: law, faults, sensing, lean, unit_n, pattern) and their GPU calls:")
    for key, calls in kinds.items():
        print(f"  {key}: {calls}")
    print(f'for bench_gpu_kernel.py --resources --keys: "{list(kinds)}"')


def _host_batch(samples: int, duration: float, law: str, output_rate: float):
    """The host's share of a metrics-only batch (``--host-batch``): `check` and `batch_metrics`
    of ``samples`` runs with the kernel a stand-in, in the simulator, best of 3."""
    from railride.engine import gpu
    from railride.run.checks import check
    from railride.run.reduced import batch_metrics
    from railride.run.solver import SolverSettings

    if not gpu.simulated():
        sys.exit("bench_gpu: --host-batch runs in the simulator: set NUMBA_ENABLE_CUDASIM=1")
    gpu._device_functions = lambda *key: _StandIn()
    on_gpu = SolverSettings(output_rate=output_rate, backend="gpu")
    scs, susp = _batch(min(samples, 256), duration, law)
    batch_metrics(check(scs, None, susp, on_gpu, "mark", histories=False))  # compiles the tables' parts
    scs, susp = _batch(samples, duration, law)
    best = (np.inf, np.inf)
    for _ in range(3):
        t0 = time.perf_counter()
        plan = check(scs, None, susp, on_gpu, "mark", histories=False)
        t1 = time.perf_counter()
        batch_metrics(plan)
        best = min(best, (t1 - t0, time.perf_counter() - t1), key=sum)
    print(f"{os.cpu_count()} CPU cores; {datetime.date.today().isoformat()}")
    print(f"\n{samples} x {law}, fra4 (64 tracks and speeds), {duration:g} s, metrics only, the kernel a "
          f"stand-in: check {best[0]:.2f} s, batch_metrics {best[1]:.2f} s, "
          f"the host's share {sum(best):.2f} s")  # fmt: skip


class _StandIn:
    """In place of the GPU kernel (`--host-only`): a launch returns at once. Sums of metrics get
    one row of random values between 0.5 and 1.5 a run, and histories a slow sine, so that the
    study's arithmetic goes on; the states and status stay as they were (every run finishes)."""

    def __init__(self):
        self.rng = np.random.default_rng(0)

    def __getitem__(self, launch):
        return self._launch

    def _launch(self, m, *args):
        from railride.engine.sample_parts import ACC_MAX, ACC_MIN, ACC_ROWS, ACC_SQUARES

        outs, reduce, acc = args[-14:-5], args[-3], args[-1]
        if reduce:
            v = self.rng.uniform(0.5, 1.5, (m, 4))
            acc[:, ACC_SQUARES : ACC_SQUARES + 4] = v * v
            acc[:, ACC_MIN : ACC_MIN + 4] = -v
            acc[:, ACC_MAX : ACC_MAX + 4] = v
            acc[:, ACC_ROWS] = 1.0
        else:  # a slow sine of 1e-3 in every channel: cheap, and something for comfort to weigh
            for out in outs:
                out[:] = 1e-3 * np.sin(0.01 * np.arange(out.shape[1]))[None, :, None]


if __name__ == "__main__":
    main()
