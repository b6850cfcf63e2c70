"""``railride fmu``: an FMU written, or one error line naming the option, before anything is written."""

import shutil
import zipfile

import pytest

from clihelp import assert_input_error, ok, run

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler to build the FMU")


def test_fmu_writes_an_fmu_with_its_sources_and_a_binary(tmp_path):
    result = ok("fmu", "--out", tmp_path / "v.fmu", "--vehicle", "crh380a", "--load", "1.3", "--damper", "passive")
    assert f"wrote {tmp_path / 'v.fmu'}" in result.stdout
    with zipfile.ZipFile(tmp_path / "v.fmu") as z:
        names = set(z.namelist())
        xml = z.read("modelDescription.xml").decode()
    assert {"modelDescription.xml", "sources/railride_fmu.c", "sources/model.h"} <= names
    assert any(n.startswith("binaries/") for n in names)
    assert "crh380a, load 1.3" in xml and "secondary_clearance_1R" in xml  # its bump stops


def test_a_damper_file_goes_into_the_fmu_and_a_spencer_file_is_refused(tmp_path):
    (tmp_path / "own.toml").write_text('[damper]\npreset = "railway"\nn = 2.0\n')
    ok("fmu", "--out", tmp_path / "v.fmu", "--damper", tmp_path / "own.toml", "--sources-only")
    with zipfile.ZipFile(tmp_path / "v.fmu") as z:
        assert "#define RR_BW_N 2.0\n" in z.read("sources/model.h").decode()
    (tmp_path / "spencer.toml").write_text('[damper]\npreset = "spencer1997"\nc1a = 1.0e5\n')
    result = run("fmu", "--out", tmp_path / "s.fmu", "--damper", tmp_path / "spencer.toml")
    assert_input_error(result, "--damper = 'spencer (own parameters)'", "the Spencer model")
    assert not (tmp_path / "s.fmu").exists()


def test_sources_only_ships_no_binary(tmp_path):
    ok("fmu", "--out", tmp_path / "v.fmu", "--sources-only")
    with zipfile.ZipFile(tmp_path / "v.fmu") as z:
        assert not any(n.startswith("binaries/") for n in z.namelist())


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (["--damper", "spencer1997"], ["--damper = 'spencer1997'", "implements passive", "railway", "ideal"]),
        (["--dt", "0.5"], ["--dt = 0.5 s", "at most 0.01 s"]),
        (["--dt", "-1"], ["--dt"]),
        (["--load", "0"], ["--load"]),
        (["--vehicle", "nothing"], ["--vehicle"]),
    ],
)
def test_bad_options_are_one_error_line_and_nothing_is_written(tmp_path, args, fragments):
    assert_input_error(run("fmu", "--out", tmp_path / "v.fmu", *args), *fragments)
    assert not (tmp_path / "v.fmu").exists()


def test_an_out_that_is_no_fmu_or_cannot_be_written_is_refused(tmp_path):
    assert_input_error(run("fmu", "--out", tmp_path / "v.zip"), "--out", "ending in .fmu")
    (tmp_path / "file").write_text("")
    assert_input_error(run("fmu", "--out", tmp_path / "file" / "v.fmu"), "--out", "is a file")


def test_an_out_in_a_new_folder_makes_the_folder(tmp_path):
    """As every command's --out: a folder that does not exist yet is made (it failed on the
    staged file's name)."""
    ok("fmu", "--out", tmp_path / "new" / "sub" / "v.fmu", "--sources-only")
    with zipfile.ZipFile(tmp_path / "new" / "sub" / "v.fmu") as z:
        assert "modelDescription.xml" in z.namelist()
    assert [p.name for p in (tmp_path / "new" / "sub").iterdir()] == ["v.fmu"]


def test_a_random_track_goes_into_the_fmus_resources(tmp_path):
    ok("fmu", "--out", tmp_path / "r.fmu", "--scenario", "fra5", "--track-seed", "2", "--speed", "30",
       "--duration", "5", "--sources-only")  # fmt: skip
    with zipfile.ZipFile(tmp_path / "r.fmu") as z:
        xml = z.read("modelDescription.xml").decode()
        assert "resources/track.bin" in z.namelist()
    assert "the random track of the export (fra5, seed 2" in xml
    assert_input_error(run("fmu", "--out", tmp_path / "b.fmu", "--scenario", "bump"), "--scenario = 'bump'")
