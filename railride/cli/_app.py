"""The ``railride`` Typer application, which every command module registers on."""

from __future__ import annotations

import typer

app = typer.Typer(
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
        from .. import __version__

        typer.echo(f"railride {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Vertical ride of a railway vehicle with a semi-active secondary suspension."""
