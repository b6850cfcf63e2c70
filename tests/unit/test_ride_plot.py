"""`RideResult.plot`: one response into one Axes, the checks on ``ax`` and ``response``, and the
panels of responses a run does not excite, which say so instead of autoscaling rounding noise."""

import json

import numpy as np
import pytest
from matplotlib.figure import Figure

import railride as rr
from railride.errors import InputError
from railride.plots.ride import NOT_EXCITED, excited, plot_body_responses

PANELS = ["acceleration", "displacement", "pitch", "roll"]


@pytest.fixture(scope="module")
def symmetric():
    """The paper's sine on both rails alike: the symmetric car does not roll (0 up to rounding)."""
    return rr.simulate(rr.scenario("paper-sine", duration=1.0, rail_phase=0.0))


@pytest.fixture(scope="module")
def offset():
    """The paper's sine with its rails 90 deg apart: every response moves."""
    return rr.simulate(rr.scenario("paper-sine", duration=1.0))


def _said(ax) -> list[str]:
    return [t.get_text() for t in ax.texts]


def test_the_roll_panel_of_symmetric_rails_says_not_excited(symmetric):
    roll = symmetric.dataset["carbody_roll"].values
    assert 0 < np.abs(roll).max() < 1e-15  # the premise: rounding noise, not zero, not a roll
    fig = symmetric.plot()
    axes = fig.get_axes()
    assert [a.get_ylabel().split(" ")[0] for a in axes] == PANELS
    for a in axes[:3]:
        assert len(a.lines) == 1 and "not excited" not in _said(a)
    assert not axes[3].lines and _said(axes[3]) == ["not excited"]
    assert axes[3].get_ylabel() == "roll (deg)" and list(axes[3].get_yticks()) == []
    assert axes[3].get_xlim() == (0.0, 1.0)


def test_every_panel_of_offset_rails_is_drawn(offset):
    for a in offset.plot().get_axes():
        assert len(a.lines) == 1 and not a.texts


def test_anti_phase_rails_excite_roll_alone():
    ds = rr.simulate(rr.scenario("paper-sine", duration=1.0, rail_phase=180.0)).dataset
    assert excited(ds) == {"acceleration": False, "displacement": False, "pitch": False, "roll": True}


def test_the_rule_is_relative_to_the_largest_motion_of_its_kind(offset):
    ds = offset.dataset.copy(deep=True)
    record = json.loads(str(ds["vehicle_params"].values))
    # the largest carbody motion at the secondary corners, in metres (bounce, l pitch, d_s roll)
    scale = max(
        np.abs(ds["carbody_bounce"].values).max(),
        record["l"] * np.abs(ds["carbody_pitch"].values).max(),
        record["d_s"] * np.abs(ds["carbody_roll"].values).max(),
    )
    shape = ds["carbody_roll"].values / np.abs(ds["carbody_roll"].values).max()
    for fraction, moves in ((0.1 * NOT_EXCITED, False), (10 * NOT_EXCITED, True)):
        ds["carbody_roll"] = ("time", shape * fraction * scale / record["d_s"])
        assert excited(ds)["roll"] is moves
        assert excited(ds)["pitch"] and excited(ds)["displacement"]
    # a run that does not move excites nothing: every panel says so
    still = ds.copy(deep=True)
    for name in still.data_vars:
        if still[name].dtype.kind == "f":
            still[name] = still[name] * 0.0
    fig = plot_body_responses(still)
    assert all(_said(a) == ["not excited"] and not a.lines for a in fig.get_axes())


def test_a_batch_panel_is_drawn_when_one_sample_moves():
    batch = rr.simulate([rr.scenario("paper-sine", duration=0.5, rail_phase=p) for p in (0.0, 90.0)])
    assert excited(batch.dataset)["roll"]
    assert excited(batch.dataset.isel(sample=[0]))["roll"] is False
    axes = batch.plot().get_axes()
    assert len(axes[3].lines) == 2 and not axes[3].texts
    # the legend stays above the first panel when that one is not excited
    anti = rr.simulate([rr.scenario("paper-sine", duration=0.5, rail_phase=180.0, speed=v) for v in (40.0, 50.0)])
    first = anti.plot().get_axes()[0]
    assert _said(first) == ["not excited"]
    assert [t.get_text() for t in first.get_legend().get_texts()] == ["V = 40 m/s", "V = 50 m/s"]


def test_one_response_into_one_axes(offset):
    mine = Figure()
    ax = mine.subplots()
    assert offset.plot(ax=ax, response="pitch") is mine
    assert mine.get_axes() == [ax] and ax.get_ylabel() == "pitch (deg)"
    np.testing.assert_allclose(ax.lines[0].get_ydata(), np.degrees(offset.dataset["carbody_pitch"].values))
    # a sequence holding one Axes as well; and two responses into two
    other = Figure().subplots(1, 1, squeeze=False)
    offset.plot(ax=other, response="acceleration")
    np.testing.assert_array_equal(other[0, 0].lines[0].get_ydata(), offset.dataset["carbody_acceleration"].values)
    two = Figure().subplots(2)
    offset.plot(ax=two, response=["roll", "displacement"])
    assert [a.get_ylabel() for a in two] == ["roll (deg)", "displacement (m)"]
    # a figure of its own with the responses asked for
    assert [a.get_ylabel() for a in offset.plot(response="roll").get_axes()] == ["roll (deg)"]
    # four Axes, as before, return their figure
    four = Figure()
    assert offset.plot(ax=four.subplots(4, 1)) is four


def test_wrong_axes_and_responses_are_input_errors(offset):
    ax = Figure().subplots()
    with pytest.raises(InputError, match=r"ax = <Axes.*one Axes draws one response; pass response= one of "):
        offset.plot(ax=ax)
    with pytest.raises(InputError, match="ax = 'left': not matplotlib Axes; allowed None"):
        offset.plot(ax="left")
    with pytest.raises(InputError, match=r"ax = \[<Axes.*, 3\]: not matplotlib Axes"):
        offset.plot(ax=[ax, 3])
    with pytest.raises(InputError, match="ax: 4 Axes .*got 2 Axes; allowed"):
        offset.plot(ax=Figure().subplots(2))
    with pytest.raises(InputError, match="ax: 1 Axes .*got 4 Axes"):
        offset.plot(ax=Figure().subplots(4), response="roll")
    with pytest.raises(InputError, match="response = 'yaw': 'yaw' is not a response; allowed one of acceleration"):
        offset.plot(response="yaw")
    with pytest.raises(InputError, match=r"response = \['roll', 'roll'\]: a repeat"):
        offset.plot(response=["roll", "roll"])
    with pytest.raises(InputError, match="response = 3: 3 is not a response"):
        offset.plot(response=3)
