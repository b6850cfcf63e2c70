"""What the command line's errors call things: each ideal device by its own name."""

from __future__ import annotations

import pytest

from clihelp import assert_input_error, run

from railride.errors import InputError
from railride.secondary import dampers
from railride.secondary.suspension import Suspension


@pytest.mark.parametrize(("name", "words"), [("ideal", "ideal actuator"), ("ideal-damper", "ideal semi-active damper")])
def test_each_ideal_device_is_named_as_itself(name, words):
    rig = ("--amplitude", "0.01", "--frequency", "1", "--voltage", "0")
    assert_input_error(run("damper", "--damper", name, *rig), "--damper", words)
    assert_input_error(run("compare", "--damper", name, "--damper-scale", "2"), words)
    with pytest.raises(InputError, match=words):
        dampers.preset(name).scaled(2.0)
    with pytest.raises(InputError, match=words):
        Suspension.named("mr", damper=name)


def test_an_fmu_path_that_is_a_folder_is_refused_before_any_work(tmp_path):
    folder = tmp_path / "car.fmu"
    folder.mkdir()
    assert_input_error(run("fmu", "--out", str(folder), "--sources-only"), "--out", "a folder")
    assert list(folder.iterdir()) == [] and sorted(p.name for p in tmp_path.iterdir()) == ["car.fmu"]


@pytest.mark.parametrize("command", ["tune", "design"])
def test_an_optimiser_seed_without_the_evolution_is_refused(command, tmp_path):
    extra = ("--out", str(tmp_path / "d")) if command == "design" else ()
    assert_input_error(run(command, "--optimiser-seed", "5", *extra), "--optimiser-seed = 5", "evolution")


def test_an_unknown_scenario_of_a_study_is_named_before_its_seeds():
    # the seeds' check had said that seeds apply to random tracks only, hiding the unknown name
    assert_input_error(run("study", "--scenario", "nope", "--track-seed", "0,1"), "--scenario = 'nope': unknown")


def test_a_choice_not_allowed_is_said_without_the_validators_prefix():
    result = run("simulate", "--format", "xml")
    assert_input_error(result, "--format = 'xml': 'xml' is not one of")
    assert "value error" not in result.stderr.lower()


@pytest.mark.parametrize(
    ("voltages", "said"),
    [
        ("passive-off,passive-off", "'passive-off' is listed twice"),
        ("0,passive-off", "'passive-off' is listed twice (as '0')"),
    ],
)
def test_a_voltage_given_twice_is_named_as_written(voltages, said):
    assert_input_error(run("sweep", "--suspension", "mr", "--voltage", voltages), "--voltage", said)


def test_a_delay_without_a_controller_rate_is_refused():
    # without --control-rate the loops act continuously: a delay in periods would be ignored
    assert_input_error(run("ride-spectrum", "--delay", "2"), "--delay = 2", "--control-rate")


def test_resume_in_a_folder_with_no_run_table_says_it_starts_afresh(tmp_path):
    # a mistyped folder would otherwise start a new study without a word
    out = tmp_path / "new"
    result = run(
        "sweep", "--suspension", "passive", "--speed", "40", "--duration", "0.05", "--out", str(out), "--resume"
    )
    assert result.exit_code == 0, result.output
    assert f"note: --resume: {out / 'runs.csv'} does not exist yet; starting afresh" in result.stderr
    again = run(
        "sweep", "--suspension", "passive", "--speed", "40", "--duration", "0.05", "--out", str(out), "--resume"
    )
    assert again.exit_code == 0 and "starting afresh" not in again.stderr
