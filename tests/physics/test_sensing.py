"""Realistic sensing (railride.secondary.sensing): the band-limited integration against its transfer
function, a stated bound on its velocity error, bias removal, and bad input."""

import math

import numpy as np
import pytest

import railride as rr
from railride.studies.comparison import compare
from railride.secondary.control import GainSet
from railride.secondary.controllers import carbody_map
from railride.secondary.sensing import Accelerometers
from railride.run.simulation import simulate
from railride.secondary.suspension import Suspension

G = GainSet.reference()  # skyhook with all three modal gains (the shipped one has no roll gain)
TC = carbody_map(rr.Vehicle(rr.VehicleParams.preset("paper")))
C = np.array([G.skyhook.c_z, G.skyhook.c_phi, G.skyhook.c_theta])
MODES = ("bounce", "pitch", "roll")


def velocity_error(sc, sensing) -> np.ndarray:
    """Per mode, RMS(estimated - true carbody velocity) / RMS(true) from 5 s on. The estimate
    is read back from the skyhook's demand, f_d = -T_c^+ diag(c) v_est (so T_c f_d = -c v_est),
    held one controller period (the output rate) after its sample."""
    ds = simulate(sc, suspension=Suspension.named("skyhook", G).with_sensing(sensing)).dataset
    est = -(TC @ ds.damper_demand_force.values.T).T / C
    true = np.stack([ds[f"carbody_{m}_velocity"].values for m in MODES], axis=1)
    keep = ds.time.values >= 5.0
    e, t = est[keep][1:], true[keep][:-1]
    return np.sqrt(np.mean((e - t) ** 2, axis=0) / np.mean(t**2, axis=0))


def test_on_a_sine_the_velocity_error_is_that_of_the_estimators_transfer_function():
    # v_est = s^2 / (s + w)^2 v: on a sine of frequency f the relative error is
    # |1 - (j f / (j f + f_c))^2|, whatever the mode
    sc = rr.scenario("paper-sine", duration=12.0)
    f = sc.speed / 60.0  # the sine's wavelength is 60 m
    sensing = Accelerometers(noise=0.0, bias=0.0)
    ratio = (1j * f / (1j * f + sensing.cutoff_hz)) ** 2
    expected = abs(1 - ratio)
    assert expected == pytest.approx(0.214, abs=1e-3)
    assert velocity_error(sc, sensing) == pytest.approx(np.full(3, expected), rel=0.1)


@pytest.mark.parametrize(
    "sc, bound",
    [
        (rr.scenario("paper-sine", duration=12.0), 0.25),
        (rr.scenario("fra4", seed=3, duration=12.0), 0.40),
        (rr.scenario("fra4", seed=7, speed=30.0, duration=12.0), 0.40),
    ],
)
def test_the_velocity_error_stays_within_its_stated_bound(sc, bound):
    # the default accelerometers (noise, bias); the bound is stated in docs/control.md
    assert np.all(velocity_error(sc, Accelerometers()) <= bound)


def test_the_bias_is_removed_and_a_slower_estimator_corner_errs_less_on_a_sine():
    sc = rr.scenario("paper-sine", duration=12.0)
    clean = velocity_error(sc, Accelerometers(noise=0.0, bias=0.0))
    # 5 mg: a plain integral would drift by 0.05 m/s each second; the high-pass takes it out
    # (its start-up transient decays with 1 / (2 pi f_c) = 1.6 s)
    biased = velocity_error(sc, Accelerometers(noise=0.0, bias=0.05))
    assert np.allclose(biased, clean, atol=0.005)
    slower = velocity_error(sc, Accelerometers(noise=0.0, bias=0.0, cutoff_hz=0.05))
    assert np.all(slower < clean)


def test_compare_with_accelerometers_runs_the_carbody_laws_and_says_why_not_the_others():
    sc = rr.scenario("paper-sine", duration=2.0)
    cmp = compare(sc, controllers=["sas-attitude", "groundhook", "clipped-optimal"], sensing=Accelerometers())
    assert cmp.names == ["passive", "sas-attitude"]
    assert set(cmp.settings["not_run"]) == {"groundhook", "clipped-optimal"}
    assert cmp.settings["sensing"]["kind"] == "accelerometers"
    ideal = compare(sc, controllers=["sas-attitude"], bounds=False).metrics
    assert not np.allclose(cmp.metrics.sel(controller="sas-attitude"), ideal.sel(controller="sas-attitude"))


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Accelerometers(noise=-1.0), r"accelerometer 'noise' = -1.0"),
        (lambda: Accelerometers(cutoff_hz=0.0), r"accelerometer 'cutoff_hz' = 0.0"),
        (lambda: Accelerometers(seed=1.5), r"accelerometer 'seed' = 1.5"),
        (lambda: Suspension.named("mr").with_sensing(Accelerometers()), r"sensing applies to a closed loop only"),
        (
            lambda: Suspension.named("pid").with_sensing("accelerometers"),
            r"must be a railride.secondary.sensing.Accelerometers",
        ),
        (
            lambda: simulate(
                rr.scenario("paper-sine", duration=1.0),
                suspension=Suspension.named("hybrid").with_sensing(Accelerometers()),
            ),
            r"sensing with controller 'hybrid': it reads the bogies' states",
        ),
        (
            lambda: simulate(
                rr.scenario("paper-sine", duration=1.0),
                suspension=Suspension.named("pid").with_sensing(Accelerometers(antialias_hz=5000.0)),
            ),
            r"antialias_hz = 5000 Hz: too fast for dt",
        ),
    ],
)
def test_bad_sensing_names_what_is_wrong(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_the_estimators_corner_frequency_is_stated():
    assert Accelerometers().cutoff_hz == 0.1 and math.isclose(Accelerometers().antialias_hz, 100.0)
