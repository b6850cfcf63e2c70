"""The population optimiser beside the sensitivity study (railride.studies.evolution): SciPy's
differential evolution over all of a law's gains at once, within the law's budget of gain sets,
repeatable for a seed, recorded in the result; bad settings refused before any run."""

from __future__ import annotations

import pytest

import railride as rr
from railride.errors import InputError
from railride.secondary.control import GainSet
from railride.studies.evolution import MIN_BUDGET, log_gain_bounds, sizes
from railride.studies.sweep import RunTable
from railride.studies.tuning import tune, tuning_set

SET = tuning_set("fra4", track_seeds=[0, 2], speeds=[40.0], duration=1.0)
EVOLVE = dict(over=SET, budget=16, before_after=False, optimiser="evolution")


@pytest.fixture(scope="module")
def evolved():
    table = RunTable()
    return tune(["pid", "skyhook"], table=table, **EVOLVE), table


def test_the_population_and_generations_follow_from_the_budget():
    assert sizes(14, 130) == (12, 10)  # 5 a gain capped at (130 - 1) / 10: 1 + 120 gain sets
    assert sizes(1, 130) == (5, 25)  # SciPy's least, 25 generations
    assert sizes(3, 16) == (5, 3)
    for d in (1, 3, 6, 14):
        for budget in (MIN_BUDGET, 30, 130, 400):
            population, generations = sizes(d, budget)
            assert population >= 5 and generations >= 2 and 1 + population * generations <= budget


def test_the_box_is_the_global_methods_and_a_blend_stops_at_1():
    (low, high), (blend_low, blend_high) = log_gain_bounds(["pid.kp", "hybrid.alpha"])
    ref = GainSet.reference().entries()
    assert 10**low == pytest.approx(ref["pid.kp"] / 1e3) and 10**high == pytest.approx(ref["pid.kp"] * 1e2)
    assert 10**blend_low == pytest.approx(ref["hybrid.alpha"] / 1e3) and 10**blend_high == pytest.approx(1.0)


def test_each_law_spends_at_most_its_budget_counted_in_the_run_table(evolved):
    result, table = evolved
    rows = table.frame
    for law in ("pid", "skyhook"):
        study = next(s for s in result.studies if s.controller == law)
        population, generations = sizes(len(study.entries), 16)
        assert study.optimiser == "evolution" and study.population == population == 5
        assert study.passes == generations == 3 and study.stopped == "budget"
        # each gain set runs once per case of the set: the distinct gain sets are the study's runs
        n_rows = int((rows["suspension"] == law).sum())
        assert n_rows == study.runs * len(SET) and study.runs <= 1 + population * generations <= 16
        assert [c[0] for c in study.convergence] == sorted(c[0] for c in study.convergence)
        assert study.objective <= study.objective_start  # the start is one of the gain sets scored


def test_the_same_seed_gives_the_same_gains_another_seed_other_ones(evolved):
    result, _ = evolved
    again = tune(["pid"], **EVOLVE)
    assert {p: again.gains.value(p) for p in ("pid.kp", "pid.ki", "pid.kd")} == {
        p: result.gains.value(p) for p in ("pid.kp", "pid.ki", "pid.kd")
    }
    other = tune(["pid"], optimiser_seed=1, **{k: v for k, v in EVOLVE.items()})
    assert other.gains.value("pid.kp") != result.gains.value("pid.kp")


def test_the_result_records_the_optimiser(evolved):
    result, _ = evolved
    o = result.settings["optimiser"]
    assert o["name"] == "evolution" and o["seed"] == 0 and o["tol"] == 0.0
    doc = result.to_dict()
    pid = next(s for s in doc["studies"] if s["controller"] == "pid")
    assert pid["optimiser"] == "evolution" and pid["population"] == 5 and len(pid["convergence"]) == 3
    text = result.gains_toml()
    assert "differential evolution" in text and 'optimiser = {name = "evolution"' in text
    back = GainSet.from_toml(text, source="evolved.toml")
    assert back.provenance["studies"]["pid"]["optimiser"] == "evolution"
    assert back.value("pid.kp") == result.gains.value("pid.kp")


@pytest.mark.parametrize(
    "change, fragments",
    [
        ({"optimiser": "cma"}, ["optimiser = 'cma'", "sensitivity, evolution"]),
        ({"optimiser": "evolution", "budget": MIN_BUDGET - 1}, ["budget = 10", "evolution"]),
        ({"optimiser_seed": -1}, ["optimiser_seed = -1"]),
    ],
)
def test_bad_settings_are_refused_before_any_run(change, fragments):
    table = RunTable()
    with pytest.raises(InputError) as err:
        tune(["pid"], **{**EVOLVE, "table": table, **change})
    assert all(f in str(err.value) for f in fragments), str(err.value)
    assert len(table.frame) == 0
    design = dict(tracks=["fra4"], speeds=[40.0], loads=[1.0], train_seeds=[0], test_seeds=[1], duration=1.0)
    with pytest.raises(InputError) as err:
        rr.design(["pid"], **{**design, "budget": 13, "values": 3, **change}, table=table)
    assert all(f in str(err.value) for f in fragments), str(err.value)
    assert len(table.frame) == 0


def test_a_design_by_evolution_says_so():
    result = rr.design(
        ["pid"],
        tracks=["fra4"],
        speeds=[40.0],
        loads=[1.0],
        train_seeds=[0],
        test_seeds=[1],
        duration=1.0,
        budget=13,
        values=3,
        optimiser="evolution",
        optimiser_seed=3,
    )
    assert result.settings["optimiser"]["name"] == "evolution" and result.settings["optimiser"]["seed"] == 3
    assert result.to_dict()["tuning"]["studies"][-1]["optimiser"] == "evolution"
    assert 'optimiser = "differential evolution' in result.gains_toml()
