"""Plausible ranges of the vehicle and controller inputs: impossible and absurd values are
errors naming the field, the value and the range; unusual vehicles run with a warning; the
modes of what gets through are finite numbers or a clear error."""

import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from railride import dampers
from railride.studies.comparison import compare
from railride.secondary.control import PID, GainSet, SensorNoise
from railride.secondary.controllers import ClippedOptimal
from railride.frequency.frf import frequency_responses, modes
from railride.model.params import PRESETS, VehicleParams
from railride.model.params import ranges_markdown as markdown
from railride.model.plausible import PlausibilityWarning
from railride.model.vehicle import Vehicle
from railride.secondary.sensing import Accelerometers
from railride.run.simulation import simulate
from railride.secondary.suspension import Suspension
from railride.model.track import scenario

P = VehicleParams.preset("paper")
DOCS = Path(__file__).resolve().parents[2] / "docs" / "cli.md"


def significant_digits(number: str) -> int:
    return len(number.split("e")[0].replace("-", "").replace(".", "").lstrip("0"))


def test_presets_and_shipped_gains_raise_no_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        for p in PRESETS.values():
            VehicleParams(**p.to_dict())
        GainSet.default()
        GainSet.reference()
        SensorNoise(1e-3, 1e-4, 1e-3, 1e-4, seed=0)
        Accelerometers()


@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf])
def test_impossible_masses_are_errors(value):
    with pytest.raises(ValueError, match=r"'m_c' = .*carbody mass, kg\): must be a finite number > 0"):
        P.replace(m_c=value)


@pytest.mark.parametrize(
    "field, value, shown",
    [
        ("m_c", 2e12, "2e+12"),  # two billion tonnes
        ("m_b", 1e-300, "1e-300"),
        ("k_pz", 1e12, "1e+12"),  # the spring
        ("k_sz", 1e-9, "1e-09"),
        ("c_sz", 1e10, "1e+10"),
        ("I_cy", 1e20, "1e+20"),
        ("a", 50.0, "50.0"),
        ("l", 1e4, "10000.0"),
    ],
)
def test_absurd_vehicle_values_are_errors_naming_field_value_and_range(field, value, shown):
    with pytest.raises(ValueError) as err:
        P.replace(**{field: value})
    msg = str(err.value)
    assert f"'{field}' = {shown} " in msg and "must be between" in msg


def test_overlapping_bogies_are_an_error():
    with pytest.raises(ValueError, match=r"'b' = 9.5 .*must be below 'l' = 9.0"):
        P.replace(b=9.5)


def test_a_1000_tonne_carbody_runs_with_a_warning_it_records():
    with pytest.warns(PlausibilityWarning, match=r"'m_c' = 1000000.0 kg \(carbody mass\) is outside"):
        heavy = P.replace(m_c=1e6)
    doc = frequency_responses(heavy, points=3).to_dict()
    assert len(doc["warnings"]) == 1 and "'m_c'" in doc["warnings"][0]
    assert "warnings" not in frequency_responses(P, points=3).to_dict()
    # a ride and a comparison keep the warning with their parameters; a batch names it once
    short = scenario("paper-sine", duration=0.5)
    ride = simulate(short, heavy, Suspension.passive())
    assert json.loads(ride.dataset.attrs["plausibility_warnings"]) == doc["warnings"]
    batch = simulate(short, [heavy, heavy, P], Suspension.passive())
    assert json.loads(batch.dataset.attrs["plausibility_warnings"]) == doc["warnings"]
    assert "plausibility_warnings" not in simulate(short, P, Suspension.passive()).dataset.attrs
    settings = compare(short, heavy, controllers=["passive", "pid"], bounds=False).to_dict()["settings"]
    assert settings["warnings"] == doc["warnings"]


@pytest.mark.parametrize(
    "build, fragment",
    [
        (lambda: SensorNoise(1e300, 0.0, 0.0, 0.0, seed=0), "'displacement' = 1e+300"),
        (lambda: SensorNoise(0.0, 0.0, 2.0, 0.0, seed=0), "'velocity' = 2.0"),
        (lambda: Accelerometers(noise=100.0), "'noise' = 100.0"),
        (lambda: Accelerometers(bias=-20.0), "'bias' = -20.0"),
        (lambda: Accelerometers(antialias_hz=0.01), "'antialias_hz' = 0.01"),
        (lambda: PID(kp=1e300, ki=0.0, kd=0.0), "'kp' = 1e+300"),
        (lambda: PID(kp=math.inf, ki=0.0, kd=0.0), "'kp' = inf"),
        (lambda: GainSet.default().apply({"inner.G": 1e9}), "'G' = 1e+09"),
        (lambda: ClippedOptimal(0, 0, 0, 0, 0, 0, r=1e-30), "'r' = 1e-30"),
        (lambda: dampers.preset("railway").scaled(1e6), "factor = 1000000.0"),
        (lambda: Suspension.named("mr", damper_scale=1e-5), "damper_scale = 1e-05"),
    ],
)
def test_absurd_controller_and_sensor_inputs_are_errors(build, fragment):
    with pytest.raises(ValueError, match="must be (between|a finite number)") as err:
        build()
    assert fragment in str(err.value)


def test_sensor_noise_can_no_longer_improve_a_controller():
    """The issue's hole: noise of 1e300 m "improved" PID. The largest noise allowed is below
    the travel of the suspension, and it makes the ride worse, not better."""
    sc = scenario("paper-sine", duration=2.0)
    clean = simulate(sc, suspension=Suspension.named("pid")).metrics()
    noisy = Suspension.named("pid", sensor_noise=SensorNoise(0.1, 0.1, 1.0, 1.0, seed=1))
    worst = simulate(sc, suspension=noisy, on_divergence="mark").metrics()
    rms = {"statistic": "rms", "response": "acceleration_m_s2"}
    assert not float(worst.sel(rms)) < float(clean.sel(rms))


def test_an_undamped_vehicle_has_damping_ratios_of_exactly_zero():
    """Physics: with every damper removed the modes are undamped; rounding below zero is not
    shown as a negative damping ratio."""
    bare = P.replace(**{f"c_{s}{d}": 0.0 for s in "ps" for d in "xyz"})
    found = modes(bare).to_list()
    assert len(found) == 9
    assert all(0.0 <= m["damping_ratio"] < 1e-9 for m in found)  # never below zero
    assert all(math.isclose(m["frequency_hz"], m["damped_frequency_hz"], rel_tol=1e-6) for m in found)


@pytest.mark.filterwarnings("ignore::railride.model.plausible.PlausibilityWarning")
def test_modes_beyond_double_precision_are_a_clear_error():
    # gram bogies on a rigid primary: allowed, with warnings, but the bogies' roots are 1e16
    # times the carbody's, whose lowest w^2 eigh puts at 29.3 rad^2/s^2 (80-digit arithmetic:
    # 23.0)
    absurd = P.replace(m_b=1e-3, I_by=1e-6, I_bx=1e-6, k_pz=1e11)
    assert not all(m.resolved for m in Vehicle(absurd).modes())
    with pytest.raises(ValueError, match=r"cannot be computed in double precision: .*outside the typical ranges: m_b"):
        modes(absurd)


@pytest.mark.filterwarnings("ignore::railride.model.plausible.PlausibilityWarning")
def test_the_step_size_message_is_sensible_for_a_stiff_vehicle():
    stiff = P.replace(k_pz=1e11, m_b=1.0, I_by=1e-2)
    with pytest.raises(ValueError) as err:
        simulate(scenario("paper-sine", duration=0.01), stiff, Suspension.named("mr"))
    msg = str(err.value)
    advised = re.search(r"use dt <= ([0-9.e+-]+) s", msg)
    assert advised is not None and 0.0 < float(advised.group(1)) < 1e-4, msg
    assert "the default" not in msg.split("use dt")[1]  # the default is the step that failed
    numbers = re.findall(r"\d[\d.]*(?:e[+-]?\d+)?", msg)
    assert numbers and all(significant_digits(n) <= 4 for n in numbers), msg


def test_the_docs_list_the_vehicle_ranges_of_the_code():
    assert markdown() in DOCS.read_text(encoding="utf-8")


def test_values_at_the_edges_of_the_typical_ranges_stay_silent():
    from railride.model.plausible import VEHICLE

    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        # the bending fields come together: a carbody length with one of f_bend, EI_c, the
        # length beyond the outer wheelsets (a short car for the shortest)
        bending = {
            "L_c": {"l": 2.0, "b": 0.5, "f_bend": 10.0},
            "f_bend": {"L_c": 24.0},
            "EI_c": {"L_c": 24.0},
        }
        for name, r in VEHICLE.items():
            for value in r.typical:
                if name == "b" and value >= P.l:
                    continue
                VehicleParams(**{**P.to_dict(), **bending.get(name, {}), name: value})
    assert np.isfinite([m.frequency_hz for m in modes(P)]).all()


def test_a_plausibility_warning_points_at_the_callers_line():
    import warnings as w

    with w.catch_warnings(record=True) as caught:
        w.simplefilter("always")
        VehicleParams.preset("paper").replace(m_c=1.0e3)  # this line
    assert caught and all(c.filename == __file__ for c in caught), [(c.filename, c.lineno) for c in caught]
