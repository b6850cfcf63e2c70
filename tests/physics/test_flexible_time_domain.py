"""The flexible carbody in the time domain (the engine's tenth DOF), against independent
methods: the exact discretisation (matrix exponential) of the same linear vehicle, step halving
of the RK4 stepper at the bending frequency, SciPy's lsim of the state-space model that the
frequency-domain tools build on their own, and the frequency-domain ride against long random runs."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.signal import lsim

import railride as rr
from railride.analysis.comfort import floor_acceleration, ride_comfort
from railride.frequency.linear import linear_model
from railride.frequency.ride_spectrum import FLOOR, ride_spectrum
from railride.model.plausible import PlausibilityWarning
from railride.model.track import wheelset_input_table
from railride.model.vehicle import Vehicle

#: the paper's vehicle with a 24 m body bending at 10 Hz (2 % modal damping)
FLEX = rr.VehicleParams.preset("paper").replace(L_c=24.0, f_bend=10.0)
SPEED = 55.56
#: the carbody's rigid-body motion
BODY = ("carbody_bounce", "carbody_pitch", "carbody_roll")


def _centre(result) -> np.ndarray:
    return floor_acceleration(result.dataset).sel(position="centre").values


def _stiffer(f_bend: float) -> rr.VehicleParams:
    """FLEX bending at ``f_bend`` [Hz], its plausibility warning (a limit study) silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        return FLEX.replace(f_bend=f_bend)


def test_a_rigid_vehicle_runs_as_before_its_bending_at_rest():
    """The rigid car is the bending car with its bending held at rest: FLEX made rigid runs as
    the paper's car to the bit, and as the bending stiffens the bending car's rigid-body motion
    tends to the rigid car's, the difference falling as 1 / f_bend^2 (the bending's quasi-static
    deflection under the corner forces, over its modal stiffness m_eta (2 pi f_bend)^2; measured
    a factor 4.03 and 4.00 per doubling from 50 Hz); at 10 Hz the bending moves the floor."""
    sc = rr.scenario("fra4", duration=3.0, seed=2)
    run = rr.simulate(sc, "paper", rr.Suspension.named("sas-attitude-ride"))
    assert "carbody_bending" not in run.dataset  # a rigid carbody has no bending channel
    again = rr.simulate(sc, FLEX.rigid(), rr.Suspension.named("sas-attitude-ride"))
    for name in BODY:
        np.testing.assert_array_equal(again.dataset[name].values, run.dataset[name].values)
    # the limit, on the passive car (linear: the exact steps, no switching of the MR dampers)
    rigid = rr.simulate(sc, "paper").dataset
    differences = []
    for f_bend in (50.0, 100.0, 200.0):
        bent = rr.simulate(sc, _stiffer(f_bend)).dataset
        differences.append(
            max(float(np.max(np.abs(bent[n].values - rigid[n].values)) / np.max(np.abs(rigid[n].values))) for n in BODY)
        )
    assert differences[-1] < 1e-4, differences
    for coarse, fine in zip(differences, differences[1:]):
        assert 3.5 < coarse / fine < 4.5, differences  # 4 per doubling of f_bend
    flex = rr.simulate(sc, FLEX, rr.Suspension.named("sas-attitude-ride"))
    bend = flex.dataset["carbody_bending_acceleration"].values
    assert np.max(np.abs(bend)) > 0.01  # the bending is excited ...
    # ... and the centre floor feels it: the rigid CG acceleration is not the centre's
    assert np.max(np.abs(_centre(flex) - flex.dataset["carbody_acceleration"].values)) > 0.01


def test_the_engine_equals_the_numpy_reference_with_mr_dampers():
    # the NumPy reference solves with M at every stage and evaluates the rails exactly
    from railride.secondary import dampers
    from railride.testing.reference import simulate_reference

    sc = rr.scenario("bump", amplitude=0.02, duration=1.0)
    damper = dampers.preset("railway")
    ref = simulate_reference(sc, FLEX, dt=1e-4, output_every=10, damper=damper, voltage=1.0)
    ds = rr.simulate(
        sc, FLEX, rr.Suspension.semi_active("railway", voltage=1.0), solver=rr.SolverSettings(output_rate=1000.0)
    ).dataset
    names = Vehicle(FLEX).dof_names
    q = np.stack([ds[name].values for name in names], axis=-1)
    scale = np.abs(ref["q"]).max(axis=0)
    assert names[-1] == "carbody_bending" and scale[-1] > 0
    moving = scale > 1e-12  # both rails alike: the rolls stay at rounding (1e-21)
    assert np.all(np.abs(q - ref["q"]).max(axis=0)[moving] <= 1e-5 * scale[moving])


def test_rk4_converges_to_the_exact_steps_at_the_bending_frequency():
    # passive on random track: the exact discretisation is the reference; RK4's error at the
    # floor centre falls as dt^4 (a factor 16 per halving; measured in the asymptotic range)
    sc = rr.scenario("german-low", speed=70.0, duration=3.0, seed=1)
    exact = _centre(rr.simulate(sc, FLEX, solver=rr.SolverSettings(dt=1e-3, output_rate=500.0, method="exact")))
    errors = []
    for dt in (2e-3, 1e-3):
        rk4 = _centre(rr.simulate(sc, FLEX, solver=rr.SolverSettings(dt=dt, output_rate=500.0, method="rk4")))
        errors.append(np.max(np.abs(rk4 - exact)))
    assert errors[1] < 1e-3 * np.max(np.abs(exact))
    assert errors[0] / errors[1] > 10.0, errors


@pytest.mark.parametrize("name", ["passive", "sas-attitude-ride"])
def test_the_state_space_model_reproduces_the_engine(name):
    """lsim of the flexible car's state-space model (built from the vehicle's matrices by the
    frequency-domain tools) on the engine's rail input table = the engine's RK4 run, at the
    floor centre, where the bending acts most, and at the front."""
    scenario = rr.scenario("fra4", duration=8.0, seed=3)
    suspension = rr.Suspension.passive() if name == "passive" else rr.Suspension.named(name, damper="ideal")
    model = linear_model(FLEX, suspension)
    table, interval = wheelset_input_table(scenario, Vehicle(FLEX).wheelset_lag_distance, 1e-4)
    t = np.arange(table.shape[0]) * interval
    keep = t <= scenario.duration
    u = table[keep, :16]
    if len(model.inputs) == 20:
        u = np.hstack([u, np.zeros((u.shape[0], 4))])
    _, y, _ = lsim((model.A, model.B, model.C, model.D), u, t[keep])
    run = rr.simulate(
        scenario,
        FLEX,
        suspension,
        solver=rr.SolverSettings(control_rate=1e4, method="rk4" if name == "passive" else "auto"),
    )
    floor = floor_acceleration(run.dataset)
    late = floor["time"].values > 2.0
    for point in ("centre", "front"):
        engine = floor.sel(position=point).values
        state_space = np.interp(
            floor["time"].values, t[keep], y[:, model.index("outputs", f"floor_acceleration_{point}")]
        )
        error = np.sqrt(np.mean((engine - state_space)[late] ** 2))
        assert error < 0.02 * np.sqrt(np.mean(engine[late] ** 2)), (name, point, error)


@pytest.mark.slow  # two 60 s runs: about 10 s
def test_the_frequency_domain_ride_of_the_flexible_car_matches_long_random_runs():
    scenarios = [rr.scenario("fra4", duration=60.0, seed=seed) for seed in (0, 1)]
    result = rr.simulate(scenarios, FLEX)
    late = floor_acceleration(result.dataset).sel(time=slice(10.0, None))
    rms = np.sqrt((late**2).mean(("sample", "time")))
    comfort = ride_comfort(result.dataset, window=(10.0, 60.0))
    wb = np.sqrt((comfort.sel(index="aw_Wb") ** 2).mean("sample"))
    spectrum = ride_spectrum("fra4", speed=SPEED, controllers=["passive"], vehicle=FLEX)
    for point in FLOOR:
        fd = float(spectrum.rms.sel(suspension="passive", response=f"floor_acceleration_{point}"))
        assert fd == pytest.approx(float(rms.sel(position=point)), rel=0.05), point
        fd = float(spectrum.weighted.sel(suspension="passive", position=point, weighting="Wb"))
        assert fd == pytest.approx(float(wb.sel(position=point)), rel=0.05), point
