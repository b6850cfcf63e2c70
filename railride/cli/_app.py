"""The ``railride`` Typer application, which every command module registers on."""

from __future__ import annotations

import contextlib
import errno
import os
import sys
import warnings

import typer
from typer.core import TyperGroup

import railride.cli._common as _common
from railride.cli._common import (
    INTERNAL,
    INTERRUPTED,
    OK,
    USER,
    bug_line,
    set_debug,
    usage_error_line,
    usage_error_types,
)

__all__ = ["INTERRUPTED", "RailrideGroup", "app", "quiet_closed_pipe"]


def _closed(stream) -> bool:
    """Whether ``stream`` is a pipe whose reader has gone (poll reports an error on it)."""
    import select

    try:
        poller = select.poll()
        poller.register(stream.fileno(), select.POLLOUT)
        return any(events & select.POLLERR for _, events in poller.poll(0))
    except (AttributeError, OSError, ValueError):  # no file descriptor (a test's capture)
        return False


def _writable(stream) -> bool:
    """Whether ``stream``'s file descriptor is open."""
    try:
        os.fstat(stream.fileno())
        return True
    except (AttributeError, OSError, ValueError):
        return False


def quiet_closed_pipe() -> None:
    """Point stdout (and stderr, if its reader has gone too) at the null device, so that what
    is still buffered is dropped at exit instead of raising again (the Python documentation's
    way with SIGPIPE)."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    for stream in (sys.stdout, sys.stderr):
        if stream is sys.stdout or _closed(stream):
            try:
                os.dup2(devnull, stream.fileno())
            except (AttributeError, OSError, ValueError):
                pass
    os.close(devnull)


class RailrideGroup(TyperGroup):
    """The command group: Ctrl-C in a command prints one line and exits 130 (typer would
    exit 130 without a word; `tune`, `study`, `pareto` and `sweep` say first what they kept);
    a stdout whose reader has gone (``railride compare | head -1``) ends the command quietly
    with status 0, as a closed pipe is not an error (typer would exit 1, the status of an
    internal fault). A BrokenPipeError from anything else is a fault. A usage error (``--points
    abc``) is one line ``error: ...`` and status 2 like every other error: the parser would
    print its usage and a hint, with a blank line, before it."""

    def invoke(self, ctx):
        words = [str(w) for w in ctx.args]  # the command's own words, for the value a usage error names
        try:
            with _warnings_on_stderr():
                return super().invoke(ctx)
        except usage_error_types() as exc:
            command = " ".join(["railride", *filter(None, [ctx.invoked_subcommand])])
            typer.echo(f"error: {usage_error_line(exc, words, command)}", err=True)
            raise typer.Exit(getattr(exc, "exit_code", USER)) from None
        except KeyboardInterrupt:
            typer.echo("interrupted", err=True)
            raise typer.Exit(INTERRUPTED) from None
        except BrokenPipeError:
            if not (_closed(sys.stdout) or _closed(sys.stderr)):
                raise
            quiet_closed_pipe()
            raise typer.Exit(OK) from None
        except (typer.Exit, typer.Abort):
            raise
        except OSError as exc:
            if exc.errno == errno.EBADF and not _writable(sys.stdout):  # stdout closed (os.close(1))
                quiet_closed_pipe()
                raise typer.Exit(OK) from None
            if exc.errno not in _FULL:
                if _common.DEBUG:
                    raise
                typer.echo(bug_line(exc), err=True)
                raise typer.Exit(INTERNAL) from None
            # a full disk or a read-only place, stdout's included: the machine's state, not a bug
            typer.echo(f"error: cannot write: {exc.strerror or exc}", err=True)
            raise typer.Exit(USER) from None
        except Exception as exc:  # what no command's error handling took: a bug in railride
            if _common.DEBUG:
                raise
            typer.echo(bug_line(exc), err=True)
            raise typer.Exit(INTERNAL) from None


#: the errors of writing to a full disk (stdout to /dev/full too), over a quota or to a
#: read-only file system
_FULL = {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG}


@contextlib.contextmanager
def _warnings_on_stderr():
    """A `railride.model.plausible.PlausibilityWarning` (a vehicle outside the typical ranges) or a
    `railride.errors.BackendWarning` (the run went on on the CPU) as one line "warning: ..." on
    stderr, once per text, beside the result it qualifies."""
    from railride.errors import BackendWarning, TuningWarning
    from railride.model.plausible import PlausibilityWarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, (PlausibilityWarning, BackendWarning, TuningWarning)):
            typer.echo(f"warning: {message}", err=True)
        else:
            shown(message, category, filename, lineno, file, line)

    with warnings.catch_warnings():
        shown = warnings.showwarning
        warnings.simplefilter("default", PlausibilityWarning)
        warnings.simplefilter("default", BackendWarning)
        warnings.simplefilter("default", TuningWarning)
        warnings.showwarning = show
        yield


app = typer.Typer(
    cls=RailrideGroup,
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_show_locals=False,
    rich_markup_mode=None,
    help="Vertical ride of a 9-DOF railway vehicle: the paper's comparison of passive, PID and "
    "SAS suspensions and the semi-active laws beside them (start with `railride compare`), "
    "tuning every law alike, statistics over many tracks, payloads and damper faults, modes and "
    "frequency responses, simulated ride metrics on sine, bump, measured or random tracks, and "
    "MR damper rig tests (hysteresis cycles, force tracking).",
)


def _version(value: bool) -> None:
    if value:
        from railride._version import __version__

        typer.echo(f"railride {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
    debug: bool = typer.Option(
        False, "--debug", help="A bug in railride shows its traceback (else one line that says it is a bug)."
    ),
) -> None:
    """Vertical ride of a railway vehicle with a semi-active secondary suspension."""
    set_debug(debug)
