"""`railride report` wall-clock times: the paper's comparison written as one HTML file, warm
(numba's cache filled by a first run), beside `railride compare` alone; the report's own cost
in-process, split into its parts; the file's size; and, when Chromium and playwright are
there, how long the page takes to load and draw.

Run:  python benchmarks/bench_report.py [--repeat N]
      python benchmarks/bench_report.py --sizes   (the size of each kind of page, docs/report.md)
Target: `railride report`, second run, <= 10 s; the paper's page <= 3 MB. Prints a Markdown table
for docs/performance.md or docs/report.md.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _timing import min_time


def _timed(cmd) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    return time.perf_counter() - t0


#: true once plotly has drawn every figure of the page
DRAWN = "() => [...document.querySelectorAll('.plotly-graph-div')].every(d => d._fullLayout)"


def _browser_load(path: Path, repeat: int) -> float | None:
    """The best time for headless Chromium to load the page and plotly to draw every figure."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        return None
    if not Path("/usr/bin/chromium").exists():
        return None
    args = ["--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-background-networking"]
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path="/usr/bin/chromium", args=args)
        best = float("inf")
        for _ in range(repeat):
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            t0 = time.perf_counter()
            page.goto(path.as_uri(), wait_until="load")
            page.wait_for_function(DRAWN)
            best = min(best, time.perf_counter() - t0)
            page.close()
        browser.close()
    return best


#: the pages of docs/report.md's table of sizes: (what, the command's arguments after railride)
PAGES = (
    ("the paper's comparison", ["report", "--out", "{out}"]),
    ("every law, with comfort", ["compare", "--controllers", "all", "--comfort", "--report", "{out}"]),
    ("a long random track", ["compare", "--scenario", "fra4", "--duration", "60", "--report", "{out}"]),
    ("ride spectrum", ["ride-spectrum", "--track", "fra4", "--report", "{out}"]),
)


def sizes(base) -> None:
    """Write each page of `PAGES` and print its size."""
    folder = Path(tempfile.mkdtemp(prefix="railride-bench-report-"))
    print("| page | command | size |")
    print("|---|---|---|")
    for k, (what, args) in enumerate(PAGES):
        out = folder / f"page{k}.html"
        subprocess.run(base + [a.format(out=out) for a in args], check=True, capture_output=True)
        shown = " ".join("..." if a == "{out}" else a for a in args)
        size = out.stat().st_size
        print(f"| {what} | `railride {shown}` | {size / 1e6:.2f} MB ({size:,} bytes) |")
    shutil.rmtree(folder, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--sizes", action="store_true", help="only the size of each kind of page")
    args = ap.parse_args()
    exe = shutil.which("railride")
    base = [exe] if exe else [sys.executable, "-m", "railride.cli"]
    if args.sizes:
        sizes(base)
        return
    folder = Path(tempfile.mkdtemp(prefix="railride-bench-report-"))
    out = folder / "report.html"
    report = base + ["report", "--out", str(out)]
    _timed(report)  # the first run: compiles the stepper if the cache is empty
    warm = [_timed(report) for _ in range(args.repeat)]
    compare = [_timed(base + ["compare"]) for _ in range(args.repeat)]

    import railride as rr
    from railride.output import report as rep

    result = rr.compare(rr.scenario("paper-sine"))
    rep.report_html(result)  # imports and first calls
    whole = min_time(lambda: rep.report_html(result), args.repeat)
    contents = min_time(lambda: rep.contents(result), args.repeat)
    size = out.stat().st_size
    load = _browser_load(out, args.repeat)
    shutil.rmtree(folder, ignore_errors=True)

    print("| benchmark | result | target |")
    print("|---|---|---|")
    print(
        f"| `railride report` (the paper's comparison), second run (cache warm), best of {args.repeat} "
        f"| {min(warm):.2f} s (worst {max(warm):.2f} s) | <= 10 s |"
    )
    print(f"| `railride compare` alone, cache warm, best of {args.repeat} | {min(compare):.2f} s | |")
    print(f"| `report_html(comparison)` in-process, warm | {whole:.2f} s | |")
    print(f"| of which the figures and tables (`contents`) | {contents:.2f} s | |")
    print(f"| the HTML file | {size / 1e6:.1f} MB (plotly's JavaScript and the figures' data inlined, gzip-packed) | |")
    if load is not None:
        print(f"| headless Chromium: load and draw every figure, best of {args.repeat} | {load:.2f} s | |")


if __name__ == "__main__":
    main()
