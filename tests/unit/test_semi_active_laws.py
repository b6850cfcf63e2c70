"""The semi-active laws beside the paper's (railride.secondary.controllers) as gain matrices, their names,
their gain tables in a gains file, and the refusals of bad input."""

import inspect
import re

import numpy as np
import pytest

from railride import dampers
from railride.studies.comparison import check_controllers, compare
from railride.secondary.control import (
    CONSTANT_VOLTAGE,
    CONTROLLERS,
    LABELS,
    OUTER_LOOPS,
    PAPER_CONTROLLERS,
    GainSet,
)
from railride.secondary.controllers import ClippedOptimal, Groundhook, Hybrid, Skyhook, SkyhookOnOff
from railride.model.params import VehicleParams
from railride.studies.grid import grid
from railride.secondary.suspension import NAMES, Suspension
from railride.model.vehicle import Vehicle

P = VehicleParams.preset("paper")
V = Vehicle(P)


# -- names ------------------------------------------------------------------------------------------
def test_the_controllers_in_order_and_the_paper_default():
    assert CONTROLLERS == (
        "passive",
        "pid",
        "sas-attitude",
        "sas-attitude-ride",
        "skyhook",
        "skyhook-on-off",
        "groundhook",
        "hybrid",
        "clipped-optimal",
        "passive-on",
        "passive-off",
    )
    assert set(LABELS) == set(CONTROLLERS) and PAPER_CONTROLLERS == CONTROLLERS[:4]
    assert OUTER_LOOPS == CONTROLLERS[1:9] and tuple(CONSTANT_VOLTAGE) == CONTROLLERS[9:]
    assert inspect.signature(compare).parameters["controllers"].default == PAPER_CONTROLLERS
    assert NAMES == ("passive", "mr", *CONTROLLERS[1:])
    assert check_controllers(["all"]) == list(CONTROLLERS)
    assert check_controllers(["passive-off", "skyhook"]) == ["passive", "skyhook", "passive-off"]


def test_each_name_is_its_law_with_its_voltage_law():
    g = GainSet.default()
    kinds = {
        "skyhook": (Skyhook, "tracking"),
        "skyhook-on-off": (SkyhookOnOff, "on-off"),
        "groundhook": (Groundhook, "tracking"),
        "hybrid": (Hybrid, "tracking"),
        "clipped-optimal": (ClippedOptimal, "clipped"),
    }
    for name, (kind, law) in kinds.items():
        c = g.controller(name)
        assert type(c) is kind and c.name == name and c.voltage_law == law and LABELS[name] == c.label
        assert Suspension.named(name, g).controller == c
    assert g.controller("skyhook-on-off").to_dict() == g.skyhook_on_off.to_dict()  # a table of its own
    assert g.controller("passive-on") is None and g.controller("passive-off") is None
    assert GainSet.tables_read("skyhook") == ("inner", "skyhook")
    assert GainSet.tables_read("skyhook-on-off") == ("skyhook_on_off",)  # no force tracking: no inner loop
    assert GainSet.tables_read("clipped-optimal") == ("clipped_optimal",)
    assert GainSet.tables_read("hybrid") == ("inner", "hybrid") and GainSet.tables_read("passive-on") == ()


def test_passive_on_and_off_are_the_mr_dampers_at_the_ends_of_their_range():
    on, off = Suspension.named("passive-on"), Suspension.named("passive-off", damper="dyke1996", damper_scale=2.0)
    assert on == Suspension.semi_active("railway", voltage=dampers.RAILWAY.v_max)
    assert off == Suspension.semi_active("dyke1996", voltage=dampers.DYKE1996.v_min, damper_scale=2.0)
    assert not on.closed_loop and on.controller is None and on.inner is None


# -- the laws as gain matrices -------------------------------------------------------------------------
def test_groundhook_opposes_the_bogie_points_absolute_velocity():
    c_g = 7e4
    G, H = Groundhook(c_g).gains(V)
    assert G.shape == (4, 18) and np.all(H == 0)
    rates = np.zeros(9)
    rates[3:] = 0.1, -0.02, 0.03, -0.05, 0.01, 0.04  # front bogie, rear bogie: bounce, pitch, roll
    state = np.concatenate([np.full(9, 0.3), rates])  # positions and carbody rates do not enter
    state[9:12] = 0.2, 0.01, -0.03
    # a corner's bogie point at (0, y) of its bogie (R: y = -d_s), moving with z_b' + y theta_b'
    point = [
        rates[3] - P.d_s * rates[5],
        rates[3] + P.d_s * rates[5],
        rates[6] - P.d_s * rates[8],
        rates[6] + P.d_s * rates[8],
    ]
    # the force on the bogie is -c_g v_b: on the carbody, +c_g v_b
    assert G @ state == pytest.approx(c_g * np.array(point), rel=1e-12)


def test_hybrid_blends_skyhook_and_groundhook():
    c = dict(c_z=3e5, c_phi=2e7, c_theta=3e5)
    sky, _ = Skyhook(**c).gains(V)
    sky_full = np.zeros((4, 18))
    sky_full[:, :3], sky_full[:, 9:12] = sky[:, :3], sky[:, 3:]
    ground, _ = Groundhook(8e4).gains(V)
    for alpha in (0.0, 0.3, 1.0):
        G, H = Hybrid(alpha=alpha, c_g=8e4, **c).gains(V)
        assert np.allclose(G, alpha * sky_full + (1 - alpha) * ground, rtol=1e-12, atol=0) and np.all(H == 0)


def test_on_off_skyhook_has_the_skyhooks_demand():
    law = Skyhook(3e5, 2e7, 3e5)
    on_off = SkyhookOnOff(3e5, 2e7, 3e5)
    assert np.array_equal(on_off.gains(V)[0], law.gains(V)[0]) and on_off != law


# -- the gain tables ---------------------------------------------------------------------------------
def test_the_reference_tables_follow_the_passive_secondary():
    g = ref = GainSet.reference()
    c, k, l2, d2 = P.c_sz, P.k_sz, P.l**2, P.d_s**2
    assert g.skyhook == Skyhook(4 * c, 4 * c * l2, 4 * c * d2) and g.groundhook == Groundhook(c)
    assert g.hybrid == Hybrid(0.5, 4 * c, 4 * c * l2, 4 * c * d2, c)
    w = g.clipped_optimal
    assert (w.q_z, w.q_phi, w.q_theta) == pytest.approx((4 * k**2, 4 * k**2 * l2, 4 * k**2 * d2), rel=1e-12)
    assert (w.qd_z, w.qd_phi, w.qd_theta, w.r) == pytest.approx((4 * c**2, 4 * c**2 * l2, 4 * c**2 * d2, 1.0))
    assert g.skyhook_on_off == g.skyhook and g.ride_attitude == g.attitude
    assert GainSet.default().from_reference == () and ref.from_reference == ()


def test_a_gains_file_of_0_3_0_still_loads_with_the_reference_for_the_new_tables(tmp_path):
    # a file of the paper's four tables only, as railride 0.3.0 wrote them, with its own attitude loop
    own = GainSet.reference().apply({"attitude.kp_z": 123.0})
    old = own.to_toml(GainSet.PAPER_TABLES)
    assert "[sas.ride]" in old and "[skyhook]" not in old and "[sas.ride_attitude]" not in old
    path = tmp_path / "old.toml"
    path.write_text(old)
    g = GainSet.load(path)
    assert g.from_reference == ("skyhook", "groundhook", "hybrid", "clipped_optimal", "skyhook_on_off")
    # SAS (attitude+ride) and on-off skyhook read the tables they shared then: the file's own
    assert g.ride_attitude == g.attitude == own.attitude and g.skyhook_on_off == g.skyhook
    assert g.controller("sas-attitude-ride").attitude.kp_z == 123.0
    ref = GainSet.reference()
    assert (g.skyhook, g.groundhook, g.hybrid, g.clipped_optimal) == (
        ref.skyhook,
        ref.groundhook,
        ref.hybrid,
        ref.clipped_optimal,
    )
    # a file with some of the new tables takes the reference for the others only
    part = GainSet.from_toml(old + "\n[groundhook]\nc_g = 1000.0\n")
    assert part.groundhook == Groundhook(1000.0) and "groundhook" not in part.from_reference
    # the same from the constructor, and a change to a table makes it the file's own
    built = GainSet(g.inner, g.pid, g.attitude, g.ride)
    assert built.from_reference == g.from_reference and built == GainSet(**{t: g.table(t) for t in GainSet.TABLES})
    changed = built.apply({"skyhook.c_z": 1e5})
    assert changed.skyhook.c_z == 1e5 and changed.from_reference == (
        "groundhook",
        "hybrid",
        "clipped_optimal",
        "skyhook_on_off",
    )


def test_new_tables_round_trip_and_apply(tmp_path):
    g = GainSet.default().apply({"hybrid.alpha": 0.25, "clipped_optimal.r": 2.0, "groundhook.c_g": 1e4})
    text = g.to_toml()
    for head in ("[skyhook]", "[groundhook]", "[hybrid]", "[clipped_optimal]", "# N^2 s^2/rad^2"):
        assert head in text
    back = GainSet.from_toml(text, source=g.source)
    assert back == g and back.hybrid.alpha == 0.25 and back.clipped_optimal.r == 2.0
    assert GainSet.entry_names("hybrid") == (
        "hybrid.alpha",
        "hybrid.c_z",
        "hybrid.c_phi",
        "hybrid.c_theta",
        "hybrid.c_g",
    )
    assert g.value("groundhook.c_g") == 1e4 and len(g.entries()) == 19 + 6 + 3 + 3 + 1 + 5 + 7


def test_key_text_is_the_paper_tables_unless_a_new_table_differs():
    ref = GainSet.reference()
    assert ref.key_text() == ref.to_toml(GainSet.PAPER_TABLES)
    other = ref.apply({"skyhook.c_z": 1.0})  # skyhook-on-off keeps the reference: it differs
    assert other.key_text() == other.to_toml((*GainSet.PAPER_TABLES, "skyhook", "skyhook_on_off"))
    both = ref.apply({"skyhook.c_z": 1.0, "skyhook_on_off.c_z": 1.0})  # the same table again
    assert both.key_text() == both.to_toml((*GainSet.PAPER_TABLES, "skyhook"))
    own = ref.apply({"ride_attitude.kp_z": 1.0})
    assert own.key_text() == own.to_toml((*GainSet.PAPER_TABLES, "ride_attitude"))


# -- bad input -------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Hybrid(1.5, 1, 1, 1, 1), r"hybrid gain 'alpha' = 1.5 .*: must be a number in \[0, 1\]"),
        (lambda: Hybrid(-0.1, 1, 1, 1, 1), r"hybrid gain 'alpha' = -0.1 .*: must be a number in \[0, 1\]"),
        (lambda: Hybrid(float("nan"), 1, 1, 1, 1), r"hybrid gain 'alpha' = nan"),
        (lambda: Skyhook(-1.0, 0, 0), r"skyhook gain 'c_z' = -1.0 \(heave skyhook damping, N s/m\)"),
        (lambda: Groundhook("a lot"), r"groundhook gain 'c_g' = 'a lot'"),
        (lambda: ClippedOptimal(-1.0, 0, 0, 0, 0, 0, 1), r"clipped-optimal weight 'q_z' = -1.0 .*>= 0"),
        (lambda: ClippedOptimal(0, 0, 0, 0, 0, -2.0, 1), r"clipped-optimal weight 'qd_theta' = -2.0"),
        (
            lambda: ClippedOptimal(0, 0, 0, 1, 0, 0, 0.0),
            r"clipped-optimal weight 'r' = 0.0 .*: must be a finite number > 0",
        ),
        (
            lambda: check_controllers(["skyhook", "lqr"]),
            r"unknown controller 'lqr'; allowed: passive, .*, passive-off, or all",
        ),
        (lambda: Suspension.named("skyhook-off"), r"suspension = 'skyhook-off'; allowed: .*clipped-optimal"),
        (lambda: Suspension.named("passive-on", damper="ideal"), r"damper = 'ideal' with suspension 'passive-on'"),
        (lambda: Suspension.named("passive-off", voltage=1.0), r"voltage = 1.0 with suspension 'passive-off'"),
        (lambda: GainSet.default().apply({"hybrid.alpha": 2.0}), r"hybrid gain 'alpha' = 2.0"),
        (lambda: GainSet.default().controller("lqr"), r"unknown controller 'lqr'"),
        (lambda: grid(["passive-on"], damper="ideal"), r"damper = 'ideal': .*passive-on runs at a constant voltage"),
    ],
)
def test_bad_input_names_the_field(make, match):
    with pytest.raises(ValueError, match=match):
        make()


@pytest.mark.parametrize(
    "edit, match",
    [
        (lambda t: re.sub(r"alpha = [0-9.]+", "alpha = 1.2", t), r"g.toml: \[hybrid\] hybrid gain 'alpha' = 1.2"),
        (lambda t: re.sub(r"\nr = [0-9.]+", "\nr = 0.0", t), r"\[clipped_optimal\] clipped-optimal weight 'r' = 0.0"),
        (lambda t: re.sub(r"q_phi = [0-9.]+", "q_phi = -1.0", t), r"\[clipped_optimal\] .*'q_phi' = -1.0"),
        (
            lambda t: t.replace("c_g = 80000.0  # N s/m\n\n[hybrid]", "\n[hybrid]"),
            r"missing entry 'c_g' in \[groundhook\]",
        ),
        (lambda t: t + "\n[lqr]\nk = 1.0\n", r"unknown table\(s\) lqr; allowed: .*\[clipped_optimal\], \[provenance\]"),
    ],
)
def test_bad_new_tables_in_a_gains_file_name_the_entry(edit, match):
    with pytest.raises(ValueError, match=match):
        GainSet.from_toml(edit(GainSet.reference().to_toml()), source="g.toml")


def test_sweep_runs_passive_on_and_off_as_mr_at_the_ends_of_the_range():
    g = grid(["passive", "passive-on", "passive-off", "skyhook"], damper_scale=[1.0, 2.0])
    by_name = {}
    for case, values in zip(g.cases, g.values):
        by_name.setdefault(values["suspension"], []).append(case)
    assert [(c.suspension, c.voltage, c.damper_scale) for c in by_name["passive-on"]] == [
        ("mr", dampers.RAILWAY.v_max, 1.0),
        ("mr", dampers.RAILWAY.v_max, 2.0),
    ]
    assert {c.voltage for c in by_name["passive-off"]} == {dampers.RAILWAY.v_min}
    assert g.controllers == ("skyhook",)
