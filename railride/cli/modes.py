"""``railride modes``: natural frequencies and damping of the passive vehicle."""

from __future__ import annotations

import json

import typer

from ._app import app
from ._common import errors, stdout_console
from ._options import FormatOption, OutputFormat, ParamsOption, PresetOption
from ._parsing import vehicle_from_options
from ._render import modes_table


@app.command()
def modes(
    format: FormatOption = OutputFormat.table,
    params: ParamsOption = None,
    preset: PresetOption = None,
) -> None:
    """Natural frequencies and damping of the passive vehicle (9 modes, ascending frequency)."""
    with errors():
        from ..vehicle import Vehicle

        vehicle_params, _ = vehicle_from_options(params, preset)
        rows = [m.to_dict() for m in Vehicle(vehicle_params).modes()]
    if format is OutputFormat.json:
        typer.echo(json.dumps(rows, indent=2, allow_nan=False))
        return
    stdout_console().print(modes_table(rows))
