"""`railride pareto`: the result folder, the JSON and table outputs, resume, bad input."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from clihelp import assert_input_error, ok, run

PARETO = ("pareto", "--suspension", "pid", "--samples", 4, "--duration", 1)


def test_pareto_folder_json_and_resume(tmp_path):
    out = tmp_path / "p"
    doc = json.loads(ok(*PARETO, "--seed", 2, "--out", out, "--format", "json").stdout)
    names = ["pareto.csv", "pareto.json", "pareto.png", "pareto_caption.txt", "runs.csv"]
    assert sorted(p.name for p in out.iterdir()) == names
    assert json.loads((out / "pareto.json").read_text()) == doc
    assert doc["schema"] == "railride.pareto/1" and doc["suspension"] == "pid"
    assert doc["settings"]["n_samples"] == 4 and doc["settings"]["seed"] == 2
    assert doc["counts"]["samples"] == 5 and doc["runs"] == 6  # and the passive run
    frame = pd.read_csv(out / "pareto.csv")
    assert list(frame.columns) == doc["columns"] and len(frame) == 5
    assert frame["non_dominated"].sum() == doc["counts"]["non_dominated"] >= 1
    again = json.loads(ok(*PARETO, "--seed", 2, "--out", out, "--resume", "--format", "json").stdout)
    assert again["samples"] == doc["samples"]
    runs = pd.read_csv(out / "runs.csv")
    assert len(runs) == 6  # nothing ran twice
    assert set(runs["vehicle"]) == {"paper"} and set(runs["load"]) == {1.0}  # the vehicle of every run
    assert_input_error(run(*PARETO, "--out", out), "runs.csv exists", "--resume")


def test_pareto_table_lists_the_non_dominated_samples_by_acceleration():
    doc = json.loads(ok(*PARETO, "--format", "json").stdout)
    table = ok(*PARETO).stdout
    assert "non-dominated" in table and "Non-dominated samples by acceleration ratio" in table
    front = sorted((r for r in doc["samples"] if r["non_dominated"]), key=lambda r: r["acceleration_m_s2_ratio"])
    lines = [line for line in table.splitlines() if line.startswith("│")]
    listed = [line.split("│")[1].split()[0] for line in lines[1:]]  # after the counts row
    assert listed == [str(r["sample"]) for r in front]
    # more than half of the samples on the four-ratio front: the table says it is thinly sampled
    c = doc["counts"]
    said = f"{c['non_dominated']} of {c['samples']} samples are non-dominated over the four ratios"
    assert (said in " ".join(table.split())) == (2 * c["non_dominated"] > c["samples"])


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--samples", "100"), ("--samples = 100", "power of two")),
        (("--samples", "0"), ("--samples = 0",)),
        (("--seed", "-1"), ("--seed = -1",)),
        (("--suspension", "passive"), ("--suspension", "'passive'", "sas-attitude-ride")),
        (("--damper", "mr9"), ("--damper", "mr9")),
        (("--resume",), ("--resume needs --out",)),
        (("--track-seed", "2"), ("--track-seed", "random-track")),
    ],
)
def test_pareto_bad_input(args, fragments):
    assert_input_error(run(*PARETO, *args), *fragments)
