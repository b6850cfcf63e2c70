"""The Pareto view (railride.studies.pareto): the non-dominated flag against its definition, a tiny
study's files, resume, and bad input."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from railride.secondary.control import GainSet
from railride.studies.optimise import log_gain_bounds
from railride.studies.pareto import FILES, in_sample_note, non_dominated, pareto
from railride.studies.sweep import RunTable
from railride.model.track import scenario

SHORT = {"duration": 1.0}
PNG = b"\x89PNG\r\n\x1a\n"


def brute_force(points) -> list[bool]:
    """Row i is non-dominated unless some row j is <= in every column and < in one."""
    rows = [list(map(float, p)) for p in points]
    out = []
    for i, a in enumerate(rows):
        if any(np.isnan(a)):
            out.append(False)
            continue
        dominated = False
        for j, b in enumerate(rows):
            if (
                j != i
                and not any(np.isnan(b))
                and all(y <= x for x, y in zip(a, b))
                and any(y < x for x, y in zip(a, b))
            ):
                dominated = True
        out.append(not dominated)
    return out


@pytest.mark.parametrize("columns", [2, 4])
@pytest.mark.parametrize("seed", range(5))
def test_non_dominated_matches_the_definition(columns, seed):
    rng = np.random.default_rng(seed)
    points = rng.random((80, columns))
    points[::7] = np.round(points[::7], 1)  # ties in some columns
    points[5] = points[3]  # an exact duplicate
    points[11, 0] = np.nan  # a failed run
    assert non_dominated(points).tolist() == brute_force(points)


def test_non_dominated_small_cases():
    assert non_dominated([[1, 2], [2, 1], [2, 2], [1, 2]]).tolist() == [True, True, False, True]
    assert non_dominated(np.empty((0, 4))).tolist() == []
    # sums equal in floating point (1e16 + 1 rounds to 1e16) though the second row dominates
    # the first, which comes first in the visit: it must still be dropped
    assert non_dominated([[1e16, 1.0], [1e16, 0.0]]).tolist() == [False, True]
    assert non_dominated([[2.0, 0.0], [1.0, 0.0]]).tolist() == [False, True]


@pytest.fixture(scope="module")
def tiny():
    return pareto("sas-attitude", n_samples=4, seed=3, scenario_options=SHORT)


def test_a_tiny_study(tiny, tmp_path):
    frame = tiny.to_pandas()
    assert len(frame) == 5 and frame["base"].tolist() == [True] + [False] * 4
    names = list(tiny.parameters)
    assert names == [
        "attitude.kp_z",
        "attitude.kd_z",
        "attitude.kp_phi",
        "attitude.kd_phi",
        "attitude.kp_theta",
        "attitude.kd_theta",
    ]
    base = GainSet.default().attitude.to_dict()
    assert frame.loc[0, names].tolist() == [base[n.split(".")[1]] for n in names]
    lo, hi = np.array(log_gain_bounds(names)).T
    logs = np.log10(frame.loc[1:, names].to_numpy())
    assert ((logs >= lo) & (logs <= hi)).all()
    # a seeded sample: the same seed, the same gains; another seed, others
    again = pareto("sas-attitude", n_samples=4, seed=3, scenario_options=SHORT)
    assert np.array_equal(again.gains, tiny.gains)
    other = pareto("sas-attitude", n_samples=4, seed=4, scenario_options=SHORT)
    assert not np.array_equal(other.gains[1:], tiny.gains[1:])
    ratio = frame[[c for c in frame if c.endswith("_ratio") and c != "travel_ratio"]].to_numpy()
    rms = frame[[c for c in frame if c.endswith("_rms")]].to_numpy()
    assert np.allclose(ratio * tiny.passive, rms, rtol=1e-12)
    assert frame["non_dominated"].tolist() == brute_force(ratio)
    assert frame["non_dominated_acceleration_roll"].tolist() == brute_force(ratio[:, [0, 3]])

    paths = tiny.save(tmp_path / "p")
    assert [p.name for p in paths] == list(FILES) == ["pareto.png", "pareto_caption.txt", "pareto.csv", "pareto.json"]
    assert (tmp_path / "p" / "pareto.png").read_bytes().startswith(PNG)
    reloaded = pd.read_csv(tmp_path / "p" / "pareto.csv")
    pd.testing.assert_frame_equal(reloaded, frame, check_exact=False, rtol=1e-12)
    doc = json.loads((tmp_path / "p" / "pareto.json").read_text())
    assert doc["schema"] == "railride.pareto/1"
    assert doc["columns"] == list(frame.columns)
    assert doc["counts"]["samples"] == 5
    assert doc["counts"]["non_dominated"] == int(frame["non_dominated"].sum())
    assert [p["name"] for p in doc["parameters"]] == names
    assert doc["samples"][2]["attitude.kd_z"] == pytest.approx(frame.loc[2, "attitude.kd_z"])


def test_plot_returns_its_figure(tiny):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = tiny.plot()
    assert len(fig.axes) == 2
    assert "pitch" in fig.axes[0].get_ylabel() and "roll" in fig.axes[1].get_ylabel()
    assert "acceleration" in fig.axes[0].get_xlabel()
    mine = Figure()
    FigureCanvasAgg(mine)
    axes = mine.subplots(1, 2)
    assert tiny.plot(axes) is mine
    with pytest.raises(ValueError, match="two Axes|2 Axes"):
        tiny.plot(axes[0])


def test_a_resumed_study_runs_nothing_again(tmp_path):
    class Counting:
        cases = 0

        def map(self, fn, chunks):
            for i, chunk in enumerate(chunks):
                Counting.cases += len(chunk)
                yield i, fn(chunk)

    path = tmp_path / "runs.csv"
    first = pareto("pid", n_samples=2, scenario_options=SHORT, table=RunTable(path))
    assert first.runs == 4  # passive, the base gains, two samples
    again = pareto("pid", n_samples=2, scenario_options=SHORT, table=RunTable(path, resume=True), executor=Counting())
    assert Counting.cases == 0 and np.array_equal(again.rms, first.rms)


def test_the_note_when_the_base_gains_were_tuned_on_this_track():
    record = scenario("paper-sine", **SHORT).describe()
    text = GainSet.reference().to_toml()
    inline = ", ".join(f"{k} = {json.dumps(v)}" for k, v in record.items())
    tuned_here = GainSet.from_toml(f"[provenance]\nscenario_record = {{{inline}}}\n\n{text}", "g.toml")
    assert "same single track" in in_sample_note(tuned_here, record)
    elsewhere = scenario("paper-sine", speed=40.0, **SHORT).describe()
    assert in_sample_note(tuned_here, elsewhere) is None
    assert in_sample_note(GainSet.reference(), record) is None  # no provenance: nothing to say


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        ({"n_samples": 3}, "n_samples = 3"),
        ({"n_samples": 0}, "n_samples = 0"),
        ({"seed": -1}, "seed = -1"),
        ({"suspension": "passive"}, "suspension = 'passive'"),
        ({"suspension": "sas-attitude", "parameters": ["ride.kp_1R"]}, "'ride.kp_1R'"),
    ],
)
def test_pareto_refuses_bad_input(kwargs, fragment):
    with pytest.raises(ValueError) as info:
        pareto(**{"scenario_options": SHORT, **kwargs})
    assert fragment in str(info.value)


def test_the_travel_of_every_sample_and_the_front_that_counts_it(tiny):
    """Each sample's largest secondary travel against passive's; the base sample's is the one a
    comparison of the same law and gains on the same track reports (another study's path to the
    same run); a sample on the four-ratio front stays on the front with travel added (a fifth
    objective removes no point that no other point dominates in four)."""
    import railride as rr

    frame = tiny.to_pandas()
    np.testing.assert_allclose(frame["travel_ratio"], frame["travel_max_m"] / tiny.passive_travel_max, rtol=1e-15)
    assert frame["non_dominated_with_travel"].tolist() == brute_force(
        np.column_stack([tiny.ratios, frame["travel_ratio"]])
    )
    assert (frame["non_dominated_with_travel"] | ~frame["non_dominated"]).all()
    compared = rr.compare(scenario("paper-sine", duration=1.0), controllers=["sas-attitude"], bounds=False)
    travel = {r["name"]: r["damper"]["travel_max_m"] for r in compared.to_dict()["controllers"]}
    assert tiny.passive_travel_max == pytest.approx(travel["passive"], rel=1e-12)
    assert frame.loc[0, "travel_max_m"] == pytest.approx(travel["sas-attitude"], rel=1e-12)
    doc = tiny.to_dict()
    assert doc["passive_travel_m"] == tiny.passive_travel_max
    # what the front asks of the travel, counted from the rows themselves
    front = frame[frame["non_dominated"]]
    more = front["travel_ratio"][front["travel_ratio"] > 1.01]
    clearance = rr.VehicleParams.preset("paper").z_stop
    assert doc["front_travel"] == {
        "samples": len(front),
        "more_than_passive": len(more),
        "largest_ratio": float(more.max()) if len(more) else None,
        "clearance_m": clearance,
        "stop_stiffness_n_per_m": 0.0,
        "past_clearance": int((front["travel_max_m"] >= clearance).sum()),
    }
    assert doc["counts"]["non_dominated_with_travel"] == int(frame["non_dominated_with_travel"].sum())
