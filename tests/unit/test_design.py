"""railride.design: a law tuned on training seeds and judged on held-out seeds, the result, its
ranking and recommendation, and the checks of its inputs (before any run)."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

import railride as rr
from railride.errors import InputError
from railride.output.files import DESIGN_FILES
from railride.studies.design import min_budget
from railride.studies.design_result import METRICS, RMS_COLUMNS, rank, recommend
from railride.studies.objectives import Objective
from railride.studies.sweep import RunTable

#: a design of two laws that takes a few seconds: one track, speed, load, training and held-out seed
TINY = dict(
    tracks=["fra4"],
    speeds=[40.0],
    loads=[1.0],
    train_seeds=[0],
    test_seeds=[1],
    duration=2.0,
    budget=13,
    values=3,
)


@pytest.fixture(scope="module")
def tiny():
    return rr.design(["pid", "skyhook"], **TINY)


def test_the_result_holds_every_law_and_passive_per_speed_and_load(tiny):
    assert isinstance(tiny, rr.DesignResult) and isinstance(tiny, rr.Result)
    summary = tiny.to_pandas()
    assert list(dict.fromkeys(summary["controller"])) == ["passive", "pid", "skyhook"]
    assert set(summary["metric"]) == {*METRICS, "score"}
    assert (summary["n"] == 1).all()
    # one held-out run per law: track fra4, seed 1, 40 m/s, load 1
    assert len(tiny.runs) == 3 and set(tiny.runs["track_seed"]) == {1}
    passive = summary[summary["controller"] == "passive"].set_index("metric")
    assert passive.loc["acceleration_m_s2_rms", "ratio_mean"] == 1.0
    assert passive.loc["acceleration_m_s2_rms", "mean"] > 0
    # the costs: force and travel for every law, time at v_max for the MR laws only
    pid = summary[summary["controller"] == "pid"].set_index("metric")
    assert pid.loc["force_rms_n", "mean"] > 0 and pid.loc["travel_max_m", "mean"] > 0
    assert 0 <= pid.loc["voltage_at_max_fraction", "mean"] <= 1
    assert math.isnan(passive.loc["voltage_at_max_fraction", "mean"])
    assert tiny.settings["clearance_m"] == rr.VehicleParams.preset("paper").z_stop


def test_held_out_seeds_are_never_in_training(tiny):
    trained = set(tiny.tuning.runs["scenario.seed"].astype(int))
    judged = set(tiny.runs["track_seed"].astype(int))
    assert trained == {0} and judged == {1} and not trained & judged
    assert tiny.settings["train_seeds"] == [0] and tiny.settings["test_seeds"] == [1]
    assert {r["seed"] for r in tiny.tuning.settings["tuning_set"]} == {0}


def test_the_ranking_and_the_recommendation_name_the_winner(tiny):
    first = tiny.ranking[0]
    assert first["rank"] == 1 and tiny.recommended == first["controller"]
    assert [r["controller"] for r in tiny.ranking] == sorted(
        ["pid", "skyhook"], key=lambda n: next(r["score"] for r in tiny.ranking if r["controller"] == n)
    )
    label = rr.secondary.control.LABELS[tiny.recommended]
    assert tiny.recommendation.startswith(f"Recommended: {label}.")
    assert "held-out" in tiny.recommendation and "Runner-up" in tiny.recommendation
    # the score is the worst mean ratio (minimax) of the winner on its held-out runs
    ratios = tiny.table("roll_deg_rms").loc[(tiny.recommended, 40.0, 1.0), "ratio_mean"]
    assert first["score"] >= ratios


def test_the_recommendation_says_what_the_winner_gives_up(tiny):
    """Each response on which the runner-up's mean ratio to passive (from the held-out runs
    themselves) is lower than the winner's by more than 1 % is named with both numbers; the
    others are not; and the winner's largest travel against passive's."""
    win = tiny.recommended
    other = next(r["controller"] for r in tiny.ranking if r["controller"] != win)
    runs = tiny.runs
    base = runs[runs["controller"] == "passive"].set_index(["track", "track_seed", "speed_m_s", "load"])

    def ratio(law, column):
        own = runs[runs["controller"] == law].set_index(base.index.names)[column]
        return float((own / base[column]).mean())  # one speed and load: the mean over its runs

    names = {"acceleration_m_s2_rms": "acceleration", "displacement_m_rms": "displacement"}
    names.update(
        {"pitch_deg_rms": "pitch", "roll_deg_rms": "roll", "acceleration_m_s2_ptp": "peak-to-peak acceleration"}
    )
    text = tiny.recommendation
    for column, word in names.items():
        a, b = ratio(win, column), ratio(other, column)
        said = f"{word} ({b:.3f} against its {a:.3f})"
        assert (said in text) == (a - b > 0.01 * a), (word, a, b)  # level: within 1 % of the larger
    travel = ratio(win, "travel_max_m")
    assert f"Its largest secondary travel is x{travel:.2f} passive's on average." in text


def test_the_document_the_files_and_the_gains_file(tiny, tmp_path):
    jsonschema = pytest.importorskip("jsonschema")
    from pathlib import Path

    doc = json.loads(json.dumps(tiny.to_dict(), allow_nan=False))
    schema = json.loads((Path(__file__).parents[2] / "docs/schemas/railride.design-1.json").read_text())
    jsonschema.validate(doc, schema, cls=jsonschema.Draft202012Validator)
    assert doc["recommendation"]["controller"] == tiny.recommended
    assert doc["runs"] == {"training": tiny.settings["training_runs"], "judging": 3}
    paths = tiny.save(tmp_path / "d", command="railride design --budget 13")
    assert sorted(p.name for p in paths) == sorted(DESIGN_FILES)
    gains = rr.GainSet.load(tmp_path / "d" / "gains.toml")
    assert gains.provenance["aggregate"] == "mean"
    assert {r["seed"] for r in gains.provenance["tuning_set"]} == {0}
    assert gains.table("pid") == tiny.gains.table("pid")
    text = (tmp_path / "d" / "gains.toml").read_text()
    assert "held-out seeds 1 of fra4" in text and "# command: railride design --budget 13" in text
    runs = pd.read_csv(tmp_path / "d" / "design_runs.csv")
    assert len(runs) == 3 and set(runs["controller"]) == {"passive", "pid", "skyhook"}


def _summary(ratios: dict) -> pd.DataFrame:
    """A summary of one speed and load: ``ratios`` law -> four mean RMS ratios; a band of
    +-0.05 around each score."""
    rows = []
    for name, values in {"passive": [1.0] * 4, **ratios}.items():
        for col, r in zip(RMS_COLUMNS, values):
            rows.append({"controller": name, "speed_m_s": 50.0, "load": 1.0, "metric": col, "n": 5, "ratio_mean": r})
        score = max(values)
        rows.append(
            {
                "controller": name,
                "speed_m_s": 50.0,
                "load": 1.0,
                "metric": "score",
                "n": 5,
                "mean": score,
                "p5": score - 0.05,
                "p95": score + 0.05,
            }
        )
    return pd.DataFrame(rows)


def _runs(scores: dict) -> pd.DataFrame:
    return pd.DataFrame(
        [
            {"controller": n, "track": "fra4", "track_seed": s, "speed_m_s": 50.0, "load": 1.0, "score": v + 0.01 * s}
            for n, v in scores.items()
            for s in range(5)
        ]
    )


SETTINGS = {"tracks": ["fra4"], "test_seeds": [100, 101, 102, 103, 104]}


def test_the_recommendation_says_where_no_law_beats_passive():
    summary = _summary({"pid": [0.8, 0.7, 0.9, 1.10], "skyhook": [0.6, 0.9, 0.95, 1.20]})
    ranking, points = rank(summary, Objective("minimax"), ["pid", "skyhook"])
    assert [r["controller"] for r in ranking] == ["pid", "skyhook"]
    assert points[0]["no_law_beats_passive"] == [{"response": "roll", "best_ratio": 1.1, "best_controller": "pid"}]
    text = recommend(ranking, points, summary, _runs({"pid": 1.1, "skyhook": 1.2}), Objective("minimax"), SETTINGS, [])
    # passive scores 1 by minimax (every ratio 1): the best law's 1.1 is worse, so passive is kept
    assert points[0]["passive_score"] == 1.0
    assert text.startswith(
        "Recommended: keep passive. By this objective no law beats passive on held-out track: the best law, PID, "
        "scores 1.100 at worst (at 50 m/s, load 1)"
    )
    assert "against passive's 1.000." in text
    assert "worse than passive in roll at 50 m/s, load 1 (x1.100)" in text
    assert "No law is better than passive on average in roll at 50 m/s, load 1" in text
    # the bands (1.05-1.15 and 1.15-1.25) touch: they overlap; PID wins every run
    assert "overlap at 1 of 1" in text and "PID scores lower in 5 of 5" in text
    # 5 of 5 by chance: 2 x 0.5**5 = 0.0625, two-sided
    assert "(two-sided sign test over the runs that differ, p = 0.062: these runs do not tell that from chance" in text


def test_apart_bands_and_a_law_that_diverged():
    summary = _summary({"pid": [0.5, 0.5, 0.6, 0.7], "skyhook": [0.9, 0.9, 0.9, 0.9], "hybrid": [0.4] * 4})
    diverged = [
        {
            "controller": "hybrid",
            "stage": "judging",
            "runs": 1,
            "where": [{"track": "fra4", "track_seed": 102, "speed_m_s": 50.0, "load": 1.0, "diverged_at_s": 3.5}],
        }
    ]
    ranking, points = rank(summary, Objective("minimax"), ["pid", "skyhook", "hybrid"], {"hybrid"})
    assert [(r["controller"], r["rank"]) for r in ranking] == [("pid", 1), ("skyhook", 2), ("hybrid", None)]
    assert points[0]["best"] == "pid" and points[0]["no_law_beats_passive"] == []
    text = recommend(
        ranking,
        points,
        summary,
        _runs({"pid": 0.7, "skyhook": 0.9, "hybrid": 0.4}),
        Objective("minimax"),
        SETTINGS,
        diverged,
    )
    assert "better than passive on average in every RMS response" in text
    assert "apart at every one" in text
    assert "every RMS response has a law that did not diverge better than passive" in text
    assert "Hybrid diverged on held-out track (1 run, first on fra4 seed 102 at 50 m/s, load 1, t = 3.5 s)" in text


def test_min_budget_lets_every_gain_be_swept_once():
    assert min_budget("pid", 3) == 1 + 3 * 4
    assert min_budget("groundhook", 13) == 1 + 14
    # SAS (attitude+ride): 6 attitude gains, then 8 ride gains on what the first stage leaves
    # (the first stage may spend its half of what the start leaves: (B - 1) // 2 >= 48, B - 1 - that >= 64)
    need = min_budget("sas-attitude-ride", 7)
    assert need == 128 and (need - 1) // 2 >= 6 * 8 and need - 1 - (need - 1) // 2 >= 8 * 8
    assert (need - 2) - (need - 2) // 2 < 8 * 8  # one fewer would not do
    assert rr.studies.design.DEFAULT_BUDGET >= max(min_budget(n, 7) for n in rr.studies.tuning.TUNED_CONTROLLERS)


@pytest.mark.parametrize(
    "change, fragments",
    [
        ({"speeds": []}, ("speeds = []", "at least one")),
        ({"loads": []}, ("loads = []",)),
        ({"test_seeds": [0, 5]}, ("test_seeds = [0, 5]", "0 also in train_seeds", "never sees")),
        ({"budget": 5}, ("budget = 5", ">= 13", "try every gain once")),
        ({"controllers": ["lqr"]}, ("controllers = 'lqr'", "allowed: pid")),
        ({"tracks": ["paper-sine"]}, ("tracks = 'paper-sine'", "fra4")),
        (
            {"objective": "comfy"},
            ("objective = 'comfy'", "allowed: sum, weighted, minimax, constrained, n_mv, sperling"),
        ),
        ({"objective": "weighted"}, ("objective = 'weighted'", "needs its settings")),
        ({"aggregate": "median"}, ("aggregate",)),
        ({"values": 2}, ("values = 2",)),
        ({"duration": -1.0}, ("duration",)),
    ],
)
def test_bad_input_is_refused_before_any_run(change, fragments):
    table = RunTable()
    settings = {**TINY, **change}
    controllers = settings.pop("controllers", ["pid"])
    with pytest.raises(InputError) as caught:
        rr.design(controllers, table=table, **settings)
    for fragment in fragments:
        assert fragment in str(caught.value), (fragment, str(caught.value))
    assert len(table.frame) == 0


def test_passive_is_always_the_baseline_and_all_means_every_law():
    from railride.studies.design import check_design
    from railride.studies.tuning import TUNED_CONTROLLERS

    assert check_design(["passive", "pid"], **TINY).laws == ("pid",)
    assert check_design(None, **{**TINY, "budget": 400}).laws == TUNED_CONTROLLERS
    assert np.isfinite(check_design("all", **{**TINY, "budget": 400}).budget)


def test_run_cases_with_costs_adds_the_damper_columns_and_its_own_keys():
    from railride.analysis.costs import COST_COLUMNS
    from railride.studies.sweep import Case, run_cases

    opts = (("duration", 1.0), ("seed", 0), ("speed", 40.0))
    cases = [
        Case("fra4", opts),
        Case("fra4", opts, suspension="pid"),
        Case("fra4", opts, suspension="pid", damper="ideal"),
    ]
    table = RunTable()
    rows = run_cases(cases, table=table, costs=True)
    assert set(COST_COLUMNS) <= set(rows.columns)
    passive, pid, ideal = (rows.iloc[i] for i in range(3))
    assert passive["force_rms_n"] > 0 and passive["travel_max_m"] > 0 and math.isnan(passive["voltage_at_max_fraction"])
    assert 0 <= pid["voltage_at_max_fraction"] <= 1 and pid["force_max_n"] >= pid["force_rms_n"]
    assert 0 < pid["coil_power_fraction"] <= 1 and math.isnan(passive["coil_power_fraction"])
    assert math.isnan(ideal["voltage_at_max_fraction"])  # an ideal device has no voltage
    plain = run_cases(cases, table=table)
    assert not set(COST_COLUMNS) & set(plain.columns)
    assert set(plain["key"]).isdisjoint(rows["key"])  # costs are in a run's key: a table resumes neither into the other


def test_a_law_that_diverged_in_tuning_or_judging_is_listed_with_where():
    from types import SimpleNamespace

    from railride.studies.design import Plan, _diverged
    from railride.studies.tune_result import Study

    tuned = SimpleNamespace(
        studies=[
            Study("inner", ("inner.B",), None, objective=0.4),
            Study("pid", ("pid.kp",), 13, objective=0.9),
            Study("hybrid", ("hybrid.alpha",), 13, objective=math.inf),
        ]
    )
    training = pd.DataFrame(
        {
            "suspension": ["passive", "pid", "hybrid", "hybrid"],
            "scenario": ["fra4"] * 4,
            "scenario.seed": [0, 0, 0, 1],
            "scenario.speed": [40.0] * 4,
            "diverged_at_s": [np.nan, 1.0, np.nan, 2.5],
        }
    )
    runs = pd.DataFrame(
        {
            "controller": ["passive", "pid", "hybrid"],
            "track": ["fra4"] * 3,
            "track_seed": [7] * 3,
            "speed_m_s": [40.0] * 3,
            "load": [1.3] * 3,
            "diverged_at_s": [np.nan, 0.75, np.nan],
        }
    )
    plan = Plan(
        ("pid", "hybrid"),
        None,
        None,
        (1.3,),
        ("fra4",),
        (40.0,),
        (0, 1),
        (7,),
        2.0,
        None,
        "mean",
        13,
        3,
        "railway",
        None,
    )
    found = _diverged(tuned, training, runs, plan)
    # the candidate runs of pid that diverged in tuning do not count: its tuned gains are finite
    assert found == [
        {
            "controller": "hybrid",
            "stage": "tuning",
            "runs": 1,
            "where": [{"track": "fra4", "track_seed": 1, "speed_m_s": 40.0, "load": None, "diverged_at_s": 2.5}],
        },
        {
            "controller": "pid",
            "stage": "judging",
            "runs": 1,
            "where": [{"track": "fra4", "track_seed": 7, "speed_m_s": 40.0, "load": 1.3, "diverged_at_s": 0.75}],
        },
    ]


def test_the_coil_power_at_a_constant_voltage_is_its_square_over_v_max_squared():
    """A resistive coil held at v draws (v / v_max)^2 of its power at v_max once its lag has
    settled (eta = 50 1/s: within 0.3 s; a run of 4 s from 0 V spends 1/(2 eta) s of its mean
    catching up): the mean over the run is (v / v_max)^2 (1 - 1/(2 eta T)) to first order."""
    from railride.secondary.dampers import RAILWAY
    from railride.studies.sweep import Case, run_cases

    v, T = 1.125, 4.0
    opts = (("duration", T), ("seed", 0), ("speed", 40.0))
    row = run_cases([Case("fra4", opts, suspension="mr", voltage=v)], table=RunTable(), costs=True).iloc[0]
    expected = (v / RAILWAY.v_max) ** 2
    assert row["coil_power_fraction"] == pytest.approx(expected, rel=3.0 / (2 * RAILWAY.eta * T))
    assert row["voltage_at_max_fraction"] == 0.0


def test_a_measured_profile_is_cut_into_sections_for_training_and_judging(tmp_path):
    """A measured line (here 500 m of a FRA class 4 realisation, sampled every 0.25 m: shorter
    than a run at the default speed and duration, 555.6 m) is split into sections of the fastest
    run's length (40 m/s x 2 s = 80 m): tuning runs on section 0, judging on section 2, and a
    held-out run is the run of that section by itself."""
    s = np.arange(0.0, 500.25, 0.25)
    zl, zr, _, _ = rr.scenario("fra4", seed=5).track.evaluate(s)
    path = tmp_path / "line.csv"
    pd.DataFrame({"s": s, "z_L": zl, "z_R": zr}).to_csv(path, index=False)
    track = f"file:{path}"
    table = RunTable()
    result = rr.design(
        ["skyhook"], tracks=[track], speeds=[40.0], loads=[1.0], train_seeds=[0], test_seeds=[2],
        duration=2.0, budget=13, values=3, table=table,
    )  # fmt: skip
    starts = set(table.frame.loc[table.frame["scenario"] == track, "scenario.start"])
    assert starts == {0.0, 160.0}  # section 0 (tuning) and section 2 (judging), nothing else
    assert set(result.runs["track_seed"]) == {2}
    passive = result.runs[result.runs["controller"] == "passive"].iloc[0]
    alone = rr.simulate(rr.scenario(track, start=160.0, speed=40.0, duration=2.0)).metrics()
    assert passive["roll_deg_rms"] == pytest.approx(float(alone.sel(response="roll_deg", statistic="rms")), rel=1e-12)
    with pytest.raises(InputError, match="holds 6 sections of 80 m"):
        rr.design(["skyhook"], tracks=[track], speeds=[40.0], loads=[1.0], train_seeds=[0], test_seeds=[7],
                  duration=2.0, budget=13, values=3)  # fmt: skip
    with pytest.raises(InputError, match=r"speeds up to 40 m/s, duration = 20 s: the run covers s = 0 to 800"):
        rr.design(["skyhook"], tracks=[track], speeds=[40.0], loads=[1.0], train_seeds=[0], test_seeds=[1],
                  duration=20.0, budget=13, values=3)  # fmt: skip


def test_the_probes_runs_go_in_one_call_and_the_probes_then_run_nothing(monkeypatch):
    """The references on the ideal devices and the fault check of the leaders (`design_probes`)
    make their runs in one `run_cases` call ahead of them (a GPU then has them in flight
    together); when they ask, the run table holds every run, so their calls make none."""
    from railride.studies import design as design_module

    calls = []
    run_cases = design_module.run_cases

    def counted(cases, *, table, **kw):
        before = len(table.done())
        rows = run_cases(cases, table=table, **kw)
        calls.append((len(cases), len(table.done()) - before))
        return rows

    monkeypatch.setattr(design_module, "run_cases", counted)
    rr.design(["pid", "skyhook"], **TINY)
    # judging (2 laws and passive), then the probes: 2 laws on 2 devices, passive, 2 leaders faulted
    judged, ahead, *probes = calls
    assert judged == (3, 3)
    assert ahead == (3 * 3, 3 * 2 + 1)  # passive is in every ask, and runs once
    assert probes == [(3, 0), (3, 0), (3, 0)]  # two devices and the fault, all found in the table


def test_the_figure_draws_a_bar_where_one_speed_leaves_no_band(tiny):
    """At one speed a band has no width: each law's 5-95 % range is an error bar from its own
    held-out runs' percentiles."""
    from matplotlib.collections import LineCollection

    fig = tiny.plot()
    ax = fig.axes[0]  # acceleration
    bars = [c for c in ax.collections if isinstance(c, LineCollection)]
    assert len(bars) == 2  # pid and skyhook
    rows = tiny.summary[(tiny.summary["metric"] == "acceleration_m_s2_rms") & (tiny.summary["controller"] != "passive")]
    want = sorted((float(r.ratio_p5), float(r.ratio_p95)) for r in rows.itertuples())
    got = sorted((float(seg[0][1]), float(seg[1][1])) for c in bars for seg in c.get_segments())
    np.testing.assert_allclose(np.array(got), np.array(want), rtol=1e-12)


def test_a_law_level_with_passive_is_recommended_one_worse_is_not():
    """Within 1 % of passive's score a law is level with it and stays recommended; beyond, the
    design keeps passive (`passive_wins` returns passive's score)."""
    from railride.studies.design_result import passive_wins

    points = [{"passive_score": 1.0}, {"passive_score": 1.0}]
    assert passive_wins({"score": 1.005}, points) is None
    assert passive_wins({"score": 1.02}, points) == 1.0
    assert passive_wins({"score": 0.9}, points) is None
    assert passive_wins({"score": 1.5}, [{"passive_score": None}]) is None  # passive's score unknown: no claim


def test_the_fault_sentence_tells_a_law_that_never_beat_passive_from_one_the_fault_cost():
    """PID beats passive healthy (0.9) and not with the failed coil (1.1): "no longer"; skyhook
    never did (1.2, 1.3): not "no longer", but "healthy either"."""
    from types import SimpleNamespace

    from railride.studies.design_probes import fault_check

    plan = SimpleNamespace(damper="railway", laws=["pid", "skyhook"], objective=Objective("minimax"), service=None)
    healthy = [{"speed_m_s": 40.0, "load": 1.0, "scores": {"pid": 0.9, "skyhook": 1.2}}]
    faulted = [{"speed_m_s": 40.0, "load": 1.0, "scores": {"pid": 1.1, "skyhook": 1.3}}]
    text = fault_check(plan, ["pid", "skyhook"], healthy, lambda **kw: faulted)["text"]
    assert "PID then no longer beats passive everywhere" in text
    assert "Skyhook did not beat passive everywhere healthy either" in text
    assert "Skyhook then no longer" not in text


def test_a_score_that_breaks_the_constraints_is_said_to_not_a_raw_number():
    """With --max-travel a run 50 % over the bound scores the infeasible offset + 1000 x 0.5:
    the recommendation says "infeasible" and by how much, not 1500."""
    from railride.studies.design_result import score_text

    bound = Objective("minimax", travel_bound=0.04)
    j = float(bound.of_ratios({c: np.float64(0.8) for c in RMS_COLUMNS}, travel=0.06))
    assert j >= 1000.0
    assert score_text(j, bound) == "infeasible: over its constraints by 0.5 of a bound"
    assert score_text(0.8, bound) == "0.800"
    assert score_text(1500.0, Objective("minimax")) == "1500.000"  # no constraint: a number
    record = bound.to_dict()["infeasible"]  # a document's, as the command line reads it
    assert score_text(j, record, short=True) == "infeasible (+0.5)"
