"""Damper faults (railride.secondary.faults) against runs that mean the same by construction."""

import numpy as np
import pytest

from railride import dampers
from railride.secondary.faults import DamperFault
from railride.model.params import VehicleParams
from railride.run.simulation import simulate
from railride.secondary.suspension import Suspension
from railride.model.track import scenario

SC = scenario("paper-sine", duration=2.0)
ALL = ("1R", "1L", "2R", "2L")
BODY = ("carbody_bounce", "carbody_pitch", "carbody_roll")


def _body(ds) -> np.ndarray:
    return np.stack([ds[n].values for n in BODY])


def test_every_damper_disconnected_is_the_vehicle_without_secondary_dampers():
    # no force from any damper: the vehicle with c_sz = 0, run by the other code path (the
    # viscous dampers inside its damping matrix)
    faulted = simulate(SC, suspension=Suspension.named("sas-attitude").with_faults([f"{c}-disconnected" for c in ALL]))
    bare = simulate(SC, VehicleParams.preset("paper").replace(c_sz=0.0), Suspension.passive())
    assert np.allclose(_body(faulted.dataset), _body(bare.dataset), rtol=1e-9, atol=1e-12)
    assert np.all(faulted.dataset.secondary_damper_force.values == 0.0)


def test_every_coil_off_under_a_controller_is_the_dampers_at_v_min():
    # the controller's voltages are overridden at every step: the run is passive-off's (the coils
    # start at v_min in both)
    faulted = simulate(SC, suspension=Suspension.named("sas-attitude").with_faults([f"{c}-off" for c in ALL]))
    off = simulate(SC, suspension=Suspension.named("passive-off"))
    assert np.allclose(_body(faulted.dataset), _body(off.dataset), rtol=1e-9, atol=1e-12)


def test_a_stuck_coil_holds_v_max_from_its_time_and_the_run_before_is_the_healthy_one():
    base = Suspension.named("sas-attitude")
    healthy = simulate(SC, suspension=base).dataset
    stuck = simulate(SC, suspension=base.with_faults("1L-on@1.0")).dataset
    t = stuck.time.values
    before, after = t < 1.0, t >= 1.0
    assert np.array_equal(_body(stuck)[:, before], _body(healthy)[:, before])  # nothing failed yet
    v = stuck.damper_command_voltage.sel(corner="1L").values
    assert np.all(v[after] == dampers.RAILWAY.v_max) and np.any(v[before] != dampers.RAILWAY.v_max)
    others = stuck.damper_command_voltage.sel(corner="1R").values
    assert np.any(others[after] != dampers.RAILWAY.v_max)  # the others still follow the law
    assert not np.allclose(_body(stuck)[:, after], _body(healthy)[:, after])
    assert str(stuck.damper_faults.values) == "1L-on@1"


def test_faults_are_recorded_and_read_back():
    f = DamperFault.parse("2R-disconnected@0.5")
    assert (f.corner, f.mode, f.time, f.label) == ("2R", "disconnected", 0.5, "2R-disconnected@0.5")
    s = Suspension.named("pid").with_faults(["2L-on", f])
    assert [x.label for x in s.faults] == ["2R-disconnected@0.5", "2L-on"]  # corner order
    assert s.to_dict()["faults"] == ["2R-disconnected@0.5", "2L-on"]
    assert simulate(SC, suspension=s).to_dict()["suspension"]["faults"] == ["2R-disconnected@0.5", "2L-on"]
    assert "faults" not in Suspension.named("pid").to_dict()


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: DamperFault("3R", "off"), r"fault corner = '3R': allowed 1R, 1L, 2R, 2L"),
        (lambda: DamperFault("1R", "broken"), r"fault mode = 'broken': allowed off, on, disconnected"),
        (lambda: DamperFault("1R", "off", -1.0), r"fault time = -1.0: must be a finite number >= 0"),
        (lambda: DamperFault.parse("1R"), r"fault = '1R': expected CORNER-MODE\[@TIME\]"),
        (lambda: DamperFault.parse("1R-off@soon"), r"the time after @ must be a number"),
        (lambda: Suspension.named("pid").with_faults(["1R-off", "1R-on"]), r"corner 1R has more than one fault"),
        (lambda: Suspension.passive().with_faults("1R-disconnected"), r"the vehicle's own passive dampers"),
        (lambda: Suspension.named("pid", damper="ideal").with_faults("1R-off"), r"'off' and 'on' need MR dampers"),
        (lambda: simulate(SC, suspension=Suspension.named("pid").with_faults("1R-off@2")), r"not within the run"),
    ],
)
def test_bad_faults_name_what_is_wrong(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_the_ideal_actuator_can_lose_a_corner():
    base = Suspension.named("sas-attitude", damper="ideal")
    ds = simulate(SC, suspension=base.with_faults("2L-disconnected")).dataset
    assert np.all(ds.secondary_damper_force.sel(corner="2L").values == 0.0)
    assert np.any(ds.secondary_damper_force.sel(corner="2R").values != 0.0)


def test_compare_with_a_fault_reports_the_degradation_against_healthy_dampers():
    from railride.studies.comparison import compare

    cmp = compare(SC, controllers=["pid", "sas-attitude"], faults=["1R-off"])
    assert cmp.bounds is None and cmp.healthy is not None and cmp.healthy.healthy is None
    doc = cmp.to_dict()
    record = doc["faults"]
    assert record["faults"] == ["1R-off"] == doc["settings"]["faults"]
    rms = cmp.metrics.sel(statistic="rms")
    healthy = cmp.healthy.metrics.sel(statistic="rms")
    # the healthy run is the plain comparison; the passive baseline is the same in both
    plain = compare(SC, controllers=["pid", "sas-attitude"], bounds=False).metrics.sel(statistic="rms")
    assert np.array_equal(healthy.values, plain.values)
    assert np.array_equal(rms.sel(controller="passive").values, healthy.sel(controller="passive").values)
    assert rms.response.size  # the loop below checks something
    for name in ("pid", "sas-attitude"):
        row = record["controllers"][name]
        for r in rms.response.values:
            f, h, p = (
                float(a.sel(controller=c, response=r)) for a, c in ((rms, name), (healthy, name), (rms, "passive"))
            )
            assert row["faulted_rms"][str(r)] == f and row["healthy_rms"][str(r)] == h
            assert row["change_percent"][str(r)] == pytest.approx((f - h) / h * 100)
            assert (str(r) in row["worse_than_passive"]) == (f > p)
        assert row["faulted_rms"] != row["healthy_rms"]  # the fault changes the ride
    assert "faults" not in compare(SC, controllers=["pid"], bounds=False).to_dict()
