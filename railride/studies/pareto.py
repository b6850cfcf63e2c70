"""A Pareto view of a controller's gains: what trades are on offer, before any objective picks one.

`pareto` samples the gains of one controller (a seeded, scrambled Sobol' sample, uniform in
log10 over the search box of `railride.studies.optimise`, REFERENCE / 1000 to REFERENCE x 100), adds
the base gains as a sample of their own, runs every sample through `railride.studies.sweep.run_cases`
(compiled batches, a resumable run table, a Dask cluster if asked) and returns a `ParetoResult`:
the four RMS ratios to passive per sample (acceleration, displacement, pitch, roll), its largest
secondary travel against passive's, and which samples are non-dominated, over the four ratios,
in the two planes the plot shows (acceleration against pitch, acceleration against roll), and
over the four ratios and the travel.

A sample is dominated when another is at least as good in every ratio and better in one; the
non-dominated ones are the trades no objective over these ratios can improve on all at once.
Every objective of `railride.studies.tuning` that weighs the ratios positively is minimised by one of
them (over this sample).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import pandas as pd

from railride.errors import InputError
from railride.secondary.provenance import tuned_tracks
from railride.secondary.control import PAPER_CONTROLLERS, GainSet
from railride.defaults import DEFAULT_DAMPER
from railride.output.files import PARETO_FILES
from railride.analysis.metrics import RESPONSES, still_passive
from railride.model.params import resolve_vehicle
from railride.plots import PNG_DPI, FigureOptions
from railride.studies.progress import shows_progress
from railride.studies.optimise import GainEvaluator, log_gain_bounds
from railride import limits, validation
from railride.run.checks import check
from railride.run.solver import SolverSettings
from railride.studies.sweep import Case, RunTable
from railride.secondary.suspension import Suspension, damper_record

SCHEMA = "railride.pareto/1"
#: the files `ParetoResult.save` writes, in this order
FILES = PARETO_FILES  # the files `ParetoResult.save` writes
#: the gains each controller reads (the inner loop stays at the base gains: it is one setting
#: per compiled batch)
CONTROLLER_PARAMETERS = {
    n: sum((GainSet.entry_names(t) for t in GainSet.tables_read(n) if t != "inner"), ()) for n in PAPER_CONTROLLERS[1:]
}  # the paper's controllers: their gains span the log box below (a blend such as hybrid's alpha would not)
#: the ratios, by their short names, in the order of RESPONSES
RATIOS = ("acceleration", "displacement", "pitch", "roll")
#: the planes of the plot, each with its own non-dominated flag
PROJECTIONS = (("acceleration", "pitch"), ("acceleration", "roll"))
#: what a sample holds until the study returns: its case, its key and row in the run table and
#: the frame's copy (a peak of 8.4 kB a sample measured over 1024 samples)
SAMPLE_BYTES = 8 * limits.VALUE_BYTES
#: the most points of scipy's Sobol' sequence (its 30 bits)
MAX_SAMPLES = 2**30
SAMPLING = (
    "scrambled Sobol' sequence (scipy.stats.qmc.Sobol), uniform in log10 of each gain "
    "between REFERENCE / 1000 and REFERENCE x 100"
)


def non_dominated(points) -> np.ndarray:
    """True for each row of ``points`` (n, m) that no other row dominates (all columns lower is
    better: another row dominates it when it is <= in every column and < in one). Equal rows do
    not dominate each other; a row with a NaN is never non-dominated, and dominates nothing."""
    p = np.asarray(points, dtype=float)
    if p.ndim != 2:
        raise InputError(f"points of shape {p.shape}: expected (n, m)")
    valid = ~np.isnan(p).any(axis=1)
    keep = np.zeros(len(p), dtype=bool)
    front: list[int] = []
    # a row can be dominated only by one with a smaller or equal sum: visit in that order and
    # compare with the front found so far (a row dominated by a dominated row is dominated by
    # a front row too); rows equal in sum may still dominate a front row, which is then dropped
    for i in np.argsort(p.sum(axis=1), kind="stable"):
        if not valid[i]:
            continue
        if front:
            f = p[front]
            if ((f <= p[i]).all(axis=1) & (f < p[i]).any(axis=1)).any():
                continue
            beaten = (p[i] <= f).all(axis=1) & (p[i] < f).any(axis=1)
            front = [j for j, b in zip(front, beaten) if not b]
        front.append(int(i))
    keep[front] = True
    return keep


@dataclass(frozen=True, eq=False)
class ParetoResult:
    """The samples of `pareto`: ``gains`` (n, d) in SI for ``parameters``, ``rms`` (n, 4) of
    acceleration, displacement, pitch, roll, ``passive`` (4,) the passive RMS. Row 0 is the base
    gains, rows 1..n_samples the Sobol' sample. ``bounds`` (d, 2): the log10 box sampled."""

    suspension: str
    parameters: tuple
    bounds: np.ndarray
    gains: np.ndarray
    rms: np.ndarray
    passive: np.ndarray
    scenario: dict
    settings: dict = field(default_factory=dict)
    note: str | None = None  # said on the figure and in the JSON
    #: the ratios of each sample's columns, and the planes the figure draws (read by the plots)
    RATIOS: ClassVar[tuple[str, ...]] = RATIOS
    PROJECTIONS: ClassVar[tuple[tuple[str, str], ...]] = PROJECTIONS
    runs: int = 0  # rows of the run table at the end
    #: (n,) each sample's largest secondary travel [m], and passive's (None: not measured)
    travel_max: np.ndarray | None = None
    passive_travel_max: float | None = None

    @property
    def ratios(self) -> np.ndarray:
        """(n, 4) RMS / RMS(passive)."""
        return self.rms / self.passive

    @property
    def non_dominated(self) -> np.ndarray:
        """Non-dominated over the four ratios."""
        return non_dominated(self.ratios)

    @property
    def travel_ratio(self) -> np.ndarray | None:
        """(n,) largest secondary travel / passive's (None: not measured)."""
        if self.travel_max is None or not self.passive_travel_max:
            return None
        return self.travel_max / self.passive_travel_max

    @property
    def non_dominated_with_travel(self) -> np.ndarray | None:
        """Non-dominated over the four ratios and the travel ratio: the trades that count the
        suspension's travel too (None: not measured)."""
        travel = self.travel_ratio
        return None if travel is None else non_dominated(np.column_stack([self.ratios, travel]))

    def front_travel(self) -> dict | None:
        """What the four-ratio front asks of the travel, which its ratios do not weigh: its
        ``samples``, how many move the secondary more than passive by more than a comparison's
        level tolerance (``more_than_passive``, the ``largest_ratio`` among them), and how many
        reach the vehicle's clearance z_stop (``past_clearance``; None without bump stops).
        None where the travel was not measured."""
        from railride.studies.comparison import LEVEL_TOLERANCE

        ratio = self.travel_ratio
        if ratio is None:
            return None
        on = ratio[self.non_dominated & np.isfinite(ratio)]
        more = on[on > 1.0 + LEVEL_TOLERANCE]
        values = (self.settings.get("vehicle") or {}).get("values") or {}
        clearance = values.get("z_stop")
        return {
            "samples": int(on.size),
            "more_than_passive": int(more.size),
            "largest_ratio": float(more.max()) if more.size else None,
            "clearance_m": clearance,
            "stop_stiffness_n_per_m": values.get("k_stop") or 0.0,
            "past_clearance": None if not clearance else int((on * self.passive_travel_max >= clearance).sum()),
        }

    def non_dominated_in(self, x: str, y: str) -> np.ndarray:
        """Non-dominated in the plane of ratios ``x`` and ``y`` (names of RATIOS)."""
        return non_dominated(self.ratios[:, [RATIOS.index(x), RATIOS.index(y)]])

    def to_pandas(self) -> pd.DataFrame:
        """One row per sample: ``sample`` (0 = the base gains), ``base``, the gains (SI, one
        column per "table.entry"), ``<response>_rms``, ``<response>_ratio``, ``travel_max_m``
        and ``travel_ratio`` (where measured) and the flags ``non_dominated``,
        ``non_dominated_<x>_<y>`` for each plotted plane and ``non_dominated_with_travel``."""
        n = len(self.gains)
        frame = pd.DataFrame({"sample": np.arange(n), "base": np.arange(n) == 0})
        for j, p in enumerate(self.parameters):
            frame[p] = self.gains[:, j]
        ratios = self.ratios
        for k, r in enumerate(RESPONSES):
            frame[f"{r}_rms"] = self.rms[:, k]
        for k, r in enumerate(RESPONSES):
            frame[f"{r}_ratio"] = ratios[:, k]
        if self.travel_max is not None:
            frame["travel_max_m"] = self.travel_max
            frame["travel_ratio"] = self.travel_ratio
        frame["non_dominated"] = self.non_dominated
        for x, y in PROJECTIONS:
            frame[f"non_dominated_{x}_{y}"] = self.non_dominated_in(x, y)
        if self.travel_max is not None:
            frame["non_dominated_with_travel"] = self.non_dominated_with_travel
        return frame

    def to_dict(self) -> dict:
        """The `railride.pareto/1` document (docs/cli.md): settings, the search box, the passive
        RMS, counts, and every sample as a row of `to_pandas`."""
        from railride._version import __version__, versions
        from railride.analysis.labels import gain_unit

        frame = self.to_pandas()
        flags = ["non_dominated"] + [f"non_dominated_{x}_{y}" for x, y in PROJECTIONS]
        flags += ["non_dominated_with_travel"] if self.travel_max is not None else []
        rows = [{k: _plain(v) for k, v in row.items()} for row in frame.to_dict("records")]
        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            "suspension": self.suspension,
            "scenario": self.scenario,
            "settings": self.settings,
            "parameters": [
                {
                    "name": p,
                    "unit": gain_unit(p),
                    "low": float(10.0**lo),
                    "high": float(10.0**hi),
                    "base": float(self.gains[0, j]),
                }
                for j, (p, (lo, hi)) in enumerate(zip(self.parameters, self.bounds))
            ],
            "passive_rms": dict(zip(RESPONSES, map(float, self.passive))),
            "passive_travel_m": None if self.passive_travel_max is None else float(self.passive_travel_max),
            "front_travel": self.front_travel(),
            "counts": {"samples": len(frame), **{f: int(frame[f].sum()) for f in flags}},
            "note": self.note,
            "runs": int(self.runs),
            "columns": list(frame.columns),
            "samples": rows,
        }

    def plot(self, ax=None):
        """Acceleration ratio against pitch ratio, and against roll ratio (two panels; ``ax``
        None for a new figure, or two Axes). Returns the figure."""
        from railride.plots.pareto import plot_pareto

        return plot_pareto(self, ax)

    def save(self, folder, *, figure_formats=("png",), dpi: float = PNG_DPI) -> list:
        """pareto.png, pareto.csv, pareto.json into ``folder``, all or nothing (each file
        replaced atomically; other files, such as a run table, stay); the figure in each of
        ``figure_formats`` (png, pdf, svg), PNG at ``dpi``. Returns the paths."""
        from railride.output.files import write_pareto_outputs

        return write_pareto_outputs(self, folder, figures=FigureOptions(figure_formats, dpi))


def _plain(value):
    """A JSON value: Python bool, int or float; None for NaN or infinity (strict JSON)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    value = float(value)
    return value if math.isfinite(value) else None


def _power_of_two(name: str, value) -> int:
    ok = not isinstance(value, bool) and isinstance(value, (int, np.integer)) and value >= 1 and not value & (value - 1)
    if not ok:
        raise InputError(
            f"{name} = {value!r}: must be a power of two (1, 2, 4, ..., 128, ...), which "
            "keeps the balance of the Sobol' sample"
        )
    return int(value)


def _parameters(suspension: str, parameters) -> tuple:
    from railride import arguments

    if not isinstance(suspension, str) or suspension not in CONTROLLER_PARAMETERS:
        raise InputError(f"suspension = {suspension!r}: allowed {', '.join(CONTROLLER_PARAMETERS)}")
    allowed = CONTROLLER_PARAMETERS[suspension]
    if parameters is None:
        return allowed
    parameters = tuple(arguments.names("parameters", parameters, "gain names"))
    for p in parameters:
        if p not in allowed:
            raise InputError(f"parameter {p!r}: not a gain of {suspension}; allowed: {', '.join(allowed)}")
    if not parameters or len(set(parameters)) != len(parameters):
        raise InputError(f"parameters = {parameters!r}: one or more distinct gains of {suspension}")
    return parameters


def in_sample_note(gains: GainSet, record: dict) -> str | None:
    """A note when ``gains`` were tuned on the track ``record`` (`Scenario.describe`) that judges
    them (`GainSet.tuned_on`)."""
    if not gains.tuned_on(record):
        return None
    if len(tuned_tracks(gains.provenance)) > 1:  # a robust tuning's set holds this track among others
        return (
            f"The base gains ({gains.source}) were tuned on a set of tracks that holds this one at this "
            "speed, and are judged on it: their place here is in-sample, not a test on a track tuning never saw."
        )
    return (
        f"The base gains ({gains.source}) were tuned on this same single track and are judged "
        f"on it: their place here is in-sample, not a test on another track."
    )


@shows_progress("pareto")
def pareto(
    suspension: str = "sas-attitude-ride",
    *,
    n_samples: int = 128,
    seed: int = 0,
    scenario: str = "paper-sine",
    scenario_options=None,
    gains: GainSet | None = None,
    damper: str = DEFAULT_DAMPER,
    executor=None,
    table: RunTable | None = None,
    vehicle=None,
    params=None,
    load: float = 1.0,
    solver=None,
    progress=True,
    parameters=None,
) -> ParetoResult:
    """Sample the gains of ``suspension`` (pid, sas-attitude, sas-attitude-ride; by default all
    it reads, or ``parameters``) and return the RMS ratios to passive of each sample.

    ``n_samples`` (a power of two) scrambled Sobol' points with ``seed``, in log10 between
    REFERENCE / 1000 and REFERENCE x 100 (the box of `railride.studies.optimise`), the other gains at
    ``gains`` (default the shipped `GainSet.default`), which are also run as sample 0. One call
    of `run_cases`: 32-run batches, ``table`` to resume, ``executor`` for Dask;
    ``progress``: True (the default: shown on stderr after 2 s, `railride.studies.progress`),
    False (silent) or a callable ``progress(done, total, runs_per_second)`` after each chunk.
    ``vehicle`` (``params`` is
    an alias): a preset name, the path of a parameters file or `VehicleParams` (default
    "paper"), with the load factor ``load`` on its carbody, recorded in ``settings["vehicle"]``
    (`railride.model.params.vehicle_record`); ``solver``: the `SolverSettings` of every run;
    both recorded in ``settings`` where they differ from the defaults (the run keys). The base
    gains are recorded in ``settings["gains"]``, ``["gains_provenance"]`` and
    ``["gains_values"]`` (`GainSet.record`), the sampled entries in ``["gains_varied"]``. Every
    setting is checked before the first run.
    """
    from railride.secondary.suspension import damper_model
    from railride.studies.sweep import other_settings
    from railride.model.track import scenario as make_scenario

    solver = SolverSettings.of(solver)
    vehicle, vehicle_rec = resolve_vehicle(vehicle, params, load)
    names = _parameters(suspension, parameters)
    n_samples = _power_of_two("n_samples", n_samples)
    if n_samples > MAX_SAMPLES:  # scipy's Sobol' draws no more (an error that reads as a bug)
        raise InputError(f"n_samples = {n_samples}: at most 2**30 = {MAX_SAMPLES} (the Sobol' sequence's points)")
    # the memory of the study, before the sample is drawn ((n, d) floats) and its cases made: a
    # count past the memory would otherwise fail at numpy's allocation, a bug's message
    limits.check(
        SAMPLE_BYTES * (n_samples + 1),
        f"n_samples = {n_samples}: {n_samples + 1} runs",
        "give fewer samples",
    )
    seed = validation.seed("seed", seed)
    damper_model(damper)  # a known name
    from railride.studies.case import scenario_options as scenario_options_of

    scen = make_scenario(scenario, **scenario_options_of("scenario_options", scenario_options))
    base = GainSet.of(gains, scen)
    # its runs, checked by the check every simulation makes (railride.run.checks), before the first
    check(scen, vehicle, Suspension.named(suspension, base, damper), solver, "mark")
    record = scen.describe()
    table = RunTable() if table is None else table
    ev = GainEvaluator(
        names,
        suspension,
        scenario,
        scenario_options,
        base,
        None,
        damper,
        executor,
        table,
        progress,
        vehicle,
        solver,
        vehicle_columns={"vehicle": vehicle_rec["name"], "load": vehicle_rec["load"]},
        costs=True,  # the travel too: a trade in ride bought with rattle space is shown as one
    )
    bounds = np.array(log_gain_bounds(names))
    import scipy.stats.qmc  # here, not at import: scipy.stats costs half a second to load

    unit = scipy.stats.qmc.Sobol(len(names), scramble=True, seed=seed).random_base2(int(math.log2(n_samples)))
    points = scipy.stats.qmc.scale(unit, bounds[:, 0], bounds[:, 1])
    base_case = Case(scenario, ev.opts, suspension=suspension, damper=damper)
    rms, travel = ev.rms_travel([base_case, *ev.cases(points)])
    if not np.all(np.asarray(ev.passive, float) > 0):  # every ratio would be nan or inf
        raise InputError(still_passive(record))
    gains_si = np.vstack([[base.value(p) for p in names], 10.0**points])
    ran = base.record([suspension])  # the base gains (sample 0); the samples vary ``names``
    settings = {
        "n_samples": n_samples,
        "seed": seed,
        "sampling": SAMPLING,
        "damper": damper_record(damper),
        "dt_s": solver.dt,
        **solver.backend_record(),
        "base_gains": ran["source"],
        "base_gains_tuned_on": (base.provenance or {}).get("scenario"),
        # the gains record (`GainSet.record`) of the base gains, and the entries the samples set
        # instead (their values in ``samples``)
        "gains": ran["source"],
        "gains_provenance": ran["provenance"],
        "gains_values": ran["values"],
        "gains_varied": list(names),
        "vehicle": vehicle_rec,
        **other_settings(vehicle, solver),
        # base gains tuned for another vehicle, load or track: one line (`GainSet.mismatch`)
        **({"gains_mismatch": m} if (m := base.mismatch(vehicle_rec, record, damper=damper)) else {}),
    }
    return ParetoResult(
        suspension,
        names,
        bounds,
        gains_si,
        rms,
        np.asarray(ev.passive, float),
        record,
        settings,
        in_sample_note(base, record),
        len(table.frame),
        travel,
        ev.passive_travel,
    )
