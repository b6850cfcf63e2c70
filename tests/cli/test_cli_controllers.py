"""`railride compare` and `railride sweep` with the semi-active laws beside the paper's:
--controllers all, the paper's four by default, bad names and bad gains (exit status 2)."""

from __future__ import annotations

import io
import re

import pandas as pd
import pytest

from railride.secondary.control import CONTROLLERS, OUTER_LOOPS, PAPER_CONTROLLERS, GainSet
from clihelp import assert_input_error, ok, ok_json, run

SHORT = ("compare", "--duration", 1)


def test_compare_all_runs_every_controller_in_order():
    doc = ok_json(*SHORT, "--controllers", "all")
    rows = {r["name"]: r for r in doc["controllers"]}
    assert list(rows) == list(CONTROLLERS)
    assert all(rows[n]["paper"] is None for n in CONTROLLERS[4:])  # not in the paper's Table 1
    assert all(rows[n]["paper"] is not None for n in PAPER_CONTROLLERS)
    assert rows["passive-on"]["damper"]["voltage_at_max_fraction"] == 1.0
    assert (
        doc["gains"]["passive-off"] is None
        and doc["gains"]["skyhook-on-off"] == GainSet.default().skyhook_on_off.to_dict()
    )
    for name in ("passive-on", "passive-off"):  # no reference, and the results say why
        assert doc["bounds"]["ideal"][name]["reduction_percent"]["roll_deg"] is None
        assert "constant voltage" in doc["bounds"]["ideal"][name]["note"]


def test_compare_without_controllers_is_the_papers_four():
    doc = ok_json(*SHORT)
    assert [r["name"] for r in doc["controllers"]] == list(PAPER_CONTROLLERS)


def test_compare_table_says_what_has_no_bound_and_what_did_not_run():
    text = ok(*SHORT, "--controllers", "skyhook,passive-on").stdout
    assert "Passive-on: no reference (MR dampers at a constant voltage" in " ".join(text.split())  # wrapped at 80
    text = ok(*SHORT, "--controllers", "all", "--damper", "ideal").stdout
    assert "passive-on: not run (MR dampers at a constant voltage" in text
    assert "Clipped-optimal" in text


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--controllers", "skyhook,lqr"), ("--controllers", "'lqr'", "clipped-optimal", "passive-off, or all")),
        (("--controllers", "skyhook,,hybrid"), ("--controllers", "empty item", "or all")),
    ],
)
def test_compare_refuses_unknown_names(args, fragments):
    assert_input_error(run(*SHORT, *args), *fragments)


@pytest.mark.parametrize(
    "pattern, value, fragments",
    [
        (r"alpha = [0-9.]+", "alpha = 1.5", ("[hybrid]", "'alpha' = 1.5", "[0, 1]")),
        (r"\nr = [0-9.]+", "\nr = 0.0", ("[clipped_optimal]", "'r' = 0.0", "> 0")),
        (r"qd_z = [0-9.]+", "qd_z = -3.0", ("[clipped_optimal]", "'qd_z' = -3.0", ">= 0")),
    ],
)
def test_compare_refuses_bad_new_gains(tmp_path, pattern, value, fragments):
    path = tmp_path / "gains.toml"
    path.write_text(re.sub(pattern, value, GainSet.default().to_toml(), count=1))
    assert_input_error(run(*SHORT, "--controllers", "hybrid", "--gains", path), "--gains", *fragments, str(path))


def test_sweep_all_runs_every_controller():
    text = ok("sweep", "--duration", 1, "--controllers", "all", "--format", "csv").stdout
    frame = pd.read_csv(io.StringIO(text))
    assert list(frame["suspension"]) == list(CONTROLLERS)
    assert frame["acceleration_m_s2_rms"].notna().all()


def test_sweep_refuses_unknown_names_and_ideal_passive_on():
    assert_input_error(run("sweep", "--controllers", "skyhook,lqr"), "'lqr'", *OUTER_LOOPS[-2:])
    assert_input_error(
        run("sweep", "--controllers", "passive-on", "--damper", "ideal"), "--damper", "passive-on", "constant voltage"
    )
