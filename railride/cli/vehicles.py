"""``railride vehicles``: the named vehicle parameter sets, where their values come from, and their
modes (`railride.model.vehicle.presets_document`)."""

from __future__ import annotations

import textwrap
from typing import Annotated, Optional

import typer

from railride.cli._app import app
from railride.cli._common import errors, print_json, stdout_console
from railride.cli._options import FormatOption, OutputFormat
from railride.cli._render import modes_table
from railride.model.params import PRESETS


@app.command()
def vehicles(
    format: FormatOption = OutputFormat.table,
    preset: Annotated[
        Optional[str],
        typer.Option(
            "--preset",
            metavar="NAME",
            help=f"Only this preset ({', '.join(PRESETS)}). Default: every preset.",
        ),
    ] = None,
) -> None:
    """The named vehicles (the presets of --preset and of a parameters file's preset = "..."),
    each with the source of its values and its modes, nine or, with a bending carbody, ten
    (undamped and damped frequency, damping ratio). docs/model.md, Presets, lists every value as source or assumed."""
    with errors():
        from railride.model.vehicle import presets_document

        doc = presets_document(None if preset is None else [preset])
    if format is OutputFormat.json:
        print_json(doc)
        return
    console = stdout_console()
    for i, entry in enumerate(doc["presets"]):
        if i:
            console.print()
        line = textwrap.fill(f"{entry['name']}: {entry['source']}", width=console.width, break_on_hyphens=False)
        console.print(line, markup=False, soft_wrap=True)
        table = modes_table(entry["modes"])
        table.title = f"Modes of {entry['name']} (passive)"
        console.print(table)
