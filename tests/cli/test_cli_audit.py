"""Regression tests from a hostile-user audit of the command line: inputs that once ran with
another meaning, or failed only after the work."""

import pytest
from clihelp import assert_input_error, run


@pytest.mark.parametrize(
    "command",
    [
        ("study",),
        ("sweep", "--suspension", "passive", "--speed", "30"),
        ("tune", "--controllers", "pid"),
        ("design",),
        ("pareto",),
        ("simulate",),
        ("compare",),
    ],
    ids=lambda c: c[0],
)
def test_duration_0_is_refused_everywhere(command):
    # study once ran its default 10 s and recorded 0
    assert_input_error(run(*command, "--duration", "0"), "duration = 0.0", "> 0")


def test_a_slow_speed_runs_and_the_method_can_be_chosen():
    from clihelp import ok

    from railride.model.track import scenario
    from railride.run.checks import INTEGRATOR_RK4
    from railride.run.simulation import simulate

    # at 1 m/s the exact steps would need 1024 maps: "auto" takes RK4 instead of refusing
    ok("simulate", "--speed", "1", "--duration", "0.5")
    assert simulate(scenario("paper-sine", speed=1.0, duration=0.5)).dataset.attrs["integrator"] == INTEGRATOR_RK4
    assert simulate(scenario("paper-sine", duration=0.5)).dataset.attrs["integrator"] != INTEGRATOR_RK4
    assert_input_error(
        run("simulate", "--speed", "1", "--duration", "0.5", "--method", "exact"), "1024 step maps", "'rk4'"
    )
    assert_input_error(run("simulate", "--method", "euler"), "--method = 'euler'", "auto, rk4, exact")


@pytest.mark.parametrize(
    "option, value, fragment",
    [
        ("--duration", "1e308", "more than a run can count"),
        ("--speed", "1e-308", "memory"),
        ("--output-rate", "1e-308", "--output-rate = 1e-308"),
    ],
)
def test_extreme_values_are_input_errors_not_overflows(option, value, fragment):
    result = run("simulate", "--suspension", "mr", option, value)
    if option == "--speed":  # MR dampers at 1e-308 m/s: a run that stands still, or a clear refusal
        assert result.exit_code in (0, 2) and "bug in railride" not in result.stderr
        return
    assert_input_error(result, fragment)


BIG = "1" + "0" * 400  # a 401-digit count


@pytest.mark.parametrize(
    "args, fragment",
    [
        (("frf", "--fmax", "1e300", "--format", "json"), "--fmax = 1e+300 Hz: at most"),
        (("frf", "--points", BIG), "--points = 1e+400"),
        (("tracking", "--amplitude", "1e308", "--format", "json"), "--amplitude = 1e+308 N: at most"),
        (("damper", "--amplitude", "1e308", "--frequency", "1", "--voltage", "0"), "--amplitude = 1e+308 m: at most"),
        (("sweep", "--suspension", "passive", "--speed", f"20:80:{BIG}"), "--speed"),
        (("simulate", "--scenario", "fra4", "--min-wavelength", "1e-308"), "--min-wavelength"),
    ],
    ids=["frf fmax", "frf points", "tracking amplitude", "rig amplitude", "sweep count", "min wavelength"],
)
def test_values_at_the_extremes_are_one_error_line(args, fragment):
    # each once a traceback, an exit 0 with nan or inf, or JSON that could not be written
    assert_input_error(run(*args), fragment)


def test_a_full_or_closed_stdout_is_no_traceback():
    import subprocess
    import sys

    full = subprocess.run(
        [sys.executable, "-m", "railride.cli", "modes"],
        stdout=open("/dev/full", "w"),
        stderr=subprocess.PIPE,
        text=True,
    )
    assert full.returncode == 2 and full.stderr.strip() == "error: cannot write: No space left on device"
    closed = subprocess.run(
        [sys.executable, "-m", "railride.cli", "modes"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    assert closed.returncode == 0
    shut = subprocess.run(
        [sys.executable, "-c", "import os, runpy, sys; os.close(1); sys.argv = ['railride', 'modes']; "
         "runpy.run_module('railride.cli', run_name='__main__')"],
        stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert shut.returncode == 0 and "Traceback" not in shut.stderr, shut.stderr


def test_nested_and_endless_files_are_refused(tmp_path):
    deep = tmp_path / "deep.toml"
    deep.write_text("[vehicle]\nx = " + "[" * 5000 + "]" * 5000 + "\n")
    assert_input_error(run("simulate", "--vehicle", deep), "nested too deeply")
    assert_input_error(run("compare", "--gains", deep), "nested too deeply")
    assert_input_error(run("simulate", "--scenario", "file:/dev/zero"), "/dev/zero: not a regular file")


def test_the_api_takes_names_and_paths_and_names_a_wrong_type(tmp_path):
    from pathlib import Path

    import railride as rr
    from railride.errors import InputError

    assert rr.Vehicle("paper").params == rr.Vehicle().params
    track = tmp_path / "line.csv"
    track.write_text("s,z_L,z_R\n" + "".join(f"{s},0,0\n" for s in range(0, 1001, 2)))
    assert rr.scenario(Path(track), duration=1.0).name == f"file:{track}"
    for wrong in (None, 3):
        with pytest.raises(InputError, match="scenario = "):
            rr.scenario(wrong)
    with pytest.raises(InputError, match="params = 3"):
        rr.Vehicle(3)
