"""A study records the gains it ran (docs/study.md, The gains): their source as far as it is
still true, their [provenance] (how they were found) and every value per controller, in
study.json (`settings`) and as columns of study_runs.csv; `league` records the same."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest

import railride as rr
from railride.secondary.control import GainSet
from railride.studies.league import league

pytest.importorskip("jsonschema")

from tuned_gains import PROVENANCE, TUNED_KP, as_validated_json, packaged, pid_values, tuned_gains  # noqa: E402

SHORT = {"track_seeds": [0], "speeds": [40.0], "duration": 0.5}


@pytest.fixture(scope="module")
def tuned() -> GainSet:
    return tuned_gains("tuned.toml")


def test_a_study_with_tuned_gains_records_their_values_and_provenance(tuned, tmp_path):
    result = rr.study(["pid"], gains=tuned, **SHORT)
    s = result.settings
    assert s["gains"] == "tuned.toml"  # not the file the tuning started from
    assert s["gains_provenance"] == PROVENANCE
    expected = pid_values(packaged("gains.toml"), **{"pid.kp": TUNED_KP})
    assert s["gains_values"] == {"passive": {}, "pid": expected}

    result.save(tmp_path)
    doc = json.loads((tmp_path / "study.json").read_text(encoding="utf-8"))
    as_validated_json(doc, "railride.study-1")
    assert doc["settings"]["gains_provenance"] == PROVENANCE
    assert doc["settings"]["gains_values"]["pid"] == expected
    runs = pd.read_csv(tmp_path / "study_runs.csv")
    pid, passive = runs[runs["controller"] == "pid"], runs[runs["controller"] == "passive"]
    assert len(pid) == 1 and len(passive) == 1
    for entry, value in expected.items():
        column = "gain_" + entry.replace(".", "_")
        assert pid[column].tolist() == [value], column
        assert passive[column].isna().all(), column  # passive reads no gains
    assert {c for c in runs.columns if c.startswith("gain_")} == {"gain_" + e.replace(".", "_") for e in expected}


def test_a_study_with_the_shipped_gains_says_so():
    # random track: the shipped robust set (docs/tuning.md, Shipped gains)
    result = rr.study(["pid"], **SHORT)
    data = packaged("robust_gains.toml")
    s = result.settings
    assert s["gains"] == "railride/data/robust_gains.toml"
    assert s["gains_values"]["pid"] == pid_values(data)
    provenance = s["gains_provenance"]
    assert provenance["method"] == data["provenance"]["method"]
    assert provenance["controllers"] == data["provenance"]["controllers"]
    json.dumps(result.to_dict(), allow_nan=False)  # every value of the provenance is JSON's


def test_changed_gains_never_keep_their_file_as_the_whole_source():
    # `GainSet.apply` keeps the source: the record says the values are not that file's
    changed = GainSet.default().apply({"pid.kp": TUNED_KP, "inner.G": 0.002})
    record = changed.record(["pid"])
    assert record["source"] == "railride/data/gains.toml, changed: inner.G, pid.kp"
    assert record["provenance"] is None  # other gains: the file's provenance is not theirs
    assert GainSet.default().record(["pid"])["source"] == "railride/data/gains.toml"


@pytest.mark.filterwarnings("ignore::railride.errors.TuningWarning")  # the inner loop left as it starts
def test_the_gains_tune_returns_carry_their_provenance():
    res = rr.tune(["pid"], budget=5, n_values=3, scenario_options={"duration": 0.5}, before_after=False)
    gains = res.gains
    assert gains.source != res.start.source == "railride/data/reference_gains.toml"
    assert gains.provenance["controllers"] == ["pid"]
    assert gains.provenance["start_gains"] == "railride/data/reference_gains.toml"
    # the gains file still holds one [provenance], the same one
    back = GainSet.from_toml(res.gains_toml(), source="tuned.toml")
    assert back.provenance == gains.provenance
    assert back.entries() == gains.entries()
    study = rr.study(["pid"], scenario="paper-sine", duration=0.5, gains=gains)
    assert study.settings["gains"] == gains.source
    assert study.settings["gains_provenance"]["start_gains"] == "railride/data/reference_gains.toml"
    assert study.settings["gains_values"]["pid"]["pid.kp"] == gains.value("pid.kp")


def test_a_league_records_the_gains_it_ran(tuned):
    table = league(["paper-sine"], [40.0], controllers=["passive", "pid"], gains=tuned, duration=0.5)
    s = table.settings
    assert s["gains"] == "tuned.toml"
    assert s["gains_provenance"] == PROVENANCE
    assert s["gains_values"]["pid"] == pid_values(packaged("gains.toml"), **{"pid.kp": TUNED_KP})
    as_validated_json(table.to_dict(), "railride.league-1")
    assert not math.isnan(table.summary.loc["pid", "acceleration_m_s2_rms"])
