"""Options that several commands share, each declared once as a ``typing.Annotated`` alias.

Where commands word an option's help differently (what --out writes, what --gains starts
from), there is one alias per wording, built by the option's factory; the defaults stay in
the commands' signatures. Options of one command only are declared in its module."""

from __future__ import annotations

from enum import Enum
from pathlib import Path
from typing import Annotated, Optional

import typer

from railride.defaults import DEFAULT_OBJECTIVE_KIND
from railride.errors import InputError


class OutputFormat(str, Enum):
    table = "table"
    json = "json"


FormatOption = Annotated[
    OutputFormat, typer.Option("--format", case_sensitive=False, help="Output on stdout: a table or a JSON document.")
]


# -- vehicle ------------------------------------------------------------------------------------
def _presets() -> str:
    from railride.model.params import PRESETS

    return ", ".join(PRESETS)


VehicleOption = Annotated[
    Optional[str],
    typer.Option(
        "--vehicle",
        "--params",
        metavar="NAME|FILE.toml",
        help=f"The vehicle: a preset ({_presets()}) or a TOML file with a [vehicle] table (see "
        "docs/cli.md). --params is the same option. Exclusive with --preset. Default: paper.",
    ),
]
LoadOption = Annotated[
    Optional[float],
    typer.Option(
        "--load",
        metavar="X",
        help="Load factor: the carbody's mass and inertias times X (1: as the parameters give "
        "them; 1.3: crush-laden, 30 % more mass). The controllers keep their gains. Default: 1.",
    ),
]
PresetOption = Annotated[
    Optional[str],
    typer.Option(
        "--preset",
        metavar="NAME",
        help=f"Named vehicle parameter set ({_presets()}), as --vehicle NAME. Default: paper.",
    ),
]


# -- scenario -----------------------------------------------------------------------------------
def _scenario(help: str):
    return Annotated[str, typer.Option("--scenario", metavar="NAME", help=help)]


SCENARIO_HELP = (
    "paper-sine (the paper's sine rails), bump (a cosine bump on both rails), "
    "file:PATH (a measured CSV with columns s, z_L, z_R in metres), or a random "
    "track: fra1..fra6 (FRA classes; 6 is the best track), german-low, "
    "german-high, or psd:PATH, your own spectrum table (docs/track.md) "
    "(see --track-seed, --min-wavelength, --max-wavelength)."
)
#: simulate: every scenario explained
ScenarioOption = _scenario(SCENARIO_HELP)
CompareScenarioOption = _scenario(
    "paper-sine (the paper's sine rails), bump, file:PATH, fra1..fra6, german-low, german-high or psd:PATH, as for "
    "simulate."
)
#: tune, pareto and sweep
RunsScenarioOption = _scenario(
    "paper-sine, bump, file:PATH, fra1..fra6, german-low, german-high or psd:PATH, as for simulate."
)

AmplitudeOption = Annotated[
    Optional[float],
    typer.Option(
        "--amplitude",
        metavar="M",
        help="paper-sine: sine amplitude [m] (default 0.05). bump: bump height [m], negative for a dip (default 0.02).",
    ),
]
WavelengthOption = Annotated[
    Optional[float],
    typer.Option(
        "--wavelength", metavar="M", help="paper-sine: wavelength [m] (default 60). bump: bump length [m] (default 10)."
    ),
]
RailPhaseOption = Annotated[
    Optional[float],
    typer.Option(
        "--rail-phase", metavar="DEG", help="paper-sine only: phase lag of the right rail [deg] (default 90)."
    ),
]
SpeedOption = Annotated[
    Optional[float], typer.Option("--speed", metavar="M/S", help="Vehicle speed [m/s] (default 55.56).")
]
FrfSpeedOption = Annotated[
    Optional[float],
    typer.Option(
        "--speed", metavar="M/S", help="Vehicle speed [m/s]: sets the delays between the wheelsets (default 55.56)."
    ),
]
TrackSeedOption = Annotated[
    Optional[int],
    typer.Option(
        "--track-seed",
        metavar="N",
        help="Random tracks (fra1..fra6, german-low, german-high, psd:PATH) only: the seed of the track's "
        "realisation, a whole number >= 0; the same seed gives the same track (default 0).",
    ),
]
StartOption = Annotated[
    Optional[float],
    typer.Option(
        "--start",
        metavar="M",
        help="A measured profile (--scenario file:PATH) only: run its section from s = M m on, as a "
        "track of its own (a design's section k starts at k times its fastest speed x duration), >= 0.",
    ),
]
MinWavelengthOption = Annotated[
    Optional[float],
    typer.Option(
        "--min-wavelength",
        metavar="M",
        help="Random tracks only: shortest wavelength of the irregularity [m] (default 1); "
        "speed / M must not exceed the output rate / 2.5.",
    ),
]
MaxWavelengthOption = Annotated[
    Optional[float],
    typer.Option(
        "--max-wavelength",
        metavar="M",
        help="Random tracks only: longest wavelength of the irregularity [m] (default 100).",
    ),
]

# -- steps, windows, rates ----------------------------------------------------------------------
DurationOption = Annotated[
    Optional[float], typer.Option("--duration", metavar="S", help="Simulated time [s] (default 10).")
]
#: tune, pareto and sweep
RunDurationOption = Annotated[
    Optional[float], typer.Option("--duration", metavar="S", help="Simulated time of each run [s] (default 10).")
]
DtOption = Annotated[
    Optional[float],
    typer.Option(
        "--dt",
        metavar="S",
        help="Fixed time step [s] (default 1e-4): RK4's step, which must keep it stable; a run by the "
        "exact discretisation (the linear vehicle: passive dampers, or the ideal actuator with exact states; "
        "never in an FMU) steps once per output and controller sample, and dt only spaces its rail-input grid.",
    ),
]
MethodOption = Annotated[
    Optional[str],
    typer.Option(
        "--method",
        metavar="auto|rk4|exact",
        help="How runs are integrated: auto (the default: the exact discretisation where the suspension is linear "
        "and its maps are few, RK4 otherwise), rk4 (always), exact (the passive or ideal-actuator vehicle only).",
    ),
]
BackendOption = Annotated[
    Optional[str],
    typer.Option(
        "--backend",
        metavar="auto|cpu|gpu",
        help="Where batches of runs step: auto (the default: a GPU where one is usable, for batches that would "
        "step sooner there than on the CPU's threads), cpu, or gpu (an error where there is none; "
        "pip install 'railride[gpu]').",
    ),
]
OutputRateOption = Annotated[
    Optional[float],
    typer.Option(
        "--output-rate",
        metavar="HZ",
        help="Sampling rate of the stored time histories [Hz] (default 1000); 1/(rate x dt) must be a whole number.",
    ),
]
ControlRateOption = Annotated[
    float,
    typer.Option(
        "--control-rate",
        metavar="HZ",
        help="Sample rate of the outer-loop controllers [Hz]; 1/(rate x dt) must be a whole number.",
    ),
]
#: compare and sweep
WindowOption = Annotated[
    Optional[str],
    typer.Option(
        "--window", metavar="START:END", help="Time window of the metrics [s], e.g. 2:10 (default: the whole run)."
    ),
]
SimulateWindowOption = Annotated[
    Optional[str],
    typer.Option(
        "--window",
        metavar="START:END",
        help="Time window of the metrics [s], e.g. 2:10; either side may be empty (default: the whole run).",
    ),
]
ComfortOption = Annotated[
    bool,
    typer.Option(
        "--comfort",
        help="Also evaluate the ride comfort indices on the carbody floor at the centre and above "
        "the bogies (ISO 2631-1 a_w and VDV, the vertical part of EN 12299 N_MV, Sperling's "
        "Wz; docs/comfort.md) over the metrics window.",
    ),
]
SweepComfortOption = Annotated[
    bool,
    typer.Option(
        "--comfort/--no-comfort",
        help="Evaluate the ride comfort indices of every run (columns centre_aw_Wk, "
        "centre_N_MV_z, front_N_MV_z, rear_N_MV_z, centre_Wz, ...; docs/comfort.md) and, "
        "with sweep.png, plot them against the axis in comfort.png (default: on; "
        "--no-comfort for RMS and peak-to-peak only).",
    ),
]


# -- dampers ------------------------------------------------------------------------------------
def _damper(kind, help: str):
    return Annotated[kind, typer.Option("--damper", metavar="MODEL|FILE.toml", help=help + OWN_DAMPER)]


#: every --damper takes a user's own MR damper too
OWN_DAMPER = " Or FILE.toml: your own MR damper's parameters, a [damper] table (docs/dampers.md)."


CompareDamperOption = _damper(
    str,
    (
        "Dampers of the controlled suspensions: the MR models railway, dyke1996 or "
        "spencer1997; ideal-damper (the ideal semi-active damper: the demand where it "
        "dissipates, else 0; a reference, not a bound) or ideal (an ideal actuator: force = "
        "the outer loop's demand)."
    ),
)
SimulateDamperOption = _damper(
    Optional[str],
    (
        "--suspension mr only: damper model railway, dyke1996 or spencer1997 "
        "(default railway). The ideal actuator (ideal) needs a controller: see compare "
        "and sweep."
    ),
)
TuneDamperOption = _damper(
    str,
    (
        "MR damper model: railway, dyke1996 or spencer1997 (ideal-damper or ideal, the "
        "ideal devices, without the inner phase)."
    ),
)
ParetoDamperOption = _damper(
    str, ("Dampers of the controlled runs: railway, dyke1996, spencer1997, ideal-damper or ideal.")
)
SweepDamperOption = _damper(
    Optional[str],
    (
        "mr and controllers: MR damper model railway, dyke1996 or spencer1997 "
        "(default railway); controllers only: ideal-damper (the ideal semi-active damper) or "
        "ideal (an ideal actuator whose force is the outer loop's demand)."
    ),
)
#: damper and tracking: the damper on the rig
RigModelOption = Annotated[
    str,
    typer.Option(
        "--damper",
        "--model",
        metavar="MODEL|FILE.toml",
        help="Damper model: railway, dyke1996 or spencer1997 (--model: the older name of the option)." + OWN_DAMPER,
    ),
]


def _damper_scale(help: str, metavar: str = "X"):
    # read as text, so that a word gets the one-line error too
    return Annotated[Optional[str], typer.Option("--damper-scale", metavar=metavar, help=help)]


CompareDamperScaleOption = _damper_scale(
    "Factor on the MR damper's force capacity, a finite number > 0 (every force "
    "parameter times X; default 1). Not with --damper ideal."
)
LevelToleranceOption = Annotated[
    Optional[float],
    typer.Option(
        "--level-tolerance",
        metavar="FRACTION",
        help="Two RMS values closer than this fraction of the larger are level on the trade-off "
        "lines, neither better nor worse: a finite number >= 0 and < 1 (default 0.01, 1 %).",
    ),
]
SimulateDamperScaleOption = _damper_scale(
    "--suspension mr only: factor on the damper's force capacity, a finite number > 0 "
    "(every force parameter times X; default 1)."
)
TuneDamperScaleOption = _damper_scale(
    "Factor on the MR damper's force capacity, a finite number > 0 (every force "
    "parameter times X; default 1); the inner phase tracks demands scaled alike. Not "
    "with an ideal damper."
)
SweepDamperScaleOption = _damper_scale(
    "mr and controllers: factors on the MR damper's force capacity (every force "
    "parameter times X), finite numbers > 0, a range or a list (default 1); a grid "
    "axis. passive runs once, unscaled; not with --damper ideal.",
    metavar="VALUES",
)


# -- gains and the tuning objective -------------------------------------------------------------
#: what the shipped default is, in every --gains help that takes it
_SHIPPED = (
    "the shipped set for the track: robust (railride/data/robust_gains.toml, tuned on random track) on "
    "random or measured track, paper (railride/data/gains.toml, tuned on the paper's sine) on the sine and bump"
)


def _gains(help: str):
    return Annotated[Optional[Path], typer.Option("--gains", metavar="paper|robust|FILE.toml", help=help)]


CompareGainsOption = _gains(
    "Controller gains: a shipped set (paper, robust) or a TOML file with [inner], [pid], [sas.attitude] "
    f"and [sas.ride] (default: {_SHIPPED})."
)
TuneGainsOption = _gains(
    "Start values: a gains file as for compare (default: the neutral reference gains, "
    "railride/data/reference_gains.toml)."
)
ParetoGainsOption = _gains(
    "Base gains: the gains not sampled (the inner loop's among them), and one sample "
    f"of their own (default: {_SHIPPED})."
)
SweepGainsOption = _gains(f"Controllers: the base gains that --gain changes (default: {_SHIPPED}).")
StudyGainsOption = _gains(f"Controller gains, kept for every load and fault (default: {_SHIPPED}).")

ObjectiveOption = Annotated[
    Optional[str],
    typer.Option(
        "--objective",
        metavar="KIND",
        help="What each run's RMS ratios to passive r_k (acceleration, displacement, pitch, "
        "roll) are scored by: sum (sum of r_k), weighted (sum of w_k r_k, --weights), "
        "minimax (the largest r_k), constrained (sum of r_k with every r_k <= --bound); or "
        "ride comfort: n_mv (the worst ratio to passive of EN 12299's N_MV,z over the floor's "
        "centre, front and rear), sperling (the same with Sperling's Wz). "
        f"Default: {DEFAULT_OBJECTIVE_KIND}; the statement is printed with the result.",
    ),
]
WeightsOption = Annotated[
    Optional[str],
    typer.Option(
        "--weights",
        metavar="A,D,P,R",
        help="--objective weighted: the weights of acceleration, displacement, pitch, roll; >= 0, not all 0.",
    ),
]
BoundOption = Annotated[
    Optional[str],
    typer.Option(
        "--bound",
        metavar="X",
        help="--objective constrained: the largest RMS ratio to passive allowed for every response, > 0.",
    ),
]
PenaltyOption = Annotated[
    Optional[str],
    typer.Option(
        "--penalty",
        metavar="X",
        help="Added to any objective: X times the sum of the RMS ratios above 1 (responses "
        "worse than passive); >= 0 (default 0).",
    ),
]

MaxPeakOption = Annotated[
    Optional[str],
    typer.Option(
        "--max-peak",
        metavar="X",
        help="A constraint on any objective: every run's peak-to-peak carbody acceleration at most X times "
        "passive's on the same track, > 0; a run above it is infeasible.",
    ),
]
MaxTravelOption = Annotated[
    Optional[str],
    typer.Option(
        "--max-travel",
        metavar="M",
        help="A constraint on any objective: every run's largest secondary travel [m] at most M (e.g. the bump "
        "stops' clearance), > 0; a run above it is infeasible.",
    ),
]

# -- executors: tune, pareto and sweep ----------------------------------------------------------
WorkersOption = Annotated[
    Optional[int],
    typer.Option(
        "--workers", metavar="N", help="Local executor: threads of each batch, 1..cores (default: every core)."
    ),
]
#: design and tune
OptimiserOption = Annotated[
    str,
    typer.Option(
        "--optimiser",
        metavar="sensitivity|evolution",
        help="How each law's gains are tuned within the budget: the paper's one-at-a-time sensitivity "
        "study, or differential evolution over all of a law's gains at once (SciPy).",
    ),
]
OptimiserSeedOption = Annotated[
    Optional[int],
    typer.Option(
        "--optimiser-seed", metavar="N", help="The seed of the evolution (with --optimiser evolution; default 0)."
    ),
]


def optimiser_seed(optimiser: str, seed: Optional[int]) -> int:
    """--optimiser-seed, which seeds the evolution alone: 0 where it is not given; an error with
    another optimiser, which would ignore it."""
    if seed is None:
        return 0
    if optimiser.strip() != "evolution":
        raise InputError(
            f"--optimiser-seed = {seed}: applies with --optimiser evolution only (the sensitivity study "
            "draws nothing at random)"
        )
    return seed


ProcessesOption = Annotated[
    Optional[int],
    typer.Option(
        "--processes",
        metavar="N",
        help="Local executor: N worker processes, each with its share of the cores, so that the chunks' Python work "
        "runs in parallel too (for many cores; docs/performance.md).",
    ),
]
SchedulerOption = Annotated[
    Optional[str],
    typer.Option(
        "--scheduler", metavar="ADDRESS", help="Run on a Dask cluster: the scheduler's address, e.g. tcp://host:8786."
    ),
]
SchedulerFileOption = Annotated[
    Optional[Path],
    typer.Option(
        "--scheduler-file",
        metavar="FILE",
        help="Run on a Dask cluster whose scheduler wrote FILE (dask scheduler --scheduler-file FILE).",
    ),
]


# -- output folders -----------------------------------------------------------------------------
def out_folder(text: str) -> Path:
    """--out's value as a path; an empty one is refused (Path("") would be the current folder)."""
    if not text.strip():
        raise typer.BadParameter(f"{text!r} is an empty folder name; give a folder (--out . for the current one)")
    return Path(text)


def _out(help: str):
    help += " Figures as PNG at 120 dpi unless --figure-format or --dpi say otherwise."
    return Annotated[Optional[Path], typer.Option("--out", metavar="DIR", help=help, parser=out_folder)]


CompareOutOption = _out(
    "Also write compare.json, compare.nc, compare.csv and the plots acceleration.png, "
    "displacement.png, pitch.png, roll.png, damper_forces.png, voltages.png, and the "
    "acceleration spectra psd.png, psd.csv into DIR (created if missing; all or "
    "nothing)."
)
FrfOutOption = _out(
    "Also write frf.csv, frf.json, frf.png and modes.csv into DIR (created if missing; all or nothing)."
)
SimulateOutOption = _out(
    "Also write ride.nc, ride.csv, metrics.json and body_responses.png into DIR (created if missing; all or nothing)."
)
DamperOutOption = _out(
    "Also write loops.png, cycles.csv and damper.json into DIR (created if missing; all or nothing)."
)
TrackingOutOption = _out(
    "Also write tracking.png, tracking.csv and tracking.json into DIR (created if missing; all or nothing)."
)
TuneOutOption = _out(
    "Keep the run table DIR/runs.csv (updated as runs finish) and write gains.toml, "
    "sensitivity.png (sensitivity_2.png, ... beyond 12 gains), curves.csv and tune.json into DIR at the end."
)
ParetoOutOption = _out(
    "Keep the run table DIR/runs.csv (updated as runs finish) and write pareto.png, pareto_caption.txt, "
    "pareto.csv and pareto.json into DIR at the end."
)
SweepOutOption = _out(
    "Keep the run table DIR/runs.csv (updated as runs finish) and write sweep.json "
    "(and sweep.png when one or two axes have several values) into DIR at the "
    "end."
)

StudyOutOption = _out(
    "Keep the run table DIR/runs.csv (updated as runs finish) and write study.json, "
    "study_summary.csv, study_runs.csv and study.png into DIR at the end."
)
DesignOutOption = _out(
    "Keep the run table DIR/runs.csv (updated as runs finish) and write design.json, design.csv, "
    "design_runs.csv, gains.toml, design.png and design_costs.png into DIR at the end."
)

# -- figures: every command that writes an output folder -------------------------------------------
FigureFormatOption = Annotated[
    Optional[str],
    typer.Option(
        "--figure-format",
        metavar="FORMATS",
        help="With --out: the figures' file formats, a comma list of png, pdf and svg (default "
        "png); each figure is written once per format (pitch.png, pitch.pdf).",
    ),
]
DpiOption = Annotated[
    Optional[str],
    typer.Option(
        "--dpi",
        metavar="N",
        help="With --out: the resolution of PNG figures [dots per inch], a number >= 10 and <= 1200 "
        "(default 120; 300 or 600 for print). PDF and SVG are vector.",
    ),
]


def figure_options(figure_format: Optional[str], dpi: Optional[str], out: Optional[Path]):
    """--figure-format and --dpi as a `railride.plots.FigureOptions` (read as text, so that a
    word gets the one-line error too); ValueError naming the option for a bad value, or for
    either without --out."""
    from railride.plots import PNG_DPI, FigureOptions

    given = [o for o, v in (("--figure-format", figure_format), ("--dpi", dpi)) if v is not None]
    if given and out is None:
        raise InputError(f"{given[0]}: applies with --out only (the figures are written into the output folder)")
    value = PNG_DPI if dpi is None else _number(dpi)
    try:
        return FigureOptions("png" if figure_format is None else figure_format, value)
    except ValueError as exc:
        text = str(exc).replace("figure_formats = ", "--figure-format = ", 1)
        raise InputError(text.replace("dpi = ", "--dpi = ", 1) if text.startswith("dpi") else text) from None


def _number(text: str):
    """``text`` as an int or float as typed, else the text itself (FigureOptions names it)."""
    for kind in (int, float):
        try:
            return kind(text)
        except ValueError:
            pass
    return text


def _resume(help: str):
    return Annotated[bool, typer.Option("--resume", help=help)]


TuneResumeOption = _resume(
    "Continue the study whose run table is DIR/runs.csv (needs --out): runs already there are not evaluated again."
)
ParetoResumeOption = _resume("Continue the study whose run table is DIR/runs.csv (needs --out).")
StudyResumeOption = _resume(
    "Continue the study whose run table is DIR/runs.csv (needs --out): runs already there are not evaluated again."
)
DesignResumeOption = _resume(
    "Continue the design whose run table is DIR/runs.csv (needs --out): runs already there are not evaluated again."
)
SweepResumeOption = _resume(
    "Continue the sweep whose run table is DIR/runs.csv (needs --out): runs already there are not evaluated again."
)

#: compare, sweep, tune and study: the HTML report of the result (railride.output.report)
ReportOption = Annotated[
    Optional[Path],
    typer.Option(
        "--report",
        metavar="FILE.html",
        help="Also write one self-contained HTML file of the result: settings, modal table, the "
        "tables printed here, the result's table and its figures, time histories and spectra "
        "interactive (docs/report.md).",
    ),
]


#: simulate and compare: the formats of the time histories in --out
HistoryFormatOption = Annotated[
    Optional[str],
    typer.Option(
        "--history-format",
        metavar="LIST",
        help="With --out: the time histories as one or more of nc (NetCDF), csv, mat (MATLAB), "
        "comma-separated (default nc,csv). --format stays what is printed on stdout.",
    ),
]


def history_options(history_format: Optional[str], out: Optional[Path]) -> tuple:
    """--history-format as the library's formats (`railride.output.files.history_formats`); ValueError
    naming the option for a bad value, or without --out."""
    from railride.output.files import history_formats

    if history_format is None:
        return history_formats()
    if out is None:
        raise InputError("--history-format: applies with --out only (the time histories are written into it)")
    try:
        return history_formats(history_format)
    except ValueError as exc:
        raise InputError(str(exc).replace("history_formats = ", "--history-format = ", 1)) from None


# -- limits ---------------------------------------------------------------------------------------
def _limit_setter(setter: str, field: str, option: str):
    """A callback that sets one of the library's limits (`railride.limits`) as the command
    starts; None puts the default back, so one command's limit never carries over to the next
    in one process. Errors name the option."""

    def set_limit(value: Optional[str]) -> Optional[str]:
        from railride import limits
        from railride.cli._common import errors

        with errors():
            try:
                getattr(limits, setter)(value)
            except ValueError as exc:
                raise InputError(str(exc).replace(field, option, 1)) from None
        return value

    return set_limit


MaxMemoryOption = Annotated[
    Optional[str],
    typer.Option(
        "--max-memory",
        metavar="SIZE",
        callback=_limit_setter("set_max_memory", "max_memory", "--max-memory"),
        help="The most memory a run may take, e.g. 4G or 512M (powers of 1024); a larger run is "
        "refused before it starts, saying what it would need. Default: half the machine's memory.",
    ),
]


MaxStepsOption = Annotated[
    Optional[str],
    typer.Option(
        "--max-steps",
        metavar="N",
        callback=_limit_setter("set_max_work", "max_steps", "--max-steps"),
        help="The most sample-steps (samples x steps) a run may take, e.g. 1e11; a longer run is "
        "refused before it starts, saying how long it would take. Default: 1e10, about 40 minutes.",
    ),
]
