"""railride design: which law, tuned on training seeds and judged on held-out seeds, from the
command line: the tables, the JSON document, the result folder, resuming, and bad input."""

import json

import pandas as pd
import pytest

from railride.output.files import DESIGN_FILES

from clihelp import PNG, assert_input_error, ok, ok_json, run

TINY = (
    "design",
    "--controllers",
    "pid,skyhook",
    "--track",
    "fra4",
    "--speed",
    "40",
    "--load",
    "1",
    "--train-seeds",
    "0",
    "--test-seeds",
    "1",
    "--duration",
    "2",
    "--budget",
    "13",
    "--values",
    "3",
)


def test_design_table_and_json():
    text = " ".join(ok(*TINY).stdout.split())
    for fragment in ("Held out: RMS ratio to passive", "What each law asks of its dampers", "Ranking", "Recommended:"):
        assert fragment in text, fragment
    doc = ok_json(*TINY)
    assert doc["schema"] == "railride.design/1"
    assert doc["recommendation"]["controller"] in ("pid", "skyhook")
    assert doc["settings"]["train_seeds"] == [0] and doc["settings"]["test_seeds"] == [1]
    assert doc["command"].startswith("railride design --controllers pid,skyhook")


def test_design_out_and_resume(tmp_path):
    out = tmp_path / "d"
    first = ok_json(*TINY, "--out", out)
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted([*DESIGN_FILES, "runs.csv"])  # the files of the result, and the run table
    assert (out / "design_costs.png").read_bytes().startswith(PNG)
    assert (out / "design.png").read_bytes().startswith(PNG)
    assert json.loads((out / "design.json").read_text())["ranking"] == first["ranking"]
    assert len(pd.read_csv(out / "design_runs.csv")) == 3
    again = ok_json(*TINY, "--out", out, "--resume")
    assert again["runs_evaluated"] == 0 and again["results"] == first["results"]


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--speed", ""), ("--speed",)),
        (("--test-seeds", "0,7"), ("--test-seeds = [0, 7]", "also in --train-seeds")),
        (("--budget", "5"), ("--budget = 5", "try every gain once")),
        (("--controllers", "lqr"), ("--controllers = 'lqr'",)),
        (("--track", "fra9"), ("--track = 'fra9'",)),
        (("--objective", "comfy"), ("--objective = 'comfy'", "n_mv, sperling")),
        (("--max-travel", "0"), ("--max-travel = 0.0", ">= 1e-06")),
        (("--max-peak", "x"), ("--max-peak",)),
        (("--report", "/dev/null/r.html"), ("--report",)),
        (("--resume",), ("--resume needs --out",)),
    ],
)
def test_design_bad_input(args, fragments):
    assert_input_error(run(*TINY, *args), *fragments)


def test_design_on_comfort_with_a_travel_bound_and_a_report(tmp_path):
    """A comfort objective and a bound reach the tuning, the ranking and the words; the report
    holds the recommendation and both figures; the ideal devices' scores and the fault are in the
    document."""
    report = tmp_path / "d.html"
    doc = ok_json(*TINY, "--objective", "n_mv", "--max-travel", "0.05", "--report", report)
    objective = doc["settings"]["objective"]
    assert objective["kind"] == "n_mv" and objective["travel_bound_m"] == 0.05
    assert "N_MV,z ratio to passive over the floor points" in doc["recommendation"]["text"]
    assert "travel <= 50 mm" in doc["recommendation"]["text"]
    assert set(doc["references"]) == {"ideal", "ideal-damper"}
    assert doc["fault"]["fault"] == "1R-off" and "1R-off" in doc["recommendation"]["text"]
    html = report.read_text()
    assert "Recommended:" in html and html.count("<img") + html.count("plotly") >= 2
