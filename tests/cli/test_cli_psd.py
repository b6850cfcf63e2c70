"""`--scenario psd:PATH` on the command line: a user's spectrum table runs as a random track in
the commands that take one, is recorded with its SHA-256, and a bad table is one line, status 2."""

from __future__ import annotations

import numpy as np

from clihelp import assert_input_error, ok_json, run
from railride.model import psd_table
from railride.model.irregularity import spectrum


def _fra4(path):
    W = np.geomspace(2 * np.pi / 200, 2 * np.pi / 0.5, 100)
    rows = zip(W, spectrum("fra4", W), spectrum("fra4", W, "cross-level"))
    path.write_text(
        "wavenumber_rad_per_m,vertical,cross_level\n"
        + "".join(f"{float(w)!r},{float(v)!r},{float(x)!r}\n" for w, v, x in rows)
    )
    return path


def test_compare_on_a_table_of_fra4_rides_as_on_fra4(tmp_path):
    path = _fra4(tmp_path / "fra4.csv")
    args = ("compare", "--controllers", "pid", "--no-references", "--track-seed", 3, "--speed", 30, "--duration", 2)
    table = ok_json(*args, "--scenario", f"psd:{path}")
    formula = ok_json(*args, "--scenario", "fra4")
    record = table["settings"]["scenario"]
    assert record["spectrum"] == f"psd:{path}" and record["seed"] == 3
    assert record["spectrum_sha256"] == psd_table.table(f"psd:{path}").sha256
    checked = 0
    for a, b in zip(table["controllers"], formula["controllers"]):  # the table's interpolation error only
        for response, values in b["metrics"].items():
            for stat, value in values.items():
                assert abs(a["metrics"][response][stat] / value - 1) < 1e-3, (response, stat)
                checked += 1
    assert checked == 16  # passive and PID, four responses, RMS and peak-to-peak


def test_a_bad_table_or_band_is_one_line_with_status_2(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("wavenumber_rad_per_m,vertical\n1,1e-6\n0.5,1e-6\n")
    result = run("simulate", "--scenario", f"psd:{bad}")
    assert_input_error(result, f"--scenario 'psd:{bad}': row 3", "must rise strictly")
    for command in (("study", "--scenario"), ("sweep", "--scenario"), ("design", "--track"), ("tune", "--scenario")):
        assert_input_error(run(*command, f"psd:{bad}"), f"{command[1]} 'psd:{bad}': row 3")
    path = _fra4(tmp_path / "fra4.csv")
    result = run("compare", "--scenario", f"psd:{path}", "--max-wavelength", 300, "--controllers", "pid")
    assert_input_error(result, "--max-wavelength = 300 m", "beyond the 0.5 to 200 m")
    assert_input_error(run("ride-spectrum", "--track", f"psd:{tmp_path / 'gone.csv'}"), "no such spectrum table")


def test_ride_spectrum_records_the_tables_sha256(tmp_path):
    path = _fra4(tmp_path / "fra4.csv")
    settings = ok_json("ride-spectrum", "--track", f"psd:{path}", "--points", 64)["settings"]
    assert settings["spectrum_sha256"] == psd_table.table(f"psd:{path}").sha256
    assert "spectrum_sha256" not in ok_json("ride-spectrum", "--points", 64)["settings"]
