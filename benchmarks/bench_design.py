"""Cost of `railride design` with its defaults: wall time, CPU share and peak memory.

Run:  python benchmarks/bench_design.py [--out DIR] [other railride design options]
Runs `railride design --out DIR` (default: a new temporary folder) in a child process and
prints a Markdown row for docs/performance.md: the runs it evaluated, its wall time, the CPU
time of the child as a share of one core, and the child's peak resident memory. The default
design takes about 17-30 minutes on a 2-core machine. No test asserts timings.
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def main():
    args = sys.argv[1:]
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


if __name__ == "__main__":
    main()
