"""railride design --optimiser: the population optimiser beside the sensitivity study from the
command line, and a bad value refused with status 2 before any run."""

import pytest

from clihelp import assert_input_error, ok_json, run

TINY = ("design", "--controllers", "pid", "--track", "fra4", "--speed", "40", "--load", "1")
TINY += ("--train-seeds", "0", "--test-seeds", "1", "--duration", "1", "--budget", "13", "--values", "3")


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--optimiser", "cma-es"), ["--optimiser", "'cma-es'", "sensitivity, evolution"]),
        (("--optimiser", "evolution", "--budget", "10"), ["--budget", "evolution"]),
        (("--optimiser", "evolution", "--optimiser-seed", "-2"), ["--optimiser-seed"]),
    ],
)
def test_a_bad_optimiser_is_an_input_error(args, fragments, tmp_path):
    out = tmp_path / "d"
    assert_input_error(run(*TINY, *args, "--out", out), *fragments)
    assert not out.exists()


def test_design_by_evolution_records_and_prints_it():
    doc = ok_json(*TINY, "--optimiser", "evolution", "--optimiser-seed", "2")
    assert doc["settings"]["optimiser"]["name"] == "evolution" and doc["settings"]["optimiser"]["seed"] == 2
    assert doc["tuning"]["studies"][-1]["optimiser"] == "evolution"


@pytest.mark.slow  # two small designs of every law: about 35 s on 2 cores
def test_the_example_compares_the_optimisers_on_equal_budgets():
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    proc = subprocess.run(
        [sys.executable, "examples/optimisers.py", "--quick", "--controllers", "pid,skyhook"],
        cwd=root,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr
    for fragment in ("held-out score", "pid", "skyhook", "sensitivity  tuning", "evolution    tuning"):
        assert fragment in proc.stdout, fragment


def test_tune_takes_the_optimiser_too():
    assert_input_error(run("tune", "--optimiser", "annealing"), "--optimiser = 'annealing'", "sensitivity, evolution")
    doc = ok_json("tune", "--controllers", "skyhook", "--optimiser", "evolution", "--budget", "15", "--duration", "1")
    assert doc["settings"]["optimiser"]["name"] == "evolution" and doc["settings"]["optimiser"]["seed"] == 0
