"""The command line at more edges: scheduler addresses that cannot work fail fast and name the
option, the step-count limit, and Ctrl-C during a long run saving what was computed."""

from __future__ import annotations

import json
import socket
import subprocess
import sys

import pytest

from clihelp import assert_input_error, interrupt, ran_a_chunk, run

#: the command line with distributed.Client made impossible: a Client waits up to its timeout for
#: a scheduler (a half-made one 20 s more as it is collected), so a command that must refuse an
#: address before any Client exits 3 if it tries to make one (SystemExit: no `except Exception`
#: turns it into an input error)
NO_CLIENT = """
import sys
try:
    import distributed
except ImportError:
    pass
else:
    def _client(*args, **kwargs):
        print("a distributed.Client was made", file=sys.stderr)
        raise SystemExit(3)
    distributed.Client = _client
from railride.cli import main
main()
"""


def _railride(*args, timeout=120.0, no_client=False):
    command = ["-c", NO_CLIENT] if no_client else ["-m", "railride.cli"]
    try:
        return subprocess.run(
            [sys.executable, *command, *map(str, args)], capture_output=True, text=True, timeout=timeout
        )
    except subprocess.TimeoutExpired:  # a guard against hanging, not a measure of speed
        pytest.fail(f"railride {' '.join(map(str, args))} still running after {timeout:g} s")


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize(
    "address,fragment",
    [
        ("tls://127.0.0.1:{port}", "TLS certificates"),
        ("wss://127.0.0.1:{port}", "TLS certificates"),
        ("ucx://127.0.0.1:{port}", "allowed: tcp://host:port"),
        ("inproc://127.0.0.1/1/1", "allowed: tcp://host:port"),
        ("tcp://127.0.0.1:{port}", "connection refused"),
        ("127.0.0.1:{port}", "connection refused"),
    ],
)
def test_a_scheduler_that_cannot_work_fails_fast_naming_the_option(address, fragment):
    pytest.importorskip("distributed")
    address = address.format(port=_free_port())  # nothing listens there
    proc = _railride("sweep", "--speed", "30", "--duration", "1", "--scheduler", address, timeout=120, no_client=True)
    # a half-made Client once hung 20 s as it was collected, then printed a traceback: refused
    # before any Client (status 3 if one was made), with one line
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith(f"error: --scheduler = '{address}': "), lines[0]
    assert fragment in lines[0]


def test_a_tiny_step_is_refused_by_the_step_count_with_how_long_it_would_take():
    # MR dampers run the RK4 stepper: 10 s at 1e-10 s is 1e11 steps, its histories only 10001 rows
    result = run("simulate", "--suspension", "mr", "--dt", "1e-10")
    assert_input_error(result, "1e+11 sample-steps", " h at ", "raise dt", "--max-steps")


def test_max_steps_raises_and_lowers_the_limit():
    # 1 s at the default dt is 10 000 steps: admitted under a limit of a million, 2e6 at 5e-7 s refused
    assert_input_error(
        run("simulate", "--suspension", "mr", "--duration", "1", "--dt", "5e-7", "--max-steps", "1e6"),
        "2e+06 steps",
        "set with --max-steps",
    )
    assert run("simulate", "--suspension", "mr", "--duration", "1", "--max-steps", "1e6").exit_code == 0
    assert_input_error(run("simulate", "--max-steps", "1e3"), "--max-steps = '1e3'", ">= 1e6")
    assert_input_error(run("simulate", "--max-steps", "many"), "--max-steps = 'many'")


def test_ctrl_c_in_a_long_simulate_saves_the_partial_histories(tmp_path):
    xr = pytest.importorskip("xarray")
    out = tmp_path / "run"
    # 6000 s of Spencer's MR dampers (sub-stepped) at 1e-4 s: minutes of stepping on a quiet
    # machine, near the longest run the rail input table admits; interrupted after its first
    # chunk (2 s, 20 output rows), however long the start-up and a compile take
    args = ["simulate", "--suspension", "mr", "--voltage", "1", "--damper", "spencer1997"]
    args += ["--duration", "6000", "--output-rate", "10", "--out", out]
    status, _, stderr = interrupt(args, ran_a_chunk)
    assert status == 130, stderr
    assert "Traceback" not in stderr
    last = stderr.strip().splitlines()[-1]
    assert last.startswith("interrupted at t = ") and "marked partial" in last, stderr
    doc = json.loads((out / "metrics.json").read_text())
    until = doc["partial"]["until_s"]
    assert 0 < until < 6000 and doc["partial"]["duration_s"] == 6000
    assert doc["settings"]["window_s"] == [0.0, until]
    with xr.open_dataset(out / "ride.nc") as ds:
        assert ds.attrs["partial"].startswith("interrupted: up to t = ")
        assert float(ds["time"][-1]) == pytest.approx(until)
    assert not list(tmp_path.glob(".*"))  # written atomically: no staging folder left


def test_ctrl_c_in_a_sweep_keeps_the_finished_rows_and_resume_continues(tmp_path):
    out = tmp_path / "s"
    speeds = "20:80:61"  # x 3 laws x 10 s: several chunks
    args = ["sweep", "--speed", speeds, "--duration", "10", "--controllers", "passive,pid,sas-attitude", "--out", out]
    # Ctrl-C once the first chunk's rows are saved, however long the start-up takes
    status, _, stderr = interrupt(args, lambda _: (out / "runs.csv").exists())
    assert status == 130, stderr
    assert "Traceback" not in stderr
    assert "runs saved in" in stderr
    kept = (out / "runs.csv").read_text().splitlines()[1:]
    assert 0 < len(kept) < 61 * 3
    proc = _railride(*args, "--resume", timeout=600)
    assert proc.returncode == 0, proc.stderr
    rows = (out / "runs.csv").read_text().splitlines()[1:]
    assert rows[: len(kept)] == kept and len(rows) == 61 * 3
