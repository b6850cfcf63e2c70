import dataclasses
import math

import pytest
from hypothesis import given, settings, strategies as st

from railride.model.params import VehicleParams
from railride.model.plausible import VEHICLE

# The paper's appendix (Harun et al.), typed from the published table, not from the code.
APPENDIX = {
    "m_c": 3.96e4,
    "m_b": 3.25e3,
    "I_cx": 8.85e4,
    "I_cy": 2.46e6,
    "I_cz": 2.5e6,
    "I_bx": 3.06e3,
    "I_by": 3.02e3,
    "I_bz": 4.27e3,
    "k_px": 4e6,
    "k_py": 3.25e6,
    "k_pz": 7e6,
    "c_px": 0,
    "c_py": 0,
    "c_pz": 1.5e4,
    "k_sx": 1.5e5,
    "k_sy": 1.5e5,
    "k_sz": 2.9e5,
    "c_sx": 0,
    "c_sy": 5e4,
    "c_sz": 8e4,
    "l": 9.0,
    "d_s": 1.0,
    "d_p": 1.0,
    "a": 1.0,
    "b": 1.25,
    "h_cs": 1.207,
    "h_ts": 0.217,
    "h_tp": 0.452,
    "h_wp": 0.18,
}


#: beyond the appendix: no anti-roll bar, an assumed clearance to bump stops the paper does not
#: give, marked only: no stop force (docs/model.md, Presets), and a rigid carbody (no bending mode)
BEYOND = {
    "k_ar": 0.0,
    "z_stop": 0.08,
    "k_stop": 0.0,
    "L_c": None,
    "f_bend": None,
    "EI_c": None,
    "zeta_bend": 0.02,
}


def test_paper_preset_matches_the_published_appendix():
    assert VehicleParams.preset("paper").to_dict() == {**APPENDIX, **BEYOND}


def test_every_field_documents_its_unit():
    assert len(VehicleParams.describe()) == len(dataclasses.fields(VehicleParams))  # every field, none missed
    for name, unit, doc, rule in VehicleParams.describe():
        assert unit and doc and rule, name


def test_toml_round_trip_is_exact(tmp_path):
    p = VehicleParams.preset("paper")
    path = tmp_path / "vehicle.toml"
    p.save(path)
    assert VehicleParams.load(path) == p


def allowed(name):
    """Any value the field takes (with a warning outside the typical range)."""
    r = VEHICLE[name]
    return st.floats(min_value=r.low, max_value=r.high, allow_nan=False, allow_infinity=False)


@settings(max_examples=60, deadline=None)
@given(m_c=allowed("m_c"), k_sz=allowed("k_sz"), h_cs=allowed("h_cs"), c_sz=allowed("c_sz"))
@pytest.mark.filterwarnings("ignore::railride.model.plausible.PlausibilityWarning")
def test_toml_round_trip_is_lossless_for_any_valid_value(m_c, k_sz, h_cs, c_sz):
    p = VehicleParams.preset("paper").replace(m_c=m_c, k_sz=k_sz, h_cs=h_cs, c_sz=c_sz)
    assert VehicleParams.from_toml(p.to_toml()) == p


def test_toml_may_start_from_a_preset():
    p = VehicleParams.from_toml('[vehicle]\npreset = "paper"\nc_sz = 6e4\n')
    assert p.c_sz == 6e4 and p.m_c == APPENDIX["m_c"]


@pytest.mark.parametrize(
    "field, value, allowed",
    [
        ("m_c", -1.0, "> 0"),
        ("m_c", 0.0, "> 0"),
        ("I_cy", math.nan, "> 0"),
        ("k_pz", math.inf, "> 0"),
        ("c_sz", -5.0, ">= 0"),
        ("l", "nine", "> 0"),
    ],
)
def test_bad_values_name_the_field_value_and_rule(field, value, allowed):
    with pytest.raises(ValueError) as err:
        VehicleParams.preset("paper").replace(**{field: value})
    msg = str(err.value)
    assert repr(field) in msg and repr(value) in msg and allowed in msg


def test_toml_errors_are_clear(tmp_path):
    with pytest.raises(ValueError, match="unknown vehicle parameter.*m_x"):
        VehicleParams.from_toml('[vehicle]\npreset = "paper"\nm_x = 1.0\n')
    with pytest.raises(ValueError, match="missing vehicle parameter"):
        VehicleParams.from_toml("[vehicle]\nm_c = 1.0\n")
    with pytest.raises(ValueError, match="not valid TOML"):
        VehicleParams.from_toml("[vehicle\n")
    with pytest.raises(ValueError, match="'m_c' = -3"):
        VehicleParams.from_toml('[vehicle]\npreset = "paper"\nm_c = -3.0\n')
    with pytest.raises(ValueError, match="cannot read"):
        VehicleParams.load(tmp_path / "absent.toml")
    with pytest.raises(ValueError, match="unknown vehicle preset"):
        VehicleParams.preset("tgv")
