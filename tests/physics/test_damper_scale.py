"""The damper's force capacity scale: `BoucWen.scaled` / `Spencer.scaled`, `Case.damper_scale`,
`compare(damper_scale=)` and `--damper-scale`."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from railride import dampers

from railride.run import rig
from railride.studies.comparison import compare
from railride.run.simulation import simulate
from railride.secondary.suspension import Suspension
from railride.studies.sweep import Case, run_cases
from railride.model.track import scenario
from clihelp import assert_input_error, run

SHORT = {"duration": 1.0}


# -- the model ----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["railway", "dyke1996", "spencer1997"])
@pytest.mark.parametrize("factor", [4.0, 0.3])
def test_scaled_damper_gives_factor_times_the_force_on_the_rig(name, factor):
    """For the same prescribed motion and voltage every force term scales and the internal
    states (z, y, u) do not move differently: F exactly factor times, to rounding."""
    base = dampers.preset(name)
    motion = rig.SineMotion(0.015, 2.5)
    volts = [0.0, 1.0, 2.25]
    a = rig.drive(base, motion, duration=1.0, voltage=volts)
    b = rig.drive(base.scaled(factor), motion, duration=1.0, voltage=volts)
    F = a["F"].values
    assert np.abs(F).max() > 100.0
    np.testing.assert_allclose(b["F"].values, factor * F, rtol=0, atol=1e-9 * np.abs(F).max())
    np.testing.assert_allclose(b["E"].values, factor * a["E"].values, rtol=0, atol=1e-9 * np.abs(a["E"].values).max())
    for state in ("z", "y", "u"):
        np.testing.assert_allclose(
            b[state].values, a[state].values, rtol=0, atol=1e-9 * max(np.abs(a[state].values).max(), 1e-30)
        )


def test_scaled_damper_tracks_a_scaled_demand_with_the_inverse_gain():
    """The inner loop v = clip(G (f_d - B F) sgn F) sees the same voltage when f_d and F are
    factor times larger and G is divided by factor: the tracked force scales exactly."""
    base, factor = dampers.preset("railway"), 3.0
    a = rig.track(base, "sine", amplitude=8e3, frequency=1.0, G=1e-3)
    b = rig.track(base.scaled(factor), "sine", amplitude=factor * 8e3, frequency=1.0, G=1e-3 / factor)
    Fa, Fb = a.dataset["F"].values, b.dataset["F"].values
    np.testing.assert_allclose(Fb, factor * Fa, rtol=0, atol=1e-9 * np.abs(Fa).max())


def test_scaled_multiplies_the_force_parameters_and_nothing_else():
    spencer = dampers.preset("spencer1997")
    scaled = spencer.scaled(2.5)
    force = {"alpha_a", "alpha_b", "c0a", "c0b", "k0", "c1a", "c1b", "k1"}
    assert force <= {f[0] for f in spencer.describe()}  # the loop below reaches every force parameter
    for f in spencer.describe():
        name = f[0]
        want = 2.5 * getattr(spencer, name) if name in force else getattr(spencer, name)
        assert getattr(scaled, name) == want, name
    assert type(scaled) is dampers.Spencer and scaled.to_dict()["preset"] is None
    # the railway preset is the published small-scale damper times 8 (docs/dampers.md, Presets)
    railway, dyke = dampers.preset("railway"), dampers.preset("dyke1996")
    assert railway.alpha_a == 8 * 1.0872e5 and railway.c0b == 8 * 44.0 and railway.A == dyke.A


@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf, True, "2"])
def test_scaled_refuses_a_factor_that_is_not_a_positive_number(bad):
    with pytest.raises(ValueError, match="factor = .*finite number > 0"):
        dampers.preset("railway").scaled(bad)


# -- in the vehicle, compare and the sweep ------------------------------------------------------
def test_compare_records_the_scale_and_checks_it():
    sc = scenario("paper-sine", duration=0.5)
    res = compare(sc, controllers=["sas-attitude"], damper_scale=2.0)
    assert res.settings["damper"] == "railway" and res.settings["damper_scale"] == 2.0
    damper = json.loads(res.datasets["sas-attitude"].attrs["damper"])
    assert damper["alpha_a"] == 2.0 * dampers.preset("railway").alpha_a
    for bad in (0.0, -1.0, math.nan):
        with pytest.raises(ValueError, match="damper_scale"):
            compare(sc, controllers=["sas-attitude"], damper_scale=bad)


def test_case_scale_is_part_of_the_key_and_the_group():
    a = Case(scenario_options=SHORT, suspension="pid")
    b = Case(scenario_options=SHORT, suspension="pid", damper_scale=1)
    c = Case(scenario_options=SHORT, suspension="pid", damper_scale=2.0)
    assert a.key == b.key != c.key
    assert a.group != c.group
    # unscaled cases keep the keys they had before the field existed
    assert "damper_scale" not in a.to_dict() and c.to_dict()["damper_scale"] == 2.0
    passive = Case(scenario_options=SHORT)
    assert passive.group == Case(scenario_options=SHORT, damper="dyke1996").group


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"suspension": "pid", "damper_scale": 0.0}, "damper_scale = 0.*> 0"),
        ({"suspension": "pid", "damper_scale": -1.0}, "damper_scale = -1"),
        ({"suspension": "mr", "damper_scale": math.nan}, "damper_scale = nan"),
        ({"suspension": "passive", "damper_scale": 2.0}, "damper_scale = 2: the passive"),
        ({"suspension": "pid", "damper": "ideal", "damper_scale": 2.0}, "damper_scale = 2: the ideal"),
        ({"suspension": "mr", "damper": "ideal"}, "ideal.*mr"),
        ({"suspension": "pid", "damper": "mr9"}, "unknown damper model 'mr9'"),
    ],
)
def test_case_refuses_a_meaningless_scale(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Case(**kwargs)


def test_run_cases_runs_the_scaled_damper():
    cases = [Case(scenario_options=SHORT, suspension="mr", voltage=1.0, damper_scale=x) for x in (1.0, 2.0)]
    rows = run_cases(cases)
    assert list(rows["damper_scale"]) == [1.0, 2.0]
    direct = simulate(
        scenario("paper-sine", **SHORT),
        suspension=Suspension.semi_active(dampers.preset("railway").scaled(2.0), voltage=1.0),
    ).metrics()
    got = rows.iloc[1]["acceleration_m_s2_rms"]
    assert got == pytest.approx(float(direct.sel(response="acceleration_m_s2", statistic="rms")), rel=1e-12)
    assert got != pytest.approx(rows.iloc[0]["acceleration_m_s2_rms"], rel=1e-3)


# -- the command line -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "command", [("compare",), ("simulate", "--suspension", "mr"), ("sweep", "--suspension", "pid")]
)
@pytest.mark.parametrize("value", ["-1", "0", "nan", "inf"])
def test_cli_damper_scale_must_be_a_positive_number(command, value):
    result = run(*command, "--damper-scale", value)
    if command[0] == "sweep" and value in ("nan", "inf"):  # the list parser's word, as for every axis
        assert_input_error(result, f"error: --damper-scale = '{value}': '{value}' is not a finite number")
    else:
        assert_input_error(result, f"error: --damper-scale = {value}: must be a finite number > 0")


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("simulate", "--damper-scale", 2), ("--damper-scale applies to --suspension mr only",)),
        (("sweep", "--damper-scale", "1,2"), ("--damper-scale = '1,2'", "mr and the controllers")),
        (("sweep", "--suspension", "pid", "--damper-scale", "1,2,1"), ("1 is listed twice",)),
        (("sweep", "--suspension", "pid", "--damper-scale", "1,x"), ("'x' is not a number",)),
    ],
)
def test_cli_damper_scale_where_it_does_not_apply(args, fragments):
    assert_input_error(run(*args), *fragments)


def test_cli_simulate_and_compare_record_the_scale():
    result = run(
        "simulate", "--suspension", "mr", "--damper-scale", 2, "--voltage", 1, "--duration", 0.5, "--format", "json"
    )
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout)["suspension"] == {
        "type": "mr",
        "damper": "railway",
        "voltage_v": 1.0,
        "damper_scale": 2.0,
    }
    table = run("simulate", "--suspension", "mr", "--damper-scale", 2, "--duration", 0.5)
    assert "force x 2" in table.stdout
    result = run("compare", "--controllers", "pid", "--damper-scale", 0.5, "--duration", 0.5, "--format", "json")
    assert result.exit_code == 0, result.stderr
    assert json.loads(result.stdout)["settings"]["damper_scale"] == 0.5


def test_cli_sweep_over_the_damper_scale(tmp_path):
    out = tmp_path / "s"
    result = run(
        "sweep",
        "--suspension",
        "sas-attitude,passive,mr",
        "--damper-scale",
        "0.5,2",
        "--duration",
        0.5,
        "--no-comfort",
        "--format",
        "json",
        "--out",
        out,
    )
    assert result.exit_code == 0, result.stderr
    rows = json.loads(result.stdout)
    assert [(r["suspension"], r["damper_scale"]) for r in rows] == [
        ("sas-attitude", 0.5),
        ("sas-attitude", 2.0),
        ("passive", None),
        ("mr", 0.5),
        ("mr", 2.0),
    ]
    doc = json.loads((out / "sweep.json").read_text())
    assert doc["settings"]["grid"]["damper_scale"] == [0.5, 2.0]
    assert (out / "sweep.png").read_bytes().startswith(b"\x89PNG")
    # the run table has the column for every run, passive unscaled
    table = (out / "runs.csv").read_text().splitlines()
    assert "damper_scale" in table[0].split(",")


@pytest.mark.parametrize(
    "command", [("compare",), ("tune", "--controllers", "pid"), ("simulate", "--suspension", "mr")]
)
def test_cli_damper_scale_that_is_not_a_number(command):
    assert_input_error(run(*command, "--damper-scale", "abc"), "--damper-scale = 'abc'", "must be a finite number > 0")
