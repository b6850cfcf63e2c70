"""Sweeps, the sensitivity study and the global methods, at the library level."""

import numpy as np
import pytest

from railride.secondary.control import GainSet
from railride.studies.optimise import optimise, sensitivity
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
from railride.secondary.suspension import Suspension
from railride.studies.sweep import Case, RunTable, run_cases
from railride.model.track import scenario
from railride.model.params import VehicleParams
from railride.studies.tuning import (
    DEFAULT_OBJECTIVE,
    INFEASIBLE_OFFSET,
    PARAMETERS,
    REFERENCE,
    Objective,
    tracking_objective,
    tune,
)

SHORT = {"duration": 1.0}


class CountingExecutor:
    """The local executor, counting the cases it is given."""

    def __init__(self):
        self.cases = 0

    def map(self, fn, chunks):
        for i, chunk in enumerate(chunks):
            self.cases += len(chunk)
            yield i, fn(chunk)


def test_case_keys_are_stable_and_distinct():
    a = Case(scenario_options={"speed": 40.0, "duration": 1.0}, suspension="pid", gains={"pid.kd": 1e5})
    b = Case(scenario_options={"duration": 1.0, "speed": 40}, suspension="pid", gains={"pid.kd": 100000})
    c = Case(scenario_options={"speed": 41.0, "duration": 1.0}, suspension="pid", gains={"pid.kd": 1e5})
    assert a.key == b.key != c.key
    with pytest.raises(ValueError, match="suspension"):
        Case(suspension="active")


def test_a_swept_case_equals_the_direct_run():
    g = GainSet.default()
    case = Case(scenario_options={"speed": 40.0, **SHORT}, suspension="pid", gains={"pid.kd": 2e5})
    row = run_cases([case]).iloc[0]
    direct = simulate(
        scenario("paper-sine", speed=40.0, **SHORT), suspension=Suspension.named("pid", g.apply((("pid.kd", 2e5),)))
    ).metrics()
    expected = float(direct.sel(response="acceleration_m_s2", statistic="rms"))
    assert row["acceleration_m_s2_rms"] == pytest.approx(expected, rel=1e-12)
    assert row["roll_deg_ptp"] == pytest.approx(float(direct.sel(response="roll_deg", statistic="ptp")), rel=1e-12)


def test_run_table_resumes_without_redoing_runs(tmp_path):
    cases = [Case(scenario_options={"speed": v, **SHORT}) for v in (30.0, 40.0, 50.0)]
    path = tmp_path / "runs.csv"
    first = run_cases(cases[:2], table=RunTable(path))
    with pytest.raises(ValueError, match="exists"):
        RunTable(path)
    ex = CountingExecutor()
    both = run_cases(cases, table=RunTable(path, resume=True), executor=ex)
    assert ex.cases == 1  # only the new speed ran
    assert both["acceleration_m_s2_rms"].iloc[:2].tolist() == first["acceleration_m_s2_rms"].tolist()
    assert len(RunTable(path, resume=True).frame) == 3


def test_every_row_of_the_run_table_names_its_vehicle_and_load(tmp_path):
    """run_cases: ``vehicle`` and ``load`` after ``key`` in every row (default the vehicle's
    name at load 1; one dict for all cases or one per case); a robust tuning over two loads
    names each run's load, beside the carbody mass it ran with."""
    import pandas as pd

    from railride.studies.tuning import tuning_set

    case = Case(scenario_options=SHORT)
    row = run_cases([case]).iloc[0]
    assert (row["vehicle"], row["load"]) == ("paper", 1.0) and list(row.index[:3]) == ["key", "vehicle", "load"]
    heavier = VehicleParams.preset("paper").replace(m_c=4.2e4)
    assert run_cases([case], vehicle=heavier).iloc[0]["vehicle"] == "custom"
    assert run_cases([case], vehicle_columns=[{"vehicle": "mine", "load": 2.0}]).iloc[0]["load"] == 2.0
    with pytest.raises(ValueError, match="one per case"):
        run_cases([case, case], vehicle_columns=[{"vehicle": "mine", "load": 2.0}])
    path = tmp_path / "runs.csv"
    tune(
        ("pid",),
        over=tuning_set("paper-sine", loads=[1.0, 1.3], duration=0.5),
        n_values=3,
        budget=5,
        table=RunTable(path),
    )
    runs = pd.read_csv(path)
    assert set(runs["vehicle"]) == {"paper"} and set(runs["load"]) == {1.0, 1.3}
    m_c = VehicleParams.preset("paper").m_c
    assert (runs["vehicle.m_c"].fillna(m_c) == m_c * runs["load"]).all()


def test_sensitivity_study_never_worsens_the_objective_and_records_curves():
    start = GainSet.default()
    res = tune(("pid",), scenario_options=SHORT, gains=start, n_values=4, budget=30)
    history = [h["objective"] for h in res.history]
    assert len(history) >= 2 and all(b <= a + 1e-12 for a, b in zip(history, history[1:]))
    assert {c.parameter for c in res.curves} == {"pid.kp", "pid.ki", "pid.kd"}
    # the chosen value is the best of its curve, or the value the gain had before it; nothing on
    # any curve beats the end; and the tuned gains are the last values chosen
    last = {p: start.value(p) for p in ("pid.kp", "pid.ki", "pid.kd")}
    for c in res.curves:
        assert c.objective.min() >= min(history) - 1e-12
        assert c.chosen in (c.values[np.argmin(c.objective)], last[c.parameter]), (c.parameter, c.chosen)
        last[c.parameter] = c.chosen
    assert {p: res.gains.value(p) for p in last} == last != {p: start.value(p) for p in last}
    # re-evaluating the tuned gains gives the objective the study reports
    rows = run_cases(
        [
            Case(
                scenario_options=tuple(sorted(SHORT.items())),
                suspension="pid",
                gains=tuple((f"pid.{k}", v) for k, v in res.gains.pid.to_dict().items()),
            )
        ],
        base_gains=start,
    )
    rms = rows[[f"{r}_rms" for r in ("acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg")]].to_numpy()
    passive = np.array(list(res.passive.values()))
    assert res.objective is DEFAULT_OBJECTIVE  # no objective given: the one default
    assert res.objective(rms, passive)[0] == pytest.approx(history[-1], rel=1e-12)


def test_inner_loop_objective_prefers_feedback():
    # with no gain the damper stays at v_min and tracks nothing but its residual force
    assert tracking_objective(1.0, 1.15e-3) < tracking_objective(1.0, 1e-9)


def test_objective_kinds_against_hand_computed_values():
    passive = np.array([2.0, 1.0, 0.5, 4.0])
    rms = np.array(
        [
            [1.0, 0.5, 0.75, 2.0],  # ratios 0.5, 0.5, 1.5, 0.5
            [2.0, 1.0, 0.5, 4.0],
        ]
    )  # passive itself: ratios 1, 1, 1, 1
    cases = [
        (Objective(), [3.0, 4.0]),
        (Objective("weighted", (1, 0, 2, 1)), [0.5 + 0 + 3.0 + 0.5, 4.0]),
        (Objective("minimax"), [1.5, 1.0]),
        (Objective("sum", penalty=10.0), [3.0 + 10 * 0.5, 4.0]),
        (Objective("minimax", penalty=2.0), [1.5 + 2 * 0.5, 1.0]),
        (Objective("constrained", bound=2.0), [3.0, 4.0]),  # both within the bound
        (Objective("constrained", bound=1.2), [1000 + 1000 * 0.3, 4.0]),  # 1.5 is 0.3 over
    ]
    for objective, expected in cases:
        assert objective(rms, passive) == pytest.approx(expected, rel=1e-12), objective.kind
        assert objective(rms[0], passive) == pytest.approx(expected[0], rel=1e-12)  # one run


def test_minimax_sees_only_the_worst_ratio():
    ratios = np.array([[0.9, 0.1, 0.1, 0.1], [0.9, 0.9, 0.9, 0.9], [0.2, 0.2, 0.2, 0.91]])
    j = Objective("minimax").score(ratios)
    assert j[0] == j[1] == 0.9  # a tie, however much better the other three ratios are
    assert j[2] > j[0]
    assert "tie" in Objective("minimax").describe()


def test_constrained_ranks_infeasible_candidates_after_feasible_ones_by_excess():
    ratios = np.array(
        [
            [1.2, 1.2, 1.2, 1.2],  # feasible, at the bound: the worst feasible sum
            [0.1, 0.1, 0.1, 1.21],  # infeasible by 0.01, with the smallest sum
            [1.22, 1.22, 0.0, 0.0],  # infeasible by 0.04
            [1.3, 0.1, 0.1, 0.1],  # infeasible by 0.1
            [1.0, 1.0, 1.0, 1.0],  # feasible
        ]
    )
    for penalty in (0.0, 10.0):
        objective = Objective("constrained", bound=1.2, penalty=penalty)
        j = objective.score(ratios)
        assert list(np.argsort(j)) == [4, 0, 1, 2, 3]
        assert j[0] == pytest.approx(4.8 + penalty * 0.8)  # feasible: sum and penalty
        assert j[1] == pytest.approx(INFEASIBLE_OFFSET + 1000 * 0.01)
        assert j[3] == pytest.approx(INFEASIBLE_OFFSET + 1000 * 0.1)
    # a bound so loose that a feasible J could pass 1000: the offset rises above it
    loose = Objective("constrained", bound=300.0)
    j = loose.score(np.array([[300.0] * 4, [0.0, 0.0, 0.0, 300.001]]))
    assert j[0] == pytest.approx(1200.0) and j[1] > j[0]
    assert f"J = {loose.infeasible_offset:g} + 1000 x E" in loose.describe()


def test_every_setting_of_an_objective_is_in_its_statement():
    text = Objective("weighted", (1, 0.5, 2, 1), penalty=3.0).describe()
    for fragment in (
        "weighted",
        "acceleration 1, displacement 0.5, pitch 2, roll 1",
        "penalty 3 x sum_k max(0, r_k - 1)",
    ):
        assert fragment in text
    text = Objective("constrained", bound=1.2).describe()
    assert "r_k <= 1.2" in text and "J = 1000 + 1000 x E" in text and "max(0, r_k - 1.2)" in text
    assert "penalty" not in Objective("sum").describe()  # none to state
    d = Objective("constrained", bound=1.2, penalty=1.0).to_dict()
    assert (d["kind"], d["bound"], d["penalty"], d["weights"]) == ("constrained", 1.2, 1.0, None)
    assert d["infeasible"]["offset"] == 1000.0 and d["statement"].startswith("constrained: J")


@pytest.mark.parametrize(
    "kwargs, fragments",
    [
        ({"kind": "best"}, ("kind", "'best'", "sum, weighted, minimax, constrained")),
        ({"kind": "weighted"}, ("weights = None", "four numbers")),
        ({"kind": "weighted", "weights": (1, 2)}, ("weights", "four numbers")),
        ({"kind": "weighted", "weights": (1, -1, 0, 0)}, ("weights", ">= 0")),
        ({"kind": "weighted", "weights": (0, 0, 0, 0)}, ("weights", "not all 0")),
        ({"kind": "weighted", "weights": ("a", 1, 1, 1)}, ("weights", "'a'")),
        ({"kind": "sum", "weights": (1, 1, 2, 1)}, ("weights", "'weighted' only")),
        ({"kind": "constrained"}, ("bound = None", "> 0")),
        ({"kind": "constrained", "bound": 0.0}, ("bound = 0.0", "> 0")),
        ({"kind": "constrained", "bound": float("nan")}, ("bound", "finite")),
        ({"kind": "constrained", "bound": "1.2"}, ("bound = '1.2'",)),
        ({"kind": "minimax", "bound": 1.2}, ("bound = 1.2", "'constrained' only")),
        ({"penalty": -1.0}, ("penalty = -1.0", ">= 0")),
        ({"penalty": float("inf")}, ("penalty", "finite")),
    ],
)
def test_objective_refuses_bad_settings(kwargs, fragments):
    with pytest.raises(ValueError) as info:
        Objective(**kwargs)
    for fragment in fragments:
        assert fragment in str(info.value), str(info.value)


def test_the_ride_loop_starts_from_zero_ride_gains():
    start = GainSet.reference()
    start = start.apply({f"ride.{k}": 7e4 for k in start.ride.to_dict()})
    res = tune(("sas-attitude-ride",), scenario_options={"duration": 0.5}, gains=start, n_values=3, budget=60)
    # the paper's phases: the attitude loop first (ride loop off), within half the budget
    order = [c.parameter.split(".")[0] for c in res.curves]
    assert order == sorted(order, key=lambda t: t == "ride") and "ride_attitude" in order and "ride" in order
    first_ride_pass = min(c.sweep_pass for c in res.curves if c.parameter.startswith("ride."))
    stage_1 = [h["runs"] for h in res.history if h["pass"] < first_ride_pass]
    assert max(stage_1) <= 1 + (60 - 1) // 2 and res.studies[0].runs <= 60
    first = next(c for c in res.curves if c.parameter.startswith("ride."))
    # swept around REFERENCE (the centre for a gain at 0), not around the start's 7e4
    assert first.values.max() == pytest.approx(REFERENCE[first.parameter] * 30, rel=1e-3)
    assert 7e4 not in first.values
    assert res.gains.ride.to_dict()  # the loop below checks something
    for name, value in res.gains.ride.to_dict().items():
        tried = {v for c in res.curves if c.parameter == f"ride.{name}" for v in c.values}
        assert value in tried and value != 7e4


def test_tune_starts_from_the_reference_gains_and_refuses_ideal_with_inner():
    res = tune(("pid",), scenario_options={"duration": 0.5}, n_values=3, budget=10)
    ref = GainSet.reference()
    for t in GainSet.TABLES:  # the tables PID does not read: as they started
        assert t == "pid" or res.gains.table(t) == ref.table(t), t
    with pytest.raises(ValueError, match="ideal.*inner"):
        tune(("inner", "pid"), damper="ideal")


# -- the result protocol of TuneResult -------------------------------------------------------------
@pytest.fixture(scope="module")
def short_tune():
    return tune(("pid",), scenario_options={"duration": 1.0}, n_values=3, budget=10)


def test_tune_result_to_dict_is_the_tune_document(short_tune):
    import json

    res = short_tune
    doc = res.to_dict()
    assert json.loads(json.dumps(doc, allow_nan=False)) == doc
    assert list(doc) == [
        "schema",
        "railride_version",
        "versions",
        "date",
        "controllers",
        "scenario",
        "settings",
        "objective",
        "passive_rms",
        "studies",
        "history",
        "gains",
        "before_after",
        "runs",
    ]
    assert doc["schema"] == "railride.tune/3" and doc["controllers"] == ["pid"]
    [study] = doc["studies"]
    assert (study["controller"], study["budget"], study["runs"], study["passes"]) == ("pid", 10, 10, 1)
    assert doc["scenario"]["duration_s"] == 1.0
    # PID alone drives the dampers through the inner loop, which is not tuned with it: said
    note = doc["settings"].pop("inner_loop_not_tuned")
    assert note.startswith("the inner loop is not tuned: its B = 1 and G = ") and "dampers of pid" in note
    assert doc["settings"] == {
        "damper": "railway",
        "damper_scale": 1.0,
        "dt_s": 1e-4,
        "budget": 10,
        "values": 3,
        "span": 30.0,
        "tolerance": 1e-3,
        "min_span": 1.05,
        "start_gains": "railride/data/reference_gains.toml",
        "vehicle": {"name": "paper", "load": 1.0, "values": VehicleParams.preset("paper").to_dict()},
    }
    assert doc["objective"] == DEFAULT_OBJECTIVE.to_dict()
    assert doc["gains"]["pid"] == res.gains.pid.to_dict()
    assert doc["runs"] == res.n_runs == len(res.runs)
    # the before/after rows: the start gains' run and the tuned gains' run of PID
    [row] = doc["before_after"]
    assert row["suspension"] == "pid"
    rows = run_cases([Case(scenario_options=SHORT, suspension="pid")], base_gains=res.start)
    assert row["before"]["acceleration_m_s2"] == rows["acceleration_m_s2_rms"].iloc[0]
    # the tuned gains' run scores what the study reports
    assert res.objective(np.array(list(row["after"].values())), np.array(list(res.passive.values()))) == pytest.approx(
        res.history[-1]["objective"], rel=1e-12
    )


def test_tune_result_table_and_figure(short_tune):
    from matplotlib.figure import Figure

    res = short_tune
    frame = res.to_pandas()
    assert len(frame) == sum(len(c.values) for c in res.curves)
    assert list(frame.columns) == ["controller", "pass", "parameter", "value", "objective", "chosen"]
    fig = res.plot()
    assert isinstance(fig, Figure)
    mine = Figure()
    axes = mine.subplots(1, 3)
    assert res.plot(ax=axes) is mine
    with pytest.raises(ValueError, match="3 Axes"):
        res.plot(ax=axes[:2])


def test_tune_result_saves_its_folder(short_tune, tmp_path):
    import json

    res = short_tune
    paths = res.save(tmp_path / "out")
    assert [p.name for p in paths] == ["gains.toml", "sensitivity.png", "curves.csv", "tune.json"]
    assert json.loads((tmp_path / "out" / "tune.json").read_text()) == res.to_dict()
    loaded = GainSet.load(tmp_path / "out" / "gains.toml")
    assert all(loaded.table(t) == res.gains.table(t) for t in GainSet.TABLES)
    assert loaded.provenance["objective"] == res.objective.describe()
    assert loaded.provenance["scenario_record"] == res.scenario
    assert "command" not in loaded.provenance  # none given: a library call
    assert loaded.provenance["controllers"] == ["pid"] and loaded.provenance["budget"] == 10
    assert loaded.provenance["studies"]["pid"] == {
        k: v for k, v in res.studies[0].to_dict().items() if k != "controller"
    }
    text = res.gains_toml(command="railride tune --controllers pid")
    assert "# command: railride tune --controllers pid\n" in text
    assert GainSet.from_toml(text).provenance["command"] == "railride tune --controllers pid"
    extra = res.save(tmp_path / "out", extra={"command": "x"})[-1]
    assert json.loads(extra.read_text()) == {**res.to_dict(), "command": "x"}


def test_tune_without_before_after():
    res = tune(("pid",), scenario_options={"duration": 0.5}, n_values=3, budget=5, before_after=False)
    assert res.before_after == [] and res.to_dict()["before_after"] == []


def test_reference_gains_ship_with_the_package():
    from importlib import resources

    assert resources.files("railride").joinpath("data/reference_gains.toml").is_file()
    ref = GainSet.reference()
    assert ref.source == "railride/data/reference_gains.toml"
    # every tunable gain has a nonzero centre for its sweep and for the global search box
    assert all(REFERENCE[p] > 0 for ps in PARAMETERS.values() for p in ps)


def test_global_optimiser_reports_the_objective_of_the_gains_it_returns():
    res = optimise(
        ("attitude.kd_z", "attitude.kd_phi"),
        suspension="sas-attitude",
        scenario_options={"duration": 0.5},
        popsize=3,
        maxiter=2,
        seed=1,
    )
    ev = optimise.__globals__["GainEvaluator"](
        res.parameters,
        "sas-attitude",
        "paper-sine",
        {"duration": 0.5},
        None,
        None,
        "railway",
        None,
        None,
        None,
        solver=SolverSettings(dt=1e-4),
    )
    assert ev(res.log10_gains[None, :])[0] == pytest.approx(res.objective, rel=1e-12)
    assert res.gains.attitude.kd_z == pytest.approx(10 ** res.log10_gains[0])


def test_a_gain_the_controller_does_not_use_has_no_sensitivity():
    # the ride gains act only with the ride loop on: under SAS (attitude) their index is zero
    res = sensitivity(
        ("attitude.kd_z", "ride.kp_1R"), suspension="sas-attitude", scenario_options={"duration": 0.5}, n=16
    )
    assert abs(res.total[1]) < 1e-9 and abs(res.first_order[1]) < 1e-9
    assert res.total[0] > 0.1


def test_a_resumed_sweep_with_other_run_settings_runs_again(tmp_path):
    cases = [Case(scenario_options=SHORT)]
    path = tmp_path / "runs.csv"
    run_cases(cases, table=RunTable(path))
    ex = CountingExecutor()
    run_cases(cases, table=RunTable(path, resume=True), executor=ex, solver=SolverSettings(dt=5e-5))
    assert ex.cases == 1  # another dt is another run
    ex = CountingExecutor()
    run_cases(cases, table=RunTable(path, resume=True), executor=ex, solver=SolverSettings(dt=5e-5))
    assert ex.cases == 0


# -- every law alike ------------------------------------------------------------------------------
def test_every_law_gets_the_same_budget_on_its_own_gains():
    from railride.studies.tuning import TUNED_CONTROLLERS

    B = 14
    res = tune(("pid", "skyhook", "groundhook"), scenario_options={"duration": 0.5}, n_values=3, budget=B)
    frame = res.runs
    start = GainSet.reference()
    for study in res.studies:
        # the runs a study reports are the distinct runs of its law in the table, less the
        # before/after run of the tuned gains when the study did not score them
        mine = frame[frame["suspension"] == study.controller]
        assert study.runs <= B and len(mine) in (study.runs, study.runs + 1)
        assert study.stopped in ("budget", "converged")
        if study.stopped == "budget":  # the next sweep would not fit: it holds at most 4 new values
            assert study.runs > B - 4
        changed = {e for e, v in res.gains.entries().items() if v != start.value(e)}
        assert changed <= set(GainSet.tuned_entries(study.controller)) | {
            e for other in res.studies if other is not study for e in other.entries
        }
    assert [s.controller for s in res.studies] == ["pid", "skyhook", "groundhook"]
    # one gain, swept until its span is narrow: it converges within the budget or spends it
    assert res.studies[2].passes >= 2
    assert set(TUNED_CONTROLLERS) == {
        "pid",
        "sas-attitude",
        "sas-attitude-ride",
        "skyhook",
        "skyhook-on-off",
        "groundhook",
        "hybrid",
        "clipped-optimal",
    }


def test_a_law_is_tuned_on_its_own_tables_and_the_lqr_scale_is_fixed():
    assert "clipped_optimal.r" not in PARAMETERS["clipped-optimal"]  # Q and r together: one gain
    assert PARAMETERS["sas-attitude-ride"][:6] == GainSet.entry_names("ride_attitude")
    assert PARAMETERS["skyhook-on-off"] == GainSet.entry_names("skyhook_on_off")
    owned = [e for n, es in PARAMETERS.items() for e in es]
    assert len(owned) == len(set(owned))  # no gain belongs to two studies


def test_a_blend_is_swept_within_its_range():
    from railride.studies.tuning import _candidates

    values = _candidates(0.5, "hybrid.alpha", 13, 30.0, GainSet.reference())
    assert 0.0 in values and 0.5 in values and max(values) <= 1.0 and len(values) >= 6


def test_tune_refuses_what_it_cannot_tune():
    for name in ("passive", "passive-on", "lqr"):
        with pytest.raises(ValueError, match=f"controller = '{name}'.*allowed inner, pid"):
            tune((name,))
    with pytest.raises(ValueError, match="min_span = 1: must be a finite number > 1"):
        tune(("pid",), min_span=1)


# -- the shipped gains ---------------------------------------------------------------------------
@pytest.fixture(scope="module")
def shipped_ratios():
    """RMS ratios to passive of every law with the shipped gains on paper-sine."""
    from railride.studies.comparison import compare
    from railride.studies.tuning import TUNED_CONTROLLERS

    cmp = compare("paper-sine", controllers=TUNED_CONTROLLERS)
    rms = cmp.metrics.sel(statistic="rms")
    return {n: rms.sel(controller=n).values / rms.sel(controller="passive").values for n in TUNED_CONTROLLERS}


def test_shipped_gains_record_how_each_law_was_tuned(shipped_ratios):
    from railride.studies.tuning import DEFAULT_BUDGET, TUNED_CONTROLLERS

    shipped = GainSet.default()
    p = shipped.provenance
    assert p["controllers"] == list(TUNED_CONTROLLERS) and p["budget"] == DEFAULT_BUDGET
    assert shipped.untuned(TUNED_CONTROLLERS) == []
    for name in TUNED_CONTROLLERS:
        study = p["studies"][name]
        assert study["runs"] <= DEFAULT_BUDGET and study["entries"] == list(PARAMETERS[name])
        # the objective the file records is the one a fresh run of the shipped gains scores
        assert DEFAULT_OBJECTIVE(shipped_ratios[name][None, :], np.ones(4))[0] == pytest.approx(
            study["objective"], rel=1e-9
        ), name
        assert study["objective"] <= study["objective_start"]


def test_the_paper_laws_shipped_make_no_response_worse_than_passive(shipped_ratios):
    for name in ("pid", "sas-attitude", "sas-attitude-ride"):
        assert np.all(shipped_ratios[name] < 1.0), (name, shipped_ratios[name])


@pytest.mark.slow  # the whole default study: about 65 s on a 2-core machine
def test_tune_defaults_reproduce_the_shipped_gains():
    # `railride tune` with no option, from an installed package: the reference start is packaged
    shipped = GainSet.default()
    assert shipped.provenance["command"] == "railride tune"
    tuned = tune(before_after=False).gains
    for table in GainSet.TABLES:
        assert tuned.table(table) == shipped.table(table), table


def test_tune_with_a_scaled_damper_tunes_the_inner_loop_for_it():
    # a damper k times larger, tracking demands k times larger, wants G / k: the tracking error
    # is the same function of G k (the force, and so the error, scales with k)
    G = 2e-3
    assert tracking_objective(1.0, G / 4, damper_scale=4.0) == pytest.approx(tracking_objective(1.0, G), rel=1e-9)
    with pytest.raises(ValueError, match="damper_scale = -1"):
        tune(("pid",), damper_scale=-1, scenario_options=SHORT)


def test_run_keys_change_with_the_model_revision(monkeypatch):
    # a run table from an earlier model must not resume into this one
    import railride.studies.case as case_module

    c = Case(suspension="pid", gains={"pid.kd": 1e5})
    before = c.key
    monkeypatch.setattr(case_module, "MODEL_REVISION", case_module.MODEL_REVISION + 1)
    assert c.key != before


# -- robust tuning: a set of tracks and payloads -----------------------------------------------------
def test_robust_tuning_scores_the_mean_or_the_worst_of_its_cases():
    from railride.studies.tuning import tuning_set

    cases = tuning_set("fra4", track_seeds=[0, 1], loads=[1.0, 1.3], duration=0.5)
    assert len(cases) == 4 and {c.load for c in cases} == {1.0, 1.3}
    for aggregate, reduce in (("mean", np.mean), ("worst", np.max)):
        res = tune(("pid",), over=cases, aggregate=aggregate, budget=12, n_values=3)
        assert res.before_after == [] and res.settings["aggregate"] == aggregate
        assert len(res.settings["tuning_set"]) == 4
        # the tuned gains' objective, recomputed case by case from direct runs of the sweep engine
        params = VehicleParams.preset("paper")
        per_case = []
        for c in cases:
            vehicle = params.load_changes(c.load)
            passive = run_cases([Case(c.scenario, c.options, vehicle=vehicle)])
            tuned = run_cases(
                [
                    Case(
                        c.scenario,
                        c.options,
                        vehicle=vehicle,
                        suspension="pid",
                        gains=tuple((f"pid.{k}", v) for k, v in res.gains.pid.to_dict().items()),
                    )
                ],
                base_gains=GainSet.reference(),
            )
            cols = [f"{r}_rms" for r in ("acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg")]
            per_case.append(DEFAULT_OBJECTIVE(tuned[cols].to_numpy(), passive[cols].to_numpy()[0])[0])
        assert res.studies[0].objective == pytest.approx(reduce(per_case), rel=1e-9), aggregate
    loaded = GainSet.from_toml(res.gains_toml())
    assert loaded.provenance["aggregate"] == "worst" and len(loaded.provenance["tuning_set"]) == 4
    record = scenario("fra4", seed=1, duration=0.5).describe()
    assert loaded.tuned_on(record) and not loaded.tuned_on(scenario("fra4", seed=2, duration=0.5).describe())


def test_robust_tuning_refuses_what_it_cannot_use():
    from railride.studies.tuning import tuning_set

    with pytest.raises(ValueError, match="aggregate = 'median'"):
        tune(("pid",), over=tuning_set("fra4", track_seeds=[0]), aggregate="median")
    with pytest.raises(ValueError, match="over: give a non-empty sequence"):
        tune(("pid",), over=[])
    with pytest.raises(ValueError, match="scenario_options with over"):
        tune(("pid",), over=tuning_set("fra4", track_seeds=[0]), scenario_options={"speed": 30.0})
    with pytest.raises(ValueError, match="loads = 0"):
        tuning_set("fra4", loads=[0])


def test_a_study_whose_every_candidate_scores_inf_ends():
    # inf - inf is NaN, which no "improved by less than tol" test took for no improvement: the
    # span never shrank and the study swept the same (already scored) values for ever
    from railride.studies.tuning import _study

    study = _study("pid", GainSet.default(), 1000, 3, 30.0, 1e-3, 1.05, None)
    sets, sweeps = next(study), 0
    with pytest.raises(StopIteration) as end:
        while sweeps < 1000:
            sets, sweeps = study.send([np.inf] * len(sets)), sweeps + 1
    assert end.value.value[0].stopped == "converged" and sweeps < 1000
