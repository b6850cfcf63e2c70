"""Sweeps, the sensitivity study and the global methods, at the library level."""

import numpy as np
import pytest

from railride.control import GainSet
from railride.optimise import optimise, sensitivity
from railride.simulation import simulate
from railride.sweep import Case, RunTable, apply_gains, run_cases
from railride.track import scenario
from railride.tuning import Objective, tracking_objective, tune

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
    direct = simulate(scenario("paper-sine", speed=40.0, **SHORT),
                      controller=apply_gains(g, (("pid.kd", 2e5),)).controller("pid"),
                      inner=g.inner).metrics()
    assert row["acceleration_m_s2_rms"] == pytest.approx(float(direct.sel(response="acceleration_m_s2", statistic="rms")), rel=1e-12)
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


def test_sensitivity_study_never_worsens_the_objective_and_records_curves():
    start = GainSet.default()
    res = tune(("pid",), scenario_options=SHORT, gains=start, n_values=4, max_passes=2)
    history = [h["objective"] for h in res.history]
    assert all(b <= a + 1e-12 for a, b in zip(history, history[1:]))
    assert {c.parameter for c in res.curves} == {"pid.kp", "pid.ki", "pid.kd"}
    for c in res.curves:  # the chosen value is the best of its curve, or the previous value
        assert c.objective.min() >= min(history) - 1e-12
    # re-evaluating the tuned gains gives the objective the study reports
    rows = run_cases([Case(scenario_options=tuple(sorted(SHORT.items())), suspension="pid",
                           gains=tuple((f"pid.{k}", v) for k, v in res.gains.pid.to_dict().items()))],
                     base_gains=start)
    rms = rows[[f"{r}_rms" for r in ("acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg")]].to_numpy()
    passive = np.array(list(res.passive.values()))
    assert Objective()(rms, passive)[0] == pytest.approx(history[-1], rel=1e-12)


def test_inner_loop_objective_prefers_feedback():
    # with no gain the damper stays at v_min and tracks nothing but its residual force
    assert tracking_objective(1.0, 1.15e-3) < tracking_objective(1.0, 1e-9)


def test_objective_weights_and_penalty():
    passive = np.array([1.0, 1.0, 1.0, 1.0])
    rms = np.array([[0.5, 0.5, 1.5, 1.0]])
    assert Objective()(rms, passive)[0] == pytest.approx(3.5)
    assert Objective(weights=(1, 0, 0, 0))(rms, passive)[0] == pytest.approx(0.5)
    assert Objective(penalty=10.0)(rms, passive)[0] == pytest.approx(3.5 + 5.0)
    with pytest.raises(ValueError, match="weights"):
        Objective(weights=(1, 2))


def test_global_optimiser_reports_the_objective_of_the_gains_it_returns():
    res = optimise(("attitude.kd_z", "attitude.kd_phi"), suspension="sas-attitude",
                   scenario_options={"duration": 0.5}, popsize=3, maxiter=2, seed=1)
    ev = optimise.__globals__["_Evaluator"](res.parameters, "sas-attitude", "paper-sine",
                                            {"duration": 0.5}, None, None, "railway", None, None, 1e-4, None)
    assert ev(res.log10_gains[None, :])[0] == pytest.approx(res.objective, rel=1e-12)
    assert res.gains.attitude.kd_z == pytest.approx(10 ** res.log10_gains[0])


def test_a_gain_the_controller_does_not_use_has_no_sensitivity():
    # the ride gains act only with the ride loop on: under SAS (attitude) their index is zero
    res = sensitivity(("attitude.kd_z", "ride.kp_1R"), suspension="sas-attitude",
                      scenario_options={"duration": 0.5}, n=16)
    assert abs(res.total[1]) < 1e-9 and abs(res.first_order[1]) < 1e-9
    assert res.total[0] > 0.1


def test_a_resumed_sweep_with_other_run_settings_runs_again(tmp_path):
    cases = [Case(scenario_options=SHORT)]
    path = tmp_path / "runs.csv"
    run_cases(cases, table=RunTable(path))
    ex = CountingExecutor()
    run_cases(cases, table=RunTable(path, resume=True), executor=ex, dt=5e-5)
    assert ex.cases == 1  # another dt is another run
    ex = CountingExecutor()
    run_cases(cases, table=RunTable(path, resume=True), executor=ex, dt=5e-5)
    assert ex.cases == 0
