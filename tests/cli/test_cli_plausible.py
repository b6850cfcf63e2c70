"""Plausible vehicle and controller inputs on the command line: absurd values exit 2 with one
line, unusual vehicles print a warning on stderr beside their result, `modes` never prints inf
or NaN (its JSON neither)."""

import json
import re

import pytest

from railride.secondary.control import GainSet

from clihelp import assert_input_error, run


def strict_json(text: str):
    """JSON without the Infinity and NaN that Python writes and other readers refuse."""

    def refuse(name):
        raise AssertionError(f"{name} in JSON")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture
def vehicle(tmp_path):
    def write(**changes) -> str:
        path = tmp_path / "car.toml"
        lines = ["[vehicle]", 'preset = "paper"', *(f"{k} = {v}" for k, v in changes.items())]
        path.write_text("\n".join(lines) + "\n")
        return str(path)

    return write


@pytest.mark.parametrize("fmt", ["table", "json"])
@pytest.mark.parametrize("field, value", [("m_b", "1e-300"), ("k_sz", "1e300"), ("k_pz", "1e12"), ("b", "20.0")])
def test_modes_refuses_an_absurd_vehicle(vehicle, fmt, field, value):
    result = run("modes", "--params", vehicle(**{field: value}), "--format", fmt)
    assert_input_error(result, f"'{field}' = ")


def test_modes_of_an_unusual_vehicle_are_finite_json_with_a_warning(vehicle):
    result = run("modes", "--params", vehicle(m_c="1e6", I_cy="1e9"), "--format", "json")
    assert result.exit_code == 0, result.stderr
    rows = strict_json(result.stdout)["modes"]
    assert len(rows) == 9 and all(r["damping_ratio"] >= 0 for r in rows)
    warnings = result.stderr.strip().splitlines()
    assert len(warnings) == 2 and all(line.startswith("warning: vehicle parameter ") for line in warnings)
    assert "'m_c' = 1000000.0 kg" in warnings[0] and "'I_cy' = 1e+09" in warnings[1]


def test_modes_beyond_double_precision_exit_2(vehicle):
    result = run("modes", "--params", vehicle(m_b="1e-3", I_by="1e-6", I_bx="1e-6", k_pz="1e11"), "--format", "json")
    assert result.exit_code == 2 and result.stdout == ""
    assert "error: the modes of this vehicle cannot be computed in double precision" in result.stderr


def test_frf_records_the_warning_in_its_document(vehicle, tmp_path):
    result = run("frf", "--params", vehicle(m_c="1e6"), "--points", 3, "--out", tmp_path / "frf")
    assert result.exit_code == 0, result.stderr
    assert "warning: vehicle parameter 'm_c'" in result.stderr
    doc = strict_json((tmp_path / "frf" / "frf.json").read_text())
    assert doc["warnings"] and "'m_c'" in doc["warnings"][0]


def test_the_step_size_message_of_a_stiff_vehicle(vehicle):
    result = run("simulate", "--params", vehicle(k_pz="1e11", m_b="1.0", I_by="1e-2"), "--suspension", "mr")
    assert result.exit_code == 2
    error = [line for line in result.stderr.splitlines() if line.startswith("error: ")]
    assert len(error) == 1 and "use --dt <= " in error[0] and "<= 0 s" not in error[0]
    numbers = re.findall(r"\d[\d.]*(?:e[+-]?\d+)?", error[0])
    assert numbers  # the loop below checks something
    for number in numbers:
        assert len(number.split("e")[0].replace(".", "").lstrip("0")) <= 4, error[0]


@pytest.mark.parametrize(
    "args, fragment",
    [
        (("--sensor-noise", "1e300,0,0,0"), "'displacement' = 1e+300"),
        (("--sensor-noise", "0,0,0,5"), "'angular_rate' = 5.0"),
        (("--damper-scale", "1e6"), "1000000.0"),
    ],
)
def test_compare_refuses_absurd_controller_inputs(args, fragment):
    assert_input_error(run("compare", "--controllers", "pid", "--duration", "0.5", *args), fragment)


@pytest.mark.parametrize("entry, value", [("kp", "1e300"), ("kp", "inf"), ("G", "1e9")])
def test_gains_files_refuse_absurd_gains(tmp_path, entry, value):
    text = GainSet.default().to_toml()
    path = tmp_path / "gains.toml"
    path.write_text(re.sub(rf"\n{entry} = [0-9.e+]+", f"\n{entry} = {value}", text, count=1))
    assert_input_error(run("compare", "--gains", path, "--duration", "0.5"), f"'{entry}' = ")
