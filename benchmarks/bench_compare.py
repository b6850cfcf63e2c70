"""`railride compare` wall-clock times: the first run on a fresh install (numba's cache
empty, so compilation is included) and a second run (cache warm).

Run:  python benchmarks/bench_compare.py [--repeat N]
Targets: first run <= 15 s, second run <= 3 s. Prints a Markdown table for docs/performance.md.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import time
from pathlib import Path


def _clear_cache() -> None:
    """Empty the folder numba caches the engine's kernels in: the engine's __pycache__, or its
    folder under NUMBA_CACHE_DIR where that is set (as the command it times reads it)."""
    from railride.engine.cache_guard import cache_dir

    cache = Path(cache_dir())
    for f in list(cache.glob("*.nbi")) + list(cache.glob("*.nbc")):
        f.unlink()


def _timed(cmd) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out-dir", default="/tmp/railride-bench-compare", help="the folder --out writes (replaced)")
    args = ap.parse_args()
    exe = shutil.which("railride")
    cmd = [exe, "compare"] if exe else [sys.executable, "-m", "railride.cli", "compare"]
    firsts, seconds, no_bounds = [], [], []
    for _ in range(args.repeat):
        _clear_cache()
        firsts.append(_timed(cmd))
        seconds.append(_timed(cmd))
        no_bounds.append(_timed(cmd + ["--no-bounds"]))  # what the ideal-device runs cost
    out_dir = Path(args.out_dir)
    shutil.rmtree(out_dir, ignore_errors=True)
    with_out = _timed(cmd + ["--out", str(out_dir)])
    print("| benchmark | result | target |")
    print("|---|---|---|")
    print(
        f"| `railride compare`, first run (numba cache empty: compilation included), best of {args.repeat} "
        f"| {min(firsts):.1f} s (worst {max(firsts):.1f} s) | <= 15 s |"
    )
    print(
        f"| `railride compare`, second run (cache warm), best of {args.repeat} "
        f"| {min(seconds):.2f} s (worst {max(seconds):.2f} s) | <= 3 s |"
    )
    print(
        f"| `railride compare --no-bounds`, cache warm, best of {args.repeat} "
        f"| {min(no_bounds):.2f} s (worst {max(no_bounds):.2f} s) | |"
    )
    print(f"| `railride compare --out DIR` (cache warm: NetCDF, CSV, JSON, six plots) | {with_out:.2f} s | |")


if __name__ == "__main__":
    main()
