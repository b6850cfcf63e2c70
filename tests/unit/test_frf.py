"""The frequency-response study (railride.frequency.frf): `FrfResult` follows the result protocol and its
document is that of `railride frf`; `Modes` is the modal table of `railride modes`."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import railride as rr
from clihelp import PNG, ok, ok_json
from railride.output import files
from railride.analysis.spectra import FRF_PATTERNS, frf_peaks
from railride.output.files import FRF_FILES
from railride.frequency.frf import FrfResult, Modes, frequency_responses, modes
from railride.model.modes import MODE_COLUMNS, checked_modes
from railride.model.params import PAPER, vehicle_record
from railride.model.vehicle import Mode, Vehicle


@pytest.fixture(scope="module")
def result():
    return frequency_responses(points=40)


def _failing_png(*args, **kwargs):
    raise OSError("disk full (simulated)")


def test_the_document_is_the_command_lines(result, tmp_path):
    assert result.to_dict() == ok_json("frf", "--points", 40)
    doc = ok_json("frf", "--rails", "anti-phase", "--points", 5, "--speed", 30, "--fmin", 0.5, "--fmax", 12)
    assert frequency_responses("paper", speed=30, rails="anti-phase", fmin=0.5, fmax=12, points=5).to_dict() == doc
    stiff = tmp_path / "stiff.toml"
    stiff.write_text('[vehicle]\npreset = "paper"\nk_sz = 5.8e5\n', encoding="utf-8")
    doc = ok_json("frf", "--points", 7, "--params", stiff)
    assert doc["vehicle_params_file"] == str(stiff)
    assert frequency_responses(stiff, points=7).to_dict() == doc


def test_the_vehicle_is_recorded_as_it_was_given():
    paper = rr.VehicleParams.preset("paper")
    assert frequency_responses(paper, points=3).to_dict()["vehicle_preset"] == "paper"
    custom = paper.replace(k_sz=5.8e5)
    doc = frequency_responses(custom, points=3).to_dict()
    assert "vehicle_preset" not in doc and doc["vehicle_params"] == custom.to_dict()
    assert list(doc)[:5] == ["schema", "railride_version", "versions", "vehicle_params", "vehicle"]
    assert doc["vehicle"] == {"name": "custom", "load": 1.0, "values": custom.to_dict()}
    with pytest.raises(ValueError, match="vehicle = 3"):
        frequency_responses(3)
    with pytest.raises(ValueError, match="params = 3"):
        frequency_responses(params=3)


def test_to_pandas_peaks_and_the_modal_table(result):
    frame = result.to_pandas()
    assert frame.shape == (2 * 40, 12) and list(frame["pattern"].unique()) == list(FRF_PATTERNS)
    assert frame["frequency_hz"].iloc[0] == 0.1 and frame["frequency_hz"].iloc[39] == 30.0
    assert result.peaks() == frf_peaks(frame) == result.to_dict()["peaks"]
    table = result.modes.to_pandas()
    assert list(table.columns) == list(MODE_COLUMNS) and len(table) == 9
    assert result.patterns == FRF_PATTERNS
    csv = ok("frf", "--points", 40, "--format", "csv").stdout
    assert csv == frame.to_csv(index=False)


def test_plot_draws_into_the_given_axes(result):
    mine = Figure()
    axes = mine.subplots(4, 2)  # per response its magnitude and its phase
    assert result.plot(ax=axes) is mine
    assert mine.get_axes() == list(axes.ravel())
    assert all(a.has_data() for a in axes.ravel())
    own = result.plot()
    assert own is not mine and len(own.get_axes()) == 8
    assert " ".join(own._suptitle.get_text().split()) == result.title()  # wrapped to the figure's width
    assert "V = 55.56 m/s, vehicle paper" in result.title()


def test_save_writes_the_frf_folder(result, tmp_path, monkeypatch):
    paths = result.save(tmp_path / "out")
    assert [p.name for p in paths] == list(FRF_FILES)
    assert json.loads((tmp_path / "out" / "frf.json").read_text()) == result.to_dict()
    assert (tmp_path / "out" / "frf.png").read_bytes().startswith(PNG)
    assert (tmp_path / "out" / "frf.csv").read_text() == result.to_pandas().to_csv(index=False)
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "out" / "modes.csv"), result.modes.to_pandas())
    monkeypatch.setattr(files, "plot_frf", _failing_png)
    with pytest.raises(OSError, match="simulated"):
        result.save(tmp_path / "new")
    before = {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()}
    with pytest.raises(OSError):
        result.save(tmp_path / "out")
    assert {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_modes_are_the_vehicles_and_the_command_lines():
    found = modes()
    assert isinstance(found, Modes) and len(found) == 9 and all(isinstance(m, Mode) for m in found)
    assert found.to_list() == ok_json("modes")["modes"] == [m.to_dict() for m in Vehicle().modes()]
    assert found.to_dict()["vehicle"] == ok_json("modes")["vehicle"] == vehicle_record(PAPER, "paper")
    assert found[1].label == "carbody bounce"
    assert found.to_pandas()["mode"].tolist() == list(range(1, 10))


def test_the_modes_document_records_the_vehicle_and_its_load():
    """`Modes.to_dict`: the ``railride.modes/1`` document of ``railride modes --format json``,
    with the vehicle's record; the modes of the loaded carbody, the values before the load."""
    loaded = modes("crh380a", load=1.3)
    doc = loaded.to_dict()
    assert (
        list(doc) == ["schema", "railride_version", "versions", "vehicle", "modes"]
        and doc["schema"] == "railride.modes/1"
    )
    assert doc["vehicle"] == vehicle_record(rr.VehicleParams.preset("crh380a"), "crh380a", 1.3)
    heavy = Vehicle(rr.VehicleParams.preset("crh380a").loaded(1.3)).modes()
    assert doc["modes"] == [m.to_dict() for m in heavy] != modes("crh380a").to_list()
    assert modes(params=PAPER).vehicle["name"] == "paper"
    with pytest.raises(ValueError, match="no vehicle record"):
        checked_modes(Vehicle()).to_dict()  # modes made without a record have no document


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"rails": "diagonal"}, "rails = 'diagonal': allowed in-phase, anti-phase, both"),
        ({"fmin": 0.0}, "fmin = 0.0: must be a finite number > 0"),
        ({"fmin": 5, "fmax": 2}, "fmax = 2 Hz: must be above fmin = 5 Hz"),
        ({"points": 1}, "points = 1: must be a whole number >= 2"),
        ({"points": 2.5}, "points = 2.5"),
        ({"speed": -1.0}, "speed = -1.0: must be a finite number > 0"),
    ],
)
def test_bad_input_names_the_field(kwargs, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        frequency_responses(**kwargs)


def test_the_result_is_exported():
    assert rr.FrfResult is FrfResult and rr.frequency_responses is frequency_responses
    assert np.all(np.diff(np.log(frequency_responses(points=9).frequency)) > 0)
