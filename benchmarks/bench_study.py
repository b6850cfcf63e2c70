"""Cost of a study over many tracks (railride.studies.study): wall time and peak memory.

Run:  python benchmarks/bench_study.py [--seeds N] [--dask | --ahead N]
Prints a Markdown row for docs/performance.md: one study of 1000 closed-loop and passive runs
of 10 s (fra4, N = 20 track seeds x 5 speeds x 2 loads x (passive + 4 controllers)), with its
wall time (compilation excluded: a warm-up study runs first) and peak resident memory. Locally:
this machine's cores, one process. With --dask: a dask.distributed LocalCluster of one worker
process with one Dask thread (its batches use every core, as docs/distributed.md advises),
reached by address like a remote cluster; the memory of the client and of the worker. No test
asserts timings.
"""

from __future__ import annotations

import argparse
import resource
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--dask", action="store_true")
    ap.add_argument("--ahead", type=int, default=None, help="local: chunks stepping beside the one whose rows are made")
    args = ap.parse_args()

    from railride.studies.study import study

    executor, cluster, where = None, None, "local, one process"
    if args.ahead is not None:
        from railride.studies.executors import LocalExecutor

        executor, where = LocalExecutor(ahead=args.ahead), f"local, one process, {args.ahead} chunk(s) ahead"
    if args.dask:
        from distributed import LocalCluster

        from railride.studies.executors import DaskExecutor

        cluster = LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None)
        executor = DaskExecutor(address=cluster.scheduler_address)
        where = "Dask LocalCluster, 1 worker process"
    controllers = ["pid", "sas-attitude", "sas-attitude-ride", "clipped-optimal"]
    study(controllers, track_seeds=[0], speeds=[40.0], duration=1.0, executor=executor)  # compile
    seeds = list(range(args.seeds))
    speeds = [30.0, 37.5, 45.0, 52.5, 60.0]
    t0 = time.perf_counter()
    res = study(controllers, track_seeds=seeds, speeds=speeds, loads=[1.0, 1.3], faults=["none"], executor=executor)
    wall = time.perf_counter() - t0
    peak_mib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    memory = f"{peak_mib:.0f} MiB"
    if cluster is not None:
        worker = executor.client.run(lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)
        memory = f"client {peak_mib:.0f} MiB, worker {max(worker.values()):.0f} MiB"
        executor.close()
        cluster.close()
    n = len(res.cases)
    print("| study | where | runs | wall time | runs/s | peak memory |")
    print("|---|---|---|---|---|---|")
    print(
        f"| fra4, {args.seeds} seeds x 5 speeds x 2 loads x (passive + 4 controllers), 10 s runs | {where} | {n} | "
        f"{wall:.1f} s | {n / wall:.1f} | {memory} |"
    )


if __name__ == "__main__":
    main()
