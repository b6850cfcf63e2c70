"""The command line's size limits (--max-memory) and resolution checks: each reproduction of an
oversized or unresolvable run exits 2 with one line, fast, and never with a traceback."""

from __future__ import annotations

import subprocess
import sys

import pytest

from clihelp import assert_input_error, ok, run

REPRODUCTIONS = [
    (("frf", "--points", "1000000000"), "points"),
    (("damper", "--amplitude", "0.01", "--voltage", "1", "--frequency", "1e-6"), "raise the frequency"),
    (("damper", "--amplitude", "0.01", "--voltage", "1", "--frequency", "1", "--cycles", "1000000000"), "fewer cycles"),
    (("simulate", "--dt", "1e-12"), "dt 1e-12 s"),
    (("compare", "--control-rate", "1e-300"), "--control-rate = 1e-300 Hz"),
    (("tune", "--values", "1000000000", "--budget", "1000000002"), "candidate values"),
    (("sweep", "--speed", "10:100:1000000000"), "--speed"),
    (("simulate", "--wavelength", "1e-6"), "--wavelength = 1e-06 m"),
    (("simulate", "--scenario", "bump", "--wavelength", "0.01"), "--wavelength = 0.01 m"),
    (("simulate", "--window", "0:inf"), "finite"),
    (("simulate", "--amplitude", "100"), "--amplitude = 100 m"),
    (("simulate", "--speed", "1e5"), "--speed = 1e+05 m/s"),
    (("simulate", "--rail-phase", "1e308"), "--rail-phase"),
]


@pytest.mark.parametrize("args,fragment", REPRODUCTIONS, ids=[" ".join(a) for a, _ in REPRODUCTIONS])
def test_each_reproduction_is_one_line_exit_2(args, fragment):
    assert_input_error(run(*args), fragment)


def test_in_a_process_of_its_own_fast_and_without_traceback():
    # refused before the frequency responses are computed (which would fail the command with
    # status 3 here), whatever the machine's speed
    prelude = (
        "import sys\n"
        "from railride.model.vehicle import Vehicle\n"
        "def worked(*args, **kwargs):\n"
        "    print('the frequency responses were computed', file=sys.stderr)\n"
        "    raise SystemExit(3)\n"
        "Vehicle.frequency_response = worked\n"
        "from railride.cli import main\n"
        "main()\n"
    )
    try:
        done = subprocess.run(
            [sys.executable, "-c", prelude, "frf", "--points", "1000000000"],
            capture_output=True,
            text=True,
            timeout=300,
        )
    except subprocess.TimeoutExpired:  # a guard against hanging, not a measure of speed
        pytest.fail("railride frf --points 1000000000 still running after 300 s")
    assert done.returncode == 2, done.stderr
    assert done.stdout == ""
    assert (
        done.stderr.count("\n") == 1
        and done.stderr.startswith("error: --points = 1000000000")
        and "<= 1000000" in done.stderr
    )


def test_max_memory_lowers_and_raises_the_limit_per_command():
    assert_input_error(run("frf", "--points", "20000", "--max-memory", "16M"), "limit of 16 MiB")
    ok("frf", "--points", "20000", "--max-memory", "4G", "--format", "json")
    # the next command is back at the default: a limit does not carry over
    ok("frf", "--points", "20000", "--format", "json")


@pytest.mark.parametrize("size", ["abc", "0", "1.5X"])
def test_max_memory_must_be_a_size(size):
    assert_input_error(run("frf", "--max-memory", size), "--max-memory")
