"""The ``railride`` command line: ``railride compare``, ``railride modes``, ``railride vehicles``,
``railride frf``, ``railride simulate``, ``railride damper``, ``railride tracking``, ``railride
tune``, ``railride study``, ``railride design``, ``railride pareto``, ``railride sweep`` and
``railride report``.

A thin layer over the library: it parses options, calls the library's studies (`simulate`,
`compare`, `frf`, `rig`, `tune`, `study`, `pareto`, `sweep`), writes their results through their
`save()` and `railride.output.files`, and prints. See docs/cli.md. One module per command (`rig` holds `damper`
and `tracking`); `_options` declares the options several commands share, `_parsing` the
checks of their values, `_common` the errors, consoles and run machinery, `_render` the
shared tables, `_width` the tables that fit the console's width (80 columns on a pipe).

Exit statuses: 0 success (also when stdout is a pipe closed early: ``railride compare | head
-1``), 1 a bug in railride (one line that says so; ``railride --debug COMMAND`` shows its
traceback), 2 anything the user can fix (`railride.errors.InputError`: usage errors,
invalid values, unreadable files, an output folder that cannot be written or that another
railride process is writing, a run that diverged), 130 interrupted by Ctrl-C (`tune`, `study`,
`pareto` and `sweep` keep their finished runs in DIR/runs.csv for --resume). Errors print one
line ``error: <message>`` on stderr, never a traceback.
"""

from __future__ import annotations

import errno
import os
import sys

TYPE_CHECKING = False  # typing.TYPE_CHECKING, without importing typing before main() runs

__all__ = ["app", "main"]

#: the command modules, which register on `app` when imported; `railride --help` lists the
#: commands in this order
COMMANDS = (
    "compare",
    "report",
    "modes",
    "vehicles",
    "frf",
    "simulate",
    "rig",
    "tune",
    "pareto",
    "sweep",
    "study",
    "design",
    "ride_spectrum",
    "fmu",
)

if TYPE_CHECKING:
    from railride.cli._app import app


def _load():
    """`app` with every command registered (the command modules import the library)."""
    import importlib

    for name in COMMANDS:
        importlib.import_module(f".{name}", __name__)
    from railride.cli._app import app

    return app


def __getattr__(name: str):
    if name == "app":
        return _load()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def main() -> None:
    """Entry point of the ``railride`` console script: the commands are loaded here, not at
    import, so that Ctrl-C during start-up is reported like Ctrl-C during a command (status 130,
    no traceback); a stdout closed early is not an error (`railride.cli._app.RailrideGroup`
    handles both within a command)."""
    status: str | int | None = 0
    if sys.stdout is None:  # started with stdout closed (>&-): the output goes nowhere, as to a closed pipe
        sys.stdout = open(os.devnull, "w")
    hook = sys.unraisablehook
    sys.unraisablehook = lambda unraisable: _interrupt_again(unraisable, hook)
    # Ctrl-C while the commands load is recorded as it arrives: one landing in a C extension's
    # import can come back as an unrelated error with no trace of it (a TypeError from `_ssl`'s
    # init, seen in CI's timing). Python's own handler is back before a command runs (a long
    # simulation takes Ctrl-C as a request to stop at its next chunk only under that handler).
    interrupted: list[int] = []
    try:
        previous = _record_interrupts(interrupted)
        try:
            app = _load()
        except Exception:
            if interrupted:  # the error is the interrupt's, whatever it says
                raise KeyboardInterrupt from None
            raise
        finally:
            if previous is not None:
                import signal

                signal.signal(signal.SIGINT, previous)
        app(prog_name="railride")
    except SystemExit as exc:
        status = exc.code
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        status = 130  # _common.INTERRUPTED, which may not be loaded yet
    except BrokenPipeError:  # outside a command: typer's own output (--help)
        _quiet()
        status = 0
    except Exception as exc:
        # Ctrl-C in the middle of loading a module can come back wrapped: Python 3.11 turns it into
        # a RuntimeError when it lands in a class's __set_name__ (a dataclass field of pandas)
        if not _caused_by_interrupt(exc):
            raise
        print("interrupted", file=sys.stderr)
        status = 130
    finally:
        sys.unraisablehook = hook
    try:  # what is still buffered goes now, and a reader gone by then is no error either
        sys.stdout.flush()
    except BrokenPipeError:
        _quiet()
    except OSError as exc:  # a full disk behind stdout (> /dev/full); a closed one is no error
        if exc.errno != errno.EBADF:
            print(f"error: cannot write: {exc.strerror or exc}", file=sys.stderr)
            status = 2
    sys.exit(status)


def _interrupt_again(unraisable, hook) -> None:
    """`sys.unraisablehook` while a command runs. Python drops an exception raised where it cannot
    propagate (a weakref callback, a ``__del__``) with "Exception ignored in ..." and a traceback.
    Ctrl-C once landed there (importlib's module-lock callback, as the commands loaded), and the
    command ran on to its end with status 0. A KeyboardInterrupt is therefore delivered again, a
    moment later from another thread: raised within this hook it would be dropped too. Anything
    else goes to ``hook``, the one in place before."""
    if not issubclass(unraisable.exc_type, KeyboardInterrupt):
        hook(unraisable)
        return
    import _thread
    import threading

    again = threading.Timer(0.01, _thread.interrupt_main)  # as Ctrl-C: the handler in place takes it
    again.daemon = True  # never holds the interpreter's exit
    again.start()


def _record_interrupts(seen: list):
    """Handle SIGINT as Python does (KeyboardInterrupt), appending to ``seen`` first; returns the
    handler it replaced, or None where none can be set (not the main thread, or Python's own
    handler was replaced by a non-Python one)."""
    import signal

    try:
        previous = signal.getsignal(signal.SIGINT)
        if previous is not signal.default_int_handler:  # someone else's (a test runner's): leave it
            return None

        def on_sigint(signum, frame):
            seen.append(signum)
            signal.default_int_handler(signum, frame)

        signal.signal(signal.SIGINT, on_sigint)
        return previous
    except ValueError:  # not the main thread
        return None


def _caused_by_interrupt(exc: BaseException | None) -> bool:
    """Whether ``exc`` came from a KeyboardInterrupt (its cause or context, at any depth)."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


def _quiet() -> None:
    from railride.cli._app import quiet_closed_pipe

    quiet_closed_pipe()
