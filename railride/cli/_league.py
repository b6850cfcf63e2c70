"""``railride compare`` with several scenarios, speeds, track seeds or load factors: the league
table (railride.studies.league.league), and its tables."""

from __future__ import annotations

import json
from typing import Callable

import typer

from railride.errors import InputError
from railride.cli._common import ProgressBar, stderr_is_terminal, stdout_console, write_folder
from railride.cli._options import OutputFormat
from railride.cli._parsing import damper_argument, load_gains, parse_scale, vehicle_arguments
from railride.cli._render import alike_text, fmt, untuned_text, warn_gains_mismatch


def run_league(
    scenarios,
    speeds,
    seeds,
    given,
    *,
    names,
    gains,
    damper,
    damper_scale,
    solver,
    duration,
    window,
    vehicle,
    preset,
    loads,
    format,
    out,
    bounds,
    figures=None,
    report=None,
    ctx=None,
) -> None:
    """Several scenarios, speeds, track seeds or load factors (``loads``: --load's list, None:
    load 1): the league table (railride.studies.league.league), every case at every load."""
    from railride.output.files import check_out_dir, write_league_outputs
    from railride.studies.league import league
    from railride.analysis.metrics import parse_window

    options = {
        "amplitude": "--amplitude",
        "wavelength": "--wavelength",
        "rail_phase": "--rail-phase",
        "min_wavelength": "--min-wavelength",
        "max_wavelength": "--max-wavelength",
        "start": "--start",
        "sensor_noise": "--sensor-noise",
        "seed": "--seed",
        "fault": "--fault",
        "delay": "--delay",
        "sensing": "--sensing",
    }
    for key, value in given.items():
        if value is not None:
            raise InputError(
                f"{options[key]}: applies to a single scenario; a league table (several --scenario, --speed, "
                "--track-seed or --load values) runs each scenario with its defaults"
            )
    if not bounds:
        raise InputError(
            "--no-references (or --no-bounds): a league table always shows the ideal actuator beside the MR dampers"
        )
    damper_given, damper = damper, damper_argument("--damper", damper)
    loads = loads or [1.0]
    for x in loads:  # each load checked before the first run, its errors naming --load
        vehicle_options = vehicle_arguments(vehicle, preset, x)
    vehicle_options["load"] = loads if len(loads) > 1 else loads[0]
    if out is not None:
        check_out_dir(out, "--out")
    with ProgressBar(stderr_is_terminal(), lambda done: "running the league table...") as progress:
        table = league(
            scenarios,
            speeds,
            track_seeds=seeds or [0],
            **vehicle_options,
            controllers=names,
            gains=load_gains(gains),
            damper=damper,
            damper_scale=parse_scale("--damper-scale", damper_scale),
            duration=duration,
            window=parse_window(window) if window is not None else None,
            solver=solver,
            progress=lambda k, n: progress(k / n),
        )
    doc = table.to_dict()
    text = json.dumps(doc, indent=2, allow_nan=False)
    if out is not None:
        write_folder(out, lambda: write_league_outputs(table, out, figures=figures))
    parts = league_table(table, doc)
    warn_gains_mismatch(doc["settings"], damper_given)
    if format is OutputFormat.json:
        typer.echo(text)
    else:
        console = stdout_console()
        for part in parts:
            console.print(part)
    if report is not None:  # after the table: a report that cannot be written loses no output
        from railride.cli._render import save_report

        save_report(report, table, parts, ctx)


def league_table(table, doc) -> list:
    """One row per controller: mean RMS reductions (MR, ideal actuator), comfort, force, travel;
    on a narrow console the reductions, and the comfort and damper columns, in two tables."""
    from rich.text import Text

    from railride.analysis.labels import describe_scenario
    from railride.cli._width import FitTable, Split
    from railride.model.params import vehicle_text

    summary = table.summary
    cases = table.cases[table.cases.controller == "passive"]
    tuned = doc["tuned_on"]
    tuned_text = doc["settings"].get("gains_tuned_on") or (
        describe_scenario(tuned) if tuned else "not recorded in the gains file"
    )
    out_of_sample = int((~cases["in_sample"]).sum())
    settings = doc["settings"]
    at = "" if settings["speeds_m_s"] is None else " at " + ", ".join(f"{v:g}" for v in settings["speeds_m_s"]) + " m/s"
    seeds = ", ".join(map(str, sorted(set(cases["track_seed"].dropna().astype(int)))))  # random tracks' only
    loads = _loads(settings["vehicle"])
    at_loads = f", each at loads {', '.join(f'{x:g}' for x in loads)}" if len(loads) > 1 else ""
    pooled = [w for w, n in (("speeds", len(set(table.cases["speed_m_s"]))), ("loads", len(loads))) if n > 1]
    caption = (
        f"Mean over {len(cases)} cases: {', '.join(settings['scenarios'])}{at}{at_loads}"
        + (f"; track seeds {seeds} (random tracks)" if seeds else "")
        + ".\n"
        + (
            f"This mean pools the {' and '.join(pooled)}: see the table per scenario, speed and load below "
            "for each on its own.\n"
            if pooled
            else ""
        )
        + f"{vehicle_text(settings['vehicle'])}.\n"
        f"Gains tuned on: {tuned_text}. Tested on {out_of_sample} case(s) they were not tuned on"
        f" and {len(cases) - out_of_sample} they were.\n"
        "Reduction = (passive - controlled) / passive RMS x 100, MR dampers (ideal actuator, same gains, in brackets)."
        + ("\n" + alike_text(settings["tuned_alike"]) if settings.get("tuned_alike") else "")
        + ("\n" + untuned_text(settings["untuned"]) if settings.get("untuned") else "")
    )

    def reduction(key: str) -> Callable[[dict], str]:
        def cell(row: dict) -> str:
            if row["name"] == "passive":
                return "-"
            mr, ideal = row.get(f"{key}_reduction_percent"), row.get(f"{key}_ideal_reduction_percent")
            return ("n/a" if mr is None else f"{mr:.1f}") + (" (-)" if ideal is None else f" ({ideal:.0f})")

        return cell

    columns: dict[str, Callable[[dict], str]] = {  # heading -> cell of a row of doc["controllers"]
        "acceleration\n(%)": reduction("acceleration_m_s2"),
        "displacement\n(%)": reduction("displacement_m"),
        "pitch\n(%)": reduction("pitch_deg"),
        "roll\n(%)": reduction("roll_deg"),
        "a_w Wk\ncentre\n(m/s^2)": lambda row: fmt(summary.loc[row["name"]].get("centre_aw_Wk"), ".3f"),
        "N_MV,z\ncentre": lambda row: fmt(summary.loc[row["name"]].get("centre_N_MV_z"), ".2f"),
        "damper\nforce max\n(kN)": lambda row: fmt(summary.loc[row["name"]]["force_max_n"] / 1e3, ".1f"),
        "travel\nmax\n(mm)": lambda row: fmt(summary.loc[row["name"]]["travel_max_m"] * 1e3, ".1f"),
    }
    headings = list(columns)

    def build(groups: list[list[str]]):
        t = FitTable(title="League table")
        t.add_column("suspension")
        for heading in (h for g in groups for h in g):
            # "MR (ideal)" stays on one line
            t.add_column(heading, justify="right", no_wrap=heading.endswith("(%)"))
        for row in doc["controllers"]:
            t.add_row(row["label"], *[columns[h](row) for g in groups for h in g])
        return t

    groups = [headings[:4], headings[4:6], headings[6:]]  # reductions, comfort, damper
    return [Split(build, groups), Text(caption), "", *_by_speed_table(doc)]


def _loads(record: dict) -> list[float]:
    """The load factors of a `vehicle_record`: one, or the list of a league over several."""
    load = record["load"]
    return [float(x) for x in load] if isinstance(load, list) else [float(load)]


def _by_speed_table(doc) -> list:
    """Per scenario, speed and load factor (never pooled), over the track seeds: each
    response's RMS reduction % (mean, 5th to 95th percentile) and its absolute RMS (mean),
    passive included."""
    from rich.text import Text

    from railride.cli._width import FitTable, Split
    from railride.secondary.control import LABELS

    units = {"acceleration_m_s2": "m/s^2", "displacement_m": "m", "pitch_deg": "deg", "roll_deg": "deg"}
    words = {
        "acceleration_m_s2": "acceleration",
        "displacement_m": "displacement",
        "pitch_deg": "pitch",
        "roll_deg": "roll",
    }
    rows: dict[tuple, dict] = {}
    for r in doc["by_speed"]:
        rows.setdefault((r["scenario"], r["speed_m_s"], r.get("load", 1.0), r["controller"]), {})[r["response"]] = r

    def cell(r: dict, key: str) -> str:
        if key == "rms":
            return f"{r['rms_mean']:#.4g}"
        if r["reduction_mean"] is None:
            return "-"
        return f"{r['reduction_mean']:.1f} ({r['reduction_p5']:.0f} to {r['reduction_p95']:.0f})"

    heads = [(resp, "red", f"{words[resp]}\nred. % (p5 to p95)") for resp in units]
    heads += [(resp, "rms", f"{words[resp]}\nRMS ({units[resp]})") for resp in units]

    def build(groups: list[list[tuple]]):
        t = FitTable(title="Per scenario, speed and load, over the track seeds")
        t.add_column("case")
        t.add_column("load", justify="right")
        t.add_column("suspension")
        for resp, key, heading in (h for g in groups for h in g):
            t.add_column(heading, justify="right", no_wrap=key == "red")
        last = None
        for (scen, speed, load, name), resp_rows in rows.items():
            case = f"{scen} {speed:g} m/s"
            t.add_row(
                case if case != (last or ("",))[0] else "",
                f"{load:g}" if (case, load) != last else "",
                LABELS[name],
                *[cell(resp_rows[resp], key) for resp, key, _ in (h for g in groups for h in g)],
            )
            last = (case, load)
        return t

    note = (
        "Speeds and loads are kept apart, not pooled: each row is the mean over the track seeds at that speed "
        "and load factor, with the 5th to 95th percentile of the reduction in brackets, and the absolute RMS "
        "beside it."
    )
    return [Split(build, [heads[:2], heads[2:4], heads[4:6], heads[6:]]), Text(note)]
