"""Runs that keep only their metrics on the CPU (`railride.run.reduced`): the lane stepper sums
each run's metric channels as it steps, with no history. Checked against `RideResult.metrics` of
the same batch's histories, which the same stepper writes: the states are the same to the bit, so
the metrics must agree to rounding (the RMS is a sum in another order, and the units' factor
multiplies the range instead of each value)."""

from __future__ import annotations

import numpy as np
import pytest

from railride.engine import lanes as engine_lanes
from railride.model.track import scenario
from railride.run.checks import check
from railride.run.reduced import batch_metrics
from railride.run.simulation import run
from railride.run.solver import SolverSettings
from railride.secondary.control import OUTER_LOOPS
from railride.secondary.suspension import Suspension

RK4 = SolverSettings(method="rk4", backend="cpu")  # passive too on the lanes (method auto: exact steps)
TRACK = scenario("fra4", seed=3, speed=50.0, duration=0.5)
# every law at two speeds, and passive (the dashpots' branch of the records) at nine: each more
# than one group of lanes
LAWS = [Suspension.named(n) for n in OUTER_LOOPS]
BATCHES = {
    "laws": ([TRACK] * len(LAWS) + [scenario("fra4", seed=3, speed=70.0, duration=0.5)] * len(LAWS), LAWS * 2),
    "passive": (
        [scenario("fra4", seed=3, speed=v, duration=0.5) for v in range(30, 75, 5)],
        [Suspension.named("passive")] * 9,
    ),
}


def _histories(plan, window):
    res = run(plan)
    return res.metrics(window).values, res.diverged_at


@pytest.mark.parametrize("window", [None, (0.1, 0.4), (0.1234, 0.1291)])
@pytest.mark.parametrize("batch", list(BATCHES))
def test_the_lane_sums_give_the_metrics_of_the_histories(batch, window, monkeypatch):
    tracks, suspensions = BATCHES[batch]
    assert len(suspensions) > engine_lanes.LANES
    used = []
    stepper = engine_lanes.lanes_stepper
    monkeypatch.setattr(engine_lanes, "lanes_stepper", lambda *a: used.append(1) or stepper(*a))
    summed, when = batch_metrics(check(tracks, None, suspensions, RK4, "mark"), window)
    assert used  # the lanes summed them: no histories
    kept, _ = _histories(check(tracks, None, suspensions, RK4, "mark"), window)
    assert summed.shape == (len(suspensions), 4, 2) and np.isnan(when).all()
    assert np.all(kept[:, :, 1] > 0)  # every response moved: the comparison can fail
    assert np.max(np.abs(summed - kept) / kept) < 1e-13


def test_a_diverging_run_has_nan_sums_its_time_and_the_others_stand():
    batch = [Suspension.named("skyhook")] * engine_lanes.LANES
    x0 = np.zeros((len(batch), 18))
    x0[3, 9] = 1e7  # sample 3's carbody leaves +-1000 m within a step or two
    summed, when = batch_metrics(check(TRACK, None, batch, RK4, "mark", x0))
    kept, kept_when = _histories(check(TRACK, None, batch, RK4, "mark", x0), None)
    assert np.isnan(summed[3]).all() and when[3] == kept_when[3] and np.isfinite(when[3])
    others = [i for i in range(len(batch)) if i != 3]
    assert np.isnan(when[others]).all() and np.max(np.abs(summed[others] - kept[others]) / kept[others]) < 1e-13


def test_batches_the_lanes_do_not_take_keep_their_histories(monkeypatch):
    # too few runs for a group of lanes: run whole, the metrics of their histories exactly
    few = LAWS[: engine_lanes.LANES - 1]
    monkeypatch.setattr(engine_lanes, "lanes_stepper", lambda *a: pytest.fail("the lanes took a batch too small"))
    summed, _ = batch_metrics(check(TRACK, None, few, RK4, "mark"))
    kept, _ = _histories(check(TRACK, None, few, RK4, "mark"), None)
    assert np.array_equal(summed, kept)
