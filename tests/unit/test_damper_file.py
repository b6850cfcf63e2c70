"""A user's own MR damper (railride.secondary.damper_file): the [damper] table read into the same
model a preset is, its errors naming the file and key, and the gains' warning when a run's
damper is not the one they were tuned with (`GainSet.mismatch`)."""

from __future__ import annotations

import json

import pytest

import railride as rr

from railride.errors import InputError
from railride.model.params import VehicleParams, vehicle_record
from railride.secondary import damper_file, dampers
from railride.secondary.control import GainSet


@pytest.mark.parametrize("name", list(dampers.PRESETS))
def test_every_preset_round_trips_bit_for_bit(name, tmp_path):
    model = dampers.PRESETS[name]
    path = tmp_path / f"{name}.toml"
    damper_file.save(model, path)
    assert damper_file.load(path) == model
    assert damper_file.load(path).to_dict()["preset"] == name


def test_a_preset_with_overrides_is_that_preset_replaced():
    text = '[damper]\npreset = "railway"\nalpha_b = 5.0e6\nv_max = 2\n'
    assert damper_file.from_toml(text) == dampers.RAILWAY.replace(alpha_b=5.0e6, v_max=2.0)
    # dyke1996 with its force parameters x 8, written out by hand, is the railway preset
    d = dampers.DYKE1996
    scaled = "\n".join(f"{n} = {8 * getattr(d, n)!r}" for n in ("alpha_a", "alpha_b", "c0a", "c0b", "k0"))
    assert damper_file.from_toml(f'[damper]\npreset = "dyke1996"\n{scaled}\n') == dampers.RAILWAY


def test_a_whole_spencer_table_needs_no_preset():
    text = damper_file.to_toml(dampers.SPENCER1997).replace("c1a = 28300.0", "c1a = 1.0e4")
    model = damper_file.from_toml(text)
    assert isinstance(model, dampers.Spencer) and model.c1a == 1.0e4 and model.k1 == dampers.SPENCER1997.k1


WHOLE = damper_file.to_toml(dampers.RAILWAY)


@pytest.mark.parametrize(
    "text, fragments",
    [
        ("", ("needs a [damper] table",)),
        ("[damper\n", ("not valid TOML",)),
        ('[damper]\npreset = "lord"\n', ("[damper] preset = 'lord'", "allowed: dyke1996, railway, spencer1997")),
        ('[damper]\nmodel = "maxwell"\n', ("[damper] model = 'maxwell'", "allowed: bouc-wen, spencer")),
        ('[damper]\nmodel = "spencer"\npreset = "railway"\n', ("model = 'spencer' and preset = 'railway'",)),
        ("[damper]\nalpha_a = 1.0\n", ("needs model = 'bouc-wen' or 'spencer'",)),
        ('[damper]\npreset = "railway"\nc1a = 1.0\n', ("unknown bouc-wen damper parameter(s) c1a", "allowed: alpha_a")),
        ('[damper]\nmodel = "bouc-wen"\nalpha_a = 1.0\n', ("missing bouc-wen damper parameter(s) alpha_b",)),
        ('[damper]\npreset = "railway"\neta = -5.0\n', ("[damper]", "eta", "-5")),
        ('[damper]\npreset = "railway"\nalpha_a = "strong"\n', ("[damper]", "alpha_a", "strong")),
        ('[damper]\npreset = "railway"\nn = 0.5\n', ("[damper]", "'n' = 0.5", ">= 1")),
        (WHOLE.replace("gamma = 300.0", "gamma = -300.0"), ("[damper]", "gamma + beta must be > 0")),
    ],
)
def test_a_bad_table_names_the_file_and_the_key(text, fragments):
    with pytest.raises(InputError) as err:
        damper_file.from_toml(text, source="mine.toml")
    message = str(err.value)
    assert message.startswith("mine.toml: "), message
    for fragment in fragments:
        assert fragment in message, message


def test_a_path_that_is_no_damper_file_says_so(tmp_path):
    with pytest.raises(InputError, match="--damper = .*: no such damper file"):
        damper_file.resolve(str(tmp_path / "gone.toml"), "--damper")
    with pytest.raises(InputError, match="a folder, not a damper file"):
        damper_file.load(tmp_path, "--damper")
    latin = tmp_path / "latin.toml"
    latin.write_bytes(b"# \xe9\n[damper]\n")
    with pytest.raises(InputError, match="not a UTF-8 text TOML file"):
        damper_file.resolve(str(latin), "--damper")
    with pytest.raises(InputError, match="unknown damper model, and no such file; allowed: .*FILE.toml"):
        damper_file.resolve("mr9", "--damper")
    # a name stays a name; the rig's names leave out the ideal devices
    assert damper_file.resolve("spencer1997", "--damper") == "spencer1997"
    with pytest.raises(InputError, match="'ideal'; allowed: dyke1996, railway, spencer1997"):
        damper_file.resolve("ideal", "--damper", allowed=dampers.PRESETS)


def test_only_mr_models_have_a_file():
    with pytest.raises(InputError, match="only the MR models"):
        damper_file.to_toml(dampers.IDEAL)


# -- the gains' warning -----------------------------------------------------------------------------
PAPER = vehicle_record(VehicleParams.preset("paper"), None, 1.0)


def _line(damper, scale=1.0):
    return GainSet.default().mismatch(PAPER, None, ["pid"], damper, scale)


def test_the_damper_the_gains_were_tuned_with_has_no_line_by_any_name():
    assert _line("railway") is None
    assert _line("dyke1996", 8.0) is None  # railway is dyke1996 x 8
    assert _line(dampers.RAILWAY) is None
    assert _line(dampers.RAILWAY.to_dict()) is None  # a result's record of it
    assert _line(None) is None  # not compared


def test_another_damper_is_named_with_its_tune_command():
    line = _line("spencer1997")
    assert "this run has damper spencer1997 (the gains' damper: railway)" in line, line
    assert line.endswith("tune for it with: railride tune --damper spencer1997"), line
    line = _line("railway", 2.0)
    assert "damper railway x 2 (the gains' damper: railway)" in line
    assert line.endswith("railride tune --damper-scale 2")
    own = _line(dampers.RAILWAY.replace(alpha_b=5e6))
    assert "damper bouc-wen (own parameters) (the gains' damper: railway; other values: alpha_b 5e+06" in own
    assert own.endswith("railride tune --damper FILE.toml"), own
    assert "damper ideal (the gains' damper: railway)" in _line("ideal")


def test_a_sweep_of_damper_scales_is_not_warned_of_its_scales():
    from railride.studies.sweep import grid, run_sweep

    two = run_sweep(grid(["pid"], damper_scale=[1.0, 2.0], duration=0.2), comfort=False).settings
    assert "gains_mismatch" not in two
    one = run_sweep(grid(["pid"], damper_scale=[2.0], duration=0.2), comfort=False).settings
    assert "damper railway x 2" in one["gains_mismatch"]


def test_time_at_v_max_is_read_at_the_own_dampers_v_max():
    """An on-off law sits at its damper's v_max part of the time; with a damper of one's own
    whose v_max is 2 V, that time is counted at 2 V (it read as 0 against a preset's range)."""

    import railride as rr

    own = dampers.RAILWAY.replace(v_max=2.0)
    result = rr.compare(
        rr.scenario("paper-sine", duration=1.0), controllers=["skyhook-on-off"], damper=own, bounds=False
    )
    fraction = result.demands()["skyhook-on-off"]["voltage_at_max_fraction"]
    volts = result.datasets["skyhook-on-off"]["damper_command_voltage"].values
    assert volts.max() == 2.0 and fraction == pytest.approx(float((volts >= 2.0).mean()), rel=1e-12)
    assert 0.05 < fraction < 0.95


def test_the_tune_command_keeps_the_runs_damper_when_only_the_track_differs():
    """Gains tuned with the run's own damper on another track: the line's tune command tunes
    for the run, with its damper (it left the damper out when the dampers matched, so the
    command tuned for the railway damper)."""
    own = dampers.RAILWAY.replace(alpha_b=5e6)
    tuned = GainSet.default().to_toml().replace('damper = "railway"', f"damper = {_inline(own.to_dict())}")
    gains = GainSet.from_toml(tuned, source="own.toml")
    fra4 = rr.scenario("fra4", duration=0.5).describe()
    line = gains.mismatch(PAPER, fra4, ["pid"], own, 1.0)
    assert line is not None and "damper" not in line.split("; tune for it with:")[0], line
    assert "railride tune --damper FILE.toml --scenario fra4" in line, line
    spencer = gains.mismatch(PAPER, fra4, ["pid"], "dyke1996", 8.0)  # the railway damper by another name
    assert "--damper dyke1996 --damper-scale 8" in spencer, spencer


def _inline(record: dict) -> str:
    return "{" + ", ".join(f"{k} = {json.dumps(v)}" for k, v in record.items() if v is not None) + "}"
