"""The comfort objectives and the peak and travel bounds of `Objective`: J worked by hand from
ratios, and a tuning with a travel bound whose tuned gains keep it on the training runs."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import railride as rr
from railride.errors import InputError
from railride.studies.objectives import FLOOR_POINTS, INFEASIBLE_OFFSET, INFEASIBLE_SCALE, RMS_COLUMNS, Objective


def _ratios(rms=(0.8, 0.9, 1.1, 0.7), comfort=None, peak=None):
    out = {c: np.array([x]) for c, x in zip(RMS_COLUMNS, rms)}
    for index, values in (comfort or {}).items():
        out.update({f"{p}_{index}": np.array([x]) for p, x in zip(FLOOR_POINTS, values)})
    if peak is not None:
        out["acceleration_m_s2_ptp"] = np.array([peak])
    return out


def test_a_comfort_objective_is_the_worst_floor_point_ratio():
    ratios = _ratios(comfort={"N_MV_z": (0.7, 0.95, 0.8), "Wz": (0.9, 0.85, 0.97)})
    assert Objective("n_mv").of_ratios(ratios)[0] == pytest.approx(0.95)
    assert Objective("sperling").of_ratios(ratios)[0] == pytest.approx(0.97)
    # the penalty still reads the RMS ratios: pitch is 0.1 above passive
    assert Objective("n_mv", penalty=2.0).of_ratios(ratios)[0] == pytest.approx(0.95 + 2.0 * 0.1)
    assert "N_MV_z(p) / N_MV_z(p, passive)" in Objective("n_mv").describe()
    with pytest.raises(InputError, match="use of_runs"):
        Objective("n_mv").score(np.ones(4))


def test_the_bounds_rank_every_run_that_breaks_them_after_every_run_that_keeps_them():
    obj = Objective("minimax", peak_bound=1.0, travel_bound=0.05)
    keeps = obj.of_ratios(_ratios(peak=0.9), travel=np.array([0.04]))[0]
    assert keeps == pytest.approx(1.1)  # the worst RMS ratio
    peak = obj.of_ratios(_ratios(peak=1.2), travel=np.array([0.04]))[0]
    assert peak == pytest.approx(INFEASIBLE_OFFSET + INFEASIBLE_SCALE * 0.2)
    both = obj.of_ratios(_ratios(peak=1.2), travel=np.array([0.06]))[0]
    assert both == pytest.approx(INFEASIBLE_OFFSET + INFEASIBLE_SCALE * (0.2 + 0.2))
    assert keeps < peak < both
    text = obj.describe()
    assert "peak-to-peak carbody acceleration <= 1 x passive's" in text and "secondary travel <= 0.05 m" in text
    assert obj.to_dict()["peak_bound"] == 1.0 and obj.to_dict()["travel_bound_m"] == 0.05


def test_of_runs_takes_the_ratios_to_passive_on_the_same_track():
    cols = [*RMS_COLUMNS, "acceleration_m_s2_ptp", "travel_max_m"]
    passive = pd.Series([1.0, 2.0, 3.0, 4.0, 10.0, 0.03], index=cols)
    runs = pd.DataFrame([[0.5, 1.0, 1.5, 3.0, 9.0, 0.02], [0.5, 1.0, 1.5, 3.0, 12.0, 0.02]], columns=cols)
    j = Objective("minimax", peak_bound=1.1).of_runs(runs, passive)
    assert j[0] == pytest.approx(0.75)  # roll 3 / 4
    assert j[1] == pytest.approx(INFEASIBLE_OFFSET + INFEASIBLE_SCALE * 0.1)


@pytest.mark.parametrize(
    "settings, fragment",
    [
        ({"peak_bound": 0.0}, "peak_bound = 0.0"),
        ({"travel_bound": -1}, "travel_bound = -1"),
        ({"peak_bound": float("nan")}, "peak_bound = nan"),
    ],
)
def test_a_bound_must_be_a_positive_number(settings, fragment):
    with pytest.raises(InputError, match=fragment):
        Objective("sum", **settings)


def test_a_tuning_with_a_travel_bound_keeps_it_on_its_runs():
    """Skyhook on a short random track, tuned with and without a travel bound a little below the
    travel the unbounded tuning reaches: the bounded tuning's gains keep the bound."""
    track = {"speed": 50.0, "duration": 2.0}
    common = dict(scenario="fra4", scenario_options=track, budget=16, n_values=3, before_after=False)
    free = rr.tune(["skyhook"], **common, objective=Objective("minimax"))
    assert "travel_max_m" not in free.runs  # a plain objective asks for no damper columns: its keys stay
    sc = rr.scenario("fra4", **track)
    reached = rr.compare(sc, controllers=["passive", "skyhook"], gains=free.gains).demands()["skyhook"]["travel_max_m"]
    bound = 0.97 * reached
    bounded = rr.tune(["skyhook"], **common, objective=Objective("minimax", travel_bound=bound))
    assert "travel_max_m" in bounded.runs
    kept = rr.compare(sc, controllers=["passive", "skyhook"], gains=bounded.gains).demands()["skyhook"]["travel_max_m"]
    assert kept <= bound < reached


@pytest.mark.parametrize(
    "objective",
    [
        Objective("minimax"),
        Objective("sum", penalty=1.5),
        Objective("weighted", weights=(0.4, 0.3, 0.2, 0.1)),
        Objective("constrained", bound=1.0, penalty=2.0),
        Objective("n_mv"),
    ],
    ids=lambda o: o.kind,
)
def test_a_runs_score_does_not_depend_on_the_runs_scored_beside_it(objective):
    # tuning scores a round's runs in one call: each run's J must be what it is alone, to the
    # bit (a matrix product's BLAS summed a row in another order for another number of rows)
    rng = np.random.default_rng(4)
    n = 257
    cols = list(objective.columns)
    runs = pd.DataFrame(rng.uniform(0.2, 2.0, (n, len(cols))), columns=cols)
    passive = pd.DataFrame(rng.uniform(0.5, 1.5, (n, len(cols))), columns=cols)
    together = objective.of_runs(runs, passive)
    alone = np.array([objective.of_runs(runs.iloc[[i]], passive.iloc[i])[0] for i in range(n)])
    assert together.shape == (n,) and np.unique(together).size > 100
    assert np.array_equal(together, alone)
