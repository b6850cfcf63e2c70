"""Controller tuning by the paper's sensitivity study (spec section 9).

One parameter at a time is swept over a logarithmic range (and 0) while the others stay fixed;
the best value is kept; passes repeat until a whole pass improves the objective by less than a
tolerance. Phases follow the paper: the six SAS attitude gains with the ride loop off, then the
eight ride gains with the attitude loop fixed; PID's three gains the same way; the inner loop's
B and G on the force-tracking error of the damper rig.

The objective of a vehicle run is sum_k w_k RMS_k / RMS_k(passive) over the four carbody
responses (acceleration, displacement, pitch, roll), weights settable, plus ``penalty`` times
any ratio above 1 (0 by default: the paper's plain sum; the shipped gains use 10 so that no
response gets worse than passive).

Every vehicle evaluation goes through `railride.sweep.run_cases`, so it can run on a Dask
cluster and lands in the run table; the study itself is deterministic given the results, so a
resumed study replays its path from the table and only evaluates what is missing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .control import GainSet, InnerLoop
from .metrics import RESPONSES
from .sweep import Case, RunTable, apply_gains, run_cases

PHASES = ("inner", "pid", "attitude", "ride")
PARAMETERS = {
    "inner": ("inner.B", "inner.G"),
    "pid": ("pid.kp", "pid.ki", "pid.kd"),
    "attitude": ("attitude.kp_z", "attitude.kd_z", "attitude.kp_phi", "attitude.kd_phi",
                 "attitude.kp_theta", "attitude.kd_theta"),
    "ride": tuple(f"ride.{k}_{c}" for k in ("kp", "kd") for c in ("1R", "1L", "2R", "2L")),
}
SUSPENSION = {"pid": "pid", "attitude": "sas-attitude", "ride": "sas-attitude-ride"}
#: where a sweep starts for a gain that is 0 (scaled from the passive suspension, see gains.toml)
REFERENCE = {"pid.kp": 1e5, "pid.ki": 1e5, "pid.kd": 8e4, "attitude.kp_z": 4e5, "attitude.kd_z": 3.2e5,
             "attitude.kp_phi": 3.24e7, "attitude.kd_phi": 2.6e7, "attitude.kp_theta": 4e5,
             "attitude.kd_theta": 3.2e5, "inner.B": 1.0, "inner.G": 1e-3,
             **{f"ride.kp_{c}": 5e4 for c in ("1R", "1L", "2R", "2L")},
             **{f"ride.kd_{c}": 4e4 for c in ("1R", "1L", "2R", "2L")}}


@dataclass(frozen=True)
class Objective:
    """sum_k w_k RMS_k / RMS_k(passive) + penalty * sum_k max(0, RMS_k / RMS_k(passive) - 1)."""

    weights: tuple = (1.0, 1.0, 1.0, 1.0)  # acceleration, displacement, pitch, roll
    penalty: float = 0.0

    def __post_init__(self):
        w = tuple(float(x) for x in self.weights)
        if len(w) != 4 or not all(math.isfinite(x) and x >= 0 for x in w) or sum(w) == 0:
            raise ValueError(f"objective weights = {self.weights!r}: four numbers >= 0, not all 0 "
                             "(acceleration, displacement, pitch, roll)")
        if not (math.isfinite(self.penalty) and self.penalty >= 0):
            raise ValueError(f"objective penalty = {self.penalty!r}: a number >= 0")
        object.__setattr__(self, "weights", w)

    def __call__(self, rms: np.ndarray, passive: np.ndarray) -> np.ndarray:
        ratio = np.asarray(rms) / passive
        return ratio @ np.array(self.weights) + self.penalty * np.clip(ratio - 1, 0, None).sum(axis=-1)


@dataclass
class Curve:
    """The sensitivity curve of one parameter in one pass: objective against value."""

    phase: str
    sweep_pass: int
    parameter: str
    values: np.ndarray
    objective: np.ndarray
    chosen: float


@dataclass
class TuneResult:
    gains: GainSet
    curves: list[Curve] = field(default_factory=list)
    history: list[dict] = field(default_factory=list)  # objective after each pass of each phase
    runs: pd.DataFrame | None = None
    passive: dict | None = None


def _rms(rows: pd.DataFrame) -> np.ndarray:
    return rows[[f"{r}_rms" for r in RESPONSES]].to_numpy()


def _candidates(current: float, parameter: str, n_values: int, span: float) -> list[float]:
    ref = current if current > 0 else REFERENCE[parameter]
    values = ref * np.logspace(-math.log10(span), math.log10(span), n_values)
    # four significant digits: gains a person can read and type, nothing lost to the study
    vals = sorted({0.0, float(current), *[float(f"{v:.4g}") for v in values]})
    if parameter == "inner.B":
        vals = [v for v in vals if v > 0]  # B = 0 ignores the measured force
    return vals


def tune(phases=("attitude", "ride"), *, scenario: str = "paper-sine", scenario_options=None,
         gains: GainSet | None = None, objective: Objective | None = None, damper: str = "railway",
         executor=None, table: RunTable | None = None, n_values: int = 13, span: float = 30.0,
         max_passes: int = 5, tol: float = 1e-3, dt: float = 1e-4, window=None, progress=None,
         log=None) -> TuneResult:
    """The sensitivity study: the phases in order (from PHASES), each to convergence.

    ``n_values`` log-spaced values from 1/span to span times the current value (and 0) per
    parameter; a pass ends when every parameter of the phase was swept; a phase ends when a pass
    improves the objective by less than ``tol`` (relative) or after ``max_passes``.
    ``progress(done, total, runs_per_second)`` after each chunk; ``log(text)`` after each pass.
    """
    gains = GainSet.default() if gains is None else gains
    objective = Objective() if objective is None else objective
    opts = tuple(sorted((scenario_options or {}).items()))
    table = RunTable() if table is None else table
    unknown = [p for p in phases if p not in PHASES]
    if unknown:
        raise ValueError(f"unknown phase {unknown[0]!r}; allowed: {', '.join(PHASES)}, all")
    if not (isinstance(n_values, int) and n_values >= 3):
        raise ValueError(f"n_values = {n_values!r}: a whole number >= 3")
    if not (span > 1):
        raise ValueError(f"span = {span!r}: must be > 1")
    base = gains
    result = TuneResult(gains)

    def run(cases):
        return run_cases(cases, executor=executor, table=table, base_gains=base, dt=dt,
                         window=window, progress=progress)

    passive = _rms(run([Case(scenario, opts)]))[0]
    result.passive = dict(zip(RESPONSES, passive))
    changes: dict[str, float] = {}

    def current_value(p):
        return changes.get(p, getattr(_table(base, p), p.split(".")[1]))

    for phase in phases:
        params = PARAMETERS[phase]
        if phase == "inner":
            _tune_inner(base, changes, params, n_values, span, max_passes, tol, result, log, damper)
            continue
        suspension = SUSPENSION[phase]
        def score(change_sets):
            cases = [Case(scenario, opts, suspension=suspension, damper=damper,
                          gains=tuple(sorted({**changes, **cs}.items()))) for cs in change_sets]
            return objective(_rms(run(cases)), passive)
        best = float(score([{}])[0])
        for sweep_pass in range(1, max_passes + 1):
            start = best
            for p in params:
                vals = _candidates(current_value(p), p, n_values, span)
                obj = score([{p: v} for v in vals])
                k = int(np.argmin(obj))
                if obj[k] < best - 1e-12:
                    changes[p], best = vals[k], float(obj[k])
                result.curves.append(Curve(phase, sweep_pass, p, np.array(vals), np.asarray(obj),
                                           current_value(p)))
            result.history.append({"phase": phase, "pass": sweep_pass, "objective": best})
            if log is not None:
                log(f"{phase} pass {sweep_pass}: objective {best:.4f}")
            if start - best < tol * abs(start):
                break
    result.gains = apply_gains(base, tuple(changes.items()))
    result.runs = table.frame
    return result


def _table(gains: GainSet, parameter: str):
    return {"inner": gains.inner, "pid": gains.pid, "attitude": gains.attitude,
            "ride": gains.ride}[parameter.split(".")[0]]


def tracking_objective(B: float, G: float, damper="railway") -> float:
    """The inner loop's objective: normalised RMS tracking error, averaged over the paper's
    sine and sawtooth demands (Fig. 6) at 10 kN, 1 Hz on the damper rig."""
    from .rig import track

    return float(np.mean([track(damper, kind, 10e3, 1.0, B=B, G=G).metrics()["normalised_rms_error"]
                          for kind in ("sine", "sawtooth")]))


def _tune_inner(base, changes, params, n_values, span, max_passes, tol, result, log, damper):
    """B and G on the rig's force-tracking error (cheap: evaluated here, not on the executor)."""
    def value(p):
        return changes.get(p, getattr(base.inner, p.split(".")[1]))

    best = tracking_objective(value("inner.B"), value("inner.G"), damper)
    for sweep_pass in range(1, max_passes + 1):
        start = best
        for p in params:
            vals = _candidates(value(p), p, n_values, span)
            obj = np.array([tracking_objective(**{**{"B": value("inner.B"), "G": value("inner.G")},
                                                 p.split(".")[1]: v}, damper=damper) for v in vals])
            k = int(np.argmin(obj))
            if obj[k] < best - 1e-12:
                changes[p], best = vals[k], float(obj[k])
            result.curves.append(Curve("inner", sweep_pass, p, np.array(vals), obj, value(p)))
        result.history.append({"phase": "inner", "pass": sweep_pass, "objective": best})
        if log is not None:
            log(f"inner pass {sweep_pass}: tracking error {best:.4f}")
        if start - best < tol * abs(start):
            break
    return best
