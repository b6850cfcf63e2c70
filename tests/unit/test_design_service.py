"""A design weighted by time in service (``speed_shares``, ``load_shares``): the shares of each
speed and load, the tuning's weighted mean, and a ranking by the weighted mean of a law's scores
instead of its worst, a constraint still holding at every point."""

from __future__ import annotations

import numpy as np
import pytest

import railride as rr
from railride.errors import InputError, TuningWarning
from railride.studies.design import service_shares
from railride.studies.design_result import law_score, over_points, passive_wins
from railride.studies.tuning import TuningCase, tune


def test_the_shares_are_the_product_of_speed_and_load_normalised():
    got = service_shares((30.0, 50.0), (1.0, 1.3), [3, 1], [1, 1])
    assert got == pytest.approx({(30.0, 1.0): 0.375, (30.0, 1.3): 0.375, (50.0, 1.0): 0.125, (50.0, 1.3): 0.125})
    assert sum(got.values()) == pytest.approx(1.0)
    # one given: the other alike; none given: no weights at all
    assert service_shares((30.0,), (1.0, 1.3), None, [1, 3]) == pytest.approx({(30.0, 1.0): 0.25, (30.0, 1.3): 0.75})
    assert service_shares((30.0,), (1.0,)) is None
    # shares near the largest float still sum without overflow
    assert service_shares((30.0, 50.0), (1.0,), [1e308, 1e308]) == {(30.0, 1.0): 0.5, (50.0, 1.0): 0.5}


@pytest.mark.parametrize(
    "shares, fragments",
    [
        ([1, 2, 3], ("speed_shares = 1,2,3: 3 shares for 2 speeds (30, 50)", "one per speed")),
        ([1, 0], ("speed_shares = 0", "a finite number > 0")),
        ([1, float("nan")], ("speed_shares = nan",)),
        ("fast", ("speed_shares = 'fast'", "give a list of numbers, one per speed")),
    ],
)
def test_bad_shares_are_refused_naming_the_option(shares, fragments):
    with pytest.raises(InputError) as err:
        service_shares((30.0, 50.0), (1.0,), shares, None)
    for fragment in fragments:
        assert fragment in str(err.value), str(err.value)


def test_a_score_over_the_points_is_the_worst_or_the_weighted_mean():
    assert over_points([1.0, 0.5]) == 1.0
    assert over_points([1.0, 0.5], [0.25, 0.75]) == pytest.approx(0.625)
    assert over_points([1.0, np.inf], [0.5, 0.5]) == np.inf  # a run diverged
    # a point that breaks a constraint (at or above the infeasible offset) is not averaged away
    assert over_points([0.8, 1500.0], [0.99, 0.01], offset=1000.0) == 1500.0
    assert over_points([0.8, 0.9], [0.5, 0.5], offset=1000.0) == pytest.approx(0.85)
    points = [{"scores": {"pid": 0.8}, "passive_score": 1.0, "share": 0.9}, {"scores": {"pid": 1.4}, "share": 0.1,
              "passive_score": 1.0}]  # fmt: skip
    assert law_score(points, "pid") == pytest.approx(0.86)
    assert law_score(points, "passive") == pytest.approx(1.0)
    # worst 1.4 is worse than passive's 1, but in service 0.86 is better: the law is recommended
    assert passive_wins({"score": 0.86}, points) is None


def test_a_case_that_weighs_next_to_nothing_leaves_the_tuning_of_the_other():
    """Two speeds, the second weighted 1e-12: the weighted mean is the first case's objective to
    1e-12, so the sensitivity study takes the same steps as on the first case alone."""
    first = TuningCase("paper-sine", (("duration", 0.3), ("speed", 55.56)), 1.0)
    second = TuningCase("paper-sine", (("duration", 0.3), ("speed", 30.0)), 1.0, 1e-12)
    kw = dict(budget=15, n_values=3, before_after=False, progress=False)
    with pytest.warns(TuningWarning):
        alone = tune(["pid"], over=[first], **kw)
    with pytest.warns(TuningWarning):
        weighted = tune(["pid"], over=[first, second], **kw)
    assert weighted.gains.pid == alone.gains.pid
    # and the weights are kept with the tuning set (only where they differ from 1)
    assert [r.get("weight") for r in weighted.settings["tuning_set"]] == [1.0, 1e-12]
    assert "weight" not in alone.settings["tuning_set"][0]
    with pytest.raises(InputError, match="weight = -1"):
        TuningCase("paper-sine", (), 1.0, -1.0)


@pytest.fixture(scope="module")
def weighted():
    return rr.design(
        ["skyhook"],
        tracks=["fra4"],
        speeds=[50.0, 30.0],
        speed_shares=[1, 3],
        loads=[1.0],
        train_seeds=[0],
        test_seeds=[1, 2],
        duration=2.0,
        budget=25,
        values=3,
        progress=False,
    )


def test_a_weighted_design_ranks_by_the_mean_in_service_and_says_so(weighted):
    # the shares follow the speeds as given (50 then 30), not their sorted order
    assert weighted.settings["service"] == [
        {"speed_m_s": 50.0, "load": 1.0, "share": 0.25},
        {"speed_m_s": 30.0, "load": 1.0, "share": 0.75},
    ]
    by_speed = {p["speed_m_s"]: p for p in weighted.points}
    sky = next(r for r in weighted.ranking if r["controller"] == "skyhook")
    at = {v: by_speed[v]["scores"]["skyhook"] for v in (30.0, 50.0)}
    assert sky["score"] == pytest.approx(0.75 * at[30.0] + 0.25 * at[50.0], rel=1e-12)
    assert sky["worst_score"] == max(at.values())
    text = weighted.recommendation
    if "keep passive" in text:
        assert f"scores {sky['score']:.3f} in service (worst {sky['worst_score']:.3f} at" in text, text
    else:
        assert "time in service (50 m/s, load 1: 25 %; 30 m/s, load 1: 75 %)" in text, text
    assert "at worst" not in text
    _check_schema(weighted.to_dict())


def _check_schema(doc: dict) -> None:
    import json
    from pathlib import Path

    jsonschema = pytest.importorskip("jsonschema")
    path = Path(__file__).parents[2] / "docs" / "schemas" / "railride.design-1.json"
    jsonschema.validate(json.loads(json.dumps(doc, default=str)), json.loads(path.read_text()))


def test_the_command_line_takes_the_shares_and_checks_them():
    from clihelp import assert_input_error, run

    result = run("design", "--speed", "30,50", "--speed-share", "1,2,3", "--controllers", "skyhook")
    assert_input_error(result, "--speed-share = 1,2,3: 3 shares for 2 speeds", "one per speed")
    # equal shares are shares, not a value listed twice
    result = run("design", "--speed", "30,50,70", "--speed-share", "1,1,2", "--load", "1", "--budget", 2)
    assert_input_error(result, "--budget = 2")
    result = run("design", "--load", "1,1.3", "--load-share", "1,-1", "--controllers", "skyhook")
    assert_input_error(result, "--load-share = -1", "a finite number > 0")


def test_the_fault_sentence_speaks_of_the_mean_in_service_not_everywhere():
    """With time in service a law's score is a mean: beating passive there is not beating it at
    every speed, and the fault sentence says "in service"."""
    from types import SimpleNamespace

    from railride.studies.design_probes import fault_check
    from railride.studies.objectives import Objective

    service = {(30.0, 1.0): 0.75, (50.0, 1.0): 0.25}
    plan = SimpleNamespace(damper="railway", laws=["pid"], objective=Objective("minimax"), service=service)
    healthy = [
        {"speed_m_s": 30.0, "load": 1.0, "scores": {"pid": 0.8}, "share": 0.75},
        {"speed_m_s": 50.0, "load": 1.0, "scores": {"pid": 1.1}, "share": 0.25},
    ]
    faulted = [dict(p, scores={"pid": 1.2}) for p in healthy]
    text = fault_check(plan, ["pid"], healthy, lambda **kw: faulted)["text"]
    assert "PID scores 1.200 in service (healthy 0.875)" in text, text
    assert "PID then no longer beats passive in service" in text and "everywhere" not in text


def test_a_broken_constraint_is_not_averaged_away_in_service():
    """With a travel bound no run can keep (1 micrometre), every point is infeasible: the score
    in service is the worst, said as infeasible, not a weighted mean of offsets."""
    from railride.studies.design_result import score_text
    from railride.studies.objectives import Objective

    bound = Objective("minimax", travel_bound=1e-6)
    assert bound.constraint_offset == bound.to_dict()["infeasible"]["offset"]
    assert Objective("minimax").constraint_offset is None
    result = rr.design(
        ["skyhook"],
        tracks=["fra4"],
        speeds=[30.0, 50.0],
        speed_shares=[9, 1],
        loads=[1.0],
        train_seeds=[0],
        test_seeds=[1],
        duration=1.0,
        budget=25,
        values=3,
        objective=bound,
        progress=False,
    )
    sky = result.ranking[0]
    at = [p["scores"]["skyhook"] for p in result.points]
    assert min(at) >= bound.constraint_offset
    assert sky["score"] == sky["worst_score"] == max(at)
    assert score_text(sky["score"], bound).startswith("infeasible")


def test_the_travel_sentence_names_the_speed_where_the_travel_grows_most(weighted):
    """Rattle space is a worst case: beside its average, the recommendation names the speed and
    load where the winner's largest travel is the most above passive's (from the runs)."""
    runs = weighted.runs
    key = ["track", "track_seed", "speed_m_s", "load"]
    base = runs[runs["controller"] == "passive"].set_index(key)["travel_max_m"]
    own = runs[runs["controller"] == "skyhook"].set_index(key)["travel_max_m"]
    by_speed = (own / base).groupby(level="speed_m_s").mean()
    assert by_speed.max() > 1.01  # skyhook moves the secondary more than passive here: the sentence is said
    most = by_speed.idxmax()
    assert f"x{by_speed.max():.2f} at {most:g} m/s, load 1, the most." in weighted.recommendation


def test_the_ride_in_service_is_the_rms_of_the_runs_strung_together_by_their_shares(weighted):
    """The service RMS (each law's RMS over the time in service) against a second path: the
    held-out runs simulated one at a time (`simulate`, not the design's batches), their
    acceleration histories strung together, each as many times as its point's share asks (the
    shares 1:3 at 50 and 30 m/s, two seeds each), and the RMS of that one signal."""
    from railride.secondary.suspension import Suspension

    sky = next(r for r in weighted.ranking if r["controller"] == "skyhook")
    suspensions = {"skyhook": Suspension.named("skyhook", gains=weighted.gains), "passive": None}
    for law, suspension in suspensions.items():
        pieces = []
        for speed, times in ((50.0, 1), (30.0, 3)):
            for seed in weighted.settings["test_seeds"]:
                sc = rr.scenario("fra4", seed=seed, speed=speed, duration=weighted.settings["duration_s"])
                a = rr.simulate(sc, suspension=suspension).dataset["carbody_acceleration"].to_numpy()
                pieces += [a] * times
        rms = float(np.sqrt(np.mean(np.concatenate(pieces) ** 2)))
        recorded = sky["service_rms"]["acceleration_m_s2_rms"]["value" if law == "skyhook" else "passive"]
        assert recorded == pytest.approx(rms, rel=1e-6), law
    entry = sky["service_rms"]["acceleration_m_s2_rms"]
    assert entry["ratio"] == pytest.approx(entry["value"] / entry["passive"], rel=1e-12)
    # said in the recommendation, and absent where no time in service is given
    shown = f"acceleration {entry['value']:.3g} against passive's {entry['passive']:.3g} m/s2 (x{entry['ratio']:.3f})"
    assert shown in weighted.recommendation
    assert "Over the time in service" in weighted.recommendation


def test_the_service_sentence_weighs_a_kept_passive_against_a_better_ride_in_service():
    from railride.studies.design_service import service_sentence

    def entry(ratio):
        row = {"value": ratio * 0.5, "passive": 0.5, "ratio": ratio}
        return {
            "service_rms": dict.fromkeys(
                ("acceleration_m_s2_rms", "displacement_m_rms", "pitch_deg_rms", "roll_deg_rms"), row
            )
        }

    better = service_sentence(entry(0.9), "Skyhook", kept_passive=True)
    assert "acceleration 0.45 against passive's 0.5 m/s2 (x0.900); displacement 450 against passive's 500 mm" in better
    assert "better than passive in every response, while the score keeps passive" in better
    assert "while the score keeps passive" not in service_sentence(entry(0.9), "Skyhook", kept_passive=False)
    assert "while the score keeps passive" not in service_sentence(entry(1.1), "Skyhook", kept_passive=True)
    assert service_sentence({}, "Skyhook") == ""


def test_a_law_with_a_point_where_every_run_diverged_has_no_ride_in_service():
    import pandas as pd

    from railride.studies.design_service import ranking_entries, service_rms

    rows = []
    for law in ("passive", "pid"):
        for speed in (30.0, 50.0):
            diverged = 0.4 if (law, speed) == ("pid", 50.0) else np.inf
            rms = {"acceleration_m_s2_rms": 0.3, "displacement_m_rms": 0.01, "pitch_deg_rms": 0.1, "roll_deg_rms": 0.2}
            rows.append({"controller": law, "speed_m_s": speed, "load": 1.0, "diverged_at_s": diverged, **rms})
    rms = service_rms(pd.DataFrame(rows), {(30.0, 1.0): 0.5, (50.0, 1.0): 0.5}, ["pid"])
    assert rms["pid"] is None and ranking_entries(rms, "pid") == {}
    assert rms["passive"]["acceleration_m_s2_rms"] == pytest.approx(0.3, rel=1e-15)  # the same RMS everywhere


def test_the_fault_sentence_says_infeasible_as_the_ranking_does_not_the_offset():
    from types import SimpleNamespace

    from railride.studies.design_probes import fault_check
    from railride.studies.objectives import Objective

    bound = Objective("minimax", travel_bound=0.05)
    offset = bound.constraint_offset
    scale = bound.to_dict()["infeasible"]["scale"]
    plan = SimpleNamespace(damper="railway", laws=["pid"], objective=bound, service=None)
    healthy = [{"speed_m_s": 30.0, "load": 1.0, "scores": {"pid": 0.9}}]
    faulted = [{"speed_m_s": 30.0, "load": 1.0, "scores": {"pid": offset + 0.25 * scale}}]
    text = fault_check(plan, ["pid"], healthy, lambda **kw: faulted)["text"]
    assert "PID scores infeasible (+0.25) at worst (healthy 0.900)" in text, text
    assert f"{offset:.3f}" not in text and "1000" not in text
