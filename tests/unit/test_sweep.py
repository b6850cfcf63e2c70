"""The sweep study as a library: the grid of cases built from Python values (order, count, grid
values, the checks and how they name the fields), and the protocol of `SweepResult` (to_dict,
to_pandas, plot, save) on a short sweep."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import railride as rr
from railride import dampers
from railride.studies.executors import RunTable
from railride.studies.sweep import COMFORT_COLUMNS, SCHEMA, SweepGrid, SweepResult, grid, metric_columns, run_sweep

RMS = ["acceleration_m_s2_rms", "displacement_m_rms", "pitch_deg_rms", "roll_deg_rms"]


# -- the grid -------------------------------------------------------------------------------------
def test_grid_order_and_count():
    g = grid(
        ["passive", "mr", "pid", "sas-attitude"],
        speed=[20, 40],
        voltage=[0, "passive-on"],
        gains={"pid.kd": [1e4, 1e5], "attitude.kp_z": [0, 1e5, 2e5]},
        noise=(1e-4, 0, 0, 0),
        seed=[0, 1],
        damper_scale=[0.5, 2],
        duration=1,
    )
    v_max = dampers.preset("railway").v_max
    # per suspension, per speed; then mr per scale and voltage, a controller per scale, gain
    # combination and noise seed (passive once, unscaled)
    expected = []
    for s, v in itertools.product(["passive", "mr", "pid", "sas-attitude"], [20.0, 40.0]):
        if s == "passive":
            expected.append((s, v, None, None, (), 0))
        elif s == "mr":
            expected += [(s, v, x, volt, (), 0) for x in (0.5, 2.0) for volt in (0.0, v_max)]
        else:
            name = "pid.kd" if s == "pid" else "attitude.kp_z"
            values = (1e4, 1e5) if s == "pid" else (0.0, 1e5, 2e5)
            expected += [(s, v, x, None, ((name, k),), sd) for x in (0.5, 2.0) for k in values for sd in (0, 1)]
    got = [
        (
            c.suspension,
            dict(c.scenario_options)["speed"],
            None if c.suspension == "passive" else c.damper_scale,
            c.voltage,
            c.gains,
            c.seed,
        )
        for c in g.cases
    ]
    assert len(g) == len(g.cases) == len(g.values) == 2 * (1 + 4 + 8 + 12) == len(expected)
    assert got == expected
    assert g.columns == ("suspension", "speed_m_s", "damper_scale", "voltage_v", "pid.kd", "attitude.kp_z", "seed")
    # the grid values each run reports: None where an axis does not act
    assert g.values[0] == {
        "suspension": "passive",
        "speed_m_s": 20.0,
        "damper_scale": None,
        "voltage_v": None,
        "pid.kd": None,
        "attitude.kp_z": None,
        "seed": None,
    }
    assert g.values[2] == {
        "suspension": "mr",
        "speed_m_s": 20.0,
        "damper_scale": 0.5,
        "voltage_v": 0.0,
        "pid.kd": None,
        "attitude.kp_z": None,
        "seed": None,
    }
    assert g.grid_values() == {
        "suspension": ["passive", "mr", "pid", "sas-attitude"],
        "speed_m_s": [20.0, 40.0],
        "damper_scale": [0.5, 2.0],
        "voltage_v": [0.0, v_max],
        "pid.kd": [1e4, 1e5],
        "attitude.kp_z": [0.0, 1e5, 2e5],
        "seed": [0, 1],
    }
    assert any(c.closed_loop for c in g.cases)
    assert all(c.noise == (1e-4, 0.0, 0.0, 0.0) for c in g.cases if c.closed_loop)


def test_grid_defaults_and_the_scenario_record():
    g = grid("passive")
    assert len(g) == 1 and g.columns == ("suspension",)
    assert g.cases[0] == rr.sweep.Case()
    assert g.solver == rr.SolverSettings() and g.window is None and g.duration == 10.0
    assert g.scenario_record() == g.first_scenario == rr.scenario("paper-sine").describe()
    # a swept option is a grid axis, not a part of the scenario's record
    swept = grid("mr", wavelength=[30, 60], duration=2, window=(1, np.inf))
    assert "wavelength_m" in swept.first_scenario and "wavelength_m" not in swept.scenario_record()
    assert swept.voltages == (dampers.preset("railway").v_min,) and swept.window == (1.0, 2.0)


def test_grid_random_track_seeds():
    g = grid(["passive"], scenario="fra4", track_seed=[0, 3], min_wavelength=2, duration=1)
    assert [dict(c.scenario_options)["seed"] for c in g.cases] == [0, 3]
    assert [v["track_seed"] for v in g.values] == [0, 3]
    assert g.scenario_record()["min_wavelength_m"] == 2.0 and "seed" not in g.scenario_record()


@pytest.mark.parametrize(
    "kwargs, fragments",
    [
        (dict(suspensions=["passive", "lqr"]), ("suspensions = ['passive', 'lqr']", "unknown suspension 'lqr'")),
        (dict(suspensions=["pid", "pid"]), ("pid is listed twice",)),
        (dict(voltage=[1.0]), ("voltage = [1.0]: applies to suspensions mr only (suspensions is passive)",)),
        (dict(suspensions="mr", voltage=[9.0]), ("voltage = 9.0 V", "[0, 2.25]")),
        (dict(gains={"pid.kd": [1e4]}), ("gains = {'pid.kd': [10000.0]}: applies to the controllers",)),
        (
            dict(suspensions="pid", gains={"pid.kx": [1.0]}),
            ("gains['pid.kx'] = [1.0]: unknown gain 'pid.kx'", "allowed: pid.kp, pid.ki, pid.kd"),
        ),
        (dict(suspensions="pid", gains={"pid.kd": [-1.0]}), ("gains['pid.kd'] = [-1.0]: -1 is negative",)),
        (dict(suspensions="pid", gains={"ride.kp_1R": [1.0]}), ("ride.kp_1R acts in sas-attitude-ride only",)),
        (
            dict(suspensions="sas-attitude-ride", gains={"attitude.kp_z": [1.0]}),
            ("attitude.kp_z acts in sas-attitude only", "in sas-attitude-ride: ride_attitude.kp_z"),
        ),
        (dict(suspensions="pid", gains={"foo.x": [1.0]}), ("unknown gain 'foo.x'", "ride_attitude.*, skyhook.*")),
        (dict(suspensions="pid", seed=[1]), ("seed = [1]: applies with noise only",)),
        (dict(suspensions="pid", noise=(0, 0, 0, 0), seed=[-1]), ("seed = [-1]: -1 is negative",)),
        (dict(suspensions="pid", noise=(0, 0, 0, 0), seed=[0.5]), ("0.5 is not a whole number",)),
        (dict(damper="dyke1996"), ("damper = 'dyke1996': applies to mr and the controllers only",)),
        (dict(suspensions="pid", damper="x"), ("damper = 'x': unknown damper model",)),
        (dict(suspensions=["mr", "pid"], damper="ideal"), ("damper = 'ideal': applies to the controllers only",)),
        (dict(suspensions="pid", damper="ideal", damper_scale=[2.0]), ("damper_scale = [2.0]: the ideal device",)),
        (dict(suspensions="pid", damper_scale=[1.0, -1.0]), ("damper_scale = -1: must be a finite number > 0",)),
        (dict(scenario="fra7"), ("scenario: unknown scenario 'fra7'",)),
        (
            dict(track_seed=[1]),
            ("track_seed = [1]: applies to the random-track scenarios", "not to scenario paper-sine"),
        ),
        (dict(min_wavelength=2.0), ("min_wavelength = 2 m: applies to the random-track scenarios",)),
        (dict(scenario="fra4", amplitude=[0.01]), ("amplitude = 0.01 m: does not apply to a random track",)),
        (
            dict(scenario="fra4", min_wavelength=30, max_wavelength=20),
            ("min_wavelength = 30 m, max_wavelength = 20 m",),
        ),
        (dict(scenario="fra4", min_wavelength=0.05), ("min_wavelength = 0.05 m at speed 55.56 m/s", "resolve")),
        (dict(scenario="fra4", speed=[20, 120], min_wavelength=0.2), ("min_wavelength = 0.2 m at speed 120 m/s",)),
        (dict(speed=[20, 0]), ("speed = 0.0: must be a finite number > 0",)),
        # the other axes of the failing combination named, the one in the message not twice
        (dict(scenario="fra4", track_seed=[3], speed=[250]), ("track_seed 3: speed = 250 m/s: above the plausible",)),
        (dict(speed=[]), ("speed = []: give one or more values",)),
        (dict(duration=2, window=(1, 3)), ("window = 1:3 s",)),
        (dict(solver="fine"), ("solver = 'fine'",)),
    ],
)
def test_grid_checks_name_the_field(kwargs, fragments):
    kwargs.setdefault("suspensions", "passive")
    with pytest.raises(ValueError) as err:
        grid(**kwargs)
    for fragment in fragments:
        assert fragment in str(err.value), str(err.value)


def test_grid_errors_in_a_callers_words():
    # what the command line passes: its option names and the text typed
    names = {"suspensions": "--suspension", "damper_scale": "--damper-scale", "gains": "--gain"}
    with pytest.raises(
        ValueError,
        match=r"^--damper-scale = '1,2': applies to mr and the controllers only "
        r"\(--suspension is passive\)$",
    ):
        grid("passive", damper_scale=[1.0, 2.0], names=names, texts={"damper_scale": "1,2"})
    with pytest.raises(ValueError, match=r"^--gain = 'pid.kx=1': unknown gain 'pid.kx'"):
        grid("pid", gains={"pid.kx": [1.0]}, names=names, texts={"gains": {"pid.kx": "pid.kx=1"}})


# -- the result -----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def swept():
    """A short sweep against speed with comfort: passive and PID at three speeds."""
    g = grid(["passive", "pid"], speed=[20.0, 30.0, 40.0], duration=1.0)
    return run_sweep(g)


def test_run_sweep_result_holds_objects(swept):
    assert isinstance(swept, SweepResult) and isinstance(swept.grid, SweepGrid)
    assert swept.comfort and swept.runs == len(swept.grid) == 6
    assert swept.vehicle == rr.VehicleParams.preset("paper")
    assert list(swept.frame["case"]) == [json.dumps(c.to_dict(), sort_keys=True, default=str) for c in swept.grid.cases]


def test_comfort_columns_are_each_runs_own_indices(swept):
    # each row's comfort columns against the indices of that run simulated on its own
    from railride.analysis.comfort import ride_comfort
    from railride.studies.sweep import COMFORT_INDICES

    frame = swept.to_pandas()
    for k in (0, 4):  # passive at 20 m/s, PID at 30 m/s
        case = swept.grid.cases[k]
        alone = rr.simulate(
            rr.scenario(case.scenario, **dict(case.scenario_options)),
            None,
            case.to_suspension(rr.GainSet.default()),
        )
        indices = ride_comfort(alone.dataset)
        want = [float(indices.sel(position=p, index=x)) for p, x in COMFORT_INDICES]
        np.testing.assert_allclose(frame.loc[k, list(COMFORT_COLUMNS)].to_numpy(float), want, rtol=1e-9)


def test_to_pandas_one_row_per_run(swept):
    frame = swept.to_pandas()
    assert len(frame) == 6 and list(frame.columns) == swept.columns()
    assert list(frame.columns[:2]) == ["suspension", "speed_m_s"] and frame.columns[-1] == "key"
    assert set(metric_columns()) | set(COMFORT_COLUMNS) <= set(frame.columns)
    assert list(zip(frame["suspension"], frame["speed_m_s"])) == [
        (s, v) for s in ("passive", "pid") for v in (20.0, 30.0, 40.0)
    ]
    np.testing.assert_array_equal(frame[RMS].to_numpy(), swept.frame[RMS].to_numpy())
    assert list(frame["key"]) == [c.key for c in swept.grid.cases]
    # the vehicle's name and load after the grid's columns, in every row (the CSV of the command)
    assert list(frame.columns[2:4]) == ["vehicle", "load"]
    assert set(frame["vehicle"]) == {"paper"} and set(frame["load"]) == {1.0}


def test_to_dict_is_the_sweep_document(swept):
    doc = swept.to_dict()
    assert doc["schema"] == SCHEMA == "railride.sweep/1"
    assert list(doc) == ["schema", "railride_version", "versions", "date", "settings", "columns", "rows", "runs"]
    assert doc["settings"]["grid"] == {"suspension": ["passive", "pid"], "speed_m_s": [20.0, 30.0, 40.0]}
    assert doc["settings"]["dt_s"] == 1e-4 and doc["settings"]["window_s"] is None
    assert doc["settings"]["damper"] == "railway" and doc["settings"]["comfort"]["columns"] == list(COMFORT_COLUMNS)
    assert "speed_m_s" not in doc["settings"]["scenario"] and doc["settings"]["scenario"]["duration_s"] == 1.0
    assert doc["columns"] == swept.columns()
    assert doc["rows"] == [
        {k: (None if pd.isna(v) else v) for k, v in r.items()} for r in swept.to_pandas().to_dict("records")
    ]
    assert json.loads(json.dumps(doc, allow_nan=False)) == doc


def test_plot_draws_into_the_given_axes(swept):
    import matplotlib.pyplot as plt

    before = plt.get_fignums()  # another test's open figures are not this one's
    mine = Figure()
    axes = mine.subplots(2, 2).ravel()
    assert swept.plot(ax=axes) is mine and mine.get_axes() == list(axes)
    assert [len(a.lines) for a in axes] == [2, 2, 2, 2]  # passive and PID against speed
    two = Figure()
    pair = two.subplots(1, 2)
    assert swept.plot(ax=pair, comfort=True) is two and two.get_axes() == list(pair)
    own = swept.plot()
    assert isinstance(own, Figure) and len(own.get_axes()) == 4
    assert "against speed" in own._suptitle.get_text()
    assert plt.get_fignums() == before  # none of them through pyplot


def test_save_writes_the_files_of_the_command(swept, tmp_path):
    out = tmp_path / "sweep"
    out.mkdir()
    (out / "runs.csv").write_text("kept\n")
    paths = swept.save(out, extra={"note": "mine"})
    assert [p.name for p in paths] == ["sweep.json", "sweep.png", "comfort.png"]
    assert sorted(p.name for p in out.iterdir()) == ["comfort.png", "runs.csv", "sweep.json", "sweep.png"]
    assert json.loads((out / "sweep.json").read_text()) == {**swept.to_dict(), "note": "mine"}
    assert (out / "runs.csv").read_text() == "kept\n"
    assert (out / "sweep.png").read_bytes()[:4] == b"\x89PNG"


def test_save_without_one_numeric_axis_writes_the_document_only(tmp_path):
    g = grid("passive", duration=0.5)
    result = SweepResult(g, pd.DataFrame([dict.fromkeys(metric_columns(), 0.1)]))
    assert [p.name for p in result.save(tmp_path / "one")] == ["sweep.json"]
    with pytest.raises(ValueError, match="no single numeric axis"):
        result.plot()


def test_run_sweep_resumes_from_its_run_table(swept, tmp_path):
    path = tmp_path / "runs.csv"
    first = run_sweep(swept.grid, table=RunTable(path), comfort=False)
    calls = []
    again = run_sweep(
        swept.grid,
        table=RunTable(path, resume=True),
        comfort=False,
        progress=lambda done, total, rate: calls.append((done, total)),
    )
    assert calls == [(0, 0)] and again.runs == first.runs == 6
    assert again.to_dict()["rows"] == first.to_dict()["rows"]
    # the metrics do not depend on whether comfort was asked for
    np.testing.assert_array_equal(first.to_pandas()[RMS].to_numpy(), swept.to_pandas()[RMS].to_numpy())


def test_the_run_table_names_the_vehicle_and_a_table_from_before_still_resumes(tmp_path):
    """runs.csv holds ``vehicle`` and ``load`` after ``key`` (not in the keys); a table written
    without them (railride 0.4.0) resumes: only the new runs run, and every row returned names
    the vehicle."""
    from railride.studies.case import Case

    car = tmp_path / "car.toml"
    car.write_text('[vehicle]\npreset = "paper"\nm_c = 42000.0\n', encoding="utf-8")
    path = tmp_path / "runs.csv"
    first = run_sweep(grid("passive", speed=[20.0, 30.0], duration=0.5), table=RunTable(path), vehicle=car, load=1.1)
    runs = pd.read_csv(path, dtype={"key": str})
    assert list(runs.columns[:3]) == ["key", "vehicle", "load"]
    assert set(runs["vehicle"]) == {str(car)} and set(runs["load"]) == {1.1}
    assert set(first.to_pandas()["vehicle"]) == {str(car)} and set(first.to_pandas()["load"]) == {1.1}
    # as a table of railride 0.4.0, without the columns
    runs.drop(columns=["vehicle", "load"]).to_csv(path, index=False)
    calls = []
    again = run_sweep(
        grid("passive", speed=[20.0, 30.0, 40.0], duration=0.5),
        table=RunTable(path, resume=True),
        vehicle=car,
        load=1.1,
        progress=lambda done, total, rate: calls.append(total),
    )
    assert calls[-1] == 1  # the new speed only
    assert again.frame["key"].tolist()[:2] == runs["key"].tolist()  # the same keys as before
    assert set(again.frame["vehicle"]) == {str(car)} and set(again.frame["load"]) == {1.1}
    np.testing.assert_array_equal(again.frame[RMS].to_numpy()[:2], first.frame[RMS].to_numpy())
    table = pd.read_csv(path, dtype={"key": str})
    assert len(table) == 3 and table["vehicle"].isna().tolist() == [True, True, False]
    assert len(RunTable(path, resume=True).frame) == 3  # and it reads back
    # a vehicle named like a number stays text
    pd.DataFrame([{**table.iloc[2].to_dict(), "vehicle": "1"}]).to_csv(path, index=False)
    assert RunTable(path, resume=True).frame["vehicle"].tolist() == ["1"]
    # the keys are those of the case and the settings, whatever the columns
    assert (
        Case(scenario_options={"speed": 20.0, "duration": 0.5}).key
        == grid("passive", speed=[20.0], duration=0.5).cases[0].key
    )


def test_run_sweep_takes_a_grid():
    with pytest.raises(ValueError, match="railride.studies.grid.grid makes one"):
        run_sweep([rr.sweep.Case()])


def test_a_sweep_says_which_rows_tracks_its_gains_were_tuned_on():
    """The shipped robust gains were tuned on fra4 seeds 1-3 at 30, 50 and 70 m/s: seed 1 at 30
    m/s is in-sample, seed 0 held out; a sweep of 2-s runs says its N_MV_z is from the whole
    signal (no 5-s interval fits)."""
    import railride as rr

    res = rr.run_sweep(
        rr.studies.grid.grid(["pid"], scenario="fra4", track_seed=[0, 1], speed=[30.0], duration=2.0),
        comfort=True,
    )
    text = res.settings["tracks_judged"]
    assert "in-sample (tuned on this track at this speed): seed 1 at 30 m/s" in text
    assert "held out (tuning never ran on this track): seed 0 at 30 m/s" in text
    assert "N_MV_z from one interval, the whole signal" in res.settings["comfort"]["notes"][1]
