"""Bad vehicle files, track files and random-track options: an InputError (exit status 2 on the
command line) that names the file or option, the value and what is allowed."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from clihelp import assert_input_error, run
from railride.errors import InputError
from railride.model.params import MANCHESTER_1, PAPER, VehicleParams
from railride.model.track import MeasuredTrack, scenario


def test_a_vehicle_file_that_is_not_utf8_text_is_named(tmp_path):
    path = tmp_path / "car.toml"
    path.write_bytes(b"\xff\xfe[vehicle]\n")
    assert_input_error(run("modes", "--vehicle", path), str(path), "not a UTF-8 text TOML file")


def test_an_unknown_preset_in_a_file_names_the_file_and_the_key(tmp_path):
    for value, shown in (('"nope"', "'nope'"), ("3", "3"), ("[1]", "[1]")):
        path = tmp_path / "car.toml"
        path.write_text(f"[vehicle]\npreset = {value}\n")
        with pytest.raises(InputError) as info:
            VehicleParams.load(path)
        message = str(info.value)
        assert f"{path}: [vehicle] preset = {shown}: unknown vehicle preset" in message
        assert "allowed: crh380a, manchester-1, paper" in message


def test_a_folder_given_as_the_vehicle_is_said_to_be_one(tmp_path):
    (tmp_path / "car.toml").mkdir()
    for folder in (tmp_path, tmp_path / "car.toml"):
        assert_input_error(run("modes", "--vehicle", folder), str(folder), "a folder, not a vehicle file")
    with pytest.raises(InputError, match="a folder, not a vehicle file"):
        VehicleParams.resolve(tmp_path / "car.toml")


def test_a_rigid_carbody_with_a_bending_frequency_is_a_conflict():
    for bending in ("f_bend = 10.0", "EI_c = 5e9"):
        text = f'[vehicle]\npreset = "paper"\nrigid_carbody = true\nL_c = 24.0\n{bending}\n'
        with pytest.raises(InputError, match=rf"rigid_carbody = true and {bending.split()[0]} = .*not both"):
            VehicleParams.from_toml(text)
    # what the switch is for: a preset's bending mode off, its length given or not
    assert not VehicleParams.from_toml('[vehicle]\npreset = "manchester-1"\nrigid_carbody = true\n').flexible
    text = '[vehicle]\npreset = "manchester-1"\nrigid_carbody = true\nL_c = 23.0\n'
    assert VehicleParams.from_toml(text) == MANCHESTER_1.rigid()


def test_a_flexible_carbody_without_a_bending_mode_is_an_error():
    with pytest.raises(InputError, match=r"rigid_carbody = false, but the file or its preset 'paper' gives"):
        VehicleParams.from_toml('[vehicle]\npreset = "paper"\nrigid_carbody = false\n')
    flexible = VehicleParams.from_toml('[vehicle]\npreset = "manchester-1"\nrigid_carbody = false\n')
    assert flexible == MANCHESTER_1


def test_saved_vehicles_read_back_as_they_were(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a length without a frequency says it runs rigid
        length_only = PAPER.replace(L_c=24.0)
    for params in (PAPER, MANCHESTER_1, MANCHESTER_1.rigid(), MANCHESTER_1.replace(f_bend=None, EI_c=4e9)):
        params.save(tmp_path / "car.toml")
        assert VehicleParams.load(tmp_path / "car.toml") == params
    length_only.save(tmp_path / "car.toml")  # written with rigid_carbody = true: still read
    assert not VehicleParams.load(tmp_path / "car.toml").flexible


def test_track_messages_show_plain_numbers():
    with pytest.raises(InputError, match=r"column z_L has a non-finite value nan at data row 2$"):
        MeasuredTrack(np.array([0.0, 10.0]), np.array([0.0, np.nan]), np.zeros(2))
    with pytest.raises(InputError, match=r"data row 3 has s = 10.0 after 20.0$"):
        MeasuredTrack(np.array([0.0, 20.0, 10.0]), np.zeros(3), np.zeros(3))
    with pytest.raises(InputError, match=r"it starts at 5.0 m$"):
        MeasuredTrack(np.array([5.0, 20.0]), np.zeros(2), np.zeros(2))


def test_a_random_track_wavelength_beyond_its_length_names_the_option_given():
    with pytest.raises(InputError, match=r"^max_wavelength = 2500 m: must be at most 2000 m, the length of the"):
        scenario("fra3", max_wavelength=2500.0)
    assert_input_error(
        run("simulate", "--scenario", "fra3", "--max-wavelength", "2500"),
        "--max-wavelength = 2500 m: must be at most 2000 m",
    )
    # a longer run synthesises a longer track
    assert scenario("fra3", max_wavelength=2500.0, speed=50.0, duration=60.0).track.max_wavelength == 2500.0


def test_a_ratio_out_of_range_is_said_without_its_unit_after_the_number():
    # the unit of a ratio is "1": "between 0 and 1 1" read as a doubled number
    from railride.model.params import VehicleParams

    with pytest.raises(InputError, match=r"must be between 0 and 1 \(1 is critical damping") as caught:
        VehicleParams.preset("paper").replace(f_bend=10.0, L_c=24.0, zeta_bend=5.0)
    assert "0 and 1 1" not in str(caught.value)
