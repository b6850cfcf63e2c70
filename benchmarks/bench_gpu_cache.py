"""Whether numba-cuda's file cache would keep the GPU kernel between processes, and what it saves.

Run:  python benchmarks/bench_gpu_cache.py        (on a machine with a CUDA GPU and the gpu extra)

Every process that steps on the GPU compiles the kernel (`railride.engine.gpu`, compiled on
first use without a cache). This script tries the kernel with ``cuda.jit(cache=True)`` (`gpu.FILE_CACHE`) in two
fresh processes that share an empty ``NUMBA_CACHE_DIR``: the first compiles and writes the
cache, the second should load it (a process before them fills the cache with the CPU's kernels,
which the GPU path also calls to build its tables). Each prints the time of its first call (a batch of 64 SAS
closed loops of 0.1 s) and of a second call, the warnings numba gave, and the largest
difference of the batch from the CPU stepper's (over each history's largest value). The
package itself is not changed: the figures say whether the cache should be switched on. In the
simulator (NUMBA_ENABLE_CUDASIM=1) there is nothing to compile and the script says so.
No test asserts timings.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

CHILD = r"""
import sys, time, warnings
sys.path.insert(0, "benchmarks")
from bench_gpu import _batch, _worst
from railride.engine import gpu
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings

warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as caught:
    gpu._array_overloads()
    gpu.FILE_CACHE = True
    scs, susp = _batch(64, 0.1, "sas-attitude-ride")
    on_gpu, on_cpu = SolverSettings(backend="gpu"), SolverSettings(backend="cpu")
    t0 = time.perf_counter()
    first = simulate(scs, suspension=susp, solver=on_gpu)
    t1 = time.perf_counter()
    simulate(scs, suspension=susp, solver=on_gpu)
    t2 = time.perf_counter()
worst = _worst(first, simulate(scs, suspension=susp, solver=on_cpu))
names = sorted({f"{type(w.message).__name__}: {str(w.message)[:160]}" for w in caught})
print(f"first call {t1 - t0:.1f} s, second {t2 - t1:.2f} s; against the CPU {worst:.2e}")
print("warnings: " + ("; ".join(names) if names else "none"))
"""


WARM_UP = r"""
import sys
sys.path.insert(0, "benchmarks")
from bench_gpu import _batch
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
scs, susp = _batch(64, 0.1, "sas-attitude-ride")
simulate(scs, suspension=susp, solver=SolverSettings(backend="cpu"))
print("the CPU's kernels compiled into the cache")
"""


def main():
    if any(a in ("-h", "--help") for a in sys.argv[1:]):  # it takes no options
        print(__doc__)
        return
    if os.environ.get("NUMBA_ENABLE_CUDASIM") == "1":
        print("bench_gpu_cache: the simulator compiles nothing; run it on a GPU")
        return
    from railride.engine import gpu

    missing = gpu.why_not()
    if missing is not None:
        sys.exit(f"bench_gpu_cache: {missing}")
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    with tempfile.TemporaryDirectory(prefix="railride-cuda-cache-") as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache, "PYTHONPATH": root}
        runs = (
            ("first, the CPU's kernels alone (the tables' parts too), so that they count in neither run", WARM_UP),
            ("a fresh process, the GPU kernel not in the cache", CHILD),
            ("a second process, the GPU kernel in the cache", CHILD),
        )
        for label, code in runs:
            done = subprocess.run([sys.executable, "-c", code], cwd=root, env=env, capture_output=True, text=True)
            print(f"{label}:")
            print("  " + (done.stdout.strip() or done.stderr.strip()[-1500:]).replace("\n", "\n  "))
        files = sum(len(f) for _, _, f in os.walk(cache))
        print(f"files in the cache: {files}")


if __name__ == "__main__":
    main()
