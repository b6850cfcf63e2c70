"""``railride modes``: natural frequencies and damping of the passive vehicle (railride.frf)."""

from __future__ import annotations

from ._app import app
from ._common import errors, print_json, stdout_console
from ._options import FormatOption, OutputFormat, ParamsOption, PresetOption
from ._parsing import vehicle_source
from ._render import modes_table


@app.command()
def modes(
    format: FormatOption = OutputFormat.table,
    params: ParamsOption = None,
    preset: PresetOption = None,
) -> None:
    """Natural frequencies and damping of the passive vehicle (9 modes, ascending frequency)."""
    with errors():
        from ..frf import modes as vehicle_modes

        rows = vehicle_modes(vehicle_source(params, preset)).to_list()
    if format is OutputFormat.json:
        print_json(rows)
        return
    stdout_console().print(modes_table(rows))
