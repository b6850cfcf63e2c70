"""The README's test command, timed as a new user meets it: a fresh clone of this repository's
HEAD, a new virtual environment, then the command's two parts as the README writes them (the
install of the test extra, then the tests), each timed by the wall clock.

Run:  python benchmarks/bench_test_suite.py [--keep]
Target: the whole command within 6 minutes on a quiet 2-core machine. Prints a Markdown table
for docs/performance.md ("The test suite"). Run it on a quiet machine: the tests use every core.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def readme_test_command() -> str:
    """The second command line of the README's quick start (the one that runs the tests)."""
    with open(os.path.join(ROOT, "README.md"), encoding="utf-8") as f:
        text = f.read()
    block = re.search(r"## Quick start\s+```\n(.*?)```", text, re.S)
    lines = [line for line in (block.group(1) if block else "").splitlines() if line.strip()]
    if len(lines) != 2 or "pytest" not in lines[1]:
        sys.exit("README.md: no quick start of two command lines, the second running pytest")
    return lines[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--keep", action="store_true", help="keep the clone and its environment")
    args = parser.parse_args()
    command = readme_test_command()
    work = tempfile.mkdtemp(prefix="railride-suite-")
    clone, venv = os.path.join(work, "clone"), os.path.join(work, "venv")
    try:
        subprocess.run(["git", "clone", "-q", ROOT, clone], check=True)
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=clone, capture_output=True, text=True)
        subprocess.run([sys.executable, "-m", "venv", venv], check=True)
        env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "PYTHONPATH", "VIRTUAL_ENV")}
        env["PATH"] = os.path.join(venv, "bin") + os.pathsep + env.get("PATH", "")
        rows, summary = [], ""
        for part in (p.strip() for p in command.split("&&")):
            started = time.perf_counter()
            done = subprocess.run(part, shell=True, cwd=clone, env=env, capture_output=True, text=True)
            took = time.perf_counter() - started
            if done.returncode != 0:
                sys.exit(f"`{part}` failed ({done.returncode}):\n{(done.stdout + done.stderr)[-3000:]}")
            rows.append((part, took))
            found = re.findall(r"^=*\s*(\d+ passed.*?) in [\d.]+s", done.stdout, re.M)
            summary = found[-1] if found else summary
    finally:
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    print(f"README test command, fresh clone of {head.stdout.strip()}, {os.cpu_count()} cores:\n")
    print("| step | wall time |")
    print("|---|---|")
    for part, took in rows:
        print(f"| `{part}` | {took:.0f} s |")
    total = sum(t for _, t in rows)
    print(f"| the whole command | **{total:.0f} s ({total / 60:.1f} min)** |")
    if summary:
        print(f"\npytest: {summary}")


if __name__ == "__main__":
    main()
