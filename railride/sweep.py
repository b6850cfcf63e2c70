"""Many runs at once: cases, batches, executors and a table of finished runs.

A `Case` is one run described by plain settings (scenario and its options, vehicle parameter
changes, suspension, gain changes), so it can travel to a Dask worker and has a stable key.
`run_cases` groups compatible cases into batches for the compiled stepper, hands the chunks to
an executor (`LocalExecutor`: this machine, the batch over both cores; `DaskExecutor`: a
dask.distributed cluster) and appends every finished chunk to a `RunTable` on disk, written
atomically; a sweep started again with the same table skips the runs it already has, so an
interrupted sweep resumes where it stopped. The metrics of a case do not depend on the executor
or on the batch it ran in (a batch equals its single runs, tests/physics/test_simulate.py).
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from ._io import atomic_write
from .defaults import DEFAULT_CONTROL_RATE, DEFAULT_DAMPER, DEFAULT_OUTPUT_RATE
from .metrics import RESPONSES, STATISTICS
from .solver import SolverSettings, _with_keywords
from .suspension import NAMES, Suspension, batch_conflict

#: samples per compiled batch: bounds the memory of the time histories (about 5 MB a sample
#: for 10 s at 1 kHz)
CHUNK = 32
#: raised whenever the physics change the metrics of a run with the same settings, so that run
#: tables from before do not resume into the new model. 2: two secondary lateral and two
#: longitudinal springs per bogie, and the paper sine's entry taper.
MODEL_REVISION = 2
#: the suspensions a case can name (`Suspension.named`)
SUSPENSIONS = NAMES
#: (position, index) of `railride.comfort.ride_comfort` in a row with comfort, as the column
#: ``<position>_<index>``
COMFORT_INDICES = (("centre", "aw_Wk"), ("centre", "vdv_Wk"), ("centre", "aw_Wb"),
                   ("centre", "N_MV_z"), ("centre", "Wz"), ("front", "aw_Wk"), ("front", "N_MV_z"),
                   ("front", "Wz"), ("rear", "aw_Wk"), ("rear", "N_MV_z"), ("rear", "Wz"))
COMFORT_COLUMNS = tuple(f"{p}_{i}" for p, i in COMFORT_INDICES)


@dataclass(frozen=True)
class Case:
    """One run. ``scenario_options`` are keyword arguments of `railride.track.scenario`,
    ``vehicle`` changes to the study's vehicle parameters (`run_cases`' ``params``, default the
    `paper` preset), ``gains`` changes to the base gain set as "table.entry" (e.g. "pid.kp",
    "attitude.kd_z", "ride.kp_1R", "inner.G"). ``suspension`` is passive, mr (constant
    ``voltage``) or a controller name; a controller may see sensor noise (``noise``: standard
    deviations displacement [m], angle [rad], velocity [m/s], angular rate [rad/s]) drawn with
    ``seed``. ``damper`` names the dampers of mr and the controllers (`railride.dampers.NAMES`;
    "ideal", the ideal actuator, with a controller only) and ``damper_scale`` multiplies an MR
    damper's force capacity (`BoucWen.scaled`); it must stay 1 for passive and the ideal
    actuator, which have none to scale. `to_suspension` gives the run's `Suspension`
    (`Suspension.named`, which also checks these settings when the case is made)."""

    scenario: str = "paper-sine"
    scenario_options: tuple = ()
    vehicle: tuple = ()
    suspension: str = "passive"
    damper: str = DEFAULT_DAMPER
    voltage: float | None = None
    gains: tuple = ()
    noise: tuple = ()
    seed: int = 0
    damper_scale: float = 1.0

    def __post_init__(self):
        from . import dampers

        if self.suspension not in SUSPENSIONS:
            raise ValueError(f"suspension = {self.suspension!r}; allowed: {', '.join(SUSPENSIONS)}")
        object.__setattr__(self, "damper_scale", dampers.check_scale("damper_scale", self.damper_scale))
        for name in ("scenario_options", "vehicle", "gains"):
            value = getattr(self, name)
            if isinstance(value, dict):
                value = tuple(sorted(value.items()))
            object.__setattr__(self, name, tuple((str(k), float(v) if isinstance(v, (int, float)) else v)
                                                 for k, v in value))
        object.__setattr__(self, "noise", tuple(float(v) for v in self.noise))
        if self.noise and len(self.noise) != 4:
            raise ValueError(f"noise = {self.noise!r}: four standard deviations or none")
        self._named(None)  # the suspension's checks, here rather than in a batch

    @property
    def closed_loop(self) -> bool:
        return self.suspension not in ("passive", "mr")

    def _named(self, gains) -> Suspension:
        from .control import SensorNoise

        # noise reaches the controllers only (passive and mr runs ignore it, as they always did)
        noise = None
        if self.noise and self.closed_loop:
            displacement, angle, velocity, angular_rate = self.noise
            noise = SensorNoise(displacement, angle, velocity, angular_rate, seed=self.seed)
        return Suspension.named(self.suspension, gains, self.damper, self.damper_scale, self.voltage,
                                noise)

    def to_suspension(self, base_gains=None) -> Suspension:
        """The run's `Suspension`: `Suspension.named` with the case's gain changes applied to
        ``base_gains`` (default the shipped `GainSet.default`)."""
        from .control import GainSet

        if not self.closed_loop:
            return self._named(None)
        base = GainSet.default() if base_gains is None else base_gains
        return self._named(base.apply(self.gains))

    @property
    def key(self) -> str:
        """A stable identity for the run table (same settings and model, same key, in any
        session). The model revision is part of it, so a run table from an earlier model is
        not taken for this one's on resume."""
        text = json.dumps({**self.to_dict(), "model_revision": MODEL_REVISION}, sort_keys=True,
                          default=str)
        return hashlib.sha1(text.encode()).hexdigest()[:16]

    def to_dict(self) -> dict:
        d = asdict(self)
        for name in ("scenario_options", "vehicle", "gains"):
            d[name] = dict(d[name])
        if d["damper_scale"] == 1.0:  # the default is left out: a scale appears only when set
            del d["damper_scale"]
        return d

    @property
    def group(self) -> tuple:
        """Cases that can share one compiled batch."""
        duration = dict(self.scenario_options).get("duration", 10.0)
        kind = "passive" if self.suspension == "passive" else ("mr" if self.suspension == "mr" else "closed")
        # sensor noise is one setting per batch
        return (duration, kind, self.damper if kind != "passive" else "",
                (self.noise, self.seed) if kind == "closed" else (),
                self.damper_scale if kind != "passive" else 1.0)


def evaluate(cases: list[Case], base_gains=None, *, params=None, solver=None, window=None,
             comfort: bool = False) -> list[dict]:
    """Run ``cases`` (in compiled batches of compatible cases) and return one row per case:
    its key, settings and the RMS and peak-to-peak of the four body responses; with
    ``comfort``, also the ride comfort indices of `COMFORT_COLUMNS` (`railride.comfort.
    ride_comfort` over the same window). ``params``: the vehicle the cases' ``vehicle`` changes
    apply to (`VehicleParams` or a preset name, default "paper"); ``solver``: the
    `SolverSettings` of every run. Runs in any process: a Dask worker calls it too."""
    from .control import GainSet
    from .simulation import _resolve_params, simulate
    from .track import scenario as make_scenario

    base_gains = GainSet.default() if base_gains is None else base_gains
    vehicle = _resolve_params(params)
    solver = SolverSettings.of(solver)
    scenarios: dict = {}
    rows: dict[int, dict] = {}
    by_group: dict[tuple, list[int]] = {}
    for i, c in enumerate(cases):
        by_group.setdefault(c.group, []).append(i)
    for group, idx in by_group.items():
        for start in range(0, len(idx), CHUNK):
            part = [cases[i] for i in idx[start:start + CHUNK]]
            scs = []
            for c in part:
                skey = (c.scenario, c.scenario_options)
                if skey not in scenarios:
                    scenarios[skey] = make_scenario(c.scenario, **dict(c.scenario_options))
                scs.append(scenarios[skey])
            pars = [vehicle.replace(**dict(c.vehicle)) for c in part]
            suspensions = [c.to_suspension(base_gains) for c in part]
            if batch_conflict(suspensions) is not None:  # the inner loop is one setting per batch
                for i in idx[start:start + CHUNK]:  # positions, not lookups: cases may repeat
                    rows[i] = evaluate([cases[i]], base_gains, params=vehicle, solver=solver,
                                       window=window, comfort=comfort)[0]
                continue
            res = simulate(scs, pars, suspensions, solver=solver, on_divergence="mark")
            # a diverged run keeps its row, with NaN metrics and the time it diverged: the other
            # runs of the study go on
            m = res.metrics(window).values  # (sample, response, statistic)
            diverged_at = res.diverged_at
            cf = None
            if comfort:
                from .comfort import ride_comfort

                ds = res.dataset
                if "sample" not in ds.dims:
                    ds = ds.expand_dims(sample=[0])
                ok = np.flatnonzero(np.isnan(diverged_at))  # a diverged run has no comfort
                cf = ride_comfort(ds.isel(sample=ok), window=window) if ok.size else None
            for j, i in enumerate(idx[start:start + CHUNK]):
                if i in rows:
                    continue
                row = {"key": cases[i].key, **_flat(cases[i]), "diverged_at_s": float(diverged_at[j])}
                for r, resp in enumerate(RESPONSES):
                    for s, stat in enumerate(STATISTICS):
                        row[f"{resp}_{stat}"] = float(m[j, r, s])
                if comfort:
                    for (pos, index), column in zip(COMFORT_INDICES, COMFORT_COLUMNS):
                        row[column] = (float(cf.isel(sample=int(np.searchsorted(ok, j)))
                                             .sel(position=pos, index=index))
                                       if np.isnan(diverged_at[j]) else np.nan)
                rows[i] = row
    return [rows[i] for i in range(len(cases))]


def _flat(c: Case) -> dict:
    d = {"scenario": c.scenario, "suspension": c.suspension, "damper": c.damper,
         "damper_scale": c.damper_scale, "voltage": np.nan if c.voltage is None else c.voltage,
         "noise": json.dumps(list(c.noise)) if c.noise else "", "seed": c.seed}
    d.update({f"scenario.{k}": v for k, v in c.scenario_options})
    d.update({f"vehicle.{k}": v for k, v in c.vehicle})
    d.update({f"gain.{k}": v for k, v in c.gains})
    d["case"] = json.dumps(c.to_dict(), sort_keys=True, default=str)
    return d


def other_settings(vehicle, solver: SolverSettings) -> dict:
    """The settings of a study besides its step that differ from the defaults: the solver's
    output and control rates, the vehicle when it is not the paper's. Only those enter a run's
    key and a study's record, so that the keys and records of default studies stay as they were."""
    from .params import VehicleParams

    out = {}
    if solver.output_rate != DEFAULT_OUTPUT_RATE:
        out["output_rate_hz"] = solver.output_rate
    if solver.control_rate != DEFAULT_CONTROL_RATE:
        out["control_rate_hz"] = solver.control_rate
    if vehicle != VehicleParams.preset("paper"):
        out["vehicle_params"] = vehicle.to_dict()
    return out


# -- executors ---------------------------------------------------------------------------------
class LocalExecutor:
    """Chunks run one after another in this process; each chunk's batch uses every core."""

    name = "local"

    def map(self, fn, chunks):
        for i, chunk in enumerate(chunks):
            yield i, fn(chunk)

    def close(self):
        pass


class DaskExecutor:
    """Chunks run as tasks on a dask.distributed cluster (``address`` tcp://host:port, or the
    ``scheduler_file`` that ``dask scheduler --scheduler-file`` writes). Needs the optional
    extra: pip install "railride[distributed]"; every worker imports the same railride.

    One chunk is one task and one compiled batch, on its share of the worker machine's cores:
    numba's thread count there (NUMBA_NUM_THREADS, every core by default) divided by the Dask
    threads of all the workers on that machine, at least 1. So batches do not multiply Dask's
    threads: one ``dask worker --nthreads 1`` per machine gives each batch every core, a default
    ``dask worker`` (a thread per core) one core to each of its batches (docs/distributed.md).

    A scheduler that does not answer within ``timeout`` seconds, a scheduler file that does not
    appear or has no address, are ValueErrors naming the address or file. `map` yields (chunk
    index, rows) in the order chunks finish; a chunk lost with a dead worker is run again by the
    scheduler."""

    name = "dask"

    def __init__(self, address: str | None = None, scheduler_file: str | None = None,
                 timeout: float = 10.0):
        try:
            from distributed import Client
        except ImportError:
            raise ValueError("the Dask executor needs dask.distributed: pip install "
                             "\"railride[distributed]\"") from None
        if (address is None) == (scheduler_file is None):
            raise ValueError("give a scheduler address (tcp://host:port) or a scheduler file")
        if scheduler_file is not None:
            address = self._address_from_file(scheduler_file, timeout)
        self.address = address
        where = f"{address}" + ("" if scheduler_file is None else f" (from {scheduler_file})")
        try:
            self._handshake(address, timeout)
            # not the default client: this executor's tasks only, the caller's Dask code untouched
            self.client = Client(address, timeout=timeout, set_as_default=False)
        except Exception as exc:  # refused, timed out, not a Dask scheduler, unknown scheme
            why = str(exc) or "no answer (the scheduler's port, not its dashboard's?)"
            raise ValueError(f"cannot reach the Dask scheduler at {where} within {timeout:g} s: "
                             f"{type(exc).__name__}: {why}") from None

    @staticmethod
    def _address_from_file(path, timeout: float) -> str:
        """The address in a scheduler file, waiting up to ``timeout`` for the scheduler to write it
        (distributed's own Client would wait for a missing file forever)."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                address = json.loads(Path(path).read_text())["address"]
                if isinstance(address, str) and address:
                    return address
                problem = f"address = {address!r}"
            except FileNotFoundError:
                problem = "no such file"
            except (OSError, ValueError, TypeError, KeyError) as exc:
                problem = f"not a Dask scheduler file ({type(exc).__name__}: {exc})"
            if time.monotonic() >= deadline:
                raise ValueError(f"scheduler file {str(path)!r}: {problem} after {timeout:g} s")
            time.sleep(0.1)

    @staticmethod
    def _handshake(address: str, timeout: float) -> None:
        """Open and close one connection to a tcp ``address`` within ``timeout``: the Client
        itself waits forever on a port that accepts but does not speak Dask (a dashboard's)."""
        import asyncio
        from concurrent.futures import ThreadPoolExecutor

        try:
            from distributed.comm import connect
            from distributed.comm.addressing import parse_address
            from distributed.comm.registry import get_backend
        except ImportError:  # internals moved in another version: the Client alone then
            return

        scheme = parse_address(address)[0]
        get_backend(scheme)  # an unknown scheme is a ValueError here, not a half-made Client
        if scheme != "tcp":
            return

        async def once():
            comm = await connect(address, timeout=timeout)
            await comm.close()

        # in a thread of its own: the caller may be inside an event loop (Jupyter)
        with ThreadPoolExecutor(1) as pool:
            pool.submit(lambda: asyncio.run(asyncio.wait_for(once(), timeout))).result()

    def map(self, fn, chunks):
        import uuid

        from distributed import as_completed
        from distributed.comm import get_address_host

        # the Dask threads on each machine (by host address), so a task knows its share
        nthreads = self.client.nthreads()
        per_host: dict[str, int] = {}
        for worker, n in nthreads.items():
            host = get_address_host(worker)
            per_host[host] = per_host.get(host, 0) + n
        shares = {worker: per_host[get_address_host(worker)] for worker in nthreads}
        tag = uuid.uuid4().hex[:8]
        futures = {self.client.submit(self._run_chunk, fn, shares, chunk,
                                      key=f"railride-chunk-{tag}-{i}"): i
                   for i, chunk in enumerate(chunks)}
        try:
            for fut in as_completed(futures, loop=self.client.loop):
                i = futures.pop(fut)
                yield i, fut.result()
        finally:  # stopped early (an error, Ctrl-C): drop what has not finished
            if futures:
                self.client.cancel(list(futures))

    @staticmethod
    def _run_chunk(fn, shares: dict, chunk):
        """On a worker: ``fn(chunk)`` on numba's thread count divided by the Dask threads on this
        machine (``shares``, as the map started; this worker's own for a worker that joined
        later). The thread count is per thread (`numba.set_num_threads`), so restored after."""
        import numba
        from distributed import get_worker

        worker = get_worker()
        share = shares.get(worker.address, worker.state.nthreads)
        before = numba.get_num_threads()
        numba.set_num_threads(max(1, numba.config.NUMBA_NUM_THREADS // max(1, share)))
        try:
            return fn(chunk)
        finally:
            numba.set_num_threads(before)

    def close(self):
        self.client.close()


# -- the table of finished runs ----------------------------------------------------------------
class RunTable:
    """Every finished run, one row each, kept in a CSV file rewritten atomically after each
    chunk: a reader never sees half a file, and an interrupted sweep loses at most the chunks
    in flight."""

    def __init__(self, path: str | Path | None = None, resume: bool = False):
        self.path = None if path is None else Path(path)
        self.frame = pd.DataFrame()
        if self.path is not None and self.path.exists():
            if not resume:
                raise ValueError(f"{self.path} exists: pass resume to continue that sweep, or "
                                 "choose another output folder")
            try:
                # keys are hex digests: an all-digit one must stay text to be recognised
                self.frame = pd.read_csv(self.path, dtype={"key": str})
            except (OSError, ValueError) as exc:
                raise ValueError(f"cannot read the run table {self.path}: {exc}") from None

    def done(self) -> dict[str, dict]:
        if self.frame.empty:
            return {}
        return {row["key"]: row for row in self.frame.to_dict("records")}

    def add(self, rows: list[dict]) -> None:
        if not rows:
            return
        self.frame = pd.concat([self.frame, pd.DataFrame(rows)], ignore_index=True)
        if self.path is not None:
            atomic_write(self.path, lambda p: self.frame.to_csv(p, index=False))


def run_cases(cases: list[Case], *, executor=None, table: RunTable | None = None, base_gains=None,
              params=None, solver=None, window=None, chunk: int = CHUNK, progress=None,
              comfort: bool = False, dt=None) -> pd.DataFrame:
    """Evaluate ``cases``, skipping those already in ``table``; returns their rows in order.
    ``params``: the vehicle (`VehicleParams` or a preset name, default "paper") the cases'
    ``vehicle`` changes apply to; ``solver``: the `SolverSettings` of every run (``dt``, the
    step alone, as the command line still gives it). ``comfort``: the rows also hold the ride
    comfort indices (`evaluate`).

    ``progress(done, total, runs_per_second)`` is called after each chunk.
    """
    import functools

    from .simulation import _resolve_params

    solver = _with_keywords(solver, dt)  # TEMPORARY: dt= removed when the CLI moves onto Suspension
    vehicle = _resolve_params(params)
    executor = LocalExecutor() if executor is None else executor
    table = RunTable() if table is None else table
    done = table.done()
    # a run's result depends on the case and on these settings: both go into its key, so a
    # resumed sweep with another step, window, base gain set or vehicle does not reuse old rows
    from .control import GainSet
    base = GainSet.default() if base_gains is None else base_gains
    settings = {"dt": solver.dt, "window": None if window is None else [float(w) for w in window],
                "base_gains": base.to_toml(), **other_settings(vehicle, solver)}
    if comfort:  # only then: the keys of sweeps without comfort stay as they were
        settings["comfort"] = True
    settings = json.dumps(settings, sort_keys=True)
    keys = [hashlib.sha1((c.key + settings).encode()).hexdigest()[:16] for c in cases]
    pending, seen = [], set()
    key_of = {}
    for c, k in zip(cases, keys):
        key_of[c.key] = k
        if k not in done and k not in seen:
            pending.append(c)
            seen.add(k)
    # group compatible cases so each chunk is one compiled batch
    pending.sort(key=lambda c: str(c.group))
    chunks = [pending[i:i + chunk] for i in range(0, len(pending), chunk)]
    fn = functools.partial(evaluate, base_gains=base, params=vehicle, solver=solver, window=window,
                           comfort=comfort)
    t0, n_done = time.perf_counter(), 0
    if progress is not None:
        progress(0, len(pending), 0.0)
    for _, rows in executor.map(fn, chunks):
        for row in rows:
            row["key"] = key_of[row["key"]]  # the case's key with the run settings
            done[row["key"]] = row
        table.add(rows)
        n_done += len(rows)
        if progress is not None:
            elapsed = time.perf_counter() - t0
            progress(n_done, len(pending), n_done / elapsed if elapsed > 0 else math.inf)
    return pd.DataFrame([done[k] for k in keys])
