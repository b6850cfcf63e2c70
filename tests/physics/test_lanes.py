"""The lane stepper (`railride.engine.lanes.run_lanes`): LANES samples advanced together in vector
form, against the sample-by-sample stepper (`run_batch`) it replaces for batches, and against
itself in other company."""

import numpy as np
import pytest

from railride import dampers

from railride.engine import lanes as engine_lanes
from railride.testing.agreement import histories, worst_difference
from railride.secondary.control import SensorNoise
from railride.errors import DivergenceError
from railride.model.params import VehicleParams
from railride.secondary.sensing import Accelerometers
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
from railride.secondary.suspension import Suspension
from railride.model.track import scenario

L = engine_lanes.LANES
SHORT = scenario("paper-sine", duration=0.5)
STIFF = scenario("paper-sine", duration=0.2)  # Spencer dampers: sub-stepped, slow
RK4 = SolverSettings(method="rk4")  # the linear suspensions would take the exact steps
LAWS = (  # every voltage law: tracking, on-off (skyhook-on-off), clipped (clipped-optimal)
    "pid",
    "sas-attitude",
    "sas-attitude-ride",
    "skyhook",
    "skyhook-on-off",
    "groundhook",
    "hybrid",
    "clipped-optimal",
)
PAPER = VehicleParams.preset("paper")
NOISE = SensorNoise(1e-4, 1e-4, 1e-3, 1e-3, 7)
FAULTS = (["1R-off"], ["2L-on@0.2"], ["1L-disconnected@0.1"], [], ["2R-off@0.3", "1R-on"], [], ["1L-disconnected"], [])

CASES = {
    "passive dashpots (in C)": dict(scenario=SHORT, params=[PAPER.replace(c_sz=c) for c in np.linspace(2e4, 1.2e5, 9)]),
    "viscous damper model (forces per stage)": dict(
        scenario=SHORT,
        params=[PAPER.replace(k_sz=k) for k in np.linspace(2e5, 6e5, 8)],
        suspension=Suspension.passive(dampers.Viscous(c=4e4)),
    ),
    "Bouc-Wen, open loop": dict(
        scenario=SHORT,
        suspension=[Suspension.semi_active("railway", voltage=float(v)) for v in np.linspace(0, 2.25, 9)],
    ),
    "Bouc-Wen, every law, delays 3 and 7": dict(
        scenario=SHORT,
        suspension=[Suspension.named(n) for n in LAWS]
        + [Suspension.named("sas-attitude").with_delay(3), Suspension.named("pid").with_delay(7)],
    ),
    "Spencer, open loop": dict(
        scenario=STIFF,
        suspension=[Suspension.semi_active("spencer1997", voltage=float(v)) for v in np.linspace(0, 2.25, 8)],
    ),
    "Spencer, every law": dict(scenario=STIFF, suspension=[Suspension.named(n, damper="spencer1997") for n in LAWS]),
    "ideal actuator": dict(scenario=SHORT, suspension=[Suspension.named(n, damper="ideal") for n in LAWS]),
    "ideal semi-active damper": dict(
        scenario=SHORT, suspension=[Suspension.named(n, damper="ideal-damper") for n in LAWS]
    ),
    "sensor noise": dict(scenario=SHORT, suspension=[Suspension.named(n, sensor_noise=NOISE) for n in LAWS]),
    "faults": dict(scenario=SHORT, suspension=[Suspension.named(n).with_faults(f) for n, f in zip(LAWS, FAULTS)]),
    "random track, eight speeds": dict(
        scenario=[scenario("fra4", duration=0.5, speed=float(v)) for v in np.linspace(20, 60, 8)],
        suspension=Suspension.named("sas-attitude-ride"),
    ),
}


@pytest.fixture
def lane_calls(monkeypatch):
    """How many kernel calls (chunks) went through the lane stepper."""
    calls = []
    make = engine_lanes.lanes_stepper

    def counted_stepper(*setup):
        step = make(*setup)

        def counted(*args):
            calls.append(args[0])
            return step(*args)

        return counted

    monkeypatch.setattr(engine_lanes, "lanes_stepper", counted_stepper)
    return calls


def _reference(monkeypatch, **kw):
    """The same run by run_batch, sample after sample."""
    with monkeypatch.context() as m:
        m.setattr(engine_lanes, "lanes_fit", lambda *args: False)
        return simulate(**kw)


@pytest.mark.parametrize("case", list(CASES))
def test_lanes_agree_with_the_sample_stepper(case, monkeypatch, lane_calls):
    kw = dict(CASES[case], solver=RK4, on_divergence="mark")
    lanes = simulate(**kw)
    assert lane_calls  # the batch went through the lane stepper ...
    ref = _reference(monkeypatch, **kw)
    assert len(lane_calls) == 1  # ... and the reference did not
    # the same arithmetic in another order: differences at rounding level (measured <= 1e-13)
    assert worst_difference(histories(lanes), histories(ref)) < 1e-11
    # (groundhook's gains are not stable on the ideal actuator: diverged alike in both)
    assert np.array_equal(lanes.diverged_at, ref.diverged_at, equal_nan=True)


def _sample(result, i):
    return {k: v[i] for k, v in histories(result).items()}


@pytest.mark.parametrize(
    "make",
    [
        lambda v: Suspension.semi_active("spencer1997", voltage=v),  # sub-step counts differ by voltage
        lambda v: Suspension.named(LAWS[int(v * 7 / 2.25)]).with_delay(1 + int(v * 4)),  # laws and delays
    ],
    ids=["Spencer, per-lane sub-steps", "every law and delay"],
)
def test_a_sample_does_not_depend_on_its_lane_mates(make):
    volts = np.linspace(0.0, 2.25, 16)
    first = [make(float(v)) for v in volts]
    # sample 5 again, now in lane 0 of the second group (padded) among other samples
    second = [make(float(v)) for v in volts[[9, 12, 3, 14, 0, 7, 11, 2]]] + [first[5]]
    a = simulate(STIFF, suspension=first, solver=RK4)
    b = simulate(STIFF, suspension=second, solver=RK4)
    assert _sample(a, 5)  # the loop below checks something
    for k, v in _sample(a, 5).items():
        assert np.array_equal(v, _sample(b, 8)[k]), k  # bit for bit


def test_a_diverging_lane_is_marked_and_the_others_go_on(monkeypatch, lane_calls):
    x0 = np.zeros((9, 18))
    x0[4, 9] = 1e5  # sample 4's carbody leaves +-1000 m within 0.01 s
    kw = dict(scenario=SHORT, suspension=[Suspension.named(n) for n in LAWS + ("pid",)], initial_state=x0, solver=RK4)
    lanes = simulate(**kw, on_divergence="mark")
    ref = _reference(monkeypatch, **kw, on_divergence="mark")
    assert lane_calls
    assert np.isfinite(lanes.diverged_at[4]) and lanes.diverged_at[4] == ref.diverged_at[4]
    assert np.all(np.isnan(np.delete(lanes.diverged_at, 4)))
    assert worst_difference(histories(lanes), histories(ref)) < 1e-11  # NaN from the same row on
    with pytest.raises(DivergenceError, match="sample 4 at t ="):
        simulate(**kw)


def test_padding_lanes_write_nothing_and_short_batches_take_the_sample_stepper(lane_calls):
    volts = [float(v) for v in np.linspace(0.0, 2.25, L + 1)]
    batch = simulate(SHORT, suspension=[Suspension.semi_active("railway", voltage=v) for v in volts])
    assert len(lane_calls) == 1
    # the last sample fills a group with its copies, which must leave its histories alone
    alone = simulate(SHORT, suspension=[Suspension.semi_active("railway", voltage=volts[-1])] * L)
    assert _sample(alone, 0)  # the loop below checks something
    for k, v in _sample(alone, 0).items():
        assert np.array_equal(v, _sample(batch, L)[k]), k
    simulate(SHORT, suspension=[Suspension.semi_active("railway", voltage=v) for v in volts[: L - 1]])
    assert len(lane_calls) == 2  # fewer samples than lanes: run_batch


def test_chunked_runs_continue_and_sensing_takes_the_sample_stepper(lane_calls):
    batch = [Suspension.named(n) for n in LAWS]
    whole = simulate(SHORT, suspension=batch)
    seen = []
    chunked = simulate(SHORT, suspension=batch, progress=seen.append)
    assert len(seen) > 1 and len(lane_calls) == len(seen) + 1
    assert worst_difference(histories(chunked), histories(whole)) < 1e-11
    sensed = [Suspension.named("sas-attitude").with_sensing(Accelerometers())] * L
    simulate(SHORT, suspension=sensed)
    assert len(lane_calls) == len(seen) + 1  # realistic sensing: run_batch only
