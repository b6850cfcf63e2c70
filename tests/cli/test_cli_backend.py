"""`--backend auto|cpu|gpu` on every command that runs batches: a bad value or a GPU that is not
there is an input error before any run; with one (here numba's CUDA simulator, tests/conftest.py)
the runs step on it and say so in their record."""

import json
from pathlib import Path

import pytest
from clihelp import assert_input_error, ok_json, run

from railride.engine import gpu

COMMANDS = ("simulate", "compare", "report", "sweep", "study", "tune", "pareto", "design")


@pytest.mark.parametrize("command", COMMANDS)
def test_a_bad_backend_is_refused_naming_the_option(command, tmp_path):
    result = run(command, "--backend", "tpu", *(["--out", tmp_path / "o.html"] if command == "report" else []))
    assert_input_error(result, "--backend", "tpu", "auto, cpu, gpu")
    assert result.stdout == ""


@pytest.mark.parametrize("command", ("simulate", "compare", "sweep"))
def test_backend_gpu_without_a_gpu_is_refused_before_any_run(command, monkeypatch):
    monkeypatch.setattr(gpu, "why_not", lambda: "no CUDA GPU or driver was found")
    result = run(command, "--backend", "gpu")
    assert_input_error(result, "--backend = 'gpu'", "no CUDA GPU", "cpu")
    assert result.stdout == ""


@pytest.mark.skipif(gpu.why_not() is not None, reason="no GPU and no simulator")
def test_compare_on_the_gpu_matches_the_cpu_and_records_where_it_ran():
    common = ("compare", "--controllers", "sas-attitude,skyhook", "--duration", "0.02", "--window", "0:0.02")
    on_gpu = ok_json(*common, "--backend", "gpu")
    on_cpu = ok_json(*common, "--backend", "cpu")
    assert on_gpu["settings"]["backend"] == "gpu" and on_cpu["settings"]["backend"] == "cpu"
    jsonschema = pytest.importorskip("jsonschema")
    schema = Path(__file__).parents[2] / "docs" / "schemas" / "railride.comparison-1.json"
    jsonschema.validate(on_gpu, json.loads(schema.read_text(encoding="utf-8")))
    assert [c["name"] for c in on_gpu["controllers"]] == ["passive", "sas-attitude", "skyhook"]
    assert len(on_cpu["controllers"]) == len(on_gpu["controllers"])  # zip would drop a missing one
    for a, b in zip(on_gpu["controllers"], on_cpu["controllers"]):
        assert b["metrics"]  # the loop below checks something
        for response, stats in b["metrics"].items():
            for stat, value in stats.items():
                assert a["metrics"][response][stat] == pytest.approx(value, rel=1e-9), (b["name"], response, stat)


def test_studies_record_the_backend_and_resume_across_backends(tmp_path):
    out = tmp_path / "st"
    common = ("study", "--controllers", "pid", "--duration", "1", "--track-seed", "0", "--out", out)
    first = ok_json(*common)
    assert "backend" not in first["settings"]  # "auto", the default: records stay as they were
    again = ok_json(*common, "--backend", "cpu", "--resume")
    assert again["settings"]["backend"] == "cpu"
    assert again["runs_evaluated"] == 0  # the backend is not in the runs' keys: nothing ran again
