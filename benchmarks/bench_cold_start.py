"""Cold and warm start of `railride compare`.

First the README's quick start in a fresh virtual environment: ``pip install .`` of this source
tree (whose build compiles the engine into the package, setup.py), then the first and second
`railride compare`; and the same with RAILRIDE_NO_PRECOMPILE=1 (the build skips the engine, so
the first run compiles it). Then, with the installed railride: a fresh process with an empty
numba cache, the same cache again, the import alone, and the compile time of each kernel the
comparison builds (timed on numba's compile events, in one cold process).

Run:  python benchmarks/bench_cold_start.py [--repeat N] [--no-install]
Target: first `railride compare` after install <= 5 s. Prints Markdown tables for
docs/performance.md ("Cold start"). CPU time is less disturbed than wall time by other work on
a shared machine; each row keeps the shortest of N repeats (the installs run once).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
from pathlib import Path
import subprocess
import sys
import tempfile
import time

#: compare in one cold process, reporting numba's compile time of each kernel it compiled
KERNEL_TIMES = """
import json, time
from numba.core import event
t0 = time.perf_counter()
import railride
t_import = time.perf_counter() - t0
times, started = {}, {}

class Timer(event.Listener):  # global: the stepper compiles on a worker thread
    def on_start(self, ev):
        started[ev.data["dispatcher"]] = time.perf_counter()

    def on_end(self, ev):
        d = ev.data["dispatcher"]
        if d.py_func.__module__ == "railride.engine.kernels" and d.py_func.__name__ in ("run_batch", "exact_run"):
            times[d.py_func.__name__] = time.perf_counter() - started[d]

event.register("numba:compile", Timer())
railride.compare(railride.scenario("paper-sine"))
print(json.dumps({"import": t_import, "compile": times}))
"""


def _run(cmd, cache: str | None, env: dict | None = None) -> tuple[float, float, str]:
    """(wall, CPU of the child [s], its stderr) of ``cmd`` with numba's cache in ``cache`` (None:
    numba's own choice, next to the package)."""
    env = dict(os.environ if env is None else env)
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = cache
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, out.stderr + out.stdout


def _fresh_install(precompile: bool) -> None:
    """The README's first command in a new virtual environment, timed by step."""
    source = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    venv = tempfile.mkdtemp(prefix="railride-venv-")
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "RAILRIDE_NO_PRECOMPILE")}
    if not precompile:
        env["RAILRIDE_NO_PRECOMPILE"] = "1"
    try:
        subprocess.run([sys.executable, "-m", "venv", venv], check=True)
        py, rr = os.path.join(venv, "bin", "python"), os.path.join(venv, "bin", "railride")
        label = "engine compiled by the build" if precompile else "RAILRIDE_NO_PRECOMPILE=1"
        wall, cpu, log = _run([py, "-m", "pip", "install", "-v", source], None, env)
        said = [line.strip() for line in log.splitlines() if line.strip().startswith("railride:")]  # setup.py's line
        rows = [("`pip install .`" + (f" ({said[0]})" if said else ""), (wall, cpu))]
        for what in ("first `railride compare`", "second `railride compare`"):
            wall, cpu, err = _run([rr, "compare"], None, env)
            notes = [line for line in err.splitlines() if line.startswith("compiling")]
            rows.append((what + (f" (stderr: {notes[0]})" if notes else ""), (wall, cpu)))
        for what, (wall, cpu) in rows:
            print(f"| {label} | {what} | {wall:.1f} s | {cpu:.1f} s |")
    finally:
        shutil.rmtree(venv, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2, help="repeats of each measurement (the best is kept)")
    parser.add_argument("--no-install", action="store_true", help="skip the fresh-install rows")
    args = parser.parse_args()
    if not args.no_install:
        print("| install | step | wall | CPU |")
        print("|---|---|---|---|")
        _fresh_install(precompile=True)
        _fresh_install(precompile=False)
        print()
    # the railride of this interpreter's environment (beside it), else the one on PATH
    beside = Path(sys.executable).parent / "railride"
    railride = (str(beside) if beside.exists() else shutil.which("railride")) or sys.exit(
        "railride is not installed (python -m pip install .)"
    )
    cold: list[tuple[float, float]] = []
    warm: list[tuple[float, float]] = []
    notes = set()
    for _ in range(args.repeat):
        cache = tempfile.mkdtemp(prefix="railride-numba-")
        try:
            wall, cpu, err = _run([railride, "compare"], cache)
            cold.append((wall, cpu))
            notes.update(line for line in err.splitlines() if line.startswith("compiling"))
            wall, cpu, err = _run([railride, "compare"], cache)
            warm.append((wall, cpu))
            assert "compiling" not in err, err
        finally:
            shutil.rmtree(cache, ignore_errors=True)
    imports = [_run([sys.executable, "-c", "import railride"], tempfile.gettempdir())[:2] for _ in range(args.repeat)]
    cache = tempfile.mkdtemp(prefix="railride-numba-")
    try:
        detail = json.loads(_run([sys.executable, "-c", KERNEL_TIMES], cache)[2].strip().splitlines()[-1])
    finally:
        shutil.rmtree(cache, ignore_errors=True)

    def row(what, pairs):
        wall, cpu = min(p[0] for p in pairs), min(p[1] for p in pairs)
        print(f"| {what} | {wall:.1f} s | {cpu:.1f} s |")

    print("| `railride compare` (paper-sine, 10 s) | wall | CPU |")
    print("|---|---|---|")
    row("first run, empty numba cache", cold)
    row("later runs", warm)
    row("`import railride` alone", imports)
    for name, seconds in sorted(detail["compile"].items(), key=lambda kv: -kv[1]):
        print(f"| compile `kernels.{name}` (wall, in the first run) | {seconds:.1f} s | |")
    print()
    print("stderr of the first run:", "; ".join(sorted(notes)) or "(nothing)")


if __name__ == "__main__":
    main()
