"""How much of a study chunk's work beside its stepping can run in parallel with another chunk's.

Run:  python benchmarks/bench_gil.py [--threads 2] [--repeat 5] [--duration 10]
N chunks like those of bench_study.py's 1,000-run study (32 SAS (attitude+ride) runs each on
fra4, four seeds x eight speeds 30-82.5 m/s, --duration s, histories at 1 kHz; each chunk on
seeds of its own) are stepped once. Then each stage of what a chunk does beside the stepping runs
on them: the random tracks (their realisations, the track store emptied first), the input and
forcing tables (the table stores emptied first, then kept), check, pack and assemble, the ride
metrics, the comfort indices, the rows, and the whole chunk as a study evaluates it
(`railride.studies.sweep.evaluate` with comfort) with its step stage a stand-in that hands back
the outputs of its real stepping, with its tracks and tables built afresh and kept.

Each stage runs for N = --threads chunks (default 2) one after another in one thread (t1),
then for one chunk in each of N threads started together (tN), best of --repeat, with numba
on one thread (NUMBA_NUM_THREADS=1, set here unless given), so that no stage spreads over the
cores by itself. On N free cores a stage that runs in parallel throughout takes tN = t1 / N,
one that cannot tN = t1; the share s that runs one at a time, from tN = t1 (s + (1 - s) / N),
is printed (clipped to 0..1): the GIL, and whatever else the threads queue for (memory
bandwidth, the page faults of new arrays). That share of a chunk cannot overlap other chunks,
which is what bounds a study in threads on many cores (docs/performance.md). Needs N free
cores; no test asserts timings.
"""

from __future__ import annotations

import argparse
import datetime
import os
import threading
import time


def _chunk(duration: float, seed0: int):
    from railride.studies.case import Case

    return [
        Case("fra4", (("duration", duration), ("seed", seed0 + s), ("speed", v)), suspension="sas-attitude-ride")
        for s in range(4)
        for v in (30.0, 37.5, 45.0, 52.5, 60.0, 67.5, 75.0, 82.5)
    ]


def _stages(duration: float, n: int) -> dict:
    """name -> (empty the stores, work(k)): the stage's work once on chunk k < n (chunks on
    other tracks, so that threads never share a track or table in a store)."""
    from railride.analysis.comfort import ride_comfort
    from railride.model import irregularity
    from railride.run import inputs as run_inputs
    from railride.run.checks import check
    from railride.run.simulation import assemble, inputs, pack, simulate
    from railride.studies.case import Case, scenario_of
    from railride.run import simulation
    from railride.studies.sweep import _add_rows, evaluate

    chunks = [_chunk(duration, 100 * k) for k in range(n)]
    stepped: list = []  # each chunk's step stage, for the stand-in of the last stage
    real_step = simulation.step
    simulation.step = lambda *a, **k: stepped.append(real_step(*a, **k)) or stepped[-1]
    scs = [[scenario_of(c.scenario, c.scenario_options) for c in cases] for cases in chunks]
    suspensions = [Case.suspensions(cases) for cases in chunks]
    results = [simulate(s, suspension=p, on_divergence="mark") for s, p in zip(scs, suspensions)]
    plans = [check(s, None, p, None, "mark") for s, p in zip(scs, suspensions)]
    simulation.step = real_step
    channels = [r.comfort_channels() for r in results]
    which = threading.local()

    def stand_in(*args, **kwargs):  # the chunk's stepping, done: its outputs as they came
        return stepped[which.k]

    def whole(k):
        which.k = k
        simulation.step = stand_in
        evaluate(chunks[k], comfort=True)

    m = [r.metrics().values for r in results]

    def empty():
        irregularity._TRACKS.clear()
        run_inputs._INPUT_TABLES.clear()
        run_inputs._FORCING_TABLES.clear()

    def plumbing():
        plan = check(scs[0], None, suspensions[0], None, "mark")
        pack(plan, inputs(plan))
        assemble(plan, stepped[0])

    def tracks(k):
        for c in chunks[k]:
            scenario_of(c.scenario, c.scenario_options)

    return {
        "random tracks": (empty, tracks),
        "input and forcing tables": (empty, lambda k: inputs(plans[k])),
        "input and forcing tables, kept (every thread on one chunk)": (
            lambda: None,
            lambda k: inputs(plans[0]),
        ),
        "check, pack and assemble, tables kept (likewise)": (lambda: None, lambda k: plumbing()),
        "ride metrics": (empty, lambda k: results[k].metrics()),
        "comfort indices": (empty, lambda k: ride_comfort(channels[k])),
        "rows": (empty, lambda k: _add_rows({}, chunks[k], list(range(32)), m[k], results[k].diverged_at)),
        "the whole chunk (`evaluate` with comfort), its stepping a stand-in": (empty, whole),
        # every thread on one chunk: its tables fit the stores (two chunks' 64 would not)
        "the same, its tracks and tables kept from before, as a study's other chunks find them": (
            lambda: None,
            lambda k: whole(0),
        ),
    }


def _one_thread(empty, work, n: int) -> float:
    empty()
    t0 = time.perf_counter()
    for k in range(n):
        work(k)
    return time.perf_counter() - t0


def _threads(empty, work, n: int) -> float:
    empty()
    go = threading.Barrier(n + 1)

    def run(k):
        go.wait()
        work(k)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(n)]
    for t in threads:
        t.start()
    go.wait()
    t0 = time.perf_counter()
    for t in threads:
        t.join()
    return time.perf_counter() - t0


def main():
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # before numba starts: a stage on one core
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--threads", type=int, default=2, help="chunks at once, one a thread (N)")
    args = ap.parse_args()
    n = max(2, args.threads)
    stages = _stages(args.duration, n)
    threads = os.environ["NUMBA_NUM_THREADS"]
    print(f"{os.cpu_count()} CPU cores, numba threads {threads}; {datetime.date.today().isoformat()}")
    print(
        f"\n| stage | one chunk's work (t1 / {n}) | {n} chunks in one thread (t1) | one in each of {n} threads (tN) "
        "| speed-up t1 / tN | share not in parallel |"
    )  # fmt: skip
    print("|---|---|---|---|---|---|")
    for name, (empty, work) in stages.items():
        _one_thread(empty, work, n)  # warm: compiled parts, imports
        t1 = min(_one_thread(empty, work, n) for _ in range(args.repeat))
        tn = min(_threads(empty, work, n) for _ in range(args.repeat))
        # t_N = t1 (s + (1 - s) / N) for a share s that runs one at a time
        serial = min(1.0, max(0.0, (n * tn / t1 - 1.0) / (n - 1)))
        print(
            f"| {name} | {t1 / n * 1e3:.1f} ms | {t1 * 1e3:.1f} ms | {tn * 1e3:.1f} ms | {t1 / tn:.2f} "
            f"| {serial * 100:.0f} % |"
        )
    print(
        "\nThe tracks and tables are each chunk's own where the stores are emptied; in a study a "
        "scenario's are built once and shared by its laws' and loads' chunks."
    )


if __name__ == "__main__":
    main()
