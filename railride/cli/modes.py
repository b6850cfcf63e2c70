"""``railride modes``: natural frequencies and damping of the passive vehicle (railride.frequency.frf)."""

from __future__ import annotations

from railride.cli._app import app
from railride.cli._common import errors, print_json, stdout_console
from railride.cli._options import FormatOption, LoadOption, OutputFormat, PresetOption, VehicleOption
from railride.cli._parsing import vehicle_arguments
from railride.cli._render import modes_table


@app.command()
def modes(
    format: FormatOption = OutputFormat.table,
    vehicle: VehicleOption = None,
    preset: PresetOption = None,
    load: LoadOption = None,
) -> None:
    """Natural frequencies and damping of the linear passive vehicle (viscous secondary dampers
    c_sz; 9 modes, 10 with a bending carbody; ascending frequency)."""
    with errors():
        from railride.frequency.frf import modes as vehicle_modes
        from railride.model.params import vehicle_text

        doc = vehicle_modes(**vehicle_arguments(vehicle, preset, load)).to_dict()
    if format is OutputFormat.json:
        print_json(doc)
        return
    stdout_console().print(modes_table(doc["modes"], vehicle_text(doc["vehicle"])))
