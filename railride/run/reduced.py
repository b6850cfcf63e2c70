"""Runs that keep only their ride metrics, summed as they step.

A study that reads only the RMS and peak-to-peak of the four carbody responses (a sweep, a tuning
round or a design's search without comfort or costs) needs no time history. On the GPU
(`railride.engine.gpu`, ``reduce``) and on the CPU's lane stepper (`railride.engine.lanes`,
``sums``) each sample adds every output row inside the window to its own sums of squares, least
and largest values (`railride.engine.sample_parts.accumulate_metrics`), so that a run takes a few
bytes instead of megabytes: a GPU can take the large batches that pay there, and the CPU no longer
writes, and the system no longer maps and clears, 11 MB of histories a 20-s run. Every other run
(a batch too small for the lanes, realistic sensing, the exact discretisation) runs whole and
takes `RideResult.metrics`, the one definition of the metrics; the sums give the same numbers to
rounding (the RMS is a sum in another order), tested against it.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from railride.analysis.metrics import RESPONSES, check_window
from railride.engine import layout
from railride.engine.sample_parts import ACC_MAX, ACC_MIN, ACC_ROWS, ACC_SQUARES, N_ACC
from railride.errors import DivergenceError, InputError
from railride.run.checks import check
from railride.run.simulation import (
    RunPlan,
    _gpu_failed,
    divergence_message,
    inputs,
    pack,
    run,
    stepped_on,
    stepper_arguments,
)


def batch_metrics(plan: RunPlan, window=None) -> tuple[np.ndarray, np.ndarray]:
    """(metrics, diverged_at) of the runs of a checked ``plan``: metrics (sample, response,
    statistic) as `RideResult.metrics` gives them (`railride.analysis.metrics.RESPONSES`, RMS
    and peak-to-peak, over ``window`` = (start, end) s), NaN for a run that diverged, and the
    time each diverged [s] (NaN where it did not). On the GPU the sums are made on the device,
    with no histories; a GPU failure says so in one line and runs the batch again on the CPU.
    On the CPU the lane stepper sums them likewise where it takes the batch; other batches run
    whole, in batches of `CPU_BATCH` whose histories bound the memory."""
    if stepped_on(plan) != "gpu":
        return _on_lanes(plan, window)
    from railride.engine import gpu

    w0, w1 = window_rows(plan.n_out + 1, plan.solver.output_rate, window)
    tables = inputs(plan)
    packed = pack(plan, tables, rows=2)  # two rows: "recorded" for the stepper, one row rewritten
    acc = _fresh_sums(plan.n)
    dt, stride = plan.solver.dt, plan.stride
    vehicle, dampers, rails, control, outputs = stepper_arguments(plan, tables, packed)
    try:
        gpu.run_gpu(
            plan.n, packed.law, packed.x, 0, plan.n_steps, True, stride, dt, vehicle, dampers, rails, control, outputs,
            reduce=((w0, w1), acc),
        )  # fmt: skip
    except gpu._Failed as failed:  # nothing of the batch is kept: it runs again, whole, on the CPU
        _gpu_failed(failed.cause)
        return _on_cpu(plan, window)
    return metrics_from_sums(acc, packed.status, packed.fail_step, dt, plan.on_divergence)


#: runs per CPU batch of a metrics-only plan: histories of the size a study's chunk holds
CPU_BATCH = 32


def _fresh_sums(n: int) -> np.ndarray:
    """n samples' metric sums before the first row: zero sums, +inf least, -inf largest."""
    acc = np.zeros((n, N_ACC))
    acc[:, ACC_MIN : ACC_MIN + 4] = math.inf
    acc[:, ACC_MAX : ACC_MAX + 4] = -math.inf
    return acc


def _on_lanes(plan: RunPlan, window) -> tuple[np.ndarray, np.ndarray]:
    """`batch_metrics` on the CPU's lane stepper, summed as it steps (`run_lanes`' ``sums``); a
    batch the lanes do not take (the exact steps, too few runs, or the rest of `lanes_fit`, which
    reads the packed arrays) runs whole (`_on_cpu`)."""
    from railride.engine import lanes

    if plan.exact or plan.n < lanes.LANES:  # before any packing
        return _on_cpu(plan, window)
    w0, w1 = window_rows(plan.n_out + 1, plan.solver.output_rate, window)
    tables = inputs(plan)
    packed = pack(plan, tables, rows=2)  # two rows: "recorded" for the stepper, one row rewritten
    if not lanes.lanes_fit(plan.n, packed.P, packed.control[7]):
        return _on_cpu(plan, window)
    acc = _fresh_sums(plan.n)
    arrays = tables.arrays
    step = lanes.lanes_stepper(plan.n, packed.law, arrays["A"], arrays["TS"], packed.P, arrays["stops"])
    sums = (True, np.array([w0, w1], dtype=np.int64), acc)
    dt, groups = plan.solver.dt, stepper_arguments(plan, tables, packed)
    step(plan.n, packed.law, packed.x, 0, plan.n_steps, True, plan.stride, dt, *groups, sums)
    return metrics_from_sums(acc, packed.status, packed.fail_step, dt, plan.on_divergence)


def _on_cpu(plan: RunPlan, window) -> tuple[np.ndarray, np.ndarray]:
    """`batch_metrics` on the CPU: whole runs, `RideResult.metrics` of their histories, in
    batches of `CPU_BATCH` runs (each checked again, for its own size)."""
    solver = dataclasses.replace(plan.solver, backend="cpu")
    values, diverged = [], []
    for lo in range(0, plan.n, CPU_BATCH):
        hi = min(plan.n, lo + CPU_BATCH)
        if hi - lo == plan.n and stepped_on(plan) == "cpu":
            part = plan
        else:
            x0 = plan.x0 if plan.x0 is None or plan.x0.ndim == 1 else plan.x0[lo:hi]  # one row, or a row a run
            on = (plan.scenarios[lo:hi], plan.param_sets[lo:hi], plan.suspensions[lo:hi])
            part = check(*on, solver, plan.on_divergence, x0)
        res = run(part)
        got = res.metrics(window).values
        values.append(got if got.ndim == 3 else got[None])
        diverged.append(np.atleast_1d(res.diverged_at))
    return np.concatenate(values), np.concatenate(diverged)


def window_rows(n_rows: int, output_rate: float, window) -> tuple[int, int]:
    """(first, last) output row inside ``window`` = (start, end) s, both included, as
    `RideResult.metrics` selects them; an input error where it holds fewer than two rows."""
    if window is None:
        return 0, n_rows - 1
    t = np.arange(n_rows) / output_rate
    start, end = check_window(window, float(t[-1]), float(t[0]))
    keep = np.flatnonzero((t >= start - 1e-12) & (t <= end + 1e-12))
    if keep.size < 2:
        raise InputError(f"window = {start:g}:{end:g} s holds fewer than two output samples")
    return int(keep[0]), int(keep[-1])


def metrics_from_sums(acc, status, fail_step, dt: float, on_divergence: str = "mark"):
    """(metrics, diverged_at) from the sums (`railride.engine.sample_parts.N_ACC` columns a
    sample): RMS = sqrt(sum x^2 / rows), peak-to-peak = largest - least, in the units of
    `RESPONSES`. A run that diverged raises `DivergenceError` unless ``on_divergence`` is "mark"."""
    bad = status != layout.STATUS_OK
    if bad.any() and on_divergence != "mark":
        raise DivergenceError(divergence_message(status, fail_step, dt))
    factor = np.array([f for _, f in RESPONSES.values()])
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(acc[:, ACC_SQUARES : ACC_SQUARES + 4] / acc[:, ACC_ROWS, None]) * factor
        ptp = (acc[:, ACC_MAX : ACC_MAX + 4] - acc[:, ACC_MIN : ACC_MIN + 4]) * factor
    values = np.stack([rms, ptp], axis=-1)
    values[bad] = np.nan
    if not np.all(np.isfinite(values[~bad])):
        raise RuntimeError("a ride metric is not finite: the run did not produce finite responses")
    return values, np.where(bad, fail_step * dt, np.nan)
