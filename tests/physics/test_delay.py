"""The controller's computation and communication delay (Suspension.delay), against the
definition: a demand takes effect `delay` controller periods after the sample it comes from."""

import numpy as np
import pytest

from railride.studies.comparison import compare
from railride.secondary.control import GainSet
from railride.run.simulation import simulate
from railride.secondary.suspension import Suspension
from railride.model.track import scenario

SC = scenario("paper-sine", duration=1.0)
BODY = ("carbody_bounce", "carbody_pitch", "carbody_roll")


@pytest.mark.parametrize("delay", [1, 5])
def test_the_demand_in_effect_was_computed_delay_periods_earlier(delay):
    s = Suspension.named("skyhook", GainSet.default()).with_delay(delay)
    ds = simulate(SC, suspension=s).dataset
    t = ds.time.values
    G, _ = GainSet.default().skyhook.gains(
        __import__("railride").Vehicle(__import__("railride").VehicleParams.preset("paper"))
    )
    sampled = 0.5 - delay * 1e-3  # the controller samples at 1 kHz, as the output
    m = np.array([float(ds[n].values[np.isclose(t, sampled)][0]) for n in (*BODY, *(f"{n}_velocity" for n in BODY))])
    held = ds.damper_demand_force.values[np.isclose(t, 0.5)][0]
    assert held == pytest.approx(G @ m, rel=1e-9)
    # no demand before the first one arrives
    early = ds.damper_demand_force.values[t < delay * 1e-3 - 1e-9]
    assert np.all(early == 0.0) and np.any(ds.damper_demand_force.values[t > delay * 1e-3] != 0.0)
    assert simulate(SC, suspension=s).to_dict()["suspension"].get("delay_periods", 1) == delay


def test_a_delay_that_makes_a_law_unstable_is_said_not_a_nan():
    cmp = compare(SC, controllers=["pid", "sas-attitude"], damper="ideal", delay=10)
    why = cmp.settings["not_run"]["pid"]
    assert why.startswith("diverged at t = ") and "with a delay of 10 controller periods" in why
    assert "sas-attitude" in cmp.names and cmp.settings["delay_periods"] == 10
    assert np.all(np.isfinite(cmp.metrics.values))


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Suspension.named("pid").with_delay(0), r"delay = 0: must be a whole number >= 1 and <= 64"),
        (lambda: Suspension.named("pid").with_delay(65), r"delay = 65: must be a whole number >= 1 and <= 64"),
        (lambda: Suspension.named("pid").with_delay(1.5), r"delay = 1.5: must be a whole number"),
        (lambda: Suspension.named("mr").with_delay(2), r"delay = 2: applies to a closed loop only"),
    ],
)
def test_bad_delays_name_the_field(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_a_study_over_delays_lists_the_unstable_runs():
    from railride.studies.study import study

    from railride.secondary.control import GainSet

    # the paper set's PID, whose loop on the ideal actuator is close to its sampled stability limit
    res = study(
        ["pid"], damper="ideal", track_seeds=[0], speeds=[40.0], delays=[1, 10], duration=1.0, gains=GainSet.default()
    )
    assert [(f["controller"], f["delay_periods"]) for f in res.failed] == [("pid", 10)]
    s = res.summary
    assert set(s[s.controller == "pid"]["delay"]) == {1, 10}
    assert s[(s.controller == "pid") & (s.delay == 1)]["n"].min() == 1
