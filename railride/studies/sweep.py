"""Many runs at once: cases, their batches, and the sweep study over a grid of them.

A `Case` is one run described by plain settings (scenario and its options, vehicle parameter changes,
suspension, gain changes), so it can travel to a Dask worker and has a stable key. `run_cases` groups
compatible cases into batches for the compiled stepper, scenario by scenario so that runs sharing rail
tables run in the same or neighbouring chunks (`_chunks`), hands the chunks to an executor
(`railride.studies.executors`: `LocalExecutor`, this machine, the batch over both cores; `DaskExecutor`,
a dask.distributed cluster) and appends every finished chunk to a `RunTable` on disk, written
atomically; a sweep started again with the same table skips the runs it already has, so an
interrupted sweep resumes where it stopped. The metrics of a case do not depend on the executor or
on the batch it ran in (a batch equals its single runs, tests/physics/test_simulate.py).

The sweep study: `grid` (`railride.studies.grid`) turns the values of each axis into the cases
of every combination, checked before the first run; `run_sweep` runs them and returns a
`SweepResult` (the ``railride.sweep/1`` document, a table, the figures, a result folder).
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import time
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from railride.errors import InputError
from railride.defaults import DEFAULT_CONTROL_RATE, DEFAULT_OUTPUT_RATE
from railride.studies.progress import shows_progress
from railride.studies.executors import CHUNK, DaskExecutor, LocalExecutor, ProcessExecutor, RunTable  # noqa: F401 (their home before)
from railride.analysis.metrics import RESPONSES, STATISTICS
from railride.plots import PNG_DPI, FigureOptions
from railride.model.params import VehicleParams, resolve_argument, resolve_vehicle, vehicle_record
from railride.run.solver import SolverSettings
from railride.secondary.suspension import batch_conflict, damper_label, damper_record
from railride.secondary.provenance import judged_text
from railride.studies.case import MODEL_REVISION, SUSPENSIONS, Case, scenario_of  # noqa: F401 (their home before)
from railride.studies.grid import SweepGrid, grid  # noqa: F401 (the grid of the sweep study, here too)

#: runs per batch where a study keeps only the metrics and the GPU takes them (`gpu_batches`):
#: their sums stay on the device (`railride.run.reduced`), a few bytes a run, and a GPU pays from
#: thousands of samples (a choice: this size was not measured on a GPU, docs/gpu.md)
GPU_CHUNK = 8192
#: (position, index) of `railride.analysis.comfort.ride_comfort` in a row with comfort, as the column
#: ``<position>_<index>``
COMFORT_INDICES = (
    ("centre", "aw_Wk"),
    ("centre", "vdv_Wk"),
    ("centre", "aw_Wb"),
    ("centre", "N_MV_z"),
    ("centre", "Wz"),
    ("front", "aw_Wk"),
    ("front", "N_MV_z"),
    ("front", "Wz"),
    ("rear", "aw_Wk"),
    ("rear", "N_MV_z"),
    ("rear", "Wz"),
)
COMFORT_COLUMNS = tuple(f"{p}_{i}" for p, i in COMFORT_INDICES)
#: the schema of `SweepResult.to_dict` (sweep.json)
SCHEMA = "railride.sweep/1"
#: the columns that name the vehicle of a run (its name and load factor) in the run table
#: (runs.csv, `run_cases`) and the sweep's rows (`SweepResult.rows`), as study_runs.csv does
VEHICLE_COLUMNS = ("vehicle", "load")


def evaluate(
    cases: list[Case],
    base_gains=None,
    *,
    params=None,
    solver=None,
    window=None,
    comfort: bool = False,
    costs: bool = False,
) -> list[dict]:
    """Run ``cases`` (in compiled batches of compatible cases) and return one row per case:
    its key, settings and the RMS and peak-to-peak of the four body responses; with
    ``comfort``, also the ride comfort indices of `COMFORT_COLUMNS` (`railride.analysis.comfort.
    ride_comfort` over the same window); with ``costs``, what the run asks of its dampers
    (`railride.analysis.costs.COST_COLUMNS`). ``params``: the vehicle the cases' ``vehicle`` changes
    apply to (`VehicleParams` or a preset name, default "paper"); ``solver``: the
    `SolverSettings` of every run. Runs in any process: a Dask worker calls it too."""
    from railride.secondary.control import GainSet
    from railride.run.simulation import simulate

    base_gains = GainSet.of(base_gains, [c.scenario for c in cases])
    vehicle = VehicleParams.of(params)
    solver = SolverSettings.of(solver)
    rows: dict[int, dict] = {}
    made: dict[tuple, object] = {}  # one Scenario per setting in this call (a measured profile read once)
    by_group: dict[tuple, list[int]] = {}
    for i, c in enumerate(cases):
        by_group.setdefault(c.group, []).append(i)
    metrics_only = not (comfort or costs)
    for group, idx in by_group.items():
        parts = _batches(idx, solver, metrics_only, [cases[i].duration for i in idx])
        while parts:
            part_idx = parts.pop(0)
            part = [cases[i] for i in part_idx]
            scs = [_scenario(made, c) for c in part]
            pars = [_vehicle(made, vehicle, c) for c in part]
            suspensions = Case.suspensions(part, base_gains)
            if batch_conflict(suspensions) is not None:  # the inner loop is one setting per batch
                for i in part_idx:  # positions, not lookups: cases may repeat
                    rows[i] = evaluate(
                        [cases[i]],
                        base_gains,
                        params=vehicle,
                        solver=solver,
                        window=window,
                        comfort=comfort,
                        costs=costs,
                    )[0]
                continue
            plan = _device_plan(scs, pars, suspensions, solver) if metrics_only else None
            if plan is not None:  # on the GPU, summed on the device with no histories
                from railride.run.reduced import batch_metrics

                m, diverged_at = batch_metrics(plan, window)
                _add_rows(rows, cases, part_idx, m, diverged_at)
                continue
            # runs the GPU does not take (the exact steps, a remainder too small for "auto"): CPU batches
            if len(part_idx) > CHUNK:
                parts[:0] = [part_idx[k : k + CHUNK] for k in range(0, len(part_idx), CHUNK)]
                continue
            if metrics_only:  # summed as the lane stepper steps, with no histories, where it takes the batch
                from railride.run.checks import check
                from railride.run.reduced import batch_metrics

                m, diverged_at = batch_metrics(check(scs, pars, suspensions, solver, "mark"), window)
                _add_rows(rows, cases, part_idx, m, diverged_at)
                continue
            res = simulate(scs, pars, suspensions, solver=solver, on_divergence="mark")
            # a diverged run keeps its row, with NaN metrics and the time it diverged: the other
            # runs of the study go on
            m = res.metrics(window).values  # (sample, response, statistic)
            diverged_at = res.diverged_at
            cf: np.ndarray | None = None
            if comfort:
                from railride.analysis.comfort import ride_comfort

                ds = res.comfort_channels()  # the channels comfort reads, not the run's whole Dataset
                if "sample" not in ds.dims:
                    ds = ds.expand_dims(sample=[0])
                ok = np.flatnonzero(np.isnan(diverged_at))  # a diverged run has no comfort
                if ok.size:  # the columns as one array (sample, column): xarray per value cost 4x the indices
                    # every run ok (the rule): no copy of the histories
                    indices = ride_comfort(ds if ok.size == ds.sizes["sample"] else ds.isel(sample=ok), window=window)
                    values = indices.transpose("sample", "position", "index").values
                    where = [
                        (list(indices["position"].values).index(p), list(indices["index"].values).index(x))
                        for p, x in COMFORT_INDICES
                    ]
                    cf = np.stack([values[:, p, x] for p, x in where], -1)
            paid = _costs(res, part[0], window) if costs else None
            _add_rows(rows, cases, part_idx, m, diverged_at, (cf, ok) if comfort else None, paid)
    return [rows[i] for i in range(len(cases))]


def _batches(idx: list[int], solver: SolverSettings, metrics_only: bool, durations=()) -> list[list[int]]:
    """The compiled batches of one group's cases (positions ``idx``, runs of ``durations`` [s]):
    `CHUNK` runs each, or, for runs that keep only their metrics where the GPU takes them
    (`gpu_batches`), `GPU_CHUNK`. A large batch the GPU does not take after all (a remainder too
    small for "auto", the exact steps) is split into `CHUNK`s by `evaluate`."""
    on_gpu = metrics_only and gpu_batches(solver, min(len(idx), GPU_CHUNK), max(durations, default=None))
    size = GPU_CHUNK if on_gpu else CHUNK
    return [idx[start : start + size] for start in range(0, len(idx), size)]


def _device_plan(scenarios, params, suspensions, solver: SolverSettings):
    """The checked plan of a metrics-only batch that steps on the GPU (`railride.run.reduced`);
    None where it does not: the CPU runs those in batches of `CHUNK`, with their histories."""
    from railride.run.checks import check
    from railride.run.simulation import stepped_on

    if not gpu_batches(solver, len(scenarios), max(sc.duration for sc in scenarios)):
        return None
    try:
        plan = check(scenarios, params, suspensions, solver, "mark", histories=False)
    except InputError:  # said again, where it holds, by the check of each CPU-sized batch
        return None
    return plan if stepped_on(plan) == "gpu" else None


def gpu_batches(solver: SolverSettings, n: int, duration: float | None = None) -> bool:
    """Whether a study's metrics-only batch of n runs of ``duration`` [s] (None: long runs) goes to
    the GPU: with backend "gpu", or "auto" where one is usable and the batch would step sooner
    there (`railride.run.solver.gpu_pays`). Where "auto" finds none, a study runs its usual
    batches on the CPU without a word: it never asked for more."""
    from railride.run.solver import auto_takes, gpu_missing

    if solver.backend != "auto":
        return solver.backend == "gpu"
    return auto_takes(n, None if duration is None else duration / solver.dt) and gpu_missing() is None


def _add_rows(rows: dict, cases: list[Case], part_idx: list[int], m, diverged_at, comfort=None, paid=None) -> None:
    """The rows of a batch's runs (positions ``part_idx`` in ``cases``) into ``rows``: key,
    settings, metrics ``m`` (run, response, statistic), the time each diverged, and the comfort
    indices ((indices of the runs that did not diverge, their positions), `COMFORT_COLUMNS`) and
    costs (`railride.analysis.costs.COST_COLUMNS`) where given."""
    for j, i in enumerate(part_idx):
        if i in rows:
            continue
        row = {"key": cases[i].key, **_flat(cases[i]), "diverged_at_s": float(diverged_at[j])}
        for r, resp in enumerate(RESPONSES):
            for s, stat in enumerate(STATISTICS):
                row[f"{resp}_{stat}"] = float(m[j, r, s])
        if comfort is not None:
            cf, ok = comfort
            for k, column in enumerate(COMFORT_COLUMNS):
                row[column] = (
                    float(cf[int(np.searchsorted(ok, j)), k]) if np.isnan(diverged_at[j]) and cf is not None else np.nan
                )
        if paid is not None:
            from railride.analysis.costs import COST_COLUMNS

            for k, column in enumerate(COST_COLUMNS):
                row[column] = float(paid[j, k]) if np.isnan(diverged_at[j]) else np.nan
        rows[i] = row


def _costs(res, case: Case, window) -> np.ndarray:
    """`railride.analysis.costs.damper_costs` of a batch's runs (one damper model per batch)."""
    from railride.analysis.costs import COST_CHANNELS, damper_costs
    from railride.analysis.metrics import select_window
    from railride.secondary.suspension import damper_model

    # every suspension with MR dampers has a command voltage (a law's, or a constant one)
    v_max = (
        getattr(damper_model(case.damper, case.damper_scale), "v_max", None) if case.suspension != "passive" else None
    )
    # the channels the costs read, not the run's whole Dataset
    return damper_costs(select_window(res.channels(COST_CHANNELS), window), v_max)


def _vehicle(made: dict, vehicle: VehicleParams, c: Case) -> VehicleParams:
    """The case's vehicle, one object per distinct change in this call (checked once, and one
    vehicle model a batch builds for all the runs that share it)."""
    key = ("vehicle", c.vehicle)
    if key not in made:
        made[key] = vehicle.replace(**dict(c.vehicle))
    return made[key]


def _scenario(made: dict, c: Case):
    key = (c.scenario, c.scenario_options)
    if key not in made:
        made[key] = scenario_of(*key)
    return made[key]


def _flat(c: Case) -> dict:
    d = {
        "scenario": c.scenario,
        "suspension": c.suspension,
        "damper": damper_label(c.damper),
        "damper_scale": c.damper_scale,
        "voltage": np.nan if c.voltage is None else c.voltage,
        "noise": json.dumps(list(c.noise)) if c.noise else "",
        "seed": c.seed,
    }
    d.update({f"scenario.{k}": v for k, v in c.scenario_options})
    d.update({f"vehicle.{k}": v for k, v in c.vehicle})
    d.update({f"gain.{k}": v for k, v in c.gains})
    if c.faults:
        d["faults"] = ",".join(c.faults)
    if c.delay != 1:
        d["delay_periods"] = c.delay
    if c.sensing != "ideal":
        d["sensing"] = c.sensing
    d["case"] = json.dumps(c.to_dict(), sort_keys=True, default=str)
    return d


def other_settings(vehicle, solver: SolverSettings) -> dict:
    """The settings of a study besides its step that differ from the defaults: the solver's
    output and control rates, the vehicle when it is not the paper's. Only those enter a run's
    key and a study's record, so that the keys and records of default studies stay as they were."""
    from railride.model.params import VehicleParams

    out = {}
    if solver.output_rate != DEFAULT_OUTPUT_RATE:
        out["output_rate_hz"] = solver.output_rate
    if solver.control_rate != DEFAULT_CONTROL_RATE:
        out["control_rate_hz"] = solver.control_rate
    if vehicle != VehicleParams.preset("paper"):
        out["vehicle_params"] = vehicle.to_dict()
    return out


def run_cases(
    cases: list[Case],
    *,
    executor=None,
    table: RunTable | None = None,
    base_gains=None,
    vehicle=None,
    params=None,
    solver=None,
    window=None,
    chunk: int = CHUNK,
    progress=None,
    comfort: bool = False,
    vehicle_columns=None,
    costs: bool = False,
) -> pd.DataFrame:
    """Evaluate ``cases``, skipping those already in ``table``; returns their rows in order.
    ``vehicle`` (``params`` is an alias): the vehicle (`VehicleParams`, a preset name or the
    path of a parameters file, default "paper") the cases' ``vehicle`` changes apply to;
    ``solver``: the `SolverSettings` of every run. ``comfort``: the rows also hold the ride
    comfort indices (`evaluate`); ``costs``: what each run asks of its dampers (force, travel,
    time at v_max: `railride.analysis.costs.COST_COLUMNS`).

    Every row names the vehicle it ran in the columns ``vehicle`` (its name) and ``load`` (the
    load factor), after ``key``: ``vehicle_columns``, one dict of them for every case or a list
    of one per case (a study's loads), default the name of ``vehicle`` and load 1
    (`railride.model.params.vehicle_record`). They do not enter the keys; rows of a table
    written without them get them in the rows returned (same key, same vehicle values).

    ``progress(done, total, runs_per_second)`` is called after each chunk.
    """
    solver = SolverSettings.of(solver)
    vehicle, source = resolve_argument(vehicle, params)
    named = _vehicle_columns(vehicle_columns, cases, vehicle, source)
    executor = LocalExecutor() if executor is None else executor
    table = RunTable() if table is None else table
    done = table.done()
    # a run's result depends on the case and on these settings: both go into its key, so a
    # resumed sweep with another step, window, base gain set or vehicle does not reuse old rows
    from railride.secondary.control import GainSet

    base = GainSet.of(base_gains, [c.scenario for c in cases])
    settings = {
        "dt": solver.dt,
        "window": None if window is None else [float(w) for w in window],
        "base_gains": base.key_text(),
        **other_settings(vehicle, solver),
    }
    if comfort:  # only then: the keys of sweeps without comfort stay as they were
        settings["comfort"] = True
    if costs:  # the same; the revision of the columns: a table with other columns is not reused
        from railride.analysis.costs import COSTS_REVISION

        settings["costs"] = COSTS_REVISION
    settings_text = json.dumps(settings, sort_keys=True)
    keys = [hashlib.sha1((c.key + settings_text).encode()).hexdigest()[:16] for c in cases]
    pending, seen = [], set()
    key_of, columns_of = {}, {}
    for c, k, columns in zip(cases, keys, named):
        key_of[c.key] = k
        columns_of[k] = columns
        if k not in done and k not in seen:
            pending.append(c)
            seen.add(k)
    on_gpu = (
        chunk == CHUNK
        and not (comfort or costs)
        and gpu_batches(solver, min(len(pending), GPU_CHUNK), max((c.duration for c in pending), default=None))
    )
    if on_gpu:
        chunk = GPU_CHUNK  # metrics summed on the GPU (`evaluate`)
    if pending and not on_gpu and hasattr(executor, "bounded"):
        # the chunks in flight within the memory limit (a chunk of 60 s runs holds about 1 GB)
        from railride.run.checks import history_bytes

        longest = max(c.duration for c in pending)
        executor = executor.bounded(history_bytes(min(chunk, len(pending)), longest * solver.output_rate + 2))
    if hasattr(executor, "chunk"):  # `railride.studies.lockstep.OwnChunks` chunks each law's cases itself
        executor.chunk, executor.on_gpu = chunk, on_gpu
    chunks = _chunks(pending, chunk)
    fn = functools.partial(
        evaluate, base_gains=base, params=vehicle, solver=solver, window=window, comfort=comfort, costs=costs
    )
    t0, n_done = time.perf_counter(), 0
    if progress is not None:
        progress(0, len(pending), 0.0)
    for _, rows in executor.map(fn, chunks):
        for i, row in enumerate(rows):
            key = key_of[row.pop("key")]  # the case's key with the run settings
            rows[i] = done[key] = {"key": key, **columns_of[key], **row}
        table.add(rows)
        n_done += len(rows)
        if progress is not None:
            elapsed = time.perf_counter() - t0
            progress(n_done, len(pending), n_done / elapsed if elapsed > 0 else math.inf)
    table.flush()  # the table on disk holds every run when this returns (chunks write it at intervals)
    # a row of a table from before the vehicle columns: the same key is the same vehicle values
    return pd.DataFrame([{**done[k], **columns_of[k]} for k in keys])


def _vehicle_columns(given, cases: list[Case], vehicle, source) -> list[dict]:
    """The ``vehicle`` and ``load`` columns of each case's row (`run_cases`)."""
    if given is None:
        record = vehicle_record(vehicle, source)
        given = {"vehicle": record["name"], "load": record["load"]}
    if isinstance(given, dict):
        return [dict(given)] * len(cases)
    given = [dict(g) for g in given]
    if len(given) != len(cases):
        raise InputError(f"vehicle_columns: {len(given)} for {len(cases)} cases; give one per case, or one for all")
    return given


def table_order(cases: list[Case]):
    """A sort key of cases that puts the runs that share input tables together: the ranks of
    their vehicle, track (realisation or profile) and scenario (speed), each in the order first
    met in ``cases`` (a case not among them gets the next rank)."""
    ranks: tuple[dict, dict, dict] = ({}, {}, {})

    def rank(level: int, value) -> int:
        return ranks[level].setdefault(value, len(ranks[level]))

    def near(c: Case) -> tuple:
        profile = tuple((k, v) for k, v in c.scenario_options if k not in ("speed", "duration"))
        return (rank(0, c.vehicle), rank(1, (c.scenario, profile)), rank(2, (c.scenario, c.scenario_options)))

    for c in cases:  # ranks in the order given
        near(c)
    return near


def _chunks(cases: list[Case], chunk: int) -> list[list[Case]]:
    """``cases`` in chunks of at most ``chunk``, each of one group (one compiled batch), with
    the runs that share tables together: by vehicle, then track (realisation or profile), then
    scenario (speed), each in the order first met. The chunks of the groups are interleaved by
    the first scenario they hold, so the controllers' chunks run next to the passive chunk on
    the same scenarios and find its tables kept (bounded by bytes, `railride.run.simulation`): a
    study's tables are built about once each, and its memory does not grow with its runs. The
    vehicle comes first so that a batch mixes vehicles only where one vehicle's runs end, as
    before: "auto" gives a passive batch of several vehicles RK4 rather than the exact steps."""
    near = table_order(cases)
    groups: dict[str, list[Case]] = {}
    for c in sorted(cases, key=near):
        groups.setdefault(str(c.group), []).append(c)
    out = [part[i : i + chunk] for _, part in sorted(groups.items()) for i in range(0, len(part), chunk)]
    out.sort(key=lambda part: near(part[0]))  # stable: a tie keeps the groups' order
    return out


# -- the sweep study -------------------------------------------------------------------------------
def metric_columns() -> list[str]:
    """The metric columns of every run: ``<response>_<statistic>``, statistic by statistic."""
    return [f"{r}_{s}" for s in STATISTICS for r in RESPONSES]


@dataclass(frozen=True, eq=False)
class SweepResult:
    """The runs of a sweep (`run_sweep`): ``grid`` (the cases, their grid values and the
    settings), ``frame`` (the rows of `run_cases`, one per case, in the grid's order),
    ``comfort`` (whether they hold the comfort indices, `COMFORT_COLUMNS`), ``vehicle`` (the
    `VehicleParams` of the runs), ``runs`` (rows of the run table at the end), ``date``
    (when the sweep finished, UTC, ISO 8601) and ``vehicle_record`` (the vehicle's name, load
    and values, `railride.model.params.vehicle_record`; None: made from ``vehicle``)."""

    grid: SweepGrid
    frame: pd.DataFrame = field(repr=False)
    comfort: bool = False
    vehicle: object = None
    runs: int = 0
    date: str = ""
    vehicle_record: dict | None = None

    def metric_columns(self) -> list[str]:
        return metric_columns() + (list(COMFORT_COLUMNS) if self.comfort else [])

    @property
    def diverged(self) -> np.ndarray:
        """True for each case whose run diverged (no metrics, the time in ``diverged_at_s``)."""
        if "diverged_at_s" not in self.frame:
            return np.zeros(len(self.grid.cases), dtype=bool)
        return self.frame["diverged_at_s"].notna().to_numpy()

    def record(self) -> dict:
        """The vehicle's record: name, load and values (``vehicle_record``, else made from
        ``vehicle``, `railride.model.params.vehicle_record`)."""
        from railride.model.params import vehicle_record

        if self.vehicle_record is not None:
            return self.vehicle_record
        return vehicle_record(VehicleParams.of(VehicleParams.preset("paper") if self.vehicle is None else self.vehicle))

    def columns(self) -> list[str]:
        """The columns of `to_pandas`: the grid's, ``vehicle`` and ``load`` (the vehicle's name
        and load factor, the same in every row), the metrics, ``diverged_at_s`` when a run
        diverged, and ``key`` (`Case.key`)."""
        return (
            list(self.grid.columns)
            + list(VEHICLE_COLUMNS)
            + self.metric_columns()
            + (["diverged_at_s"] if self.diverged.any() else [])
            + ["key"]
        )

    def rows(self) -> list[dict]:
        """One row per run: its grid values (None where an axis does not act), the vehicle's
        name and load, its metrics (None for a run that diverged) and its case's key."""
        metrics, diverged = self.metric_columns(), self.diverged
        record = self.record()
        vehicle = {"vehicle": str(record["name"]), "load": record["load"]}
        rows = []
        for case, values, (_, result), bad in zip(self.grid.cases, self.grid.values, self.frame.iterrows(), diverged):
            row = {**values, **vehicle, **{m: None if bad else float(result[m]) for m in metrics}}
            if diverged.any():  # a run that diverged has no metrics, but the time it went
                row["diverged_at_s"] = float(result["diverged_at_s"]) if bad else None
            rows.append({**row, "key": case.key})
        return rows

    @property
    def settings(self) -> dict:
        """What the sweep ran: the scenario's fixed settings, each axis and its values, the damper, the
        base gains (``gains``, ``gains_provenance``, ``gains_values``: `GainSet.record` of the
        controllers; ``gains_varied``: the entries the gain axes set instead; ``gains_source`` as
        ``gains``), the sensor noise, the step and the metrics window; with comfort, what its columns
        are (`comfort_settings`); the vehicle's record (name, load, values); a solver's rates and a
        vehicle other than the defaults (`other_settings`); ``gains_mismatch`` (`GainSet.mismatch`)
        and ``tracks_judged`` (`judged_text`) where they have something to say."""
        g = self.grid
        vehicle = VehicleParams.preset("paper") if self.vehicle is None else self.vehicle
        record, tracks = self.record(), self._tracks()
        none: dict = {"source": None, "provenance": None, "values": {}}  # no controller reads gains
        ran = g.base_gains.record(g.controllers) if g.controllers else none
        return {
            "scenario": g.scenario_record(),
            "grid": g.grid_values(),
            "damper": damper_record(g.damper) if ("mr" in g.suspensions or g.controllers) else None,
            "gains_source": ran["source"],
            # the base gains the controllers ran (`GainSet.record`); the entries of a gain axis
            # ran with the values of their row instead (``gains_varied``, their values in ``grid``)
            "gains": ran["source"],
            "gains_provenance": ran["provenance"],
            "gains_values": ran["values"],
            "gains_varied": [name for name, _ in g.gains],
            "sensor_noise": None
            if g.noise is None
            else dict(zip(("displacement", "angle", "velocity", "angular_rate"), g.noise)),
            "dt_s": float(g.solver.dt),
            **g.solver.backend_record(),
            "window_s": None if g.window is None else list(g.window),
            **({"comfort": comfort_settings(g.duration, g.window)} if self.comfort else {}),
            "vehicle": record,
            **other_settings(vehicle, g.solver),
            # over the controllers' tracks: the gains tuned for another case, and the tracks tuned on
            **({"gains_mismatch": m} if tracks and (m := self._mismatch(record, tracks)) else {}),
            **({"tracks_judged": j} if tracks and (j := judged_text(g.base_gains, tracks)) else {}),
        }

    def _mismatch(self, record: dict, tracks: list[dict]) -> str | None:
        """`GainSet.mismatch` of the base gains, with the controllers' damper where the grid does
        not vary its scale (a sweep of scales asks what other dampers give)."""
        g = self.grid
        if g.damper_scales is not None and len(g.damper_scales) > 1:
            return g.base_gains.mismatch(record, tracks)
        scale = 1.0 if g.damper_scales is None else g.damper_scales[0]
        return g.base_gains.mismatch(record, tracks, damper=g.damper, damper_scale=scale)

    def _tracks(self) -> list[dict]:
        """The controllers' tracks in the grid's order (a set's changes from one process to the next)."""
        g = self.grid
        ran = dict.fromkeys((c.scenario, c.scenario_options) for c in g.cases if c.suspension in g.controllers)
        return [scenario_of(name, opts).describe() for name, opts in ran]

    def report_contents(self):
        """What this result shows in its HTML report (`railride.output.report.write_report`)."""
        from railride.output.report import sweep_contents

        return sweep_contents(self)

    def to_dict(self) -> dict:
        """The ``railride.sweep/1`` document (docs/cli.md): the settings, the columns, every
        run as a row of `rows`, and the rows of the run table."""
        from railride._version import __version__, versions

        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            "date": self.date,
            "settings": self.settings,
            "columns": self.columns(),
            "rows": self.rows(),
            "runs": int(self.runs),
        }

    def to_pandas(self) -> pd.DataFrame:
        """One row per run, the columns of `columns` (empty where an axis does not act)."""
        return pd.DataFrame(self.rows(), columns=self.columns())

    def plot(self, ax=None, *, comfort: bool = False, axis: str | None = None, series: str | None = None):
        """The RMS of the four carbody responses against the swept axis (four panels,
        `railride.plots.sweep.plot_sweep`), or with ``comfort`` N_MV,z and a_w Wk against it
        (two panels, `plot_sweep_comfort`); with a second swept axis, one line per value of it
        (``series``). ``ax``: the Axes to draw in, or None for a new figure. Returns the
        figure; InputError where there is none to draw (`figure_note` says why)."""
        from railride.plots.sweep import plot_sweep, plot_sweep_comfort

        return (plot_sweep_comfort if comfort else plot_sweep)(self, ax, axis=axis, series=series)

    @property
    def figure_note(self) -> str | None:
        """One line saying why this sweep has no figure (no sweep.png: no axis, or more than two,
        with several values; `railride.plots.sweep.sweep_figure_note`), or None when it has one."""
        from railride.plots.sweep import sweep_figure_note

        return sweep_figure_note(self)

    def save(self, folder, *, extra: dict | None = None, figure_formats=("png",), dpi: float = PNG_DPI) -> list:
        """sweep.json (`to_dict`, then the entries of ``extra``, such as a command line's facts) and,
        when one or two axes have several values (`figure_note` is None), sweep.png and, with comfort,
        comfort.png (each in every one of ``figure_formats``: png, pdf, svg; PNG at ``dpi``) into
        ``folder``, all or nothing (other files, such as the run table runs.csv, stay). Returns the paths."""
        from railride.output.files import write_sweep_outputs

        figures = FigureOptions(figure_formats, dpi)
        return write_sweep_outputs(self, folder, {**self.to_dict(), **(extra or {})}, figures=figures)


def comfort_settings(duration: float, window) -> dict:
    """``settings.comfort`` of a sweep with comfort: the columns and their units, where the
    positions are and what N_MV_z is (the same for every run of a grid: they share one
    duration)."""
    from railride.analysis.comfort import INDEX_UNITS
    from railride.analysis.comfort_record import intervals_in, n_mv_basis

    whole = intervals_in(window, duration)  # 0: shorter than one interval, the whole signal
    unit = {
        i: INDEX_UNITS["aw" if i.startswith("aw_") else "vdv" if i.startswith("vdv_") else i]
        for _, i in COMFORT_INDICES
    }
    return {
        "columns": list(COMFORT_COLUMNS),
        "units": {c: unit[i] for (_, i), c in zip(COMFORT_INDICES, COMFORT_COLUMNS)},
        "positions": {
            "centre": "x = 0",
            "front": "x = +l (above the front bogie centre)",
            "rear": "x = -l (above the rear bogie centre)",
        },
        "n_intervals": max(1, whole),
        "notes": [
            "N_MV_z is the vertical term of EN 12299 only: the model has no lateral or longitudinal motion",
            n_mv_basis(whole),
        ],
    }


@shows_progress("sweep")
def run_sweep(
    grid: SweepGrid,  # noqa: F811 (the argument shadows the function `grid` on purpose)
    *,
    executor=None,
    table: RunTable | None = None,
    vehicle=None,
    params=None,
    load: float = 1.0,
    progress=True,
    comfort: bool = True,
) -> SweepResult:
    """Run every case of ``grid`` (`railride.studies.sweep.grid`) and return a `SweepResult`.

    One call of `run_cases`: compiled batches of 32 runs, on ``executor`` (default
    `LocalExecutor`; `DaskExecutor` for a cluster), skipping the runs already in ``table``
    (a `RunTable`; one kept on disk makes the sweep resumable), ``progress``: True (the
    default: shown on stderr after 2 s, `railride.studies.progress`), False (silent) or a
    callable ``progress(done, total, runs_per_second)`` after each chunk. ``vehicle``
    (``params`` is an alias): a preset name,
    the path of a parameters file or `VehicleParams` (default "paper"), with the load factor
    ``load`` on its carbody; `SweepResult.settings` records both (``vehicle``). ``comfort``:
    also the ride comfort indices of every run over the grid's window
    (`railride.analysis.comfort.ride_comfort`). The runs use the grid's base gains, solver
    settings and metrics window.
    """
    from datetime import datetime, timezone

    if not isinstance(grid, SweepGrid):
        raise InputError(
            f"grid = {type(grid).__name__}: must be a railride.studies.grid.SweepGrid "
            "(railride.studies.grid.grid makes one)"
        )
    vehicle, record = resolve_vehicle(vehicle, params, load)
    table = RunTable() if table is None else table
    frame = run_cases(
        list(grid.cases),
        executor=executor,
        table=table,
        base_gains=grid.base_gains,
        params=vehicle,
        solver=grid.solver,
        window=grid.window,
        progress=progress,
        comfort=bool(comfort),
        vehicle_columns={"vehicle": record["name"], "load": record["load"]},
    )
    date = datetime.now(timezone.utc).replace(microsecond=0).isoformat().replace("+00:00", "Z")
    return SweepResult(grid, frame, bool(comfort), vehicle, len(table.frame), date, record)
