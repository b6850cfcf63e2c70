"""Cost of a study over many tracks (railride.studies.study): wall time and peak memory.

Run:  python benchmarks/bench_study.py [--seeds N] [--dask [--workers N] [--worker-threads T] | --ahead N |
                                       --processes N] [--profile] [--held]
Prints a Markdown row for docs/performance.md: one study of 1000 closed-loop and passive runs
of 10 s (--duration) (fra4, N = 20 track seeds x 5 speeds x 2 loads x (passive + 4 controllers)), with its
wall time (compilation excluded: a warm-up study runs first) and peak resident memory. Locally:
this machine's cores, one process. With --dask: a dask.distributed LocalCluster of one worker
process with one Dask thread (its batches use every core, as docs/distributed.md advises),
reached by address like a remote cluster; the memory of the client and of the worker. With
--workers N, N worker processes of one Dask thread each; --worker-threads T sets the numba
threads of each worker (NUMBA_NUM_THREADS in the workers' environment; default: the machine's
cores shared among the workers, as railride's Dask executor shares them). The scaling of N
workers is their rate over that of one worker with the same threads. With --profile (local
only), the serial share: the part of the wall time in which no chunk is in the compiled
stepper (the step stage of `railride.run.simulation`), from the union of the step stage's
intervals in every thread, and the process's user and system CPU time and minor page faults
during the study (the system share is the kernel's work: on a 2-core VM, perf found most of it
zeroing the pages of new arrays). With --held (local only), the threads of numba's pool that
stepping chunks held (`railride.run.cores.CPU_THREADS`), sampled every 2 ms: their mean over the study and
the share of its time at each count (run with NUMBA_NUM_THREADS=16 to see how many chunks step at
once on 16 threads, even on fewer cores). No test asserts timings.
"""

from __future__ import annotations

import argparse
import collections
import resource
import time

from _timing import clipped, covered  # benchmarks/_timing.py: run as a script, this folder is on the path


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--duration", type=float, default=10.0, help="seconds of each run")
    ap.add_argument("--dask", action="store_true")
    ap.add_argument("--workers", type=int, default=1, help="--dask: worker processes")
    ap.add_argument("--worker-threads", type=int, default=None, help="--dask: numba threads of each worker")
    ap.add_argument("--ahead", type=int, default=None, help="local: chunks stepping beside the one whose rows are made")
    ap.add_argument("--profile", action="store_true", help="local: the serial share of the wall time")
    ap.add_argument("--processes", type=int, default=None, help="ProcessExecutor: worker processes of this machine")
    ap.add_argument("--held", action="store_true", help="local: the threads that stepping chunks held")
    args = ap.parse_args()

    from railride.studies.study import study

    from railride.studies.executors import LocalExecutor

    executor, cluster = LocalExecutor(ahead=args.ahead), None  # ahead None: chunks_ahead of the threads
    where = f"local, one process, {executor.ahead} chunk(s) ahead" + (" (default)" if args.ahead is None else "")
    if args.processes is not None:
        from railride.studies.executors import ProcessExecutor

        executor, where = ProcessExecutor(args.processes), f"{args.processes} worker processes (ProcessExecutor)"
    if args.dask:
        import os

        from distributed import LocalCluster

        from railride.studies.executors import DaskExecutor

        if args.worker_threads is not None:  # the workers are child processes: they read it as numba starts
            os.environ["NUMBA_NUM_THREADS"] = str(args.worker_threads)
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        executor = DaskExecutor(address=cluster.scheduler_address)
        threads = "" if args.worker_threads is None else f", {args.worker_threads} numba thread(s) each"
        where = f"Dask LocalCluster, {args.workers} worker process(es){threads}"
    controllers = ["pid", "sas-attitude", "sas-attitude-ride", "clipped-optimal"]
    study(controllers, track_seeds=[0], speeds=[40.0], duration=1.0, executor=executor)  # compile
    seeds = list(range(args.seeds))
    speeds = [30.0, 37.5, 45.0, 52.5, 60.0]
    intervals = _watch_steps() if args.profile and args.processes is None else None
    held = _watch_held() if args.held and args.processes is None and not args.dask else None
    parent = resource.getrusage(resource.RUSAGE_SELF)
    t0 = time.perf_counter()
    res = study(
        controllers,
        track_seeds=seeds,
        speeds=speeds,
        loads=[1.0, 1.3],
        faults=["none"],
        executor=executor,
        duration=args.duration,
    )
    wall = time.perf_counter() - t0
    t1 = t0 + wall
    counts = held() if held is not None else None
    after = resource.getrusage(resource.RUSAGE_SELF)
    parent_cpu = (after.ru_utime - parent.ru_utime) + (after.ru_stime - parent.ru_stime)
    peak_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    memory = f"{peak_mib:.0f} MiB"
    if args.processes is not None:
        executor.close()
    if cluster is not None:
        worker = executor.client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)
        memory = f"client {peak_mib:.0f} MiB, worker {max(worker.values()):.0f} MiB"
        executor.close()
        cluster.close()
    n = len(res.cases)
    print("| study | where | runs | wall time | runs/s | peak memory |")
    print("|---|---|---|---|---|---|")
    print(
        f"| fra4, {args.seeds} seeds x 5 speeds x 2 loads x (passive + 4 controllers), {args.duration:g} s runs "
        f"| {where} | {n} | "
        f"{wall:.1f} s | {n / wall:.1f} | {memory} |"
    )
    if intervals is not None:
        stepping = covered(clipped(intervals, [(t0, t1)]))
        print(
            f"\nthreads {_threads()}: the stepper ran {stepping:.1f} s of the {wall:.1f} s; no chunk was stepping for "
            f"{wall - stepping:.1f} s, the serial share: {(wall - stepping) / wall * 100:.1f} %"
        )
        inside = [(a, b) for a, b in intervals if b > t0 and a < t1]
        if inside:
            head = min(a for a, _ in inside) - t0
            tail = t1 - max(b for _, b in inside)
            print(
                f"of which {head:.2f} s before the first chunk stepped, {tail:.2f} s after the last one, and "
                f"{wall - stepping - head - tail:.2f} s between ({len(inside)} step calls)"
            )

    if args.profile and args.processes is None and not args.dask:
        user, system = after.ru_utime - parent.ru_utime, after.ru_stime - parent.ru_stime
        print(
            f"\nthe process during the study: CPU {user:.1f} s user and {system:.1f} s system "
            f"({system / max(user + system, 1e-9) * 100:.1f} % system), "
            f"{after.ru_minflt - parent.ru_minflt} minor page faults"
        )

    if counts:
        by_count = sorted(collections.Counter(counts).items())
        shares = ", ".join(f"{k}: {100 * v / len(counts):.0f} %" for k, v in by_count)
        print(
            f"\nthreads {_threads()}: stepping chunks held {sum(counts) / len(counts):.1f} threads on average; "
            f"the time at each count held: {shares}"
        )
    if args.profile and args.processes is not None:
        print(
            f"\nthe parent process's CPU time during the study: {parent_cpu:.2f} s of the {wall:.1f} s wall time, "
            f"the serial share: {parent_cpu / wall * 100:.1f} %"
        )


def _watch_held():
    """Sample `railride.run.cores.CPU_THREADS.used` every 2 ms in a thread; the function returned
    stops it and gives the samples."""
    import threading

    from railride.run.cores import CPU_THREADS

    samples: list = []
    stop = threading.Event()

    def watch():
        while not stop.is_set():
            samples.append(CPU_THREADS.used)
            time.sleep(0.002)

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()

    def done() -> list:
        stop.set()
        watcher.join()
        return samples

    return done


def _threads() -> int:
    import numba

    return numba.get_num_threads()


def _watch_steps() -> list:
    """Record the (start, end) of every call of the simulation's step stage, in any thread."""
    from railride.run import simulation

    intervals: list = []
    step = simulation.step

    def timed(*args, **kwargs):
        start = time.perf_counter()
        try:
            return step(*args, **kwargs)
        finally:
            intervals.append((start, time.perf_counter()))

    simulation.step = timed
    return intervals


if __name__ == "__main__":
    main()
