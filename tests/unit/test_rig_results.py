"""The damper rig's results (railride.run.rig): `Cycles` and `Tracking` follow the result protocol,
their documents are those of `railride damper` / `railride tracking`, and `TrackingMetrics`."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from clihelp import PNG, ok_json
from railride.output import files
from railride.run import rig
from railride.output.files import DAMPER_FILES, TRACKING_FILES


@pytest.fixture(scope="module")
def cycles():
    return rig.cycles("railway", 0.01, 2.0, [0.0, 2.25], n_cycles=2)


@pytest.fixture(scope="module")
def tracking():
    return rig.track(n_cycles=2)


def _failing_png(*args, **kwargs):
    raise OSError("disk full (simulated)")


# -- Cycles ---------------------------------------------------------------------------------------
def test_cycles_document_is_the_command_lines(cycles):
    cli = ok_json("damper", "--amplitude", 0.01, "--frequency", 2, "--voltage", "0,2.25", "--cycles", 2)
    assert cycles.to_dict() == cli
    doc = ok_json(
        "damper", "--amplitude", 0.005, "--frequency", 4, "--voltage", "2.25,0.5", "--model", "dyke1996", "--cycles", 3
    )
    assert rig.cycles("dyke1996", 0.005, 4.0, [2.25, 0.5], n_cycles=3).to_dict() == doc


def test_cycles_to_pandas_is_the_csv_table(cycles):
    frame = cycles.to_pandas()
    assert list(frame.columns) == ["voltage", "time", *rig_channels()]
    assert len(frame) == cycles.dataset.sizes["voltage"] * cycles.dataset.sizes["time"]
    high = frame[frame["voltage"] == 2.25]
    assert high["F"].max() == cycles.to_dict()["cycles"][1]["force_max_n"]


def rig_channels():
    from railride.output.tables import RIG_CHANNELS

    return list(RIG_CHANNELS)


def test_cycles_plot_draws_into_the_given_axes(cycles):
    mine = Figure()
    axes = mine.subplots(1, 2)
    assert cycles.plot(ax=axes) is mine
    assert mine.get_axes() == list(axes)
    for a in axes:  # one loop per voltage
        assert [line.get_label() for line in a.lines if line.get_label().endswith(" V")] == ["0 V", "2.25 V"]
    own = cycles.plot()
    assert own is not mine and len(own.get_axes()) == 2
    assert own._suptitle.get_text() == ("railway damper (bouc-wen model), x = 10 mm sin(2 pi 2 Hz t), cycle 2 of 2")


def test_cycles_save(cycles, tmp_path, monkeypatch):
    paths = cycles.save(tmp_path / "out")
    assert [p.name for p in paths] == list(DAMPER_FILES)
    assert json.loads((tmp_path / "out" / "damper.json").read_text()) == cycles.to_dict()
    assert (tmp_path / "out" / "loops.png").read_bytes().startswith(PNG)
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "out" / "cycles.csv"), cycles.to_pandas())
    # all or nothing: a failing figure leaves no folder, and an existing one as it was
    monkeypatch.setattr(files, "plot_hysteresis", _failing_png)
    with pytest.raises(OSError, match="simulated"):
        cycles.save(tmp_path / "new")
    before = {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()}
    with pytest.raises(OSError):
        cycles.save(tmp_path / "out")
    assert {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_cycles_refuse_bad_input_naming_the_field():
    with pytest.raises(ValueError, match=r"n_cycles = 1: must be a whole number >= 2 \(the first cycle is start-up\)"):
        rig.cycles("railway", 0.01, 1.0, [0.0], n_cycles=1)
    with pytest.raises(ValueError, match="amplitude = 0.0: must be a finite number > 0"):
        rig.cycles("railway", 0.0, 1.0, [0.0])
    with pytest.raises(ValueError, match="frequency = 1000.0 Hz: a cycle"):
        rig.cycles("railway", 0.01, 1000.0, [0.0])


# -- Tracking -------------------------------------------------------------------------------------
def test_tracking_document_is_the_command_lines(tracking):
    assert tracking.to_dict() == ok_json("tracking", "--cycles", 2)
    doc = ok_json(
        "tracking",
        "--desired",
        "sawtooth",
        "--cycles",
        2,
        "--B",
        0.5,
        "--G",
        0.002,
        "--frequency",
        2,
        "--amplitude",
        5000,
        "--model",
        "dyke1996",
        "--stroke",
        0.03,
    )
    result = rig.track("dyke1996", "sawtooth", 5000.0, 2.0, B=0.5, G=0.002, stroke=0.03, n_cycles=2)
    assert result.to_dict() == doc


def test_tracking_metrics_are_a_typed_value(tracking):
    m = tracking.metrics()
    assert isinstance(m, rig.TrackingMetrics)
    assert m.window_s == (1.0, 2.0) and m.window_s == tracking.window
    assert m.normalised_rms_error == m.rms_error_n / m.rms_demand_n
    assert m.rms_demand_n == pytest.approx(10e3 / math.sqrt(2), rel=1e-3)
    assert m.to_dict() == {
        "rms_error_n": m.rms_error_n,
        "rms_demand_n": m.rms_demand_n,
        "normalised_rms_error": m.normalised_rms_error,
        "window_s": [1.0, 2.0],
    }
    assert m.to_dict() == tracking.to_dict()["metrics"]
    with pytest.raises(dataclasses.FrozenInstanceError):
        m.rms_error_n = 0.0
    # the fields are plain floats, whatever they were built from
    built = rig.TrackingMetrics(np.float32(1.5), 3, np.float64(0.5), [np.int64(1), 2])
    assert built == rig.TrackingMetrics(1.5, 3.0, 0.5, (1.0, 2.0))
    assert all(type(v) is float for v in (built.rms_error_n, built.rms_demand_n, *built.window_s))
    # no demand: the normalised error is undefined
    silent = dataclasses.replace(
        tracking, dataset=tracking.dataset.assign(desired_force=tracking.dataset["desired_force"] * 0.0)
    )
    assert math.isnan(silent.metrics().normalised_rms_error)


def test_tracking_to_pandas_is_the_csv_table(tracking):
    frame = tracking.to_pandas()
    assert frame.index.name == "time" and len(frame) == tracking.dataset.sizes["time"]
    assert {"F", "desired_force", "u", "v"} <= set(frame.columns)
    np.testing.assert_array_equal(frame["F"].values, tracking.dataset["F"].values)


def test_tracking_plot_draws_into_the_given_axes(tracking):
    mine = Figure()
    axes = mine.subplots(2, 1)
    assert tracking.plot(ax=axes) is mine
    assert mine.get_axes() == list(axes) and len(axes[0].lines) == 2 and len(axes[1].lines) == 2
    own = tracking.plot()
    assert own._suptitle.get_text().startswith(
        "sine demand 10 kN at 1 Hz, railway damper, B = 1, G = 0.00115 V/N: normalised RMS error 0.20"
    )


def test_tracking_save(tracking, tmp_path, monkeypatch):
    paths = tracking.save(tmp_path / "out")
    assert [p.name for p in paths] == list(TRACKING_FILES)
    assert json.loads((tmp_path / "out" / "tracking.json").read_text()) == tracking.to_dict()
    frame = pd.read_csv(tmp_path / "out" / "tracking.csv", index_col="time")
    pd.testing.assert_frame_equal(frame, tracking.to_pandas())
    monkeypatch.setattr(files, "plot_tracking", _failing_png)
    with pytest.raises(OSError, match="simulated"):
        tracking.save(tmp_path / "new")
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_tracking_refuses_bad_input_naming_the_field():
    with pytest.raises(ValueError, match="desired = 'square': allowed sine, sawtooth"):
        rig.track(desired="square")
    with pytest.raises(ValueError, match=r"n_cycles = 1: .*\(the first cycle is start-up\)"):
        rig.track(n_cycles=1)
    with pytest.raises(ValueError, match="G = nan"):
        rig.track(G=float("nan"), n_cycles=2)
    with pytest.raises(ValueError, match="stroke = 0.0"):
        rig.track(stroke=0.0)
