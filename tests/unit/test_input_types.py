"""Inputs at the edges of their types: NumPy scalars wherever Python numbers go, seeds that stay
whole numbers end to end, and integers too large for a float in the TOML files."""

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import railride as rr
from railride import dampers, validation
from railride.cli._parsing import value_list
from railride.secondary.control import PID, GainSet, SensorNoise
from railride.secondary.sensing import Accelerometers
from railride.studies.sweep import Case, grid
from railride.model.track import RandomTrack

NUMPY_TYPES = [np.int8, np.int16, np.int64, np.uint8, np.uint32, np.float16, np.float32, np.float64]


def _plain(value) -> bool:
    """Holds Python numbers only, all the way down: what JSON and the records need."""
    if isinstance(value, dict):
        return all(_plain(v) for v in value.values())
    if isinstance(value, (list, tuple)):
        return all(_plain(v) for v in value)
    return value is None or type(value) in (int, float, str, bool)


def _same(a, b) -> bool:
    """Equal, floats to the precision of the narrowest type given (float16: 1/50 is 0.0199966)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if type(a) is float and type(b) is float:
        return math.isclose(a, b, rel_tol=1e-3)
    return type(a) is type(b) and a == b


# Each entry point with a value given as the Python number ``x`` (small whole numbers that every
# NumPy type above holds exactly) and the record it makes, to compare with the same call on
# Python numbers.
ENTRY_POINTS = {
    "scenario speed": lambda t: rr.scenario("paper-sine", speed=t(40), duration=t(2)).describe(),
    "bump": lambda t: rr.scenario("bump", amplitude=t(1) / 50, wavelength=t(10)).describe(),
    "random track seed": lambda t: rr.scenario("fra4", seed=t(3), duration=t(1)).describe(),
    "solver": lambda t: rr.SolverSettings(dt=t(1) / 1000, output_rate=t(100), control_rate=t(100)).to_dict(),
    "vehicle field": lambda t: rr.VehicleParams.preset().replace(c_sz=t(100), l=t(9)).to_dict(),
    "vehicle load": lambda t: rr.VehicleParams.preset().loaded(t(2)).to_dict(),
    "gain table": lambda t: PID(kp=t(100), ki=t(0), kd=t(50)).to_dict(),
    "gain change": lambda t: GainSet.default().apply({"pid.kd": t(120)}).table("pid").to_dict(),
    "sensor noise": lambda t: SensorNoise(t(1) / 1000, t(0), t(0), t(0), seed=t(5)).__dict__,
    "accelerometers": lambda t: Accelerometers(noise=t(0), bias=t(0), seed=t(7)).to_dict(),
    "damper scale": lambda t: dampers.preset("railway").scaled(t(2)).to_dict(),
    "mr voltage": lambda t: rr.Suspension.semi_active(dampers.preset("railway"), voltage=t(1)).to_dict(),
    "named suspension": lambda t: rr.Suspension.named("mr", None, "railway", t(2), t(1)).to_dict(),
    "delay": lambda t: rr.Suspension.named("pid", GainSet.default(), "railway", 1.0, None).with_delay(t(2)).to_dict(),
    "sweep grid": lambda t: [
        c.to_dict()
        for c in grid(
            ["passive", "mr", "pid"],
            speed=[t(30)],
            voltage=[t(1)],
            damper_scale=[t(2)],
            gains={"pid.kp": [t(100)]},
            noise=[t(0)] * 4,
        ).cases
    ],
    "sweep grid seeds": lambda t: [
        c.to_dict() for c in grid(["pid"], scenario="fra4", track_seed=t(3), noise=[0.0] * 4, seed=[t(4)]).cases
    ],
}
# whole numbers only: a float type gives a float, which these refuse as they refuse 2.0
WHOLE_ONLY = {"delay"}


def _python(t):
    return int if np.issubdtype(t, np.integer) else float


@pytest.mark.parametrize("name", list(ENTRY_POINTS))
@pytest.mark.parametrize("numpy_type", NUMPY_TYPES, ids=lambda t: t.__name__)
def test_numpy_scalars_go_wherever_python_numbers_do(name, numpy_type):
    if name in WHOLE_ONLY and not np.issubdtype(numpy_type, np.integer):
        with pytest.raises(ValueError, match="whole number"):
            ENTRY_POINTS[name](numpy_type)
        return
    if numpy_type is np.float16 and name == "solver":
        pytest.skip("float16 holds 0.001 as 0.0010004, a step the output rate refuses, as it should")
    expected = ENTRY_POINTS[name](_python(numpy_type))
    record = ENTRY_POINTS[name](numpy_type)
    assert _same(record, expected), (record, expected)
    assert _plain(record), record
    json.dumps(record, allow_nan=False)  # no NumPy scalar left for JSON to choke on


def test_numpy_scalars_run_and_give_the_python_numbers_result():
    scen, solver = rr.scenario("paper-sine", speed=40.0, duration=1.0), rr.SolverSettings()
    ref = rr.simulate(scen, None, solver=solver).metrics().values
    res = rr.simulate(
        rr.scenario("paper-sine", speed=np.int64(40), duration=np.float32(1)),
        rr.VehicleParams.preset().replace(c_sz=np.float64(8e4)),
        solver=rr.SolverSettings(dt=np.float64(solver.dt)),
    )
    assert np.array_equal(res.metrics().values, ref)


@settings(max_examples=60, deadline=None)
@given(
    value=st.one_of(st.integers(-(2**70), 2**70), st.floats(allow_nan=True, allow_infinity=True)),
    kind=st.sampled_from(["python", "int64", "float32", "float64"]),
)
def test_number_rules_agree_on_python_and_numpy_numbers(value, kind):
    """A value passes `validation.number` as a Python number exactly when it passes as a NumPy
    scalar of a type that holds it, and either way comes back a Python float."""
    if kind == "int64":
        if not isinstance(value, int) or not -(2**63) <= value < 2**63:
            return
        given_value = np.int64(value)
    elif kind in ("float32", "float64"):
        with np.errstate(over="ignore"):
            given_value = getattr(np, kind)(value)
        value = float(given_value)
    else:
        given_value = value
    finite = math.isfinite(value) if isinstance(value, float) else abs(value) < 1.8e308
    if finite and value > 0:
        out = validation.number("x", given_value)
        assert type(out) is float and out == float(value)
    else:
        with pytest.raises(ValueError, match=r"^x = .*: must be a finite number > 0$"):
            validation.number("x", given_value)


@pytest.mark.parametrize("bad", [True, np.bool_(False), "40", [40.0]])
def test_bools_and_text_stay_refused(bad):
    with pytest.raises(ValueError, match="speed"):
        rr.scenario("paper-sine", speed=bad)


# -- seeds ------------------------------------------------------------------------------------
BIG = 9007199254740993  # 2**53 + 1: the first whole number a float64 cannot hold


def test_a_seed_past_2_53_is_not_rounded_anywhere():
    assert float(BIG) != BIG  # the premise: through a float it would become ...992
    assert value_list("--seed", f"{BIG},{BIG + 2}", integer=True) == [BIG, BIG + 2]
    assert value_list("--track-seed", f"{BIG}:{BIG + 4}:3", integer=True) == [BIG, BIG + 2, BIG + 4]
    assert SensorNoise(0.0, 0.0, 0.0, 0.0, seed=BIG).seed == BIG
    assert Accelerometers(seed=np.uint64(BIG)).seed == BIG
    assert rr.scenario("fra4", seed=BIG).track.seed == BIG
    g = grid(["passive", "pid"], scenario="fra4", track_seed=[BIG], noise=[0.0] * 4, seed=[BIG + 2])
    assert len(g.cases) == len(g.values) > 0  # zip would stop at the shorter
    for case, values in zip(g.cases, g.values):
        assert dict(case.scenario_options)["seed"] == BIG and values["track_seed"] == BIG
    pid = g.cases[-1]
    assert pid.seed == BIG + 2 and pid.to_suspension().sensor_noise.seed == BIG + 2
    record = json.loads(json.dumps(pid.to_dict()))
    assert record["seed"] == BIG + 2 and record["scenario_options"]["seed"] == BIG


def test_neighbouring_big_seeds_are_different_tracks():
    a, b = (RandomTrack("fra4", seed=s, length=200.0) for s in (BIG - 1, BIG))
    x = np.linspace(0.0, 100.0, 50)
    assert not np.array_equal(a.evaluate(x)[0], b.evaluate(x)[0])


def test_the_largest_seed_works_and_the_next_is_refused():
    top = 2**64 - 1
    assert rr.scenario("fra4", seed=top).track.seed == top
    assert RandomTrack("fra4", seed=np.uint64(top)).seed == top
    for bad in (2**64, 10**400, -1, 2.5, True, "3"):
        with pytest.raises(ValueError, match=r"seed = .*: must be a whole number >= 0 and <= 2\*\*64 - 1"):
            rr.scenario("fra4", seed=bad)
    with pytest.raises(ValueError, match=r"18446744073709551616 is too large; track seeds are at most 2\*\*64 - 1"):
        grid("passive", scenario="fra4", track_seed=[2**64])


def test_the_run_keys_of_seeded_cases_are_those_of_before():
    """Keys written before seeds stayed whole (the track seed as text, the noise seed an int):
    a run table of then still resumes. The values are the sha1 of those texts."""
    track = Case("fra4", (("seed", 3), ("speed", 30.0)))
    assert track.key == "3257e90addf495f3"
    noisy = Case("paper-sine", suspension="pid", noise=(0.001, 0.0, 0.0, 0.0), seed=np.int64(5))
    assert noisy.key == Case("paper-sine", suspension="pid", noise=(0.001, 0.0, 0.0, 0.0), seed=5).key
    assert type(noisy.seed) is int


# -- big integers in the TOML files --------------------------------------------------------------
HUGE = "1" * 400


def test_a_huge_integer_in_a_parameters_file_names_file_table_and_entry(tmp_path):
    path = tmp_path / "vehicle.toml"
    path.write_text(f'[vehicle]\npreset = "paper"\nc_sz = {HUGE}\n')
    with pytest.raises(ValueError) as err:
        rr.VehicleParams.load(path)
    msg = str(err.value)
    assert msg.startswith(f"{path}: [vehicle] ") and "'c_sz'" in msg and "1.111e+399" in msg
    assert "must be a finite number >= 0" in msg and HUGE not in msg
    full = rr.VehicleParams.preset().to_toml()  # every field listed, no preset
    start = full.index("\nm_c = ") + 1
    path.write_text(full[:start] + f"m_c = -{HUGE}" + full[full.index("\n", start) :])
    with pytest.raises(ValueError, match=r": \[vehicle\] vehicle parameter 'm_c' = -1.111e\+399 \(a 400-digit"):
        rr.VehicleParams.load(path)


def test_a_huge_integer_in_a_gains_file_names_file_table_and_entry(tmp_path):
    text = GainSet.default().to_toml()
    path = tmp_path / "gains.toml"
    for table, entry in (("pid", "kp"), ("inner", "G"), ("clipped_optimal", "r")):
        start = text.index(f"[{table}]")
        line = text.index(f"\n{entry} = ", start) + 1
        path.write_text(text[:line] + f"{entry} = {HUGE}" + text[text.index("\n", line) :])
        with pytest.raises(ValueError) as err:
            GainSet.load(path)
        msg = str(err.value)
        assert msg.startswith(f"{path}: [{table}] ") and f"'{entry}'" in msg and "1.111e+399" in msg, msg


def test_an_integer_past_pythons_digit_limit_is_a_toml_error(tmp_path):
    path = tmp_path / "v.toml"
    path.write_text(f'[vehicle]\npreset = "paper"\nc_sz = {"9" * 5000}\n')
    with pytest.raises(ValueError, match=rf"^{path}: not valid TOML: an integer with more than 4300 digits$"):
        rr.VehicleParams.load(path)
    with pytest.raises(ValueError, match=rf"^{path}: not valid TOML: an integer with more than 4300 digits$"):
        GainSet.load(path)


@pytest.mark.parametrize("command", ["simulate --params {p}", "compare --controllers pid --gains {g}"])
def test_the_cli_turns_a_huge_toml_integer_into_exit_2(tmp_path, command):
    import subprocess
    import sys

    p, g = tmp_path / "v.toml", tmp_path / "g.toml"
    p.write_text(f'[vehicle]\npreset = "paper"\nk_sz = {HUGE}\n')
    text = GainSet.default().to_toml()
    start = text.index("[pid]")
    line = text.index("\nkd = ", start) + 1
    g.write_text(text[:line] + f"kd = {HUGE}" + text[text.index("\n", line) :])
    args = command.format(p=p, g=g).split()
    run = subprocess.run([sys.executable, "-m", "railride", *args], capture_output=True, text=True, timeout=300)
    assert run.returncode == 2, run.stderr
    assert "Traceback" not in run.stderr and "OverflowError" not in run.stderr
    assert "1.111e+399" in run.stderr and HUGE not in run.stderr


# -- numbers in messages ---------------------------------------------------------------------------
@pytest.mark.parametrize(
    "value, shown",
    [
        (np.float32(0.1), "0.1"),
        (0.1 + 0.2, "0.3"),
        (2.25001, "2.25001"),  # what was typed, not rounded onto the limit
        (np.int64(-4), "-4"),
        (2**64, "18446744073709551616"),
        (10**400, "1e+400 (a 401-digit whole number)"),
        (-(3 * 10**50), "-3e+50 (a 51-digit whole number)"),
    ],
)
def test_numbers_in_messages(value, shown):
    assert validation.shown(value) == shown
