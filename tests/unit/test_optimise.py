"""The global methods' results (railride.studies.optimise): `OptimiseResult` and `SensitivityResult`
follow the result protocol; the convergence is that of the search."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from railride.output.files import json_text
from railride.studies.optimise import (
    OPTIMISE_FILES,
    SENSITIVITY_FILES,
    OptimiseResult,
    SensitivityResult,
    optimise,
    sensitivity,
)

PNG = b"\x89PNG\r\n\x1a\n"
SHORT = {"duration": 0.5}


@pytest.fixture(scope="module")
def found():
    return optimise(
        ("attitude.kd_z", "attitude.kd_phi"),
        suspension="sas-attitude",
        scenario_options=SHORT,
        popsize=3,
        maxiter=2,
        seed=1,
    )


@pytest.fixture(scope="module")
def indices():
    return sensitivity(("attitude.kd_z", "ride.kp_1R"), suspension="sas-attitude", scenario_options=SHORT, n=4)


def _failing(*args, **kwargs):
    raise OSError("disk full (simulated)")


# -- OptimiseResult -------------------------------------------------------------------------------
def test_the_convergence_is_that_of_the_search(found):
    frame = found.to_pandas()
    assert list(frame.columns) == ["generation", "runs", "objective", "best"]
    assert frame["generation"].tolist() == list(range(found.generations + 1))
    # 3 x 2 runs per generation, after the passive run
    assert frame["runs"].tolist() == [1 + 6 * (g + 1) for g in frame["generation"]]
    assert frame["runs"].iloc[-1] == found.n_runs
    assert frame["best"].iloc[-1] == found.objective
    assert np.all(np.diff(frame["best"]) <= 0) and np.all(frame["best"] <= frame["objective"])


def test_the_optimise_document(found):
    doc = json.loads(json_text(found.to_dict()))  # strict JSON
    assert doc["schema"] == "railride.optimise/1"
    assert doc["suspension"] == "sas-attitude" and doc["scenario"]["duration_s"] == 0.5
    assert doc["settings"]["popsize"] == 3 and doc["settings"]["seed"] == 1
    assert doc["objective"]["kind"] == found.objective_definition.kind
    assert doc["objective_value"] == found.objective and doc["runs"] == found.n_runs
    assert [p["name"] for p in doc["parameters"]] == list(found.parameters)
    assert len(found.log10_gains) == len(doc["parameters"]) > 0  # zip would stop at the shorter
    for p, lg in zip(doc["parameters"], found.log10_gains):
        assert p["value"] == 10.0**lg and p["low"] <= p["value"] <= p["high"]
    assert doc["gains"]["attitude"]["kd_z"] == found.gains.attitude.kd_z
    assert [c["best"] for c in doc["convergence"]] == found.to_pandas()["best"].tolist()


def test_the_optimise_plot_and_folder(found, tmp_path, monkeypatch):
    mine = Figure()
    ax = mine.subplots()
    assert found.plot(ax=ax) is mine and mine.get_axes() == [ax] and ax.has_data()
    assert found.plot() is not mine
    paths = found.save(tmp_path / "out")
    assert [p.name for p in paths] == list(OPTIMISE_FILES)
    assert (tmp_path / "out" / "optimise.png").read_bytes().startswith(PNG)
    assert json.loads((tmp_path / "out" / "optimise.json").read_text()) == json.loads(json_text(found.to_dict()))
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "out" / "optimise.csv"), found.to_pandas())
    import railride.plots.optimise

    monkeypatch.setattr(railride.plots.optimise, "plot_convergence", _failing)
    with pytest.raises(OSError, match="simulated"):
        found.save(tmp_path / "new")
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_an_objective_that_is_not_finite_is_null_in_the_document(found):
    import dataclasses

    diverged = dataclasses.replace(found, objective=float("inf"), convergence=np.array([[7.0, np.inf], [13.0, 1.2]]))
    doc = json.loads(json_text(diverged.to_dict()))
    assert doc["objective_value"] is None
    assert [c["objective"] for c in doc["convergence"]] == [None, 1.2]
    assert isinstance(diverged, OptimiseResult)


# -- SensitivityResult ----------------------------------------------------------------------------
def test_the_sensitivity_document_and_table(indices):
    frame = indices.to_pandas()
    assert frame.shape == (2, 3) and frame["parameter"].tolist() == list(indices.parameters)
    assert frame.to_dict("records") == indices.table()
    doc = json.loads(json_text(indices.to_dict()))
    assert doc["schema"] == "railride.sensitivity/1" and doc["runs"] == indices.n_runs == 1 + 4 * (2 + 2)
    assert doc["settings"]["n"] == 4 and doc["suspension"] == "sas-attitude"
    assert len(doc["parameters"]) == len(indices.first_order) == len(indices.total) == 2  # zip stops at the shortest
    for row, s, t in zip(doc["parameters"], indices.first_order, indices.total):
        assert row["first_order"] == s and row["total"] == t


def test_the_sensitivity_plot_and_folder(indices, tmp_path, monkeypatch):
    mine = Figure()
    ax = mine.subplots()
    assert indices.plot(ax=ax) is mine and mine.get_axes() == [ax]
    assert len(ax.patches) == 2 * 2  # first-order and total bars per gain
    assert [t.get_text() for t in ax.get_yticklabels()] == list(indices.parameters)
    paths = indices.save(tmp_path / "out")
    assert [p.name for p in paths] == list(SENSITIVITY_FILES)
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "out" / "sobol.csv"), indices.to_pandas())
    import railride.plots.optimise

    monkeypatch.setattr(railride.plots.optimise, "plot_indices", _failing)
    before = {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()}
    with pytest.raises(OSError, match="simulated"):
        indices.save(tmp_path / "out")
    assert {p.name: p.read_bytes() for p in (tmp_path / "out").iterdir()} == before
    assert isinstance(indices, SensitivityResult)
