"""What every command shares besides parsing: the error contract (one line ``error: ...`` and an
exit status, never a traceback), the consoles, progress bars and status notes on stderr, and
the machinery of the many-run commands (executors, run tables, Ctrl-C)."""

from __future__ import annotations

import contextlib
import errno
import functools
import json
import math
import sys
from pathlib import Path
from typing import Any, Optional

import typer

from railride.errors import InputError


# -- errors ---------------------------------------------------------------------------------------
class CliError(Exception):
    """A problem to report as ``error: ...`` with an exit status."""

    def __init__(self, message: str, status: int):
        super().__init__(message)
        self.status = status


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return text or type(exc).__name__


#: the exit statuses: success, an internal fault (a bug), anything the user can fix, Ctrl-C
#: (128 + SIGINT, the shells' convention)
OK, INTERNAL, USER, INTERRUPTED = 0, 1, 2, 130


#: ``railride --debug``: a bug's traceback instead of its one line (`set_debug`)
DEBUG = False


def set_debug(on: bool) -> None:
    global DEBUG
    DEBUG = bool(on)


def bug_line(exc: BaseException) -> str:
    """The one line a bug in railride gets on the command line (status 1)."""
    return (
        f"error: a bug in railride ({type(exc).__name__}: {_one_line(exc)}); please report it. "
        "railride --debug COMMAND ... shows its traceback"
    )


@contextlib.contextmanager
def errors():
    """What the user gave is wrong (`railride.errors.InputError`), a file it names cannot be
    read or written (OSError), a run diverged (`railride.errors.DivergenceError`: its inputs are
    the user's to change) -> status 2; anything else is a bug in railride -> status 1. One line
    on stderr, no traceback (``railride --debug`` re-raises a bug). A closed stdout
    (BrokenPipeError), Ctrl-C and typer's own exits pass through: the entry point
    (`railride.cli._app`) deals with them."""
    from railride.errors import DivergenceError

    try:
        yield
    except (typer.Exit, typer.Abort, KeyboardInterrupt, BrokenPipeError):
        raise
    except CliError as exc:
        status, message = exc.status, _one_line(exc)
    except (InputError, DivergenceError) as exc:
        status, message = USER, _one_line(exc)
    except OSError as exc:
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        status, message = USER, f"{exc.strerror or exc}{where}"
    except Exception as exc:
        if DEBUG:
            raise
        typer.echo(bug_line(exc), err=True)
        raise typer.Exit(INTERNAL) from None
    else:
        return
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(status)


def usage_error_types() -> tuple:
    """The parser's usage errors (no number where an option takes one, an unknown option, a
    missing value): typer's own click from typer 0.22 on, click before."""
    import importlib

    found = []
    for module in ("typer._click.exceptions", "click.exceptions"):
        with contextlib.suppress(ImportError, AttributeError):
            found.append(importlib.import_module(module).UsageError)
    return tuple(found)


def usage_error_line(exc, args, command: str = "railride") -> str:
    """A usage error as one line like every other error, where the parser prints its usage,
    a hint and a blank line before it: ``--points = '1e-300': input should be a valid
    integer ...``, the value the user typed taken from ``args`` (the command's words);
    otherwise the parser's message and where to look (``command --help``)."""
    message = _one_line(exc).rstrip(".")
    if message.lower().startswith("value error, "):  # the parser's validator's own prefix, no word of ours
        message = message[len("value error, ") :]
    param = getattr(exc, "param", None)
    flags = [o for o in getattr(param, "opts", ()) if o.startswith("-")]
    value = None
    for i, word in enumerate(args):
        if word in flags and i + 1 < len(args):
            flag, value = word, args[i + 1]
        elif any(word.startswith(f + "=") for f in flags):
            flag, _, value = word.partition("=")
    if value is not None and message:
        return f"{flag} = {value!r}: {message[0].lower()}{message[1:]}"
    text = " ".join(exc.format_message().split()).rstrip(".")
    path = getattr(getattr(exc, "ctx", None), "command_path", "").split()
    if len(path) > 1:  # the program's own name, also where a test runner names it otherwise
        command = " ".join(["railride", *path[1:]])
    return f"{text[:1].lower()}{text[1:]}; see {command} --help"


@contextlib.contextmanager
def option_names(fields: dict, defaults=()):
    """The library's errors in the command's words: in a ValueError raised inside, each field
    ``name = ...`` (or ``<=``, ``>=``) of ``fields`` (library name -> option) is named by its
    option instead (``amplitude = 0.0: ...`` -> ``--amplitude = 0.0: ...``); a name with an underscore,
    which reads as no word, wherever it stands (``raise output_rate``). A field in
    ``defaults`` (its option not given) gets "(the default)" after its value. Use inside
    `errors`."""
    try:
        yield
    except InputError as exc:
        text = reworded(str(exc), fields, defaults)
        if text == str(exc):
            raise
        raise InputError(text) from exc


def reworded(text: str, fields: dict, defaults=()) -> str:
    """``text`` with the library's field names replaced by the options' (see `option_names`)."""
    import re

    for name, option in fields.items():
        field = rf"(?<![\w'./-]){re.escape(name)}"
        if name in defaults:  # the value, and its unit when the library gives one
            text = re.sub(
                rf"{field}( = [^\s:;,]+(?: (?:s|Hz|m|m/s|V))?)(?=[\s:;,]|$)", rf"{name}\1 (the default)", text
            )
        text = re.sub(field + (r"(?![\w-])" if "_" in name else "(?= [<>]?= )"), option, text)
    return text


# -- consoles and output --------------------------------------------------------------------------
def stderr_is_terminal() -> bool:
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


#: the width of tables and text printed to a pipe or a file, unless COLUMNS says otherwise
PIPE_WIDTH = 80


def stdout_console(width: int = PIPE_WIDTH):
    """The stdout console: on a terminal its width (or COLUMNS); to a pipe or a file, COLUMNS if
    set, else ``width`` columns (rich would take the width of a terminal on stdin or stderr).
    Tables fit it (`railride.cli._width`)."""
    import os

    try:
        terminal = sys.stdout.isatty()
    except (AttributeError, ValueError):
        terminal = False
    fixed = None if terminal or os.environ.get("COLUMNS") else width
    return _console_type()(file=sys.stdout, highlight=False, width=fixed)


@functools.cache
def _console_type():
    """rich's Console, but a reader gone from the pipe raises BrokenPipeError, for the entry
    point to end quietly with status 0, where rich would exit with status 1."""
    from rich.console import Console

    class PipeConsole(Console):
        def on_broken_pipe(self) -> None:
            self.quiet = True
            raise BrokenPipeError(errno.EPIPE, "the reader of the pipe has gone")

    return PipeConsole


#: the older name of `stdout_console`
wide_stdout_console = stdout_console


def stderr_console():
    return _console_type()(file=sys.stderr, highlight=False)


def status_note(message: str):
    if not stderr_is_terminal():
        return contextlib.nullcontext()
    return stderr_console().status(message)


def write_folder(out: Path, write, *, own_folder: bool = True) -> None:
    """Run ``write()`` (a `railride.output.files` writer or a result's ``save``) with a status note;
    OSError -> status 2. ``own_folder``: ``out`` is the command's result folder, so a line says
    when it also holds files the command did not write (another command's results,
    `railride.cli._folders.others_note`)."""
    from railride.cli._folders import entries, others_note

    before = entries(Path(out)) if own_folder else set()
    try:
        with status_note(f"writing outputs to {out}..."):
            paths = write()
    except OSError as exc:
        raise CliError(f"cannot write the output folder {out}: {exc.strerror or exc}", 2) from None
    typer.echo(f"wrote {', '.join(p.name for p in paths)} to {out}", err=True)
    if note := others_note(Path(out), before, paths):
        typer.echo(note, err=True)


def print_json(doc) -> None:
    typer.echo(json.dumps(doc, indent=2, allow_nan=False))


def _first_message(verb_text: str) -> str:
    """The bar's first text: while the stepper is neither compiled nor in numba's cache, that it
    compiles."""
    from railride.engine import compiled

    return "compiling the stepper (once)..." if compiled.needs_compiling() else verb_text


def compile_message(kernel: str = "run_batch") -> str:
    """The note printed when ``kernel`` starts compiling, with the time it takes."""
    from railride.engine import compiled

    return f"compiling the stepper once, about {compiled.compile_seconds(kernel):.0f} s; later runs start at once"


@contextlib.contextmanager
def compile_note(say):
    """Within the block, ``say`` the compile note once when numba starts compiling the stepper
    (a fresh install's first closed-loop run), on a pipe as on a terminal: a silent pause of ten
    seconds reads as a hang. Loading it from numba's cache says nothing."""
    from railride.engine import compiled

    said = []

    def on_start(kernel):
        if not said:
            said.append(kernel)
            say(compile_message(kernel))

    with compiled.watch_compiles(on_start):
        yield


def _say(progress, text: str) -> None:
    """A line on stderr: above the bar when there is one (it stays when the bar goes)."""
    if progress is not None:
        progress.console.print(text, markup=False, highlight=False)
    else:
        typer.echo(text, err=True)


class ProgressBar:
    """A progress bar on stderr, only when stderr is a terminal.

    ``describe(done)`` gives the bar's text for a done fraction (default: "simulating"); until
    the first report, a stepper not yet compiled in this process says that it compiles."""

    def __init__(self, enabled: bool, describe=None):
        self.enabled = enabled
        self._describe = describe or (lambda done: "simulating")
        self._progress = None
        self._task = None
        self._note = compile_note(lambda text: _say(self._progress, text))

    def __enter__(self):
        self._note.__enter__()
        if not self.enabled:
            return self
        from rich.progress import BarColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        first = _first_message(self._describe(0.0))
        self._progress = Progress(
            SpinnerColumn(),
            TextColumn("{task.description}"),
            BarColumn(),
            TextColumn("{task.percentage:>3.0f}%"),
            TimeElapsedColumn(),
            console=stderr_console(),
            transient=True,
        )
        self._progress.__enter__()
        self._task = self._progress.add_task(first, total=1.0)
        return self

    def __call__(self, done: float) -> None:
        if self._progress is not None:
            self._progress.update(self._task, completed=done, description=self._describe(done))

    def __exit__(self, *exc):
        if self._progress is not None:
            self._progress.__exit__(*exc)
        self._note.__exit__(*exc)
        return False


# -- many runs: tune, pareto and sweep ------------------------------------------------------------
class RunProgress:
    """Progress of many runs, fed by the library's ``progress(done, total, runs_per_second)``
    (once per batch of runs it asks for, then after each chunk). Counts the runs evaluated in
    this session (``evaluated``); shows a bar on stderr only when stderr is a terminal.
    ``log(text)`` prints a line on stderr (above the bar)."""

    def __init__(self, enabled: bool, verb: str):
        self.enabled = enabled
        self.verb = verb
        self.evaluated = 0
        self._base = 0
        self._progress = None
        self._task = None
        self._note = compile_note(self.log)

    def __enter__(self):
        self._note.__enter__()
        if not self.enabled:
            return self
        from rich.progress import BarColumn, MofNCompleteColumn, Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

        first = _first_message(f"{self.verb}...")
        self._progress = Progress(
            SpinnerColumn(),
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[rate]}"),
            TimeElapsedColumn(),
            console=stderr_console(),
            transient=True,
        )
        self._progress.__enter__()
        self._task = self._progress.add_task(first, total=None, rate="")
        return self

    def __call__(self, done: int, total: int, runs_per_second: float) -> None:
        if done == 0:
            self._base = self.evaluated
        self.evaluated = self._base + int(done)
        if self._progress is not None:
            ok = math.isfinite(runs_per_second) and runs_per_second > 0
            self._progress.update(
                self._task,
                completed=done,
                total=total,
                description=f"{self.verb} ({self.evaluated} runs)",
                rate=f"{runs_per_second:.1f} runs/s" if ok else "",
            )

    def log(self, text: str) -> None:
        _say(self._progress, text)

    def __exit__(self, *exc):
        if self._progress is not None:
            self._progress.__exit__(*exc)
        self._note.__exit__(*exc)
        return False


def make_executor(
    workers: Optional[int],
    scheduler: Optional[str],
    scheduler_file: Optional[Path],
    ahead: Optional[int] = None,
    processes: Optional[int] = None,
    rows_beside: bool = True,
):
    """(executor, record for the JSON): Dask with --scheduler / --scheduler-file, else the local
    executor, whose batches use --workers threads (numba's thread count, 1..cores), with
    ``ahead`` chunks stepping beside the one whose rows are made (default: by its thread count,
    `LocalExecutor` with ``rows_beside``), or with --processes N worker processes
    (`ProcessExecutor`)."""
    from railride.studies import sweep as sweep_lib

    if processes is not None:
        for given, option in ((workers, "--workers"), (scheduler, "--scheduler"), (scheduler_file, "--scheduler-file")):
            if given is not None:
                raise InputError(f"--processes with {option}: give one (processes share this machine's cores)")
        with option_names({"processes": "--processes"}):
            pool = sweep_lib.ProcessExecutor(processes)
        return pool, {"type": "processes", "processes": pool.processes}
    if scheduler is not None and scheduler_file is not None:
        raise InputError("give either --scheduler ADDRESS or --scheduler-file FILE, not both")
    if scheduler is not None or scheduler_file is not None:
        if workers is not None:
            raise InputError(
                f"--workers = {workers}: applies to the local executor only; the "
                "threads of a Dask cluster are set where its workers start "
                "(dask worker --nthreads N)"
            )
        if scheduler is not None and not scheduler.strip():
            raise InputError("--scheduler = '': give the scheduler's address, e.g. tcp://host:8786")
        # the library names the address and file by its fields: the user typed these options
        names = {"address": "--scheduler", "scheduler file": "--scheduler-file"}
        with status_note("connecting to the Dask scheduler..."), option_names(names):
            executor = sweep_lib.DaskExecutor(
                address=scheduler, scheduler_file=None if scheduler_file is None else str(scheduler_file)
            )
        where = scheduler if scheduler is not None else str(scheduler_file)
        record: dict[str, Any] = {"type": "dask", "scheduler": where}
        with contextlib.suppress(Exception):
            record["workers"] = len(executor.client.scheduler_info()["workers"])
        return executor, record
    import numba

    cores = int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]  # set at import
    if workers is not None:
        if not 1 <= workers <= cores:
            raise InputError(
                f"--workers = {workers}: must be a whole number from 1 to {cores} (the cores of this machine)"
            )
        numba.set_num_threads(workers)
    local = sweep_lib.LocalExecutor(ahead, rows_beside)  # ahead None: by the thread count just set
    record = {"type": "local", "threads": int(numba.get_num_threads()), "chunks_ahead": local.ahead}
    return local, record


def open_run_table(out: Optional[Path], resume: bool):
    """(RunTable, its path or None): DIR/runs.csv with --out, kept in memory without it."""
    from railride.studies import sweep as sweep_lib
    from railride.output.files import check_out_dir

    if out is None:
        if resume:
            raise InputError("--resume needs --out DIR: the run table it continues is DIR/runs.csv")
        return sweep_lib.RunTable(), None
    check_out_dir(out, "--out")
    path = out / "runs.csv"
    if path.exists() and not resume:
        raise InputError(
            f"--out {out}: {path} exists (the run table of an earlier run); add "
            "--resume to continue it, or choose another folder"
        )
    fresh = resume and not path.exists()
    # locks the folder against a second writer until `interruptible` ends (or this process)
    table = sweep_lib.RunTable(path, resume=resume)
    if fresh:  # a folder mistyped would start afresh unsaid (said once the folder is ours)
        typer.echo(f"note: --resume: {path} does not exist yet; starting afresh", err=True)
    return table, path


def _saved_runs(table, path: Optional[Path]) -> int:
    """The rows of the run table on disk (what an interrupted run leaves), else in memory."""
    if path is not None and path.exists():
        import pandas as pd

        try:
            return len(pd.read_csv(path, usecols=["key"]))
        except (OSError, ValueError):
            pass
    return len(table.frame)


@contextlib.contextmanager
def interruptible(table, path: Optional[Path]):
    """Ctrl-C: one line saying what was kept, status 130, no traceback. The run table's lock
    is released at the end of the block, however it ends."""
    try:
        yield
    except KeyboardInterrupt:
        table.flush()  # every finished run, before the count
        n = _saved_runs(table, path)
        if path is not None:
            typer.echo(f"interrupted: {n} runs saved in {path}; run again with --resume to continue", err=True)
        else:
            typer.echo(
                f"interrupted: {n} runs done, none saved (with --out DIR the runs are kept "
                "in DIR/runs.csv and --resume continues them)",
                err=True,
            )
        raise typer.Exit(INTERRUPTED) from None
    finally:
        table.close()


#: the options that choose where and how results are written, not what they are: left out of
#: the command a result records as the one that reproduces it
OUTPUT_ONLY = ("out", "resume", "format", "figure_format", "dpi", "report", "history_format")


def command_line(ctx: typer.Context, exclude=()) -> str:
    """The railride command being run, with the options given on the command line (not their
    defaults), for the record: reproducing a result needs only this line."""
    import shlex

    words = ["railride", ctx.info_name or ""]
    for param in ctx.command.params:
        source = ctx.get_parameter_source(param.name)
        if param.name in exclude or getattr(source, "name", "") != "COMMANDLINE":
            continue
        value = ctx.params[param.name]
        flag = max(param.opts, key=len)
        if isinstance(value, bool):
            words.append(flag if value else (param.secondary_opts or [flag])[0])
            continue
        for item in value if isinstance(value, (list, tuple)) else [value]:
            words += [flag, str(getattr(item, "value", item))]
    return shlex.join(w for w in words if w)
