"""``railride compare`` with several scenarios, speeds or track seeds: the league table
(railride.league.league), and its table."""

from __future__ import annotations

import json

import typer

from ._common import ProgressBar, stderr_is_terminal, wide_stdout_console, write_folder
from ._options import OutputFormat
from ._parsing import damper_preset, load_gains, parse_scale, vehicle_from_options
from ._render import alike_text, fmt, untuned_text


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
    params,
    preset,
    load,
    format,
    out,
    bounds,
) -> None:
    """Several scenarios, speeds or track seeds: the league table (railride.league.league)."""
    from ..files import check_out_dir, write_league_outputs
    from ..league import league
    from ..metrics import parse_window

    options = {
        "amplitude": "--amplitude",
        "wavelength": "--wavelength",
        "rail_phase": "--rail-phase",
        "min_wavelength": "--min-wavelength",
        "max_wavelength": "--max-wavelength",
        "sensor_noise": "--sensor-noise",
        "seed": "--seed",
        "fault": "--fault",
        "delay": "--delay",
        "sensing": "--sensing",
    }
    for key, value in given.items():
        if value is not None:
            raise ValueError(
                f"{options[key]}: applies to a single scenario; a league table (several --scenario, --speed "
                "or --track-seed values) runs each scenario with its defaults"
            )
    if not bounds:
        raise ValueError("--no-bounds: a league table always shows the ideal actuator beside the MR dampers")
    damper_preset("--damper", damper)
    vehicle_params, vehicle_record = vehicle_from_options(params, preset, load)
    if out is not None:
        check_out_dir(out)
    with ProgressBar(stderr_is_terminal(), lambda done: "running the league table...") as progress:
        table = league(
            scenarios,
            speeds,
            track_seeds=seeds or [0],
            params=vehicle_params,
            controllers=names,
            gains=load_gains(gains),
            damper=damper,
            damper_scale=parse_scale("--damper-scale", damper_scale),
            duration=duration,
            window=parse_window(window) if window is not None else None,
            solver=solver,
            progress=(lambda k, n: progress(k / n)) if progress.enabled else None,
        )
    doc = table.to_dict()
    text = json.dumps(doc, indent=2, allow_nan=False)
    if out is not None:
        write_folder(out, lambda: write_league_outputs(table, out))
    if format is OutputFormat.json:
        typer.echo(text)
        return
    wide_stdout_console().print(league_table(table, doc))


def league_table(table, doc):
    """One row per controller: mean RMS reductions (MR, ideal actuator), comfort, force, travel."""
    from rich.table import Table

    from ..labels import describe_scenario

    summary = table.summary()
    cases = table.cases[table.cases.controller == "passive"]
    tuned = doc["tuned_on"]
    tuned_text = describe_scenario(tuned) if tuned else "not recorded in the gains file"
    out_of_sample = int((~cases["in_sample"]).sum())
    settings = doc["settings"]
    at = "" if settings["speeds_m_s"] is None else " at " + ", ".join(f"{v:g}" for v in settings["speeds_m_s"]) + " m/s"
    seeds = ", ".join(map(str, settings["track_seeds"]))
    caption = (
        f"Mean over {len(cases)} cases: {', '.join(settings['scenarios'])}{at}; track seeds {seeds} (random tracks).\n"
        f"Gains tuned on: {tuned_text}. Tested on {out_of_sample} case(s) they were not tuned on"
        f" and {len(cases) - out_of_sample} they were.\n"
        "Reduction = (passive - controlled) / passive RMS x 100, MR dampers (ideal actuator, same gains, in brackets)."
        + ("\n" + alike_text(settings["tuned_alike"]) if settings.get("tuned_alike") else "")
        + ("\n" + untuned_text(settings["untuned"]) if settings.get("untuned") else "")
    )
    t = Table(title="League table", caption=caption, caption_justify="left")
    t.add_column("suspension")
    for label in ("acceleration", "displacement", "pitch", "roll"):
        t.add_column(f"{label}\n(%)", justify="right")
    t.add_column("a_w Wk\ncentre\n(m/s^2)", justify="right")
    t.add_column("N_MV,z\ncentre", justify="right")
    t.add_column("damper\nforce max\n(kN)", justify="right")
    t.add_column("travel\nmax\n(mm)", justify="right")
    for row in doc["controllers"]:
        n = row["name"]
        cells = []
        for r in ("acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg"):
            if n == "passive":
                cells.append("-")
                continue
            mr, ideal = row.get(f"{r}_reduction_percent"), row.get(f"{r}_ideal_reduction_percent")
            cells.append(("n/a" if mr is None else f"{mr:.1f}") + (" (-)" if ideal is None else f" ({ideal:.0f})"))
        s = summary.loc[n]
        cells += [
            fmt(s.get("centre_aw_Wk"), ".3f"),
            fmt(s.get("centre_N_MV_z"), ".2f"),
            fmt(s["force_max_n"] / 1e3, ".1f"),
            fmt(s["travel_max_m"] * 1e3, ".1f"),
        ]
        t.add_row(row["label"], *cells)
    return t
