"""Controllers judged on several tracks and speeds at once: the league table.

`league` runs `railride.compare` on every combination of scenario, speed and track seed (the
seeds apply to the random tracks only), at each load factor, with the same gains, and collects
per case, load and controller the RMS reduction of each response against passive, the same gains' reduction on
the ideal actuator (a reference for the same gains, not a bound), ride comfort at the carbody centre, and what the
controller asks of its dampers (force and travel). `LeagueTable` summarises it per controller
as the mean over the cases (`LeagueTable.summary`), and per controller, scenario, speed and
load over the track seeds (`LeagueTable.by_speed`: speed and load are design variables, never
pooled into one band), and says which cases the gains were tuned on (in-sample) and which they
meet for the first time (out-of-sample).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from railride.errors import InputError
from railride import arguments, validation
from railride.studies.progress import shows_progress
from railride.studies.comparison import check_controllers, compare
from railride.secondary.control import LABELS, PAPER_CONTROLLERS, GainSet
from railride.secondary.provenance import tuned_words
from railride.defaults import DEFAULT_DAMPER
from railride.plots import PNG_DPI, FigureOptions
from railride.model.track import is_random, scenario
from railride.secondary.suspension import damper_record
from railride.model.params import resolve_argument, resolve_vehicle, vehicle_record

SCHEMA = "railride.league/1"
RESPONSES = ("acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg")
#: comfort indices in the table (carbody centre): ISO 2631-1 a_w (Wk) and EN 12299 N_MV (vertical)
COMFORT = ("aw_Wk", "N_MV_z")
#: the percentiles of the bands per speed (`LeagueTable.by_speed`)
PERCENTILES = (5.0, 95.0)


@dataclass(frozen=True, eq=False)
class LeagueTable:
    """Per case (scenario, speed, seed), load factor and controller: ``cases`` (a DataFrame, one
    row each, the load factor in its ``load`` column); ``settings``: what was run;
    ``tuned_on``: the scenario record the gains were tuned on (None if the gains file does not
    say)."""

    cases: pd.DataFrame
    controllers: list[str]
    settings: dict = field(default_factory=dict)
    tuned_on: dict | None = None

    @property
    def summary(self) -> pd.DataFrame:
        """One row per controller (passive first): the mean over all the cases of every column
        of `cases` that is a number, and the number of cases (rows of `cases`). Where the league
        ran several speeds or load factors this mean pools them: a headline, not a statistic of
        one operating point; `by_speed` keeps each scenario, speed and load apart."""
        numeric = self.cases.select_dtypes("number").drop(columns=["speed_m_s", "track_seed", "load"], errors="ignore")
        table = numeric.groupby(self.cases["controller"], sort=False).mean()
        table["cases"] = self.cases.groupby("controller", sort=False).size()
        table["in_sample_cases"] = self.cases.groupby("controller", sort=False)["in_sample"].sum()
        return table.reindex(self.controllers)

    def by_speed(self) -> pd.DataFrame:
        """One row per controller, scenario, speed, load factor (column ``load``) and response:
        over the track seeds (the speeds and loads never pooled), the mean and the 5th and 95th
        percentiles of the RMS value (``rms_*``, absolute) and of its reduction against passive
        in % (``reduction_*``; NaN for passive), and the number of cases."""
        rows = []
        lo, hi = PERCENTILES
        cases = self.cases if "load" in self.cases else self.cases.assign(load=1.0)
        keys = ["controller", "scenario", "speed_m_s", "load"]
        for (name, scen, speed, load), part in cases.groupby(keys, sort=False):
            for r in RESPONSES:
                x = part[f"{r}_rms"].to_numpy(dtype=float)
                col = f"{r}_reduction_percent"
                red = part[col].to_numpy(dtype=float) if col in part else np.full(x.size, np.nan)
                red = red[np.isfinite(red)]
                rows.append(
                    {
                        "controller": name,
                        "scenario": scen,
                        "speed_m_s": float(speed),
                        "load": float(load),
                        "response": r,
                        "cases": int(x.size),
                        "rms_mean": float(x.mean()),
                        "rms_p5": float(np.percentile(x, lo)),
                        "rms_p95": float(np.percentile(x, hi)),
                        "reduction_mean": float(red.mean()) if red.size else np.nan,
                        "reduction_p5": float(np.percentile(red, lo)) if red.size else np.nan,
                        "reduction_p95": float(np.percentile(red, hi)) if red.size else np.nan,
                    }
                )
        return pd.DataFrame(rows)

    def to_pandas(self) -> pd.DataFrame:
        return self.cases.copy()

    def report_contents(self):
        """What this result shows in its HTML report (`railride.output.report.write_report`)."""
        from railride.output.report import league_contents

        return league_contents(self)

    def to_dict(self) -> dict:
        def clean(v):
            if isinstance(v, (float, np.floating)):
                return float(v) if np.isfinite(v) else None
            if isinstance(v, np.integer):
                return int(v)
            if isinstance(v, np.bool_):
                return bool(v)
            return v

        summary = self.summary
        return {
            "schema": SCHEMA,
            "settings": self.settings,
            "tuned_on": self.tuned_on,
            "controllers": [
                {"name": n, "label": LABELS[n], **{k: clean(v) for k, v in summary.loc[n].items()}}
                for n in self.controllers
            ],
            "cases": [{k: clean(v) for k, v in row.items()} for row in self.cases.to_dict("records")],
            "by_speed": [{k: clean(v) for k, v in row.items()} for row in self.by_speed().to_dict("records")],
        }

    def plot(self, ax=None):
        """Bar chart of the mean RMS reductions per controller and response, with the
        ideal-actuator reference as an outline beside each bar."""
        from railride.plots.league import plot_league

        return plot_league(self, ax=ax)

    def save(self, folder, *, figure_formats=("png",), dpi: float = PNG_DPI):
        """league.json, league.csv (one row per case and controller), league.png and
        league_comfort.png (N_MV against speed), the figures in each of ``figure_formats``
        (png, pdf, svg), PNG at ``dpi``."""
        from railride.output.files import write_league_outputs

        return write_league_outputs(self, folder, figures=FigureOptions(figure_formats, dpi))


def _cases(scenarios, speeds, track_seeds):
    for name in scenarios:
        if not isinstance(name, str):
            raise InputError(f"scenario = {name!r}: must be a scenario name")
    speeds = [None] if speeds is None else [validation.number("speed", v, "positive", "m/s") for v in speeds]
    seeds = [validation.seed("track_seed", s) for s in track_seeds]
    if not seeds:
        raise InputError("track_seeds: give at least one seed (default 0)")
    for name, v in itertools.product(scenarios, speeds):
        for seed in seeds if is_random(name) else [None]:
            yield name, v, seed


@shows_progress("league")
def league(
    scenarios=("paper-sine",),
    speeds=None,
    *,
    track_seeds=(0,),
    vehicle=None,
    params=None,
    load: float | Sequence[float] = 1.0,
    controllers=PAPER_CONTROLLERS,
    gains: GainSet | None = None,
    damper: str = DEFAULT_DAMPER,
    damper_scale: float = 1.0,
    duration: float | None = None,
    window=None,
    solver=None,
    comfort: bool = True,
    progress=True,
) -> LeagueTable:
    """Run `compare` on every (scenario, speed, track seed) at every load factor with the same
    gains and collect the league table. ``scenarios``: names (`railride.scenario`); ``speeds``
    [m/s] (None: each scenario's default); ``track_seeds``: the random-track realisations
    (ignored by the other scenarios). ``vehicle`` (``params`` is an alias): the vehicle as
    `compare` takes it; ``load``: one load factor on its carbody or a list of them (e.g.
    ``[1.0, 1.3]``), each > 0 and listed once, all checked before the first run; every case
    runs at every load (`resolve_vehicle` per load). The vehicle is recorded in
    ``settings["vehicle"]`` (`vehicle_record`: its ``load`` the list where there are several)
    and in the ``vehicle`` column of `cases`, the load of each row in its ``load`` column.
    The other arguments are `compare`'s; the bounds (ideal devices) are always run;
    ``settings["gains_mismatch"]``: the one line of `GainSet.mismatch` over every case and
    load, when the gains were tuned for another vehicle, load or track.
    `LeagueTable.summary` pools the speeds and loads; `LeagueTable.by_speed` keeps them apart.
    ``progress``: True (the default: shown on stderr after 2 s, `railride.studies.progress`),
    False (silent) or a callable ``progress(done_runs, total_runs)``, called after each case at
    each load."""
    scenarios = list(scenarios) if not isinstance(scenarios, str) else [scenarios]
    if not scenarios:
        raise InputError("scenarios: give at least one scenario name")
    names = check_controllers(controllers)
    loads = _loads(load)
    # every load checked and its vehicle resolved before the first run
    cars = [resolve_vehicle(vehicle, params, x)[0] for x in loads]
    record = vehicle_record(*resolve_argument(vehicle, params), loads)
    gains = GainSet.of(gains, scenarios)
    # every scenario is built (and checked) before the first run
    todo = [
        (n, v, s, scenario(n, speed=v, seed=s, duration=duration)) for n, v, s in _cases(scenarios, speeds, track_seeds)
    ]
    rows = []
    runs = list(itertools.product(todo, zip(loads, cars)))  # every case at every load, the loads inner
    for k, ((name, speed, seed, sc), (x, car)) in enumerate(runs):
        comp = compare(
            sc,
            car,
            controllers=names,
            gains=gains,
            damper=damper,
            damper_scale=damper_scale,
            window=window,
            solver=solver,
            comfort=comfort,
            bounds=True,
            progress=False,
        )
        rows.extend(_rows(comp, name, sc.speed, seed, record["name"], x))
        if progress is not None:
            progress(k + 1, len(runs))
    record_of_gains = gains.record(names)
    settings = {
        "scenarios": scenarios,
        "vehicle": record,
        "speeds_m_s": None if speeds is None else [float(v) for v in speeds],
        "track_seeds": [int(s) for s in track_seeds],
        "damper": damper_record(damper),
        "damper_scale": float(damper_scale),
        "duration_s": duration,
        "window_s": None if window is None else [float(w) for w in window],
        # the gains every case ran: where they came from, how they were found, every value
        "gains": record_of_gains["source"],
        "gains_provenance": record_of_gains["provenance"],
        "gains_values": record_of_gains["values"],
        "objective": gains.provenance.get("objective"),
        "untuned": gains.untuned(names),
        "tuned_alike": gains.tuning_budget(names),
        "gains_tuned_on": tuned_words(gains.provenance),  # every track of a robust set, in words
    }
    # gains tuned for another vehicle, load or track: one line for every case (`GainSet.mismatch`)
    mismatch = gains.mismatch(record, [sc.describe() for *_, sc in todo], names, damper, damper_scale)
    if mismatch:
        settings["gains_mismatch"] = mismatch
    return LeagueTable(pd.DataFrame(rows), names, settings, gains.provenance.get("scenario_record"))


def _loads(load) -> list[float]:
    """``load``: one load factor or a list of them -> the checked list (each a finite number
    > 0, none listed twice, at least one), errors naming ``load``."""
    many = isinstance(load, (list, tuple, np.ndarray, pd.Series))
    items = list(load) if many else [load]
    if not items:
        raise InputError("load = []: give at least one load factor, a finite number > 0 (e.g. 1.0 or [1.0, 1.3])")
    allowed = "a finite number > 0 (the factor on the carbody mass), or a list of them"
    loads = [validation.number("load", x, "positive", allowed=allowed) for x in items]
    twice = arguments.repeated(loads)
    if twice:
        raise InputError(f"load = {loads}: {twice[0]:g} is listed twice; give each load factor once")
    return loads


def _rows(comp, name: str, speed: float, seed, vehicle: str, load: float) -> list[dict]:
    red = comp.reductions
    demands = comp.demands()
    bound = (comp.bounds_record() or {}).get("ideal", {})  # reductions of the same gains on the ideal actuator
    rows = []
    for n in comp.names:
        row = {
            "scenario": name,
            "speed_m_s": float(speed),
            "track_seed": seed,
            "vehicle": vehicle,
            "load": float(load),
            "controller": n,
            "in_sample": bool(comp.in_sample),
        }
        for r in RESPONSES:
            row[f"{r}_rms"] = float(comp.metrics.sel(controller=n, response=r, statistic="rms"))
            if n != "passive":
                row[f"{r}_reduction_percent"] = float(red.sel(controller=n, response=r, statistic="rms"))
                ideal = (bound.get(n) or {}).get("reduction_percent", {}).get(r)  # None: diverged or no bound
                row[f"{r}_ideal_reduction_percent"] = np.nan if ideal is None else ideal
        if comp.comfort is not None:
            for i in COMFORT:
                row[f"centre_{i}"] = float(comp.comfort[n].sel(position="centre", index=i))
        d = demands[n]
        row.update(force_rms_n=d["force_rms_n"], force_max_n=d["force_max_n"], travel_max_m=d["travel_max_m"])
        rows.append(row)
    return rows
