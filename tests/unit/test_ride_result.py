"""`RideResult`'s result protocol (`to_dict`, `to_pandas`, `plot`, `save`), the damper a
suspension was named by, the output rate's resolution of a random track, and the studies'
checks before their first run."""

import json

import matplotlib
import numpy as np
import pytest

from railride import dampers
from railride.studies.comparison import compare
from railride.output.files import OUTPUT_FILES
from railride.analysis.metrics import to_dict as metrics_record
from railride.model.params import VehicleParams
from railride.studies.pareto import pareto
from railride.run.ride import SCHEMA, RideResult
from railride.run.simulation import simulate
from railride.run.solver import RESOLUTION, SolverSettings, check_resolution
from railride.secondary.suspension import Suspension
from railride.model.track import scenario
from railride.studies.tuning import tune

matplotlib.use("Agg")

SC = scenario("paper-sine", duration=0.5)


@pytest.fixture(scope="module")
def mr():
    return simulate(SC, suspension=Suspension.named("mr", damper="dyke1996", damper_scale=2.0, voltage=1.0))


# -- to_dict ------------------------------------------------------------------------------------
def test_the_document_of_a_run(mr):
    doc = mr.to_dict((0.1, 0.5))
    assert list(doc) == [
        "schema",
        "railride_version",
        "versions",
        "scenario",
        "vehicle",
        "vehicle_preset",
        "suspension",
        "settings",
        "metrics",
        "travel",
    ]
    assert doc["schema"] == SCHEMA == "railride.simulation/1"
    assert doc["scenario"] == SC.describe() and doc["vehicle_preset"] == "paper"
    assert doc["suspension"] == {"type": "mr", "damper": "dyke1996", "voltage_v": 1.0, "damper_scale": 2.0}
    assert doc["settings"] == {"dt_s": 1e-4, "output_rate_hz": 1000.0, "window_s": [0.1, 0.5]}
    assert doc["metrics"] == metrics_record(mr.metrics((0.1, 0.5)))
    json.dumps(doc, allow_nan=False)
    # the whole run by default; comfort on request; the vehicle as the caller names it
    whole = mr.to_dict(comfort=True, vehicle={"vehicle_params_file": "car.toml"})
    assert whole["settings"]["window_s"] == [0.0, 0.5] and "comfort" in whole
    assert list(whole)[4] == "vehicle_params_file" and "vehicle_preset" not in whole


def test_the_document_names_the_vehicle_and_the_suspension():
    soft = VehicleParams.preset("paper").replace(k_sz=3e5)
    passive = simulate(SC, soft)
    doc = passive.to_dict()
    assert doc["suspension"] == {"type": "passive"}
    assert doc["vehicle_params"] == soft.to_dict() and "vehicle_preset" not in doc
    # a Dataset alone (a result read back) gives the same document
    again = RideResult(passive.dataset).to_dict()
    assert again == doc
    closed = simulate(SC, suspension=Suspension.named("pid")).to_dict()["suspension"]
    assert closed["type"] == "pid" and closed["damper"] == "railway" and "voltage_v" not in closed
    assert closed["controller"]["name"] == "pid" and closed["inner_loop"] is not None
    with pytest.raises(ValueError, match="to_dict describes a single run"):
        simulate([SC, SC]).to_dict()


def test_plot_pandas_and_save(mr, tmp_path):
    import matplotlib.pyplot as plt

    fig = mr.plot()
    assert len(fig.axes) == 4
    mine, axes = plt.subplots(4, 1)
    assert mr.plot(ax=axes) is mine
    plt.close("all")
    assert "carbody_bounce" in mr.to_pandas().columns
    paths = mr.save(tmp_path / "ride", (0.1, 0.5))
    assert [p.name for p in paths] == list(OUTPUT_FILES)
    assert json.loads((tmp_path / "ride" / "metrics.json").read_text()) == mr.to_dict((0.1, 0.5))


# -- the damper a suspension was named by -----------------------------------------------------------
def test_a_suspension_keeps_the_name_and_scale_of_its_damper():
    scaled = Suspension.named("mr", damper="dyke1996", damper_scale=8.0)
    assert scaled.damper == dampers.RAILWAY and scaled.damper_scale == 8.0
    assert scaled.damper_name == "dyke1996"  # as named, though the model is railway's
    assert scaled == Suspension.semi_active(dampers.RAILWAY)  # the scale is a record, not the value
    assert Suspension.semi_active("railway", damper_scale=0.5).damper_name == "railway"
    assert Suspension(dampers.RAILWAY.scaled(3.0)).damper_name == "bouc-wen"  # a model given as such
    assert Suspension.named("pid", damper="ideal").damper_name == "ideal"
    assert Suspension.passive().damper_name is None
    with pytest.raises(ValueError, match="damper_scale = 0"):
        Suspension("railway", damper_scale=0)


# -- what an output rate resolves ---------------------------------------------------------------------
def test_the_output_rate_must_resolve_a_random_track():
    fine = scenario("fra4", min_wavelength=0.1, duration=1.0)  # 556 Hz at 55.56 m/s
    with pytest.raises(
        ValueError,
        match=r"min_wavelength = 0.1 m at speed 55.56 m/s passes at 555.6 Hz, "
        r"more than output_rate 1000 Hz / 2.5 = 400 Hz",
    ):
        check_resolution(fine, 1000.0)
    check_resolution(fine, 555.6 * RESOLUTION)
    check_resolution(scenario("paper-sine", speed=100.0), 10.0)  # 60 m at 100 m/s: 1.67 Hz <= 4 Hz
    with pytest.raises(ValueError, match="wavelength = 60 m"):  # the sine is checked too: 2.5 Hz > 2 Hz
        check_resolution(scenario("paper-sine", speed=150.0), 5.0)
    with pytest.raises(ValueError, match="output_rate 1000 Hz"):
        simulate(fine)


# -- the studies check their settings before the first run ------------------------------------------
@pytest.mark.parametrize(
    "run, match",
    [
        (
            lambda: compare(SC, controllers=["pid"], solver=SolverSettings(control_rate=300.0)),
            "control_rate = 300 Hz with dt = 0.0001 s",
        ),
        (lambda: compare(scenario("fra4", min_wavelength=0.1), controllers=["pid"]), "min_wavelength = 0.1 m"),
        (lambda: compare(SC, damper="ideal", damper_scale=2.0), "damper_scale = 2"),
        (
            lambda: tune(("pid",), budget=0),
            r"budget = 0: must be a whole number >= 15 \(the start run and one sweep of 13 values and 0\)",
        ),
        (lambda: tune(("pid",), n_values=2), "n_values = 2: must be a whole number >= 3"),
        (lambda: tune(("pid",), span=float("inf")), "span = inf: must be a finite number > 1"),
        (lambda: tune(("pid",), span=1.0), "span = 1.0: must be a finite number > 1"),
        (lambda: tune(("pid",), damper="mr9"), "unknown damper model 'mr9'"),
        (lambda: tune(("pid",), damper="ideal", damper_scale=2.0), "damper_scale = 2"),
        (lambda: tune(("pid",), scenario="fra4", scenario_options={"min_wavelength": 0.1}), "min_wavelength = 0.1 m"),
        (lambda: pareto("pid", seed=-1), "seed = -1: must be a whole number >= 0"),
        (lambda: pareto("pid", n_samples=3), "n_samples = 3: must be a power of two"),
        (lambda: pareto("pid", damper="mr9"), "unknown damper model 'mr9'"),
        (lambda: pareto("pid", scenario="fra4", scenario_options={"min_wavelength": 0.1}), "min_wavelength = 0.1 m"),
    ],
)
def test_the_studies_refuse_bad_settings_before_running(run, match, monkeypatch):
    from railride.run import simulation

    def no_run(*args, **kwargs):
        raise AssertionError("a run started before the settings were checked")

    monkeypatch.setattr(simulation, "simulate", no_run)
    monkeypatch.setattr("railride.studies.comparison.simulate", no_run)
    with pytest.raises(ValueError, match=match):
        run()


def test_the_studies_take_solver_settings_only():
    for call in (lambda: compare(SC, dt=1e-4), lambda: tune(("pid",), dt=1e-4), lambda: pareto("pid", dt=1e-4)):
        with pytest.raises(TypeError, match="'dt'"):
            call()
    assert np.isfinite(simulate(SC, solver=SolverSettings(dt=5e-5)).metrics().values).all()


@pytest.mark.parametrize("vehicle", ["paper", "crh380a"])
def test_comfort_before_the_dataset_is_built_equals_comfort_from_it(vehicle):
    """A study's comfort reads only the channels it needs (`RideResult.comfort_channels`) where
    the run's Dataset is not built: the same indices as from the Dataset, bending (crh380a's
    carbody bends) and the vehicle record (front and rear floor points) included."""
    susp = Suspension.named("sas-attitude")
    params = VehicleParams.of(vehicle)
    scs = [scenario("fra4", seed=s, speed=40.0, duration=2.0) for s in (1, 2)]
    for res in (simulate(scs, [params] * 2, [susp] * 2), simulate(scs[0], params, susp)):
        light = res.comfort(window=(0.5, 2.0))
        assert res._dataset is None  # the light channels only
        if vehicle == "crh380a":
            assert "carbody_bending_acceleration" in res.comfort_channels()
        full = res.comfort(window=(0.5, 2.0)) if res.dataset is not None else None
        np.testing.assert_array_equal(light.values, full.values)
        assert light.dims == full.dims and light.attrs == full.attrs


@pytest.mark.parametrize("name", ["passive", "pid", "sas-attitude"])
def test_channels_before_the_dataset_is_built_equal_the_datasets(name):
    """`RideResult.channels` (a study's damper costs read four channels of every run) gives,
    without building the run's Dataset, the Dataset's own variables: values, dimensions,
    coordinates and attributes, for a batch and a single run. A channel the run does not have
    (passive dampers have no voltage) is left out, as the Dataset leaves it out."""
    from railride.analysis.costs import COST_CHANNELS

    susp = Suspension.named(name)
    params = VehicleParams.of("crh380a")  # a bending carbody: T has its bending row
    scs = [scenario("fra4", seed=s, speed=40.0, duration=1.0) for s in (1, 2)]
    names = (*COST_CHANNELS, "carbody_corner_displacement", "rail_velocity", "carbody_bending")
    for res in (simulate(scs, [params] * 2, [susp] * 2), simulate(scs[0], params, susp)):
        light = res.channels(names)
        assert res._dataset is None
        full = res.dataset[[n for n in names if n in res.dataset.variables]]
        assert list(light.data_vars) == list(full.data_vars)
        assert ("damper_voltage" in light) == (name != "passive")
        for var in full.data_vars:
            assert light[var].dims == full[var].dims and light[var].attrs == full[var].attrs
            np.testing.assert_array_equal(light[var].values, full[var].values)
        for coord in light.coords:
            np.testing.assert_array_equal(light[coord].values, full[coord].values)
        built = res.channels(names)  # once the Dataset is built, from it
        assert list(built.data_vars) == list(full.data_vars)
