"""Statistics over tracks (railride.studies.study): the numbers recomputed from the runs, the cases a
study runs, failed runs, bad input and the result protocol."""

import json

import numpy as np
import pytest

from railride.secondary.control import GainSet
from railride.run.simulation import simulate
from railride.studies.study import METRICS, fault_condition, study
from railride.secondary.suspension import Suspension
from railride.studies.sweep import RunTable
from railride.model.track import scenario

SHORT = dict(track_seeds=[0, 1, 2], speeds=[30.0, 50.0], duration=2.0)


@pytest.fixture(scope="module")
def small():
    return study(["pid", "sas-attitude"], loads=[1.0, 1.3], faults=["none", "1R-off"], **SHORT)


def test_the_study_runs_every_case_once_with_a_healthy_passive_baseline(small):
    c = small.cases
    passive = c[c.controller == "passive"]
    assert len(passive) == 3 * 2 * 2 and set(passive.fault) == {"none"}  # seeds x speeds x loads
    assert len(c[c.controller == "pid"]) == 3 * 2 * 2 * 2  # ... x fault conditions
    assert set(c[c.fault == "1R-off"]["faults"]) == {"1R-off"}
    # a load factor scales the carbody (the run table holds the vehicle it ran)
    loaded = c[(c.load == 1.3)]["vehicle.m_c"].unique()
    assert loaded == pytest.approx([1.3 * 3.96e4])


def test_a_run_of_the_study_is_the_direct_simulation(small):
    c = small.cases
    pick = (c.controller == "pid") & (c.track_seed == 1) & (c.speed_m_s == 50.0) & (c.load == 1.0)
    row = c[pick & (c.fault == "1R-off")]
    direct = simulate(
        scenario("fra4", seed=1, speed=50.0, duration=2.0),
        suspension=Suspension.named("pid", GainSet.robust()).with_faults("1R-off"),  # the set random track takes
    )
    rms = direct.metrics().sel(statistic="rms", response="roll_deg")
    assert float(row["roll_deg_rms"].iloc[0]) == pytest.approx(float(rms), rel=1e-12)


def test_the_statistics_are_those_of_the_runs(small):
    c, s = small.cases, small.summary
    # the statistics of each speed apart, over the three track seeds: speeds are never pooled
    speed = sorted(set(c.speed_m_s))[-1]
    for name, load, fault in (("pid", 1.3, "1R-off"), ("sas-attitude", 1.0, "none")):
        mine = c[(c.controller == name) & (c.load == load) & (c.fault == fault) & (c.speed_m_s == speed)]
        base = c[(c.controller == "passive") & (c.load == load)].set_index(["track_seed", "speed_m_s"])
        for metric in ("acceleration_m_s2_rms", "centre_N_MV_z"):
            row = s[
                (s.controller == name)
                & (s.speed_m_s == speed)
                & (s.load == load)
                & (s.fault == fault)
                & (s.metric == metric)
            ].iloc[0]
            x = mine[metric].to_numpy()
            p = base.loc[list(zip(mine.track_seed, mine.speed_m_s)), metric].to_numpy()
            red = (p - x) / p * 100
            assert row["n"] == 3
            assert row["mean"] == pytest.approx(x.mean()) and row["p95"] == pytest.approx(np.percentile(x, 95))
            assert row["reduction_mean"] == pytest.approx(red.mean())
            assert row["reduction_p5"] == pytest.approx(np.percentile(red, 5))
    assert set(s.metric) == set(METRICS)


def test_the_trade_offs_are_the_runs_own_reductions_sorted_against_the_level_band(small):
    """Each condition's better, worse and level metrics, recomputed from the runs themselves
    (each run's RMS against passive's on the same track, speed and load, averaged), and the
    sentences that name the trade-offs."""
    from railride.output.trade_offs import study_trade_off_lines
    from railride.studies.study import LEVEL_PERCENT, TRADE_METRICS

    c = small.cases
    entries = small.trade_offs()
    assert len(entries) == 2 * 2 * 2 * 2  # laws x speeds x loads x fault conditions
    for e in entries:
        mine = c[
            (c.controller == e["controller"]) & (c.speed_m_s == e["speed_m_s"]) & (c.load == e["load"])
            & (c.fault == e["fault"])
        ]  # fmt: skip
        base = c[(c.controller == "passive") & (c.load == e["load"])].set_index(["track_seed", "speed_m_s"])
        for m in TRADE_METRICS:
            p = base.loc[list(zip(mine.track_seed, mine.speed_m_s)), m].to_numpy()
            red = float(np.mean((p - mine[m].to_numpy()) / p * 100))
            kind = "better_on" if red > LEVEL_PERCENT else "worse_on" if red < -LEVEL_PERCENT else "level_on"
            assert m in e[kind], (e["controller"], e["speed_m_s"], m, red)
            assert e["reductions"][m] == pytest.approx(red, rel=1e-9)
    traded = [e for e in entries if e["better_on"] and e["worse_on"]]
    assert traded  # the case has some: every law here trades displacement or pitch for comfort somewhere
    lines = study_trade_off_lines(entries, LEVEL_PERCENT)
    assert len(lines) >= 2 and all(line.startswith("trade-off: ") for line in lines[:-1])
    assert small.to_dict()["trade_offs"][0]["controller"] == entries[0]["controller"]


def test_a_run_that_diverges_is_listed_and_the_others_go_on():
    gains = GainSet.default().apply({"groundhook.c_g": 1e8})  # too stiff for the ideal actuator
    res = study(["pid", "groundhook"], damper="ideal", gains=gains, track_seeds=[0], speeds=[40.0], duration=1.0)
    assert [f["controller"] for f in res.failed] == ["groundhook"] and res.failed[0]["diverged_at_s"] > 0
    s = res.summary
    assert s[(s.controller == "groundhook")]["n"].max() == 0
    assert s[(s.controller == "pid")]["n"].min() == 1
    json.dumps(res.to_dict(), allow_nan=False)  # no NaN in the document


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(track_seeds=[-1]), r"track_seeds = -1: must be a whole number >= 0"),
        (dict(loads=[0.0]), r"loads = 0.0: must be a finite number > 0"),
        (dict(speeds=[-3.0]), r"speeds = -3.0: must be a finite number > 0"),
        (dict(faults=["3R-off"]), r"fault corner = '3R'"),
        (dict(faults=["1R-off+1R-on"]), r"corner 1R has more than one fault"),
        (dict(faults=["1R-off@5"], duration=2.0), r"not within the run"),
        (dict(faults=["1R-off"], damper="ideal"), r"'off' and 'on' need MR dampers"),
        (dict(track_seeds=[]), r"track_seeds: give at least one value"),
        (dict(controllers=["lqr"]), r"unknown controller 'lqr'"),
    ],
)
def test_bad_settings_are_refused_before_any_run(kwargs, match, monkeypatch):
    from railride.run import simulation

    def no_run(*args, **kw):
        raise AssertionError("a run started before the settings were checked")

    monkeypatch.setattr(simulation, "simulate", no_run)
    args = {"track_seeds": [0], "duration": 2.0, **kwargs}
    with pytest.raises(ValueError, match=match):
        study(args.pop("controllers", ["pid"]), **args)


def test_a_study_resumes_from_its_run_table(tmp_path):
    class Counting:
        def __init__(self):
            self.cases = 0

        def map(self, fn, chunks):
            for i, chunk in enumerate(chunks):
                self.cases += len(chunk)
                yield i, fn(chunk)

    path = tmp_path / "runs.csv"
    first = study(["pid"], table=RunTable(path), track_seeds=[0, 1], duration=1.0)
    ex = Counting()
    again = study(["pid"], table=RunTable(path, resume=True), executor=ex, track_seeds=[0, 1], duration=1.0)
    assert ex.cases == 0
    assert again.summary.equals(first.summary)


def test_the_result_protocol(small, tmp_path):
    from matplotlib.figure import Figure

    doc = small.to_dict()
    assert doc["schema"] == "railride.study/1" and doc["percentiles"] == [5.0, 95.0]
    assert json.loads(json.dumps(doc, allow_nan=False)) == doc
    pid = next(g for g in doc["results"] if g["controller"] == "pid" and g["fault"] == "1R-off" and g["load"] == 1.3)
    assert set(pid["metrics"]) == set(METRICS) and pid["metrics"]["roll_deg_rms"]["n"] == 3  # one speed's seeds
    assert {g["speed_m_s"] for g in doc["results"]} == set(small.cases.speed_m_s)
    columns = ["controller", "speed_m_s", "load", "stiffness", "fault", "delay", "metric"]
    assert list(small.to_pandas().columns[:7]) == columns
    fig = small.plot()
    assert isinstance(fig, Figure)
    # five metrics on a grid of six: the legend has the free panel to itself, clear of the data
    (holder,) = [a for a in fig.get_axes() if a.get_legend() is not None]
    assert not holder.lines and not holder.collections and not holder.axison
    ticks = [t.get_text() for t in fig.get_axes()[0].get_xticklabels()]
    # two speeds x four conditions a panel, three panels a row: one line each, upright, apart
    assert ticks[-1] == f"{max(small.cases.speed_m_s):g} m/s, load x1.3, 1R-off"
    fig.canvas.draw()
    boxes = [t.get_window_extent() for t in fig.get_axes()[0].get_xticklabels()]
    assert all(a.x1 <= b.x0 for a, b in zip(boxes, boxes[1:])), [(b.x0, b.x1) for b in boxes]
    mine = Figure()
    assert small.plot(ax=mine.subplots(1, 2), metrics=["roll_deg_rms", "centre_N_MV_z"]) is mine
    paths = small.save(tmp_path / "out")
    assert [p.name for p in paths] == ["study.json", "study_summary.csv", "study_runs.csv", "study.png"]
    assert fault_condition("2L-on@1+1R-off") == ("1R-off", "2L-on@1") and fault_condition("none") == ()


def test_a_study_on_a_sine_runs_over_speeds_alone():
    res = study(["pid"], scenario="paper-sine", speeds=[30.0, 40.0], duration=1.0)
    assert res.settings["track_seeds"] is None and len(res.cases) == 2 * 2
    rows = res.summary[(res.summary.controller == "pid") & (res.summary.metric == "roll_deg_rms")]
    assert sorted(rows.speed_m_s) == [30.0, 40.0]  # one row per speed: never pooled
    assert list(rows["n"]) == [1, 1] and np.all(np.isfinite(rows["reduction_mean"]))
    with pytest.raises(ValueError, match=r"track_seeds = \[1\]: track seeds apply to the random tracks"):
        study(["pid"], scenario="paper-sine", track_seeds=[1])


def test_a_secondary_stiffness_tolerance_is_a_condition_of_its_own():
    res = study(["pid"], track_seeds=[0], speeds=[40.0], stiffness=[0.9, 1.1], duration=1.0)
    c = res.cases
    assert sorted(c[c.controller == "passive"]["vehicle.k_sz"]) == pytest.approx([0.9 * 2.9e5, 1.1 * 2.9e5])
    # each controlled run against the passive run of the same stiffness
    for k in (0.9, 1.1):
        p = c[(c.controller == "passive") & (c.stiffness == k)]["roll_deg_rms"].iloc[0]
        x = c[(c.controller == "pid") & (c.stiffness == k)]
        assert x["roll_deg_rms_reduction"].iloc[0] == pytest.approx((p - x["roll_deg_rms"].iloc[0]) / p * 100)
    assert {g["stiffness"] for g in res.to_dict()["results"]} == {0.9, 1.1}
    with pytest.raises(ValueError, match="stiffness = 0.0: must be a finite number > 0"):
        study(["pid"], track_seeds=[0], stiffness=[0.0])


@pytest.mark.parametrize(("duration", "window", "n"), [(2.0, None, 0), (10.0, None, 2), (12.0, (1.0, 12.0), 2)])
def test_the_comfort_basis_counts_the_intervals_the_comfort_index_reads(duration, window, n):
    """The study's line on N_MV,z names as many 5 s intervals as `ride_comfort` of one of its
    runs finds in the same window (0: the whole signal)."""
    from railride.analysis.comfort import WHOLE_SIGNAL, ride_comfort
    from railride.analysis.comfort_record import n_mv_basis

    res = study(["pid"], track_seeds=[4], speeds=[40.0], duration=duration, window=window)
    run = simulate(scenario("fra4", seed=4, speed=40.0, duration=duration))
    comfort = ride_comfort(run.dataset, window=window)
    if n:
        assert int(comfort.attrs["n_intervals"]) == n
    else:  # shorter than one interval: the whole signal
        assert WHOLE_SIGNAL in comfort.attrs["notes"]
    assert res.settings["comfort_basis"] == n_mv_basis(n)


def test_the_study_says_which_tracks_its_gains_were_tuned_on():
    """The shipped robust gains were tuned on fra4 seeds 1-3 at 30, 50 and 70 m/s."""
    res = study(["pid"], track_seeds=[0, 1], speeds=[40.0, 50.0], duration=0.5)
    text = res.settings["tracks_judged"]
    assert "in-sample (tuned on this track at this speed): seed 1 at 50 m/s" in text
    assert "the tuned track at a new speed: seed 1 at 40 m/s" in text
    assert "held out (tuning never ran on this track): seed 0 at 40, 50 m/s" in text
    assert "tracks_judged" not in study(["passive"], track_seeds=[0], speeds=[40.0], duration=0.5).settings
