"""The vehicle on every command and function: ``--vehicle NAME|FILE.toml`` (``--params`` is the same
option, ``--preset NAME`` exclusive with it) and ``--load X``; ``vehicle=`` (alias ``params=``) and
``load=`` in the library; and the record of the vehicle (name, load, values) in every output."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pandas as pd
import pytest

import railride as rr
from railride.errors import InputError
from railride.model.params import PRESETS, VehicleParams, resolve_vehicle, vehicle_record, vehicle_text

from clihelp import assert_input_error, ok, ok_json, run

PAPER = VehicleParams.preset("paper")
M_C = 4.2e4  # the file's carbody mass, the one value it changes

#: every command that runs the vehicle, on its smallest case
COMMANDS = {
    "simulate": ["simulate", "--duration", 1],
    "compare": ["compare", "--duration", 1, "--controllers", "pid", "--no-bounds"],
    "tune": ["tune", "--controllers", "pid", "--values", 3, "--budget", 5, "--duration", 1],
    "study": ["study", "--controllers", "passive", "--track-seed", 0, "--duration", 1],
    "sweep": ["sweep", "--duration", 1],
    "pareto": ["pareto", "--suspension", "pid", "--samples", 1, "--duration", 1],
    "report": ["report", "--duration", 1, "--controllers", "pid", "--no-bounds"],
    "modes": ["modes"],
    "frf": ["frf", "--points", 5],
    "ride-spectrum": ["ride-spectrum", "--points", 32, "--controllers", "passive"],
    "state-space": ["state-space"],
}
#: where each command's JSON document (--format json) keeps the vehicle record; None: no document
#: on stdout (report writes HTML, sweep prints its rows)
RECORD = {
    "simulate": lambda doc: doc["vehicle"],
    "compare": lambda doc: doc["settings"]["vehicle"],
    "tune": lambda doc: doc["settings"]["vehicle"],
    "study": lambda doc: doc["settings"]["vehicle"],
    "sweep": None,
    "pareto": lambda doc: doc["settings"]["vehicle"],
    "report": None,
    "modes": lambda doc: doc["vehicle"],
    "frf": lambda doc: doc["vehicle"],
    "ride-spectrum": lambda doc: doc["settings"]["vehicle"],
    "state-space": lambda doc: doc["vehicle"],
}


@pytest.fixture
def car(tmp_path) -> Path:
    """A parameters file: the paper's vehicle with a heavier carbody."""
    path = tmp_path / "car.toml"
    path.write_text(f'[vehicle]\npreset = "paper"\nm_c = {M_C!r}\n', encoding="utf-8")
    return path


def _args(name: str, tmp_path: Path) -> list:
    args = list(COMMANDS[name])
    if name in ("tune", "study", "sweep", "pareto"):  # their run tables stay out of the working tree
        args += ["--out", tmp_path / "out"]
    if name == "report":
        args += ["--out", tmp_path / "report.html"]
    return args


# -- the command line -------------------------------------------------------------------------------
@pytest.mark.parametrize("form", ["--vehicle paper", "--vehicle FILE", "--params FILE"])
@pytest.mark.parametrize("name", list(COMMANDS))
def test_every_command_takes_a_preset_or_a_file(name, form, car, tmp_path):
    option, value = form.split()
    value = car if value == "FILE" else value
    args = [*_args(name, tmp_path), option, value]
    if RECORD[name] is None:
        ok(*args)
        return
    record = RECORD[name](ok_json(*args))
    assert record["name"] == str(value) and record["load"] == 1.0
    assert record["values"] == (PAPER.replace(m_c=M_C) if value == car else PAPER).to_dict()


@pytest.mark.parametrize("name", list(COMMANDS))
def test_an_unknown_vehicle_exits_2_before_any_work_naming_the_presets(name, tmp_path):
    result = run(*_args(name, tmp_path), "--vehicle", "no-such-car")
    assert_input_error(result, "--vehicle", "'no-such-car'", "FILE.toml", *PRESETS)
    assert not (tmp_path / "out").exists() and not (tmp_path / "report.html").exists()


@pytest.mark.parametrize("name", ["simulate", "tune", "modes"])
def test_vehicle_and_preset_are_exclusive_and_a_missing_file_is_named(name, tmp_path):
    assert_input_error(run(*_args(name, tmp_path), "--vehicle", "paper", "--preset", "paper"), "not both")
    missing = tmp_path / "missing.toml"
    assert_input_error(run(*_args(name, tmp_path), "--vehicle", missing), str(missing))
    assert_input_error(run(*_args(name, tmp_path), "--preset", "no-such-car"), "--preset", "no-such-car")


@pytest.mark.parametrize("name", ["simulate", "compare", "pareto", "modes", "frf", "ride-spectrum", "state-space"])
def test_a_load_factor_is_recorded_with_the_vehicle(name, car, tmp_path):
    record = RECORD[name](ok_json(*_args(name, tmp_path), "--vehicle", car, "--load", 1.25))
    assert record == {"name": str(car), "load": 1.25, "values": PAPER.replace(m_c=M_C).to_dict()}


def test_the_tables_captions_name_the_vehicle_and_load(car, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # a short path, which a caption keeps on one line
    assert "vehicle: paper, load 1.3" in ok("simulate", "--duration", 1, "--load", 1.3).stdout
    assert "vehicle: paper, load 1.3" in ok("modes", "--load", 1.3).stdout
    assert "vehicle: car.toml, load 1" in ok(*_args("sweep", tmp_path), "--vehicle", "car.toml").stdout
    pareto = ["pareto", "--suspension", "pid", "--samples", 1, "--duration", 1, "--out", tmp_path / "pareto"]
    assert "vehicle: car.toml, load 1.1" in ok(*pareto, "--vehicle", car.name, "--load", 1.1).stdout
    study = ["study", "--controllers", "passive", "--track-seed", 0, "--duration", 1, "--out", tmp_path / "study"]
    text = ok(*study, "--vehicle", "paper", "--load", "1,1.3").stdout
    assert "vehicle: paper, loads 1, 1.3" in text


def test_the_study_and_sweep_files_record_the_vehicle(car, tmp_path):
    ok(*_args("study", tmp_path), "--vehicle", car, "--load", "1,1.3")
    runs = pd.read_csv(tmp_path / "out" / "study_runs.csv")
    assert set(runs["vehicle"]) == {str(car)} and set(runs["load"]) == {1.0, 1.3}
    # the run table too, each run with its own load
    table = pd.read_csv(tmp_path / "out" / "runs.csv")
    assert set(table["vehicle"]) == {str(car)} and sorted(table["load"]) == [1.0, 1.3]
    doc = json.loads((tmp_path / "out" / "study.json").read_text())
    assert doc["settings"]["vehicle"]["load"] == [1.0, 1.3]
    sweep = ["sweep", "--duration", 1, "--vehicle", car, "--load", 1.1, "--out", tmp_path / "sweep"]
    printed = pd.read_csv(io.StringIO(ok(*sweep, "--format", "csv").stdout))
    assert printed[["vehicle", "load"]].values.tolist() == [[str(car), 1.1]]
    record = json.loads((tmp_path / "sweep" / "sweep.json").read_text())["settings"]["vehicle"]
    assert (record["name"], record["load"]) == (str(car), 1.1)
    table = pd.read_csv(tmp_path / "sweep" / "runs.csv")
    assert table[["vehicle", "load"]].values.tolist() == [[str(car), 1.1]]


def test_ride_nc_and_the_report_record_the_vehicle(car, tmp_path):
    import xarray as xr

    ok("simulate", "--duration", 1, "--vehicle", car, "--load", 1.2, "--out", tmp_path / "run")
    with xr.open_dataset(tmp_path / "run" / "ride.nc") as ds:
        record = json.loads(ds.attrs["vehicle"])
    assert (record["name"], record["load"], record["values"]["m_c"]) == (str(car), 1.2, M_C)
    ok(*_args("report", tmp_path), "--vehicle", car, "--load", 1.2)
    page = (tmp_path / "report.html").read_text(encoding="utf-8")
    assert f"{car}, load 1.2" in page


def test_the_league_table_records_the_vehicle(car, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    args = ["compare", "--scenario", "paper-sine,bump", "--duration", 1, "--controllers", "pid"]
    args += ["--vehicle", "car.toml", "--load", 1.2]
    doc = ok_json(*args)
    assert doc["settings"]["vehicle"] == {"name": "car.toml", "load": 1.2, "values": PAPER.replace(m_c=M_C).to_dict()}
    assert {c["vehicle"] for c in doc["cases"]} == {"car.toml"}
    assert "vehicle: car.toml, load 1.2" in ok(*args).stdout
    ok(*args, "--out", tmp_path / "league")
    assert set(pd.read_csv(tmp_path / "league" / "league.csv")["vehicle"]) == {"car.toml"}


# -- the library ------------------------------------------------------------------------------------
def test_the_record_names_a_preset_a_file_or_custom(car):
    assert vehicle_record(PAPER) == {"name": "paper", "load": 1.0, "values": PAPER.to_dict()}
    assert vehicle_record(PAPER.replace(m_c=M_C))["name"] == "custom"
    assert resolve_vehicle(str(car))[1]["name"] == str(car)
    assert resolve_vehicle(car, load=1.5)[0] == PAPER.replace(m_c=M_C).loaded(1.5)
    assert vehicle_record(PAPER, "paper", [1.0, 1.3])["load"] == [1.0, 1.3]
    assert vehicle_text(vehicle_record(PAPER, load=1.3)) == "vehicle: paper, load 1.3"
    with pytest.raises(InputError, match="load = 0"):
        vehicle_record(PAPER, load=0)
    with pytest.raises(InputError, match=r"vehicle = 'no-such-car': unknown vehicle preset.*FILE\.toml"):
        resolve_vehicle("no-such-car")
    with pytest.raises(InputError, match="params = 'no-such-car'"):
        resolve_vehicle(params="no-such-car")
    with pytest.raises(InputError, match="not both|give the vehicle once"):
        resolve_vehicle("paper", "paper")


@pytest.fixture(scope="module")
def short():
    return rr.scenario("paper-sine", duration=1.0)


def test_simulate_and_compare_take_a_name_a_path_or_parameters(short, car):
    heavy = PAPER.replace(m_c=M_C)
    # simulate's second argument (params) takes a preset name, the path of a file or parameters
    assert rr.simulate(short, str(car)).metrics().equals(rr.simulate(short, heavy).metrics())
    assert rr.simulate(short, "paper").metrics().equals(rr.simulate(short, PAPER).metrics())
    for kwargs in ({"vehicle": car}, {"params": str(car)}, {"vehicle": heavy}):
        comp = rr.compare(short, controllers=["passive"], bounds=False, **kwargs)
        assert comp.settings["vehicle_params"] == heavy.to_dict()
    comp = rr.compare(short, vehicle="paper", load=1.3, controllers=["passive"], bounds=False)
    assert comp.settings["vehicle"] == {"name": "paper", "load": 1.3, "values": PAPER.to_dict()}
    assert comp.settings["vehicle_params"] == PAPER.loaded(1.3).to_dict() and not comp.paper_case
    with pytest.raises(InputError, match="give the vehicle once"):
        rr.compare(short, vehicle="paper", params="paper")


def test_a_vehicle_object_is_taken_wherever_its_parameters_are(short):
    """A `Vehicle` stands for its parameters (it was refused as "must be VehicleParams")."""
    heavy = PAPER.replace(m_c=M_C)
    car = rr.Vehicle(heavy)
    assert rr.simulate(short, car).metrics().equals(rr.simulate(short, heavy).metrics())
    assert rr.simulate(short, vehicle=car).metrics().equals(rr.simulate(short, heavy).metrics())
    assert rr.modes(car).to_dict() == rr.modes(heavy).to_dict()
    comp = rr.compare(short, vehicle=car, controllers=["passive"], bounds=False)
    assert comp.settings["vehicle_params"] == heavy.to_dict()
    with pytest.raises(InputError, match=r"must be VehicleParams, a Vehicle, a preset name \(paper"):
        rr.simulate(short, 3.0)


def test_the_studies_take_a_name_a_path_or_parameters(car, tmp_path):
    from railride.studies.sweep import grid

    heavy = PAPER.replace(m_c=M_C)
    for given, name in (("paper", "paper"), (car, str(car)), (heavy, "custom")):
        st = rr.study(["passive"], track_seeds=[0], duration=1.0, vehicle=given)
        assert st.settings["vehicle"]["name"] == name and set(st.cases["vehicle"]) == {name}
        sw = rr.run_sweep(grid(["passive"], duration=1.0), vehicle=given, comfort=False)
        assert sw.to_dict()["settings"]["vehicle"]["name"] == name
    pa = rr.pareto("pid", n_samples=1, scenario_options={"duration": 1.0}, vehicle=str(car), load=1.1)
    assert (pa.settings["vehicle"]["name"], pa.settings["vehicle"]["load"]) == (str(car), 1.1)
    tuned = rr.tune(("pid",), budget=5, n_values=3, scenario_options={"duration": 1.0}, params=car)
    assert tuned.to_dict()["settings"]["vehicle"]["name"] == str(car)
    assert tuned.settings["vehicle_params"] == heavy.to_dict()  # in the runs' keys: not the paper's
    with pytest.raises(InputError, match="give the vehicle once"):
        rr.study(["passive"], vehicle="paper", params="paper")


def test_the_keys_of_the_paper_vehicle_stay_as_they_were():
    from railride.run.solver import SolverSettings
    from railride.studies.sweep import other_settings

    for given in (None, "paper", PAPER):
        assert other_settings(resolve_vehicle(given)[0], SolverSettings()) == {}
    assert other_settings(resolve_vehicle("paper", load=1.3)[0], SolverSettings())["vehicle_params"]["m_c"] == (
        pytest.approx(1.3 * PAPER.m_c)
    )
