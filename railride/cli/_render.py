"""Rich tables and text that several commands print: the response labels and number formats,
the ride comfort tables, the damper description and the modes table; and the --report file
that compare, sweep, tune, study and ride-spectrum write of their result (`save_report`)."""

from __future__ import annotations

from pathlib import Path
from typing import Optional

import typer

from railride.cli._common import CliError, command_line, errors, status_note

#: table labels of the four ride responses (keys of railride.analysis.metrics.RESPONSES)
RESPONSE_LABELS = {
    "acceleration_m_s2": "acceleration (m/s^2)",
    "displacement_m": "displacement (m)",
    "pitch_deg": "pitch (deg)",
    "roll_deg": "roll (deg)",
}


def fmt(value, spec: str) -> str:
    return "-" if value is None else format(value, spec)


def reduction_text(value, spec: str = ".1f") -> str:
    if value is None:
        return ""
    text = format(value, spec)
    return f"[red]{text}[/red]" if value < 0 else text


def damper_text(settings: dict) -> str:
    from railride.analysis.labels import describe_dampers

    return describe_dampers(settings, detail=True)


# -- ride comfort: simulate and compare ---------------------------------------------------------
#: (index, row label, format) of the comfort tables of `simulate` and `compare`
COMFORT_ROWS = (
    ("aw_Wk", "a_w Wk (m/s^2)", ".4f"),
    ("vdv_Wk", "VDV Wk (m/s^1.75)", ".4f"),
    ("aw_Wb", "a_w Wb (m/s^2)", ".4f"),
    ("N_MV_z", "N_MV,z (EN 12299)", ".3f"),
    ("Wz", "Wz (Sperling)", ".3f"),
)
#: where the comfort tables' positions are on the carbody floor
POSITION_LABELS = {"centre": "carbody centre", "front": "above the front bogie", "rear": "above the rear bogie"}
SHORT_POSITION_LABELS = {"centre": "centre", "front": "front bogie", "rear": "rear bogie"}


def _comfort_caption(record: dict) -> str:
    start, end = record["window_s"]
    return "\n".join(
        [
            "floor points at x = "
            + ", ".join(f"{p['x_m']:g} m" for p in record["positions"].values())
            + f"; window {start:g}-{end:g} s",
            *record["notes"],
            *([] if record.get("n_intervals", 0) >= 60 else ["*: the class of an indicative N_MV,z"]),
        ]
    )


def comfort_table(record: dict):
    """The comfort table of `simulate`: one row per index, one column per position."""
    from rich.markup import escape

    from railride.cli._width import FitTable

    positions = record["positions"]
    table = FitTable(title="Ride comfort (carbody floor)", caption=escape(_comfort_caption(record)))
    table.add_column("index")
    for name in positions:
        table.add_column(escape(POSITION_LABELS.get(name, name)), justify="right")
    for key, label, spec in COMFORT_ROWS:
        table.add_row(escape(label), *[format(p[key], spec) for p in positions.values()])
    # EN 12299's class reads 60 intervals of 5 s; from fewer it is an indication (the caption says how many)
    label = "comfort class (N_MV,z)" + ("" if record.get("n_intervals", 0) >= 60 else "*")
    table.add_row(label, *[p["N_MV_z_class"] for p in positions.values()])
    return table


def compare_comfort_table(rows: list[dict]):
    """The "ride comfort" table of `compare`: the indices at each position (rows), the
    suspensions (columns) with the reduction against passive where meaningful; on a narrow
    console one table per group of suspensions, each beside passive."""
    from rich.markup import escape

    from railride.cli._width import FitTable, Split

    first = rows[0]["comfort"]
    caption = escape(
        _comfort_caption(first) + "\nred. % = (passive - controlled) / "
        "passive x 100; none for Wz, which is not proportional to the "
        "acceleration"
    )

    def build(group: list[dict]):
        table = FitTable(title="Ride comfort on the carbody floor: centre and above the bogies", caption=caption)
        # the position heads its rows (not a column of its own): two suspensions fit 80 columns
        table.add_column("position, index")
        for r in group:
            table.add_column(escape(r["label"].replace(" (", "\n(")), justify="right", min_width=8)
            if r["name"] != "passive":
                table.add_column("red. %", justify="right", no_wrap=True)
        blank = [""] * (len(table.columns) - 1)
        for pos in first["positions"]:
            table.add_row(f"[bold]{escape(SHORT_POSITION_LABELS.get(pos, pos))}[/bold]", *blank)
            for key, label, spec in COMFORT_ROWS:
                cells = [escape(label)]
                for r in group:
                    cells.append(format(r["comfort"]["positions"][pos][key], spec))
                    if r["name"] != "passive":
                        red = r["comfort"].get("reduction_percent", {}).get(pos, {}).get(key)
                        cells.append(reduction_text(red))
                table.add_row(*cells)
            cells = ["class (N_MV,z)" + ("" if first.get("n_intervals", 0) >= 60 else "*")]
            for r in group:
                cells.append(r["comfort"]["positions"][pos]["N_MV_z_class"])
                if r["name"] != "passive":
                    cells.append("")
            table.add_row(*cells, end_section=True)
        return table

    passive = [r for r in rows if r["name"] == "passive"]
    return Split(build, [r for r in rows if r["name"] != "passive"], repeat=passive)


# -- modes: modes and frf -----------------------------------------------------------------------
def modes_table(rows: list[dict], caption: str | None = None):
    from rich.markup import escape

    from railride.cli._width import FitTable

    table = FitTable(title="Modes of the passive vehicle", caption=None if caption is None else escape(caption))
    table.add_column("#", justify="right")
    table.add_column("mode", no_wrap=True)
    table.add_column("undamped (Hz)", justify="right")
    table.add_column("damped (Hz)", justify="right")
    table.add_column("damping ratio", justify="right")
    for i, r in enumerate(rows, start=1):
        table.add_row(
            str(i),
            escape(r["label"]),
            f"{r['frequency_hz']:.3f}",
            f"{r['damped_frequency_hz']:.3f}",
            f"{r['damping_ratio']:.3f}",
        )
    return table


def alike_text(alike: dict) -> str:
    """The line saying how alike the laws were tuned (`GainSet.tuning_budget`)."""
    runs = ", ".join(f"{n} {r}" for n, r in alike["runs"].items())
    per_set = alike.get("runs_per_gain_set")
    if per_set:
        text = (
            f"Tuned alike: every law by the same study and objective, with at most {alike['budget']} gain sets "
            f"each, every set scored on the same {per_set} runs (gain sets used: {runs})."
        )
    else:
        text = (
            f"Tuned alike: every law by the same study and objective, with at most {alike['budget']} vehicle runs "
            f"each (runs used: {runs})."
        )
    return text + stopped_text(alike.get("stopped") or {})


#: why a tuning study stopped, in words (`railride.studies.tuning`)
STOPPED_WORDS = {
    "budget": "stopped when its budget ran out, before it converged",
    "converged": "converged",
    "passes": "stopped after its last pass, before it converged",
}


def stopped_text(stopped: dict) -> str:
    """The sentence on why the studies stopped (" Every study stopped when its budget ran out,
    before it converged."), each law's reason where they differ; empty without reasons."""
    if not stopped:
        return ""
    reasons = set(stopped.values())
    if len(reasons) == 1:
        reason = reasons.pop()
        word = STOPPED_WORDS.get(reason, reason)
        return f" {'Every study' if len(stopped) > 1 else 'The study'} {word}."
    return " " + "; ".join(f"{n} {STOPPED_WORDS.get(r, r)}" for n, r in stopped.items()) + "."


def untuned_text(names) -> str:
    """The line naming the laws the gains file's study did not tune (`GainSet.untuned`)."""
    return (
        f"Not tuned: {', '.join(names)} run with the starting values of their gains tables (docs/control.md), "
        "not tuned like the others: a fair ranking needs them tuned by the same study."
    )


def warn_gains_mismatch(settings: dict, damper_given: Optional[str] = None) -> None:
    """The result's ``gains_mismatch`` (`GainSet.mismatch`: gains tuned for another vehicle,
    load or track, and the `railride tune` command for this one) as one warning line on
    stderr, before the results; nothing where the settings have none. ``damper_given``: the
    --damper text, whose file's path takes the place of the command's ``FILE.toml`` (the
    library holds the damper's parameters, not the file they came from)."""
    import shlex

    from railride.secondary.dampers import NAMES

    line = settings.get("gains_mismatch")
    if line:
        if damper_given and damper_given not in NAMES:
            line = line.replace("--damper FILE.toml", f"--damper {shlex.quote(damper_given)}")
        typer.echo(f"warning: {line}", err=True)


#: columns of the console the report's tables are rendered on (an HTML page scrolls sideways)
REPORT_WIDTH = 120


def check_report_option(path: Optional[Path], option: str = "--report") -> None:
    """Before any run: ValueError naming ``option`` if no report can be written at ``path``."""
    if path is not None:
        from railride.output.report import check_report_path

        check_report_path(path, option)


def save_report(path: Path, result, parts=(), ctx: Optional[typer.Context] = None) -> None:
    """Write the report of ``result`` to ``path``, with ``parts`` (the rich tables and texts the
    command prints) rendered as HTML, and the command line of ``ctx`` as given; say so on
    stderr. A file that cannot be written: ``error: ...``, status 2."""
    import io

    from rich.console import Console

    from railride.output.report import write_report

    console = Console(record=True, file=io.StringIO(), width=REPORT_WIDTH, highlight=False)
    for part in parts:
        console.print(part)
    fragment = console.export_html(inline_styles=True, code_format='<pre class="console">{code}</pre>')
    with errors():
        try:
            with status_note(f"writing the report {path}..."):
                write_report(
                    result,
                    path,
                    console_html=[fragment] if parts else [],
                    command=None if ctx is None else command_line(ctx),
                )
        except OSError as exc:
            raise CliError(f"cannot write the report {path}: {exc.strerror or exc}", 2) from None
    typer.echo(f"wrote {path}", err=True)


def gains_text(source: str, shipped: bool) -> str:
    """Which gain set a run took, in words: a shipped set by its name and what it was tuned on
    (the library takes the robust set on random and measured track, `GainSet.for_tracks`)."""
    if not shipped:
        return f"gains file {source}"
    from railride.secondary.control import SHIPPED

    if source.endswith(SHIPPED["robust"]):
        return (
            f"gains: the shipped robust set {source}, tuned on random track and taken on random and measured "
            "track (--gains paper: the set tuned on the paper's sine)"
        )
    return (
        f"gains: the shipped paper set {source}, tuned on the paper's sine and taken on the sine and the bump "
        "(--gains robust: the set tuned on random track)"
    )


def stops_note(rows: list[dict]) -> str:
    """The bump stops under the damper table: their clearance, and which suspensions reached it."""
    clearance = next((r["damper"].get("clearance_m") for r in rows), None)
    if clearance is None:
        return " The vehicle has no bump stops: the travel is unbounded."
    stiffness = next((r["damper"].get("stop_stiffness_n_per_m", 0.0) for r in rows), 0.0)
    hit = [r["label"] for r in rows if r["damper"].get("reached_stops")]
    if not hit:
        if stiffness <= 0.0:  # a clearance with no stop modelled at it: a limit to read, not a force
            return (
                f" No suspension's travel passed the {clearance * 1e3:g} mm clearance (z_stop; this vehicle models "
                "no stop force there, k_stop = 0)."
            )
        return f" No suspension reached the bump stops ({clearance * 1e3:g} mm clearance)."
    if stiffness > 0.0:
        return (
            f" *: reached the bump stops at {clearance * 1e3:g} mm ({', '.join(hit)}): the stops bound "
            "that travel and carry force there."
        )
    return (
        f" *: beyond the {clearance * 1e3:g} mm clearance to the bump stops ({', '.join(hit)}), which this "
        "vehicle gives no stiffness (k_stop = 0): that travel is not bounded, and a real car would be on its stops."
    )
