"""Shared helpers of the command-line tests: run a command in-process, expect success or an
input error (exit status 2, one line "error: ..." naming the fragments, no traceback), and
Ctrl-C a command in a fresh interpreter once it has something to keep (`interrupt`)."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import threading
import time

import pytest
from typer.testing import CliRunner

from railride.cli import app

runner = CliRunner()
PNG = b"\x89PNG\r\n\x1a\n"


def run(*args, **kwargs):
    """The command's result. An exception other than SystemExit (which every exit, clean or
    not, raises) fails the test with its traceback: CliRunner keeps exceptions out of the
    output, so a check for "Traceback" in it could never fail."""
    result = runner.invoke(app, [str(a) for a in args], **kwargs)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        import traceback

        trace = "".join(traceback.format_exception(*result.exc_info)) if result.exc_info else ""
        raise AssertionError(f"railride {' '.join(map(str, args))} raised instead of exiting:\n{trace}")
    return result


def ok(*args):
    result = run(*args)
    assert result.exit_code == 0, (result.exit_code, result.stdout, result.stderr)
    return result


def ok_json(*args) -> dict:
    return json.loads(ok(*args, "--format", "json").stdout)


def assert_input_error(result, *fragments):
    """Exit status 2, one line "error: ..." on stderr naming the fragments, no traceback,
    nothing on stdout."""
    assert result.exit_code == 2, (result.exit_code, result.stdout, result.stderr)
    assert isinstance(result.exception, SystemExit)
    # the note of a first compile comes where the process meets a cold cache (by test order)
    lines = [line for line in result.stderr.strip().splitlines() if not line.startswith("compiling the stepper once")]
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert "Traceback" not in result.output  # and no exception but SystemExit (checked above)
    assert result.stdout == ""
    for fragment in fragments:
        if fragment is not None:
            assert fragment in lines[0], lines[0]


def is_png(path) -> bool:
    return path.is_file() and path.read_bytes()[:8] == PNG


#: the start of the stderr line `interrupt`'s command prints at each progress report of a run
PROGRESS = "railride-test-progress "
#: the command line as a user runs it, in a fresh interpreter, with each progress report of a
#: run (`railride.cli._common.ProgressBar`, called after every chunk) also printed on stderr: on
#: a pipe the bar is off, and the Ctrl-C tests must see that a chunk has finished
_REPORTING = f"""
import sys
from railride.cli import _common, main
shown = _common.ProgressBar.__call__
def report(self, done):
    print({PROGRESS!r} + repr(done), file=sys.stderr, flush=True)
    shown(self, done)
_common.ProgressBar.__call__ = report
main()
"""


def ran_a_chunk(lines: list[str]) -> bool:
    """Whether the stderr ``lines`` of `interrupt`'s command hold a progress report: a chunk of
    the run has finished, so that a Ctrl-C now has output rows to save."""
    return any(line.startswith(PROGRESS) for line in list(lines))


def _drain(stream, into: list[str]) -> None:
    for line in stream:
        into.append(line)


def interrupt(args, ready, timeout: float = 600.0) -> tuple[int, str, str]:
    """Start ``railride ARGS`` in a fresh interpreter, Ctrl-C it as soon as ``ready(lines)``
    holds for its stderr lines so far (`ran_a_chunk`, or a file it writes), and wait for it to
    end: (status, stdout, stderr less the progress lines). A slow machine only waits longer, up
    to ``timeout`` s for the sign (a cold compile) and as long again for the end; a command that
    ends first, or stays without the sign or running past it, fails the test."""
    proc = subprocess.Popen(
        [sys.executable, "-c", _REPORTING, *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    out: list[str] = []
    err: list[str] = []
    readers = [
        threading.Thread(target=_drain, args=pair, daemon=True) for pair in ((proc.stdout, out), (proc.stderr, err))
    ]
    for reader in readers:
        reader.start()
    try:
        deadline = time.monotonic() + timeout
        while not ready(err):
            if proc.poll() is not None:
                pytest.fail(f"railride {' '.join(map(str, args))} ended before it was interrupted:\n{''.join(err)}")
            if time.monotonic() > deadline:
                pytest.fail(f"railride {' '.join(map(str, args))}: nothing to interrupt after {timeout:g} s")
            time.sleep(0.05)
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:  # a guard against hanging, not a measure of speed
            pytest.fail(f"railride {' '.join(map(str, args))} went on for {timeout:g} s after Ctrl-C")
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for reader in readers:
            reader.join(timeout=30)
    return proc.returncode, "".join(out), "".join(line for line in err if not line.startswith(PROGRESS))
