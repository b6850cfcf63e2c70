"""`--comfort` of `railride simulate`, `compare` and `sweep` (issue 6): the comfort indices in the
JSON documents, the tables, the sweep's columns and comfort.png; without the option the
documents do not change. Short runs on a random track (fra4) keep the file fast."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest

from railride.analysis.comfort import comfort_class
from railride.studies.sweep import COMFORT_COLUMNS
from clihelp import PNG, ok, run


TRACK = ("--scenario", "fra4", "--track-seed", 1, "--duration", 6)
POSITIONS = {"centre", "front", "rear"}
INDICES = ("aw_Wk", "vdv_Wk", "aw_Wb", "N_MV_z", "Wz")


def check_record(record: dict) -> None:
    assert set(record["positions"]) == POSITIONS
    for name, entry in record["positions"].items():
        for index in INDICES:
            assert math.isfinite(entry[index]) and entry[index] > 0, (name, index)
        assert entry["N_MV_z_class"] == comfort_class(entry["N_MV_z"])
    assert record["positions"]["centre"]["x_m"] == 0.0
    assert record["positions"]["front"]["x_m"] == -record["positions"]["rear"]["x_m"] > 0
    assert record["n_intervals"] == 1
    assert any("vertical" in note for note in record["notes"])
    assert any("1 interval of 5 s" in note for note in record["notes"])
    assert record["units"]["aw_Wk"] == "m/s^2"


@pytest.fixture(scope="module")
def simulate_docs():
    args = ("simulate", *TRACK, "--speed", 30, "--format", "json")
    return (json.loads(ok(*args).stdout), json.loads(ok(*args, "--comfort").stdout))


def test_simulate_comfort_json(simulate_docs):
    plain, doc = simulate_docs
    check_record(doc["comfort"])
    assert doc["comfort"]["window_s"] == [0.0, 6.0]
    # front and rear see the pitch as well: more than the centre on a random track
    pos = doc["comfort"]["positions"]
    assert pos["front"]["aw_Wk"] > pos["centre"]["aw_Wk"]
    # without --comfort the document is unchanged
    assert "comfort" not in plain
    assert {k: v for k, v in doc.items() if k != "comfort"} == plain


def test_simulate_comfort_table():
    out = ok("simulate", *TRACK, "--speed", 30, "--comfort").stdout
    assert "Ride comfort" in out and "N_MV,z" in out and "above the front" in out
    # EN 12299 classes N_MV from 60 intervals of 5 s; a short run's class is marked an indication
    assert "comfort class (N_MV,z)*" in out and "*: the class of an indicative N_MV,z" in " ".join(out.split())
    plain = ok("simulate", *TRACK, "--speed", 30).stdout
    assert "Ride comfort" not in plain


def test_compare_comfort():
    args = ("compare", *TRACK, "--speed", 30, "--controllers", "passive,pid", "--format", "json")
    plain = json.loads(ok(*args).stdout)
    doc = json.loads(ok(*args, "--comfort").stdout)
    assert [r["name"] for r in doc["controllers"]] == ["passive", "pid"]
    for row in doc["controllers"]:
        check_record(row["comfort"])
    passive, pid = (r["comfort"] for r in doc["controllers"])
    assert "reduction_percent" not in passive
    red = pid["reduction_percent"]["centre"]
    base, ctrl = passive["positions"]["centre"], pid["positions"]["centre"]
    assert red["N_MV_z"] == pytest.approx((base["N_MV_z"] - ctrl["N_MV_z"]) / base["N_MV_z"] * 100)
    assert "Wz" not in red
    assert len(plain["controllers"]) == 2 and all("comfort" not in r for r in plain["controllers"])
    strip = [{k: v for k, v in r.items() if k != "comfort"} for r in doc["controllers"]]
    assert strip == plain["controllers"]
    table = ok("compare", *TRACK, "--speed", 30, "--controllers", "pid", "--comfort").stdout
    assert "Ride comfort" in table and "front bogie" in table


def test_sweep_comfort(tmp_path):
    out = tmp_path / "sw"
    args = ("sweep", *TRACK, "--speed", "20:30:2", "--suspension", "passive,pid")
    ok(*args, "--comfort", "--out", out)
    assert (out / "comfort.png").read_bytes()[:8] == PNG
    assert (out / "sweep.png").exists()
    doc = json.loads((out / "sweep.json").read_text())
    for column in ("centre_aw_Wk", "centre_N_MV_z", "front_N_MV_z", "rear_N_MV_z", "centre_Wz"):
        assert column in doc["columns"]
        assert len(doc["rows"]) == 4 and all(math.isfinite(r[column]) and r[column] > 0 for r in doc["rows"])
    assert doc["settings"]["comfort"]["columns"] == list(COMFORT_COLUMNS)
    runs = pd.read_csv(out / "runs.csv", dtype={"key": str})
    assert set(COMFORT_COLUMNS) <= set(runs.columns) and len(runs) == 4
    # the same grid with --no-comfort: no comfort columns, no comfort.png
    plain_out = tmp_path / "plain"
    ok(*args, "--no-comfort", "--out", plain_out)
    plain = json.loads((plain_out / "sweep.json").read_text())
    assert not (plain_out / "comfort.png").exists()
    assert "comfort" not in plain["settings"]
    assert not set(COMFORT_COLUMNS) & set(plain["columns"])
    # the comfort setting is part of the run table's key: no row is shared between the two
    plain_runs = pd.read_csv(plain_out / "runs.csv", dtype={"key": str})
    assert set(plain_runs["key"]).isdisjoint(set(runs["key"].astype(str)))
    # the rows' RMS values do not depend on --comfort
    assert plain["rows"] and len(plain["rows"]) == len(doc["rows"])
    for a, b in zip(plain["rows"], doc["rows"]):
        assert a["acceleration_m_s2_rms"] == pytest.approx(b["acceleration_m_s2_rms"], rel=1e-12)


def test_a_window_shorter_than_an_interval_is_said_once_and_alike():
    """Shorter than EN 12299's 5 s: the index is from one interval, the whole signal, and the
    notes say so, not also "1 interval of 5 s"."""
    result = run("simulate", "--duration", "1", "--window", "0:0.5", "--comfort", "--format", "json")
    assert result.exit_code == 0, result.output
    notes = json.loads(result.stdout)["comfort"]["notes"]
    assert any("the whole signal" in note for note in notes) and not any("of 5 s" in n for n in notes)
