"""The ``railride`` Typer application, which every command module registers on."""

from __future__ import annotations

import typer

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_show_locals=False,
    rich_markup_mode=None,
    help="Vertical ride of a 9-DOF railway vehicle: the paper's comparison of passive, PID and "
    "SAS suspensions (start with `railride compare`), modes and frequency responses, "
    "simulated ride metrics on sine, bump, measured or random tracks, and MR damper rig "
    "tests (hysteresis cycles, force tracking).",
)
