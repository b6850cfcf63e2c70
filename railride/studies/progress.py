"""Progress of a long library call, shown unless the caller says not to.

Every study (`tune`, `design`, `study`, `pareto`, `run_sweep`, `league`, `compare`) takes
``progress``: True (the default) shows it on stderr once the call has run `DELAY` seconds, so
that short calls stay silent; False or None shows nothing; a callable receives the numbers
itself (``progress(done, total, runs_per_second)``, as `railride.studies.sweep.run_cases` calls
it; `compare` calls it with the fraction done). On a terminal or in Jupyter the bar is rich's;
elsewhere (a log file, a pipe) one plain line at most every `EVERY` seconds.
"""

from __future__ import annotations

import functools
import inspect
import math
import sys
import time
from typing import Any

#: seconds a call runs before its progress is shown (a shorter call says nothing)
DELAY = 2.0
#: seconds between two plain lines where no live bar can be drawn
EVERY = 30.0


def resolve(progress, verb: str, *, fraction: bool = False):
    """The callable a study passes down for its ``progress`` argument: None for False or None,
    the caller's own callable, or a `Shown` for True. ``fraction``: the study reports the
    fraction done (one number) instead of (done, total, runs per second)."""
    if progress is None or progress is False:
        return None
    if progress is True:
        return Shown(verb, fraction=fraction)
    if callable(progress):
        return progress
    from railride.errors import InputError

    raise InputError(f"progress = {progress!r}: allowed True (shown), False (silent) or a callable")


def shows_progress(verb: str, *, fraction: bool = False):
    """Decorate a study whose keyword ``progress`` follows `resolve`: the study receives the
    callable (or None), and a bar it showed is closed when it returns or fails."""

    def decorate(study):
        default = inspect.signature(study).parameters["progress"].default

        @functools.wraps(study)
        def run(*args, **kwargs):
            shown = resolve(kwargs.get("progress", default), verb, fraction=fraction)
            kwargs["progress"] = shown
            try:
                return study(*args, **kwargs)
            finally:
                if isinstance(shown, Shown):
                    shown.close()

        return run

    return decorate


class Shown:
    """Progress on stderr, from the first report after `DELAY` s: a rich bar where rich can draw
    one live (a terminal, Jupyter), else a plain line every `EVERY` s. ``clock`` and ``stream``
    (where the lines go; never a live bar) are for tests."""

    def __init__(self, verb: str, *, fraction: bool = False, clock=time.monotonic, stream=None):
        self.verb, self.fraction, self.clock = verb, fraction, clock
        self.stream = stream
        self.start = clock()
        self.last_line = -math.inf
        self.console: Any = None  # rich's console on stderr, made at the first report shown
        self.bar: Any = None  # a rich Progress once shown live
        self.task: Any = None

    def __call__(self, done, total=None, runs_per_second: float = math.nan) -> None:
        now = self.clock()
        if now - self.start < DELAY:
            return
        if self.fraction:
            done, total = round(100 * float(done)), 100
        text = self._text(done, total, runs_per_second)
        if self.console is None and self.stream is None:
            from rich.console import Console

            self.console = Console(stderr=True)
        if self.console is not None and (self.console.is_terminal or self.console.is_jupyter):
            self._bar(self.console, done, total, text)
        elif now - self.last_line >= EVERY:
            self.last_line = now
            print(text, file=self.stream or sys.stderr, flush=True)

    def _text(self, done, total, rate) -> str:
        unit = "%" if self.fraction else "runs"
        count = f"{done}/{total} {unit}" if total else f"{done} {unit}"
        speed = f", {rate:.1f} runs/s" if isinstance(rate, float) and math.isfinite(rate) and rate > 0 else ""
        return f"{self.verb}: {count}{speed} ({self.clock() - self.start:.0f} s)"

    def _bar(self, console, done, total, text) -> None:
        if self.bar is None:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

            # one bar for the whole call, its batches one after another; gone when it ends
            self.bar = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                MofNCompleteColumn(),
                TimeElapsedColumn(),
                console=console,
                transient=True,
                auto_refresh=False,
            )
            self.bar.start()
            self.task = self.bar.add_task(self.verb, total=total)
        self.bar.update(self.task, completed=done, total=total, description=text.split(" (")[0], refresh=True)

    def close(self) -> None:
        """Stop a live bar (`shows_progress` calls it when the study returns)."""
        if self.bar is not None:
            self.bar.stop()
            self.bar = None
