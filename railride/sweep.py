"""Many runs at once: cases, batches, executors and a table of finished runs.

A `Case` is one run described by plain settings (scenario and its options, vehicle parameter
changes, suspension, gain changes), so it can travel to a Dask worker and has a stable key.
`run_cases` groups compatible cases into batches for the compiled stepper, hands the chunks to
an executor (`LocalExecutor`: this machine, the batch over both cores; `DaskExecutor`: a
dask.distributed cluster) and appends every finished chunk to a `RunTable` on disk, written
atomically; a sweep started again with the same table skips the runs it already has, so an
interrupted sweep resumes where it stopped. The metrics of a case do not depend on the executor
or on the batch it ran in (a batch equals its single runs, tests/test_simulate.py).
"""

from __future__ import annotations

import hashlib
import json
import math
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from ._io import atomic_write
from .metrics import RESPONSES, STATISTICS

#: samples per compiled batch: bounds the memory of the time histories (about 5 MB a sample
#: for 10 s at 1 kHz)
CHUNK = 32
SUSPENSIONS = ("passive", "mr", "pid", "sas-attitude", "sas-attitude-ride")


@dataclass(frozen=True)
class Case:
    """One run. ``scenario_options`` are keyword arguments of `railride.track.scenario`,
    ``vehicle`` changes to the `paper` parameters, ``gains`` changes to the base gain set as
    "table.entry" (e.g. "pid.kp", "attitude.kd_z", "ride.kp_1R", "inner.G"). ``suspension`` is
    passive, mr (constant ``voltage``) or a controller name; a controller may see sensor noise
    (``noise``: standard deviations displacement [m], angle [rad], velocity [m/s], angular rate
    [rad/s]) drawn with ``seed``."""

    scenario: str = "paper-sine"
    scenario_options: tuple = ()
    vehicle: tuple = ()
    suspension: str = "passive"
    damper: str = "railway"
    voltage: float | None = None
    gains: tuple = ()
    noise: tuple = ()
    seed: int = 0

    def __post_init__(self):
        if self.suspension not in SUSPENSIONS:
            raise ValueError(f"suspension = {self.suspension!r}; allowed: {', '.join(SUSPENSIONS)}")
        for name in ("scenario_options", "vehicle", "gains"):
            value = getattr(self, name)
            if isinstance(value, dict):
                value = tuple(sorted(value.items()))
            object.__setattr__(self, name, tuple((str(k), float(v) if isinstance(v, (int, float)) else v)
                                                 for k, v in value))
        object.__setattr__(self, "noise", tuple(float(v) for v in self.noise))
        if self.noise and len(self.noise) != 4:
            raise ValueError(f"noise = {self.noise!r}: four standard deviations or none")

    @property
    def key(self) -> str:
        """A stable identity for the run table (same settings, same key, in any session)."""
        text = json.dumps(self.to_dict(), sort_keys=True, default=str)
        return hashlib.sha1(text.encode()).hexdigest()[:16]

    def to_dict(self) -> dict:
        d = asdict(self)
        for name in ("scenario_options", "vehicle", "gains"):
            d[name] = dict(d[name])
        return d

    @property
    def group(self) -> tuple:
        """Cases that can share one compiled batch."""
        duration = dict(self.scenario_options).get("duration", 10.0)
        kind = "passive" if self.suspension == "passive" else ("mr" if self.suspension == "mr" else "closed")
        # sensor noise is one setting per batch
        return (duration, kind, self.damper if kind != "passive" else "",
                (self.noise, self.seed) if kind == "closed" else ())


def apply_gains(base, changes):
    """A GainSet with "table.entry" changes applied."""
    from .control import GainSet

    tables = {"inner": base.inner, "pid": base.pid, "attitude": base.attitude, "ride": base.ride}
    grouped: dict[str, dict] = {}
    for name, value in changes:
        table, _, entry = name.partition(".")
        if table not in tables or not entry:
            raise ValueError(f"gain {name!r}: expected table.entry with table one of {', '.join(tables)}")
        grouped.setdefault(table, {})[entry] = value
    for table, entries in grouped.items():
        tables[table] = tables[table].replace(**entries)
    return GainSet(tables["inner"], tables["pid"], tables["attitude"], tables["ride"], base.source)


def evaluate(cases: list[Case], base_gains=None, dt: float = 1e-4, window=None) -> list[dict]:
    """Run ``cases`` (in compiled batches of compatible cases) and return one row per case:
    its key, settings and the RMS and peak-to-peak of the four body responses. Runs in any
    process: a Dask worker calls it too."""
    from .control import GainSet, SensorNoise
    from .params import VehicleParams
    from .simulation import simulate
    from .track import scenario as make_scenario

    base_gains = GainSet.default() if base_gains is None else base_gains
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
            pars = [VehicleParams.preset("paper").replace(**dict(c.vehicle)) for c in part]
            kind = group[1]
            if kind == "passive":
                res = simulate(scs, pars, dt=dt)
            elif kind == "mr":
                res = simulate(scs, pars, dt=dt, damper=group[2], voltage=[c.voltage for c in part])
            else:
                gsets = [apply_gains(base_gains, c.gains) for c in part]
                inners = {g.inner for g in gsets}
                if len(inners) != 1:  # the inner loop is one setting per batch
                    for c, g in zip(part, gsets):
                        rows[cases.index(c)] = evaluate([c], base_gains, dt, window)[0]
                    continue
                noise, seed = group[3]
                res = simulate(scs, pars, dt=dt, damper=group[2], inner=gsets[0].inner,
                               controller=[g.controller(c.suspension) for c, g in zip(part, gsets)],
                               sensor_noise=SensorNoise(*noise, seed=seed) if noise else None)
            m = res.metrics(window).values  # (sample, response, statistic)
            for j, i in enumerate(idx[start:start + CHUNK]):
                if i in rows:
                    continue
                row = {"key": cases[i].key, **_flat(cases[i])}
                for r, resp in enumerate(RESPONSES):
                    for s, stat in enumerate(STATISTICS):
                        row[f"{resp}_{stat}"] = float(m[j, r, s])
                rows[i] = row
    return [rows[i] for i in range(len(cases))]


def _flat(c: Case) -> dict:
    d = {"scenario": c.scenario, "suspension": c.suspension, "damper": c.damper,
         "voltage": np.nan if c.voltage is None else c.voltage,
         "noise": json.dumps(list(c.noise)) if c.noise else "", "seed": c.seed}
    d.update({f"scenario.{k}": v for k, v in c.scenario_options})
    d.update({f"vehicle.{k}": v for k, v in c.vehicle})
    d.update({f"gain.{k}": v for k, v in c.gains})
    d["case"] = json.dumps(c.to_dict(), sort_keys=True, default=str)
    return d


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
    """Chunks run as tasks on a dask.distributed cluster (``address`` tcp://host:port or a
    ``scheduler_file``). Needs the optional extra: pip install "railride[distributed]"."""

    name = "dask"

    def __init__(self, address: str | None = None, scheduler_file: str | None = None,
                 timeout: float = 30.0):
        try:
            from distributed import Client
        except ImportError:
            raise ValueError("the Dask executor needs dask.distributed: pip install "
                             "\"railride[distributed]\"") from None
        if (address is None) == (scheduler_file is None):
            raise ValueError("give a scheduler address (tcp://host:port) or a scheduler file")
        try:
            self.client = Client(address, timeout=timeout) if address else \
                Client(scheduler_file=scheduler_file, timeout=timeout)
        except (OSError, TimeoutError) as exc:
            raise ValueError(f"cannot reach the Dask scheduler at {address or scheduler_file}: {exc}") from None

    def map(self, fn, chunks):
        from distributed import as_completed

        futures = {self.client.submit(fn, chunk, pure=False): i for i, chunk in enumerate(chunks)}
        for fut in as_completed(futures):
            yield futures[fut], fut.result()

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
                self.frame = pd.read_csv(self.path)
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
              dt: float = 1e-4, window=None, chunk: int = CHUNK, progress=None) -> pd.DataFrame:
    """Evaluate ``cases``, skipping those already in ``table``; returns their rows in order.

    ``progress(done, total, runs_per_second)`` is called after each chunk.
    """
    import functools

    executor = LocalExecutor() if executor is None else executor
    table = RunTable() if table is None else table
    done = table.done()
    keys = [c.key for c in cases]
    pending, seen = [], set()
    for c, k in zip(cases, keys):
        if k not in done and k not in seen:
            pending.append(c)
            seen.add(k)
    # group compatible cases so each chunk is one compiled batch
    pending.sort(key=lambda c: str(c.group))
    chunks = [pending[i:i + chunk] for i in range(0, len(pending), chunk)]
    fn = functools.partial(evaluate, base_gains=base_gains, dt=dt, window=window)
    t0, n_done = time.perf_counter(), 0
    if progress is not None:
        progress(0, len(pending), 0.0)
    for _, rows in executor.map(fn, chunks):
        table.add(rows)
        for row in rows:
            done[row["key"]] = row
        n_done += len(rows)
        if progress is not None:
            elapsed = time.perf_counter() - t0
            progress(n_done, len(pending), n_done / elapsed if elapsed > 0 else math.inf)
    return pd.DataFrame([done[k] for k in keys])
