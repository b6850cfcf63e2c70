"""`Suspension` and `SolverSettings`: the checks at construction, the named suspensions against
the same suspensions spelled with the plain constructor, batches, and the gain tables of
`GainSet`."""

import dataclasses
import json

import numpy as np
import pytest

from railride import dampers
from railride.secondary.control import PID, GainSet, InnerLoop, SensorNoise, ZeroDemand
from railride.model.params import VehicleParams
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
from railride.secondary.suspension import NAMES, Suspension, batch_conflict
from railride.studies.sweep import Case, run_cases
from railride.model.track import scenario

SC = scenario("paper-sine", duration=0.5)
G = GainSet.default()
NOISE = SensorNoise(1e-3, 1e-4, 1e-3, 1e-4, seed=3)


def _same(a, b):
    """Two Datasets with the same variables, values and attributes (but the creation time)."""
    assert set(a.variables) == set(b.variables)
    for name in a.variables:
        assert a[name].dtype == b[name].dtype and a[name].shape == b[name].shape, name
        if a[name].dtype.kind == "f":
            np.testing.assert_array_equal(a[name].values, b[name].values, err_msg=name)
        else:
            assert np.array_equal(a[name].values, b[name].values), name
    drop = {"created_utc"}
    assert {k: v for k, v in a.attrs.items() if k not in drop} == {k: v for k, v in b.attrs.items() if k not in drop}


# -- construction ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Suspension(voltage=1.0), r"voltage = 1.0: applies to MR dampers only"),
        (lambda: Suspension(dampers.Viscous(c=1e4), voltage=0.0), r"voltage = 0.0: applies to MR dampers only"),
        (lambda: Suspension("railway", voltage=3.0), r"voltage = 3.0 V: must lie in \[0, 2.25\]"),
        (
            lambda: Suspension.semi_active(controller=PID(1, 0, 0), voltage=1.0),
            r"voltage = 1.0 with controller = 'pid': give either voltage",
        ),
        (lambda: Suspension(damper="ideal"), r"damper = 'ideal': the ideal actuator .* needs controller="),
        (lambda: Suspension(damper="ideal-damper", voltage=1.0), r"damper = 'ideal-damper'.*got voltage = 1.0"),
        (lambda: Suspension.ideal(None), r"controller = None"),
        (lambda: Suspension.ideal(PID(1, 0, 0), dissipative="yes"), r"dissipative = 'yes'"),
        (
            lambda: Suspension("ideal", controller=PID(1, 0, 0), inner=InnerLoop(1.0, 1e-3)),
            r"inner = InnerLoop.*no inner loop",
        ),
        (lambda: Suspension(inner=InnerLoop(1.0, 1e-3)), r"inner applies to a closed loop only"),
        (lambda: Suspension("railway", sensor_noise=NOISE), r"sensor_noise applies to a closed loop only"),
        (lambda: Suspension(controller=PID(1, 0, 0)), r"controller = 'pid' with damper = None"),
        (
            lambda: Suspension(dampers.Viscous(c=1e4), controller=PID(1, 0, 0)),
            r"controller = 'pid': a controller needs MR dampers",
        ),
        (lambda: Suspension(damper="magic"), r"unknown damper model 'magic'"),
        (lambda: Suspension(damper=42), r"damper = 42: must be None"),
        (lambda: Suspension("railway", controller="pid"), r"controller = 'pid': must be an outer loop"),
        (lambda: Suspension("railway", controller=PID(1, 0, 0), inner=(1.0, 1e-3)), r"inner = \(1.0"),
        (lambda: Suspension("railway", controller=PID(1, 0, 0), sensor_noise=0.1), r"sensor_noise = 0.1"),
        (lambda: Suspension.passive(dampers.RAILWAY), r"damper = BoucWen"),
        (lambda: Suspension.semi_active("ideal"), r"damper = 'ideal': a semi-active suspension has MR dampers"),
        (lambda: Suspension.semi_active("railway", damper_scale=0.0), r"damper_scale = 0.0: must be"),
        (lambda: Suspension.named("lqr"), r"suspension = 'lqr'; allowed: passive, mr, pid"),
        (lambda: Suspension.named("passive", damper_scale=2.0), r"damper_scale = 2: the passive"),
        (lambda: Suspension.named("passive", voltage=1.0), r"voltage = 1.0: applies to suspension 'mr' only"),
        (lambda: Suspension.named("passive", sensor_noise=NOISE), r"sensor_noise applies to a closed loop only"),
        (lambda: Suspension.named("pid", damper="ideal", damper_scale=2.0), r"damper_scale = 2: the ideal"),
        (lambda: Suspension.named("mr", damper="ideal"), r"damper = 'ideal' with suspension 'mr'"),
        (lambda: Suspension.named("pid", voltage=1.0), r"voltage = 1.0 with controller = 'pid'"),
        (lambda: Suspension.named("pid", damper="mr9"), r"unknown damper model 'mr9'"),
        (lambda: Suspension.named("pid", damper=3), r"damper = 3: must be a name .* or a model"),
    ],
)
def test_invalid_combinations_name_the_field(make, match):
    with pytest.raises(ValueError, match=match):
        make()


def test_named_takes_a_damper_model_as_its_name():
    assert Suspension.named("pid", damper=dampers.RAILWAY) == Suspension.named("pid", damper="railway")
    assert Suspension.named("mr", damper=dampers.RAILWAY, damper_scale=2.0).damper == dampers.RAILWAY.scaled(2.0)
    # semi_active scales a model as it scales a name (one resolution, `damper_model`)
    assert Suspension.semi_active(dampers.RAILWAY, damper_scale=2.0) == Suspension.semi_active(
        "railway", damper_scale=2.0
    )


def test_the_kinds_names_and_records():
    cases = {
        Suspension.passive(): ("passive", "passive", False, "Passive"),
        Suspension.named("passive"): ("passive", "passive", False, "Passive"),
        Suspension.passive(dampers.Viscous(c=8e4)): ("passive", "passive", False, "Passive"),
        Suspension.semi_active(): ("semi-active", "mr", False, "railway MR dampers at 0 V"),
        Suspension.named("mr", damper="dyke1996", voltage=1.5): (
            "semi-active",
            "mr",
            False,
            "dyke1996 MR dampers at 1.5 V",
        ),
        Suspension.named("pid"): ("semi-active", "pid", True, "PID"),
        Suspension.named("sas-attitude-ride", damper_scale=2): (
            "semi-active",
            "sas-attitude-ride",
            True,
            "SAS (attitude+ride)",
        ),
        Suspension.named("sas-attitude", damper="ideal"): ("ideal", "sas-attitude", True, "SAS (attitude) (ideal)"),
        Suspension.ideal(ZeroDemand(), dissipative=True): ("ideal", "none", True, "no outer loop (ideal-damper)"),
    }
    for s, (kind, name, closed, label) in cases.items():
        assert (s.kind, s.name, s.closed_loop, s.label) == (kind, name, closed, label), s
        record = json.loads(json.dumps(s.to_dict(), allow_nan=False))  # JSON-safe
        assert record["kind"] == kind and record["name"] == name
    pid = Suspension.named("pid", sensor_noise=NOISE).to_dict()
    assert pid["damper"]["preset"] == "railway" and pid["voltage_v"] is None
    assert pid["controller"] == {"name": "pid", "gains": G.pid.to_dict()}
    assert pid["inner_loop"] == G.inner.to_dict() and pid["sensor_noise"]["seed"] == 3
    mr = Suspension.named("mr", voltage=1.0).to_dict()
    assert mr["voltage_v"] == 1.0 and mr["controller"] is None and mr["inner_loop"] is None
    ideal = Suspension.named("pid", damper="ideal-damper").to_dict()
    assert ideal["damper"]["model"] == "ideal-damper" and ideal["inner_loop"] is None


def test_a_suspension_is_a_frozen_value():
    a = Suspension.named("pid")
    assert a == Suspension.semi_active("railway", controller=G.pid, inner=G.inner)
    assert a == Suspension(dampers.RAILWAY, controller=G.pid)  # the shipped inner loop by default
    assert hash(a) == hash(Suspension.named("pid", G))
    assert a != Suspension.named("pid", damper_scale=2.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        a.voltage = 1.0
    # names become models; an open loop's voltage is its v_min unless given
    assert Suspension("spencer1997").damper is dampers.SPENCER1997
    assert Suspension("railway").voltage == 0.0
    assert Suspension.named("mr", damper_scale=2.0).damper == dampers.RAILWAY.scaled(2.0)


# -- the same runs as the plain constructor ---------------------------------------------------------
def _plain(name, damper, scale, G=G):
    """The suspension `Suspension.named` calls ``name``, spelled with the plain constructor: the
    damper model, the voltage, the outer loop and the inner loop."""
    if name == "passive":
        return Suspension()
    model = dampers.preset(damper) if scale == 1.0 else dampers.preset(damper).scaled(scale)
    if name == "mr":
        return Suspension(model, voltage=1.0)
    if name in ("passive-on", "passive-off"):
        return Suspension(model, voltage=model.v_max if name == "passive-on" else model.v_min)
    ideal = damper in dampers.IDEAL_NAMES
    return Suspension(model, controller=G.controller(name), inner=None if ideal else G.inner)


#: every name on every device it runs on (the slow Spencer model: open loop and one closed loop)
NAMED = [
    (n, d, x)
    for n in NAMES
    for d, x in (("railway", 1.0), ("railway", 2.0), ("spencer1997", 1.0), ("ideal", 1.0), ("ideal-damper", 1.0))
    if not (n in ("mr", "passive-on", "passive-off") and d in dampers.IDEAL_NAMES)
    and not (n == "passive" and (x != 1.0 or d != "railway"))
    and not (d == "spencer1997" and n not in ("mr", "pid"))
]


@pytest.mark.parametrize("name, damper, scale", NAMED)
def test_named_suspensions_run_as_the_plain_constructor(name, damper, scale):
    sc = scenario("paper-sine", duration=0.2) if damper == "spencer1997" else SC
    voltage = 1.0 if name == "mr" else None
    # the shipped groundhook gain, tuned where the MR dampers saturate, diverges on the ideal
    # devices at this step: the neutral gains there
    g = GainSet.reference() if name == "groundhook" and damper in dampers.IDEAL_NAMES else G
    new = simulate(sc, suspension=Suspension.named(name, g, damper, scale, voltage)).dataset
    plain = simulate(sc, suspension=_plain(name, damper, scale, g)).dataset
    _same(new, plain)


def test_a_closed_loop_with_noise_and_another_solver_runs_as_the_plain_constructor():
    solver = SolverSettings(dt=5e-5, output_rate=500.0, control_rate=400.0)
    new = simulate(SC, suspension=Suspension.named("sas-attitude", G, sensor_noise=NOISE), solver=solver)
    plain = simulate(
        SC,
        suspension=Suspension("railway", controller=G.controller("sas-attitude"), inner=G.inner, sensor_noise=NOISE),
        solver=SolverSettings(dt=5e-5, output_rate=500.0, control_rate=400.0),
    )
    _same(new.dataset, plain.dataset)
    assert new.solver == solver and new.suspension.name == "sas-attitude"
    assert new.dataset.attrs["control_rate_hz"] == 400.0 and new.dataset.attrs["dt_s"] == 5e-5


def test_passive_keeps_its_invariants():
    ds = simulate(SC, suspension=Suspension.passive()).dataset
    _same(ds, simulate(SC).dataset)
    assert ds.attrs["suspension"] == "passive viscous secondary dampers" and ds.attrs["damper"] == "null"
    assert "damper_voltage" not in ds and "controller" not in ds
    force = ds["secondary_damper_force"].values  # the dashpots c_sz: f = -c x' on the carbody
    rate = ds["secondary_deflection_velocity"].values
    np.testing.assert_allclose(force, -VehicleParams.preset("paper").c_sz * rate, rtol=1e-12, atol=1e-9)


def test_simulate_has_one_spelling():
    # the keywords of earlier versions are gone: a suspension and solver settings, or nothing
    with pytest.raises(TypeError, match="'damper'"):
        simulate(SC, None, Suspension.passive(), damper="railway")
    with pytest.raises(TypeError, match="'dt'"):
        simulate(SC, solver=SolverSettings(), dt=1e-4)
    with pytest.raises(TypeError, match="'volts'"):
        simulate(SC, volts=1.0)
    with pytest.raises(ValueError, match="suspension = 'pid': must be a railride.Suspension"):
        simulate(SC, "paper", "pid")
    with pytest.raises(ValueError, match=r"params = Suspension\(.*\): must be VehicleParams"):
        simulate(SC, Suspension.passive())  # the suspension is the third argument


# -- batches ------------------------------------------------------------------------------------
def test_a_batch_of_suspensions_equals_the_separate_runs():
    outer = [Suspension.named(n, G) for n in ("pid", "sas-attitude", "sas-attitude-ride")]
    outer.append(Suspension.semi_active(controller=ZeroDemand()))
    volts = [Suspension.semi_active("railway", voltage=v) for v in (0.0, 1.0, 2.25)]
    for batch in (outer, volts):
        ds = simulate(SC, suspension=batch).dataset
        assert ds.sizes["sample"] == len(batch)
        for i, s in enumerate(batch):
            single = simulate(SC, suspension=s).dataset
            for name in (
                "carbody_bounce",
                "carbody_roll",
                "carbody_acceleration",
                "secondary_damper_force",
                "damper_command_voltage",
            ):
                np.testing.assert_array_equal(
                    ds[name].isel(sample=i).values, single[name].values, err_msg=f"{s.name} {name}"
                )
    names = simulate(SC, suspension=outer).dataset["controller"].values
    assert list(names) == ["pid", "sas-attitude", "sas-attitude-ride", "none"]
    # one item is broadcast against a list of scenarios
    both = simulate([SC, scenario("bump", duration=0.5)], suspension=Suspension.named("pid"))
    assert both.dataset.sizes["sample"] == 2 and both.suspension == [Suspension.named("pid")] * 2


@pytest.mark.parametrize(
    "batch, field",
    [
        ([Suspension.semi_active(), Suspension.semi_active("dyke1996")], "damper = 'dyke1996'"),
        ([Suspension.passive(), Suspension.semi_active()], "damper = 'railway'"),
        ([Suspension.semi_active(voltage=1.0), Suspension.named("pid")], "closed_loop = True"),
        ([Suspension.named("pid"), Suspension.named("pid", G.apply({"inner.G": 1e-3}))], "inner = InnerLoop"),
        ([Suspension.named("pid"), Suspension.named("pid", sensor_noise=NOISE)], "sensor_noise = SensorNoise"),
    ],
)
def test_a_batch_shares_its_damper_inner_loop_and_noise(batch, field):
    assert field in batch_conflict(batch)
    with pytest.raises(ValueError, match=f"a batch of suspensions shares one damper model.*suspension 1 has {field}"):
        simulate(SC, suspension=batch)
    with pytest.raises(ValueError, match="equally many scenarios, parameter sets and suspensions"):
        simulate([SC, SC], suspension=[Suspension.passive()] * 3)


# -- solver settings -----------------------------------------------------------------------------
def test_solver_settings_defaults_and_steps():
    s = SolverSettings()
    assert (s.dt, s.output_rate, s.control_rate) == (1e-4, 1000.0, 1000.0)
    assert s.output_steps == 10 and s.control_steps() == 10
    assert s.to_dict() == {"dt_s": 1e-4, "output_rate_hz": 1000.0, "control_rate_hz": 1000.0}
    assert SolverSettings(dt=2e-4, output_rate=250).output_steps == 20
    assert SolverSettings.of(None) == s and SolverSettings.of(s) is s
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.dt = 1e-3
    # the controller period is checked where a closed loop runs: a passive run at dt = 4e-4 s
    # keeps the default control rate (2.5 steps a period)
    odd = SolverSettings(dt=4e-4, output_rate=250)
    with pytest.raises(ValueError, match="control_rate = 1000 Hz with dt = 0.0004 s: the controller period"):
        odd.control_steps()
    simulate(SC, solver=odd)
    with pytest.raises(ValueError, match="control_rate = 1000 Hz"):
        simulate(SC, suspension=Suspension.named("pid"), solver=odd)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"dt": -1e-4}, r"dt = -0.0001: must be a finite number > 0"),
        ({"dt": float("nan")}, r"dt = nan"),
        ({"dt": "1e-4"}, r"dt = '1e-4'"),
        ({"output_rate": 0.0}, r"output_rate = 0.0"),
        ({"control_rate": float("inf")}, r"control_rate = inf"),
        ({"dt": True}, r"dt = True"),
        ({"output_rate": 3000.0}, r"output_rate = 3000 Hz with dt = 0.0001 s: .* whole number of steps"),
        ({"dt": 0.05}, r"dt = 0.05 s is too large for output_rate = 1000 Hz"),
    ],
)
def test_solver_settings_are_checked_at_construction(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SolverSettings(**kwargs)
    with pytest.raises(ValueError, match=r"solver = 0.0001: must be a railride.SolverSettings"):
        simulate(SC, solver=1e-4)


# -- gain tables ---------------------------------------------------------------------------------
def test_gain_set_knows_its_tables():
    assert GainSet.TABLES[:4] == GainSet.PAPER_TABLES == ("inner", "pid", "attitude", "ride")
    assert GainSet.TABLES[4:] == (
        "ride_attitude",
        "skyhook",
        "skyhook_on_off",
        "groundhook",
        "hybrid",
        "clipped_optimal",
    )
    assert GainSet.entry_names("pid") == ("pid.kp", "pid.ki", "pid.kd")
    assert GainSet.tables_read("sas-attitude-ride") == ("inner", "ride_attitude", "ride")
    assert G.value("ride.kd_2L") == G.ride.kd_2L and G.value("inner.B") == G.inner.B
    assert len(G.entries(GainSet.PAPER_TABLES)) == 2 + 3 + 6 + 8 and G.entries(("pid",)) == {
        "pid.kp": G.pid.kp,
        "pid.ki": G.pid.ki,
        "pid.kd": G.pid.kd,
    }
    changed = G.apply({"pid.kd": 2e5, "inner.G": 1e-3})
    assert changed.pid.kd == 2e5 and changed.inner.G == 1e-3 and changed.pid.kp == G.pid.kp
    assert changed.source == G.source and changed.provenance == {}
    assert G.apply(()) == G
    for bad, match in (("pid", "expected table.entry"), ("lqr.k", "expected table.entry"), ("pid.kf", "unknown gain")):
        with pytest.raises(ValueError, match=match):
            G.apply({bad: 1.0})
        with pytest.raises(ValueError, match=match):
            G.value(bad)
    with pytest.raises(ValueError, match="gain table 'sas'"):
        GainSet.entry_names("sas")
    with pytest.raises(ValueError, match="controller = 'passive'"):
        GainSet.tables_read("passive")


# -- sweeps ----------------------------------------------------------------------------------
def test_a_case_gives_its_suspension_and_keeps_its_key():
    # keys of existing cases stay what they were (run tables resume on them)
    assert Case().key == "340d3635a06e8d0d"
    assert Case(suspension="pid", gains={"pid.kd": 2e5}).key == "432dde16f9ae5046"
    assert Case(suspension="mr", voltage=1.0).key == "31efb2eb0f97e6e2"
    assert Case(suspension="sas-attitude-ride", damper="ideal").key == "6afefdfe696186fb"
    case = Case(suspension="pid", gains={"pid.kd": 2e5}, noise=(1e-3, 1e-4, 1e-3, 1e-4), seed=3)
    assert case.to_suspension() == Suspension.named("pid", G.apply({"pid.kd": 2e5}), sensor_noise=NOISE)
    base = G.apply({"pid.kp": 1.0})
    assert case.to_suspension(base).controller == PID(1.0, G.pid.ki, 2e5)
    assert Case(suspension="mr", voltage=2.0, damper_scale=2).to_suspension() == Suspension.named(
        "mr", damper_scale=2.0, voltage=2.0
    )
    assert Case(noise=(1e-3, 1e-4, 1e-3, 1e-4)).to_suspension() == Suspension.passive()  # as before
    with pytest.raises(ValueError, match="voltage = 3.0 V: must lie in"):
        Case(suspension="mr", voltage=3.0)


def test_cases_that_differ_in_track_and_vehicle_alone_share_one_suspension():
    # a tuning round makes one suspension per gain set, not one per run: the shared one must be
    # what each case makes alone, and cases with other settings must get their own
    cases = [
        Case("fra4", {"seed": seed, "speed": v}, vehicle=load, suspension="pid", gains={"pid.kd": kd})
        for kd in (1e5, 2e5)
        for seed in (1, 2)
        for v in (30.0, 60.0)
        for load in ((), (("m_c", 4.0e4),))
    ]
    cases += [Case("paper-sine", suspension="pid", gains={"pid.kd": 1e5}), Case("fra4", suspension="skyhook")]
    cases += [Case("fra4", suspension="pid", gains={"pid.kd": 1e5}, delay=2)]
    cases += [Case("fra4", suspension="mr", voltage=1.0)]
    made = Case.suspensions(cases)
    assert [m == c.to_suspension() for m, c in zip(made, cases)] == [True] * len(cases)
    assert len({id(m) for m in made}) == 2 + 4  # a suspension per gain set on fra4, one per other setting
    assert made[0].controller != made[-4].controller  # paper-sine takes the paper's gains, fra4 the robust set
    for _ in range(2):  # a setting's check is kept, its error is not: raised each time
        with pytest.raises(ValueError, match="voltage = 3.0 V: must lie in"):
            Case("fra4", {"seed": 1}, suspension="mr", voltage=3.0)


def test_the_shipped_gains_are_read_once_and_each_caller_gets_its_own_provenance():
    first, second = GainSet.robust(), GainSet.robust()
    assert first == second and first.provenance == second.provenance and first.provenance
    first.provenance["note"] = "changed by a caller"
    assert "note" not in GainSet.robust().provenance


def test_run_cases_takes_the_vehicle_and_keys_it_only_when_not_the_paper_one():
    cases = [Case(scenario_options={"duration": 1.0})]
    solver = SolverSettings(dt=5e-5)
    paper = run_cases(cases, solver=solver, window=(0.2, 1.0))
    key = paper["key"].iloc[0]  # the paper's vehicle is not in the key: keys from before params= hold
    named = run_cases(cases, solver=solver, window=(0.2, 1.0), params="paper")
    assert named["key"].iloc[0] == key
    soft = VehicleParams.preset("paper").replace(k_sz=3e5)
    other = run_cases(cases, solver=solver, window=(0.2, 1.0), params=soft)
    assert other["key"].iloc[0] != key
    direct = simulate(scenario("paper-sine", duration=1.0), soft, solver=solver).metrics((0.2, 1.0))
    assert other["acceleration_m_s2_rms"].iloc[0] == float(direct.sel(response="acceleration_m_s2", statistic="rms"))
    # another output rate is another run too
    faster = run_cases(cases, solver=SolverSettings(dt=5e-5, output_rate=2000.0), window=(0.2, 1.0))
    assert faster["key"].iloc[0] != key
