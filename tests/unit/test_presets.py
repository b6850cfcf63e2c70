"""The published vehicle presets: their source values, their plausibility, their carbody and bogie
modes against hand formulas, and `railride vehicles`."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from railride.errors import InputError
from railride.model.params import PRESET_SOURCES, PRESETS, VehicleParams
from railride.model.plausible import notes
from railride.model.vehicle import Vehicle

ROOT = Path(__file__).resolve().parents[2]

#: the values each source gives, typed from the sources (docs/model.md, Presets), not from the code
SOURCE_VALUES = {
    "manchester-1": {
        "m_c": 32000.0,
        "I_cx": 56800.0,
        "I_cy": 1.97e6,
        "m_b": 2615.0,
        "I_bx": 1722.0,
        "I_by": 1476.0,
        "l": 9.5,
        "b": 1.28,
        "d_p": 1.0,
        "d_s": 1.0,
        "k_pz": 1.22e6,
        "c_pz": 4e3,
        "k_sz": 430e3,
        "c_sz": 20e3,
        "k_sy": 160e3,
        "k_sx": 160e3,
        "k_ar": 940e3,
    },
    "crh380a": {
        "m_c": 43862.5,
        "I_cx": 1.094e5,
        "I_cy": 1.654e6,
        "m_b": 2400.0,
        "I_bx": 1944.0,
        "I_by": 1314.0,
        "l": 8.75,
        "b": 1.25,
        "d_p": 1.0,
        "d_s": 1.23,
        "k_pz": 1.176e6,
        "k_sz": 0.19e6,
        "c_sz": 40e3,
    },
}

pytestmark = pytest.mark.filterwarnings("error::railride.model.plausible.PlausibilityWarning")


def test_the_presets_are_named_and_each_has_a_source_line():
    assert list(PRESETS) == ["paper", "manchester-1", "crh380a"]
    assert set(PRESET_SOURCES) == set(PRESETS)
    for name, text in PRESET_SOURCES.items():
        assert text.strip() and "\n" not in text, name


@pytest.mark.parametrize("name", sorted(SOURCE_VALUES))
def test_each_preset_holds_its_source_values(name):
    p = VehicleParams.preset(name)
    for field, value in SOURCE_VALUES[name].items():
        assert getattr(p, field) == pytest.approx(value, rel=1e-12), field


@pytest.mark.parametrize("name", list(PRESETS))
def test_each_preset_is_a_plausible_full_size_vehicle(name):
    p = VehicleParams.preset(name)
    assert notes(p) == []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert VehicleParams(**p.to_dict()) == p  # builds again without a PlausibilityWarning
    assert p.a == pytest.approx(0.7465 if name != "paper" else 1.0)
    assert p.z_stop is not None
    assert p.k_stop > 0 if name != "paper" else p.k_stop == 0  # the paper's clearance is only marked


def test_an_unknown_preset_lists_the_presets():
    with pytest.raises(InputError) as info:
        VehicleParams.preset("manchester")
    for name in PRESETS:
        assert name in str(info.value)


# -- modes against hand formulas ---------------------------------------------------------------------
def _series(a: float, b: float) -> float:
    return a * b / (a + b)


def _hz(stiffness: float, inertia: float) -> float:
    return float(np.sqrt(stiffness / inertia) / (2 * np.pi))


def held_bogies(p: VehicleParams) -> dict[str, float]:
    """The carbody on its secondary with both bogies held still (docs/model.md's element table):
    four vertical springs at (+-l, +-d_s); per bogie two lateral springs acting on roll through
    h_cs, two longitudinal ones on pitch, and the anti-roll bar on roll."""
    return {
        "carbody bounce": _hz(4 * p.k_sz, p.m_c),
        "carbody pitch": _hz(4 * p.k_sz * p.l**2 + 4 * p.k_sx * p.h_cs**2, p.I_cy),
        "carbody roll": _hz(4 * p.k_sz * p.d_s**2 + 4 * p.k_sy * p.h_cs**2 + 2 * p.k_ar, p.I_cx),
    }


def massless_bogies(p: VehicleParams) -> dict[str, float]:
    """The carbody on its secondary with the bogies free but massless, each on its primary: the
    stiffness the carbody sees is its own minus what a bogie gives way (static condensation,
    K_cc - K_cb^2 / K_bb per bogie, from the element table).

    Bounce: per bogie 2 k_sz in series with 4 k_pz. Pitch: those series springs at +-l, and per
    bogie the longitudinal pair (deflection h_cs phi_c + h_ts phi_b) with the bogie's pitch held
    by 4 k_pz b^2 + 4 k_px h_tp^2 + 2 k_sx h_ts^2. Roll: per bogie the carbody sees
    2 k_sz d_s^2 + 2 k_sy h_cs^2 + k_ar, coupled to the bogie's roll by -(2 k_sz d_s^2 + k_ar)
    + 2 k_sy h_cs h_ts, the bogie's roll held by 2 k_sz d_s^2 + k_ar + 2 k_sy h_ts^2 +
    4 k_pz d_p^2 + 4 k_py h_tp^2."""
    vertical = _series(2 * p.k_sz, 4 * p.k_pz)  # per bogie
    k_bogie_pitch = 4 * p.k_pz * p.b**2 + 4 * p.k_px * p.h_tp**2 + 2 * p.k_sx * p.h_ts**2
    pitch_lon = 2 * p.k_sx * p.h_cs**2 - (2 * p.k_sx * p.h_cs * p.h_ts) ** 2 / k_bogie_pitch
    k_cc = 2 * p.k_sz * p.d_s**2 + 2 * p.k_sy * p.h_cs**2 + p.k_ar
    k_cb = -(2 * p.k_sz * p.d_s**2 + p.k_ar) + 2 * p.k_sy * p.h_cs * p.h_ts
    k_bb = 2 * p.k_sz * p.d_s**2 + p.k_ar + 2 * p.k_sy * p.h_ts**2 + 4 * p.k_pz * p.d_p**2 + 4 * p.k_py * p.h_tp**2
    return {
        "carbody bounce": _hz(2 * vertical, p.m_c),
        "carbody pitch": _hz(2 * vertical * p.l**2 + 2 * pitch_lon, p.I_cy),
        "carbody roll": _hz(2 * (k_cc - k_cb**2 / k_bb), p.I_cx),
    }


@pytest.mark.parametrize("name", list(PRESETS))
def test_carbody_modes_against_the_carbody_on_its_secondary(name):
    # the hand formulas are of a rigid carbody: the presets that bend are taken rigid here (the
    # bending, coupled at the secondary, lowers their bounce by about 1 %: checked below)
    p = VehicleParams.preset(name).rigid()
    modes = {m.label: m.frequency_hz for m in Vehicle(p).modes()}
    held, free = held_bogies(p), massless_bogies(p)
    for label in ("carbody bounce", "carbody pitch", "carbody roll"):
        f = modes[label]
        # Holding the bogies still stiffens the carbody (a constraint only raises frequencies,
        # Rayleigh): the held formula leaves out the primary in series and is up to 11 % high
        # (crh380a's roll: its anti-roll bar rolls the bogie on a primary only about three times
        # stiffer in roll than the bar and the secondary).
        assert f <= held[label] * (1 + 1e-9), label
        assert f == pytest.approx(held[label], rel=0.12), label
        # With the bogies free but massless the formula leaves out only the bogies' own mass,
        # which can only lower the frequency: their share of the mode's kinetic energy is
        # (theta_b / theta_c)^2 2 I_bx / I_cx in roll, below 0.2 % for these presets, and
        # (z_b / z_c)^2 2 m_b / m_c in bounce, below 0.5 %, so the frequency falls short by
        # less than 1 %.
        assert f <= free[label] * (1 + 1e-9), label
        assert f == pytest.approx(free[label], rel=0.01), label


@pytest.mark.parametrize("name", [n for n in PRESETS if VehicleParams.preset(n).flexible])
def test_a_bending_carbody_keeps_its_rigid_modes_within_two_percent(name):
    # a 10 Hz bending mode coupled at the secondary: the rigid-body modes of the carbody, at
    # 1-2 Hz, move by the small share of the bending in them (measured 1.0 % in bounce)
    p = VehicleParams.preset(name)
    rigid = {m.label: m.frequency_hz for m in Vehicle(p.rigid()).modes()}
    modes = {m.label: m.frequency_hz for m in Vehicle(p).modes()}
    assert modes["carbody bending"] == pytest.approx(p.bending_hz, rel=0.05)
    for label in ("carbody bounce", "carbody pitch", "carbody roll"):
        assert modes[label] == pytest.approx(rigid[label], rel=0.02), label


@pytest.mark.parametrize("name", list(PRESETS))
def test_bogie_bounce_against_the_bogie_between_rails_and_a_still_carbody(name):
    # Each bogie between the rails (4 k_pz) and a carbody 10-20 times heavier that hardly moves at
    # the bogie's frequency (2 k_sz): omega^2 = (4 k_pz + 2 k_sz) / m_b. The carbody is not quite
    # still (its in-phase coupling through 2 k_sz shifts the bogie modes by under 0.3 % here):
    # 1 % tolerance.
    p = VehicleParams.preset(name)
    hand = _hz(4 * p.k_pz + 2 * p.k_sz, p.m_b)
    found = [m.frequency_hz for m in Vehicle(p).modes() if "bogie bounce" in m.label]
    assert len(found) == 2
    for f in found:
        assert f == pytest.approx(hand, rel=0.01)


def test_the_bar_and_the_softer_secondary_order_the_carbody_modes():
    # the paper's car rolls first; the benchmark's and the high-speed car's bars put roll last
    # of the three carbody modes
    first = {name: [m.label for m in Vehicle(p).modes()][:3] for name, p in PRESETS.items()}
    assert first["paper"][0] == "carbody roll"
    assert first["manchester-1"][2] == "carbody roll" and first["crh380a"][2] == "carbody roll"


# -- railride vehicles --------------------------------------------------------------------------------
def _run(*args):
    from typer.testing import CliRunner

    from railride.cli import app

    result = CliRunner().invoke(app, ["vehicles", *args], env={"COLUMNS": "80"})
    return result


def test_the_command_lists_every_preset_with_its_source_and_modes():
    result = _run()
    assert result.exit_code == 0, (result.stdout, result.stderr)
    text = result.stdout
    assert max(len(line.rstrip()) for line in text.splitlines()) <= 80
    assert "\N{HORIZONTAL ELLIPSIS}" not in text
    flat = " ".join(text.split())
    for name, p in PRESETS.items():
        assert f"{name}: {PRESET_SOURCES[name]}" in flat
        modes = Vehicle(p).modes()
        assert modes  # the loop below checks something
        for m in modes:
            assert f"{m.frequency_hz:.3f}" in text


def test_the_command_writes_a_json_document_of_its_schema():
    jsonschema = pytest.importorskip("jsonschema")
    result = _run("--format", "json")
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    schema = json.loads((ROOT / "docs" / "schemas" / "railride.vehicles-1.json").read_text(encoding="utf-8"))
    jsonschema.validate(doc, schema, cls=jsonschema.Draft202012Validator)
    assert [e["name"] for e in doc["presets"]] == list(PRESETS)
    for entry in doc["presets"]:
        modes = Vehicle(VehicleParams.preset(entry["name"])).modes()
        assert [m["label"] for m in entry["modes"]] == [m.label for m in modes]
        assert [m["frequency_hz"] for m in entry["modes"]] == [m.frequency_hz for m in modes]
        assert entry["source"] == PRESET_SOURCES[entry["name"]]


def test_the_command_shows_one_preset_and_refuses_an_unknown_one():
    doc = json.loads(_run("--preset", "crh380a", "--format", "json").stdout)
    assert [e["name"] for e in doc["presets"]] == ["crh380a"]
    result = _run("--preset", "ice3")
    assert result.exit_code == 2 and result.stdout == ""
    line = result.stderr.strip()
    assert line.startswith("error: ") and "'ice3'" in line and "\n" not in line
    for name in PRESETS:
        assert name in line
