"""The left-right symmetry of the closed loops on rails in exact anti-phase (a pure roll input),
and the MR coil's lag as what makes PID's symmetric ride unstable (docs/control.md, "A symmetry
two laws do not keep")."""

import dataclasses

import numpy as np

import railride as rr
from railride.secondary.control import SAS, GainSet, Ride
from railride.secondary.suspension import damper_model

GAINS = GainSet.default()
ANTI = rr.scenario("paper-sine", duration=5.0, rail_phase=180.0)


def _ride(suspension, initial_state=None):
    return rr.simulate(ANTI, suspension=suspension, initial_state=initial_state).dataset


def _symmetric(ride: Ride) -> Ride:
    """The ride loop with each axle's right and left gains replaced by their mean."""
    g = dataclasses.asdict(ride)
    for kind in ("kp", "kd"):
        for axle in ("1", "2"):
            mean = (g[f"{kind}_{axle}R"] + g[f"{kind}_{axle}L"]) / 2
            g[f"{kind}_{axle}R"] = g[f"{kind}_{axle}L"] = mean
    return Ride(**g)


def test_symmetric_laws_on_mr_dampers_keep_a_pure_roll_ride():
    # mirrored rails give mirrored corner states; a law with equal right and left gains then
    # demands equal and opposite forces, and the MR dampers (odd in their deflection, rate and
    # hysteresis) give them: bounce and pitch stay at rounding beside the roll
    for sus in (
        rr.Suspension.named("sas-attitude"),
        rr.Suspension.semi_active("railway", controller=SAS(GAINS.ride_attitude, _symmetric(GAINS.ride))),
        rr.Suspension.semi_active("railway", voltage=1.0),
    ):
        ds = _ride(sus)
        roll = np.abs(ds["carbody_roll"]).max().item()
        for name in ("carbody_bounce", "carbody_pitch"):
            assert np.abs(ds[name]).max().item() < 1e-12 * roll, (sus.label, name)


def test_the_shipped_ride_gains_differ_right_and_left_and_make_bounce_from_roll():
    # the tuned ride loop pushes the right and left corners of an axle differently, so a pure
    # roll input makes bounce even on the ideal actuator: the first seconds already show it
    assert GAINS.ride.kp_2R != GAINS.ride.kp_2L
    ds = _ride(rr.Suspension.ideal(SAS(GAINS.ride_attitude, GAINS.ride)))
    assert np.abs(ds["carbody_bounce"]).max().item() > 1e-5  # m


def _bounce_after(suspension) -> tuple[float, float]:
    """The largest bounce in the first and the last second after an initial bounce of 1e-9 m."""
    x0 = np.zeros(18)
    x0[0] = 1e-9
    ds = _ride(suspension, x0)
    b, t = np.abs(ds["carbody_bounce"].values), ds["time"].values
    return b[t <= 1.0].max(), b[t > 4.0].max()


def test_the_coils_lag_makes_pids_symmetric_ride_unstable():
    # PID on the MR dampers: a seed of bounce grows (about 1.2 /s, docs/control.md); with a coil
    # ten times faster the same loop lets it decay, as the ideal semi-active damper does
    model = damper_model("railway", 1.0)
    first, last = _bounce_after(rr.Suspension.named("pid"))
    assert last > 10 * first
    for sus in (
        rr.Suspension.semi_active(model.replace(eta=10 * model.eta), controller=GAINS.pid),
        rr.Suspension.ideal(GAINS.pid, dissipative=True),
    ):
        first, last = _bounce_after(sus)
        assert last < first
