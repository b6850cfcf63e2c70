"""Every variable and coordinate of the xarray results the public API returns carries a
``long_name`` and a ``units`` attribute (CF conventions: "1" for a dimensionless number, "" for
a label or text), so that xarray's plots label their axes and a netCDF reader knows what it
holds."""

import numpy as np
import pytest
import xarray as xr

import railride as rr
from railride.run import rig
from railride.model.vehicle import Vehicle

SC = rr.scenario("paper-sine", duration=0.3)


def _unlabelled(obj) -> list[str]:
    """The names of the variables and coordinates of ``obj`` (a Dataset or a DataArray, the
    array itself included) that lack a non-empty ``long_name`` or a ``units`` attribute."""
    if isinstance(obj, xr.DataArray):
        parts = {f"<{obj.name}>": obj, **{f"coord {k}": v for k, v in obj.coords.items()}}
    else:
        parts = {str(k): v for k, v in obj.variables.items()}
    bad = []
    for name, var in parts.items():
        long_name = var.attrs.get("long_name")
        if not (isinstance(long_name, str) and long_name.strip()):
            bad.append(f"{name}: no long_name")
        if not isinstance(var.attrs.get("units"), str):
            bad.append(f"{name}: no units")
    return bad


@pytest.fixture(scope="module")
def runs():
    """A passive run, a batch of MR dampers at two voltages with a damper fault, a closed loop
    and a bending carbody: between them every channel `build_dataset` makes."""
    mr = rr.Suspension.named("mr", voltage=1.0)
    return {
        "passive": rr.simulate(SC),
        "batch": rr.simulate(SC, suspension=[mr, rr.Suspension.named("mr", voltage=2.0).with_faults(["1R-off"])]),
        "pid": rr.simulate(SC, suspension=rr.Suspension.named("pid")),
        "flexible": rr.simulate(SC, "crh380a"),
    }


@pytest.mark.parametrize("name", ["passive", "batch", "pid", "flexible"])
def test_every_channel_of_a_ride_is_named_with_its_unit(runs, name):
    result = runs[name]
    assert _unlabelled(result.dataset) == []
    assert _unlabelled(result.metrics()) == []
    assert _unlabelled(result.comfort()) == []


def test_ride_channels_say_their_units(runs):
    ds = runs["batch"].dataset
    assert ds["carbody_roll"].attrs["units"] == "rad"
    assert ds["time"].attrs["units"] == "s"
    assert ds["corner"].attrs["units"] == ""  # a label
    assert ds["sample"].attrs["units"] == ""
    metrics = runs["passive"].metrics()
    assert metrics["response"].attrs["units"] == "" and metrics["statistic"].attrs["units"] == ""


def test_comfort_and_floor_acceleration_are_named(runs):
    from railride.analysis.comfort import floor_acceleration

    assert _unlabelled(floor_acceleration(runs["flexible"].dataset)) == []
    comfort = runs["passive"].comfort()
    assert comfort["x_m"].attrs["units"] == "m"


def test_the_reduction_against_a_baseline_is_named(runs):
    from railride.analysis.metrics import reduction

    passive = runs["passive"].metrics()
    assert _unlabelled(reduction(passive * 0.5, passive)) == []
    assert reduction(passive * 0.5, passive).attrs["units"] == "%"


def test_the_damper_rig_results_are_named():
    motion = rig.SineMotion(0.01, 1.0)
    assert _unlabelled(rig.drive("railway", motion, duration=0.2, voltage=[0.0, 1.0])) == []
    assert _unlabelled(rig.drive("railway", motion, duration=0.2, command=lambda t: 0 * t + 1.0)) == []
    assert _unlabelled(rig.cycles("railway", 0.01, 2.0, [0.0, 1.0], n_cycles=2).dataset) == []
    assert _unlabelled(rig.track(n_cycles=2).dataset) == []


def test_the_frequency_response_of_the_vehicle_is_named():
    for preset in ("paper", "crh380a"):
        ds = Vehicle(preset).frequency_response(np.array([0.5, 1.0, 2.0]), 30.0)
        assert _unlabelled(ds) == []
        assert ds["carbody_pitch"].attrs["units"] == "rad/m"


def test_the_comparison_is_named():
    import railride as rr

    c = rr.compare(rr.scenario("paper-sine", duration=0.5), bounds=False)
    for obj in (c.metrics, c.reductions, c.combined()):
        assert _unlabelled(obj) == []
