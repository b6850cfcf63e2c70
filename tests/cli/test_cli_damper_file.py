"""`--damper FILE.toml`: a user's own MR damper on the rig and in the vehicle commands. Its
parameters reach the physics (a rig cycle against the closed forms of a dashpot and of a
friction damper), a file of a preset's values runs that preset, and the gains warn when they
were tuned with another damper."""

from __future__ import annotations

import math

import pytest

from clihelp import assert_input_error, ok, ok_json, run

#: a Bouc-Wen damper with no hysteresis: F = (c0a + c0b u) x'
DASHPOT = """[damper]
model = "bouc-wen"
alpha_a = 0.0
alpha_b = 0.0
c0a = 5000.0
c0b = 2000.0
k0 = 0.0
A = 1.2
n = 1.0
gamma = 300.0
beta = 300.0
eta = 50.0
v_min = 0.0
v_max = 2.0
"""
RIG = ("--amplitude", 0.01, "--frequency", 1.5, "--cycles", 3)


def test_a_dashpot_file_dissipates_pi_c_omega_amplitude_squared(tmp_path):
    path = tmp_path / "dashpot.toml"
    path.write_text(DASHPOT)
    doc = ok_json("damper", "--damper", path, *RIG, "--voltage", "0,2")
    omega, amplitude = 2 * math.pi * 1.5, 0.01
    for cycle, c in zip(doc["cycles"], (5000.0, 9000.0)):
        assert cycle["energy_per_cycle_j"] == pytest.approx(math.pi * c * omega * amplitude**2, rel=1e-3)
        assert cycle["force_max_n"] == pytest.approx(c * omega * amplitude, rel=1e-3)
    assert doc["damper"]["preset"] is None and doc["damper"]["c0b"] == 2000.0


def test_a_friction_file_dissipates_four_times_yield_force_times_amplitude(tmp_path):
    # hysteresis only, saturating within 0.1 mm of a 10 mm stroke: the loop is nearly the
    # rectangle of a friction damper, yield force alpha z_bound = alpha A / (gamma + beta)
    path = tmp_path / "friction.toml"
    path.write_text(
        DASHPOT.replace("alpha_a = 0.0", "alpha_a = 5.0e7")
        .replace("c0a = 5000.0", "c0a = 0.0")
        .replace("c0b = 2000.0", "c0b = 0.0")
        .replace("gamma = 300.0", "gamma = 6000.0")
        .replace("beta = 300.0", "beta = 6000.0")
    )
    doc = ok_json("damper", "--damper", path, *RIG, "--voltage", "0")
    yield_force = 5.0e7 * 1.2 / 12000.0
    assert doc["cycles"][0]["force_max_n"] == pytest.approx(yield_force, rel=1e-3)
    # the reversals take the loop's corners off: less than the rectangle, by about z_bound / A / stroke
    energy = doc["cycles"][0]["energy_per_cycle_j"]
    assert 0.97 * 4 * yield_force * 0.01 < energy < 4 * yield_force * 0.01


def test_a_file_of_a_presets_values_runs_that_preset_without_a_warning(tmp_path):
    from railride.secondary import damper_file, dampers

    path = tmp_path / "mine.toml"
    damper_file.save(dampers.RAILWAY, path)
    args = ("compare", "--controllers", "pid", "--duration", 0.3, "--no-references")
    named, filed = ok_json(*args), ok_json(*args, "--damper", path)
    assert [c["metrics"] for c in filed["controllers"]] == [c["metrics"] for c in named["controllers"]]
    assert "gains_mismatch" not in filed["settings"]
    result = ok(*args, "--damper", path)
    assert "warning" not in result.stderr


def test_another_damper_file_warns_and_is_recorded_whole(tmp_path):
    path = tmp_path / "strong.toml"
    path.write_text('[damper]\npreset = "railway"\nalpha_b = 5.0e6\n')
    args = ("compare", "--controllers", "pid", "--duration", 0.3, "--no-references", "--damper", path)
    result = ok(*args)
    warnings = [line for line in result.stderr.splitlines() if line.startswith("warning: ")]
    assert len(warnings) == 1 and "damper bouc-wen (own parameters) (the gains' damper: railway" in warnings[0]
    assert "other values: alpha_b 5e+06 against 3.969e+06" in warnings[0]
    assert f"railride tune --damper {path}" in warnings[0]  # the file given, where the library says FILE.toml
    assert "bouc-wen (own parameters) MR dampers" in result.stdout
    settings = ok_json(*args)["settings"]
    assert settings["damper"]["alpha_b"] == 5.0e6 and settings["damper"]["preset"] is None
    # the stronger field makes another ride than the railway preset's
    plain = ok_json("compare", "--controllers", "pid", "--duration", 0.3, "--no-references")
    ran = ok_json(*args)["controllers"]
    assert ran[0]["metrics"] == plain["controllers"][0]["metrics"]  # passive: no MR damper in it
    assert ran[1]["metrics"] != plain["controllers"][1]["metrics"]
    # study's caption names it in words, not as a Python record
    study = ok("study", "--controllers", "pid", "--duration", 0.2, "--track-seed", "0", "--damper", path)
    assert "bouc-wen (own parameters) dampers" in " ".join(study.stdout.split()) and "{'model'" not in study.stdout


@pytest.mark.parametrize(
    "command",
    [
        ("compare", "--duration", 0.2),
        ("simulate", "--suspension", "mr", "--duration", 0.2),
        ("tune", "--controllers", "pid"),
        ("study", "--controllers", "pid"),
        ("sweep", "--suspension", "mr"),
        ("damper", *RIG, "--voltage", 0),
        ("tracking",),
    ],
)
def test_a_bad_damper_file_is_one_line_naming_the_file_and_key(command, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('[damper]\npreset = "railway"\neta = -1.0\n')
    assert_input_error(run(*command, "--damper", path), f"{path}: [damper]", "eta")
    assert_input_error(run(*command, "--damper", tmp_path / "gone.toml"), "--damper = ", "no such damper file")


def test_simulate_records_the_files_every_parameter_and_says_own(tmp_path):
    path = tmp_path / "strong.toml"
    path.write_text('[damper]\npreset = "railway"\nalpha_b = 5.0e6\n')
    args = ("simulate", "--suspension", "mr", "--voltage", 1, "--duration", 0.2, "--damper", path)
    record = ok_json(*args)["suspension"]["damper"]
    assert record["preset"] is None and record["alpha_b"] == 5.0e6 and record["model"] == "bouc-wen"
    assert "MR, bouc-wen (own parameters) dampers at 1 V" in " ".join(ok(*args).stdout.split())
    assert ok_json("simulate", "--suspension", "mr", "--duration", 0.2)["suspension"]["damper"] == "railway"
