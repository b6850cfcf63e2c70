"""Shared helpers of the command-line tests: run a command in-process, expect success or an
input error (exit status 2, one line "error: ..." naming the fragments, no traceback)."""

from __future__ import annotations

import json

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
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert "Traceback" not in result.output  # and no exception but SystemExit (checked above)
    assert result.stdout == ""
    for fragment in fragments:
        if fragment is not None:
            assert fragment in lines[0], lines[0]


def is_png(path) -> bool:
    return path.is_file() and path.read_bytes()[:8] == PNG
