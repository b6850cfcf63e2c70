"""The ``railride`` command line: ``railride compare``, ``railride modes``, ``railride frf``,
``railride simulate``, ``railride damper``, ``railride tracking``, ``railride tune``,
``railride study``, ``railride pareto``, ``railride sweep`` and ``railride report``.

A thin layer over the library: it parses options, calls the library's studies (`simulate`,
`compare`, `frf`, `rig`, `tune`, `study`, `pareto`, `sweep`), writes their results through their
`save()` and `railride.files`, and prints. See docs/cli.md. One module per command (`rig` holds `damper`
and `tracking`); `_options` declares the options several commands share, `_parsing` the
checks of their values, `_common` the errors, consoles and run machinery, `_render` the
shared tables, `_width` the tables that fit the console's width (80 columns on a pipe).

Exit statuses: 0 success, 1 the simulation diverged, 2 bad input (usage errors, invalid values,
unreadable files, an output folder that cannot be written), 130 `tune`, `study`, `pareto` or `sweep`
interrupted by Ctrl-C (the finished runs stay in DIR/runs.csv for --resume). Errors print one line
``error: <message>`` on stderr, never a traceback.
"""

from __future__ import annotations

# the commands register on `app` when imported, and `railride --help` lists them in this order
from . import compare, report, modes, frf, simulate, rig, tune, pareto, sweep, study, ride_spectrum  # noqa: F401
from ._app import app

__all__ = ["app", "main"]


def main() -> None:
    """Entry point of the ``railride`` console script."""
    app(prog_name="railride")
