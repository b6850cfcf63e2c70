"""Issue 6 on the command line: random-track scenarios (--track-seed, --min-wavelength,
--max-wavelength) for simulate, compare, sweep and tune; `railride frf`; the acceleration PSD of
`compare --out`; the plot of `sweep --out`. Short runs keep the file fast."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from railride.analysis.spectra import FRF_MAGNITUDES, FRF_PATTERNS
from railride.output.files import COMPARE_FILES, FRF_FILES
from clihelp import assert_input_error, is_png, ok, ok_json, run


RANDOM = ("simulate", "--scenario", "fra4", "--duration", 1, "--format", "json")


# -- random tracks --------------------------------------------------------------------------------
def test_simulate_random_track_is_reproducible():
    first = json.loads(ok(*RANDOM, "--track-seed", 3).stdout)
    again = json.loads(ok(*RANDOM, "--track-seed", 3).stdout)
    other = json.loads(ok(*RANDOM, "--track-seed", 4).stdout)
    sc = first["scenario"]
    assert sc["name"] == "fra4" and sc["profile"] == "random" and sc["spectrum"] == "fra4"
    assert sc["seed"] == 3 and sc["min_wavelength_m"] == 1.0 and sc["max_wavelength_m"] == 100.0
    assert first["metrics"] == again["metrics"]  # exactly the same track and run
    assert other["scenario"]["seed"] == 4
    assert len(first["metrics"]) == 4  # the loop below checks something
    for key, values in first["metrics"].items():
        assert all(np.isfinite(v) for v in values.values())
        assert values["rms"] > 0
        assert values["rms"] != other["metrics"][key]["rms"], key


def test_simulate_random_track_band_and_default_seed():
    doc = json.loads(
        ok(
            "simulate",
            "--scenario",
            "german-high",
            "--duration",
            1,
            "--min-wavelength",
            2,
            "--max-wavelength",
            50,
            "--format",
            "json",
        ).stdout
    )
    sc = doc["scenario"]
    assert sc["seed"] == 0 and sc["min_wavelength_m"] == 2.0 and sc["max_wavelength_m"] == 50.0
    table = ok("simulate", "--scenario", "fra2", "--track-seed", 5, "--duration", 1).stdout
    assert "random track: seed 5, wavelengths 1-100 m" in table


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--scenario", "fra7"), ("--scenario", "unknown scenario 'fra7'")),
        (("--scenario", "fra4", "--track-seed", -1), ("--track-seed = -1", ">= 0")),
        (("--track-seed", 3), ("--track-seed = 3", "random-track", "paper-sine")),
        (("--scenario", "bump", "--min-wavelength", 2), ("--min-wavelength = 2 m", "bump")),
        (("--scenario", "fra4", "--min-wavelength", -2), ("--min-wavelength = -2", "> 0")),
        (("--scenario", "fra4", "--max-wavelength", 0), ("--max-wavelength = 0", "> 0")),
        (
            ("--scenario", "fra4", "--min-wavelength", 50, "--max-wavelength", 10),
            ("--min-wavelength = 50 m", "--max-wavelength = 10 m", "band"),
        ),
        (("--scenario", "fra4", "--min-wavelength", 150), ("--min-wavelength = 150 m", "[150, 100]")),
        (("--scenario", "fra4", "--min-wavelength", 0.1), ("--min-wavelength = 0.1 m", "--output-rate", "resolve")),
        (
            ("--scenario", "fra4", "--output-rate", 100),
            ("--min-wavelength = 1 m (the default)", "--output-rate 100 Hz"),
        ),
        (("--scenario", "fra4", "--amplitude", 0.01), ("--amplitude", "random track")),
    ],
)
def test_simulate_bad_random_track_input(args, fragments):
    assert_input_error(run("simulate", "--duration", 1, *args), *fragments)


@pytest.mark.parametrize(
    "command",
    [
        ("compare", "--duration", 1),
        ("sweep", "--duration", 1),
        ("tune", "--controllers", "pid", "--duration", 1),
    ],
)
def test_other_commands_refuse_bad_random_track_input(command, tmp_path):
    out = tmp_path / "out"
    assert_input_error(run(*command, "--scenario", "fra7", "--out", out), "unknown scenario")
    assert_input_error(
        run(*command, "--scenario", "fra4", "--min-wavelength", 30, "--max-wavelength", 20, "--out", out),
        "--min-wavelength = 30 m",
    )
    assert_input_error(
        run(*command, "--scenario", "fra4", "--min-wavelength", 0.05, "--out", out),
        "--min-wavelength = 0.05 m",
        "resolve",
    )
    assert_input_error(
        run(*command, "--scenario", "paper-sine", "--track-seed", 1, "--out", out), "--track-seed", "random-track"
    )
    assert_input_error(run(*command, "--scenario", "fra4", "--track-seed", -2, "--out", out), "--track-seed", "-2")
    assert not out.exists()  # nothing written


def test_compare_random_track_json():
    doc = ok_json("compare", "--controllers", "pid", "--scenario", "fra5", "--track-seed", 2, "--duration", 1)
    sc = doc["settings"]["scenario"]
    assert sc["profile"] == "random" and sc["spectrum"] == "fra5" and sc["seed"] == 2
    assert [r["name"] for r in doc["controllers"]] == ["passive", "pid"]


def test_sweep_track_seed_axis_is_not_the_noise_seed(tmp_path):
    out = tmp_path / "sweep"
    rows = json.loads(
        ok(
            "sweep",
            "--scenario",
            "fra4",
            "--track-seed",
            "0:1:2",
            "--suspension",
            "passive,pid",
            "--noise",
            "1e-4,0,0,0",
            "--seed",
            "7",
            "--duration",
            1,
            "--min-wavelength",
            2,
            "--out",
            out,
            "--format",
            "json",
        ).stdout
    )
    doc = json.loads((out / "sweep.json").read_text())
    assert doc["settings"]["grid"]["track_seed"] == [0, 1]
    assert doc["settings"]["grid"]["seed"] == [7]
    assert "seed" not in doc["settings"]["scenario"]  # swept: in the grid
    assert doc["settings"]["scenario"]["min_wavelength_m"] == 2.0
    assert [(r["suspension"], r["track_seed"], r["seed"]) for r in rows] == [
        ("passive", 0, None),
        ("passive", 1, None),
        ("pid", 0, 7),
        ("pid", 1, 7),
    ]
    passive = [r["acceleration_m_s2_rms"] for r in rows if r["suspension"] == "passive"]
    assert passive[0] != passive[1]  # two different tracks
    # the same track as simulate: seed 1, band 2-100 m
    single = json.loads(
        ok(
            "simulate",
            "--scenario",
            "fra4",
            "--track-seed",
            1,
            "--duration",
            1,
            "--min-wavelength",
            2,
            "--format",
            "json",
        ).stdout
    )
    assert single["metrics"]["acceleration_m_s2"]["rms"] == pytest.approx(passive[1], rel=1e-9)
    # resumed: every run comes from the table (stable keys)
    result = ok(
        "sweep",
        "--scenario",
        "fra4",
        "--track-seed",
        "0:1:2",
        "--suspension",
        "passive,pid",
        "--noise",
        "1e-4,0,0,0",
        "--seed",
        "7",
        "--duration",
        1,
        "--min-wavelength",
        2,
        "--out",
        out,
        "--resume",
        "--format",
        "json",
    )
    assert json.loads(result.stdout) == rows
    assert json.loads((out / "sweep.json").read_text())["runs_evaluated"] == 0


def test_tune_on_a_random_track(tmp_path):
    doc = ok_json(
        "tune",
        "--controllers",
        "pid",
        "--values",
        3,
        "--budget",
        5,
        "--duration",
        0.5,
        "--scenario",
        "german-low",
        "--track-seed",
        1,
    )
    assert doc["scenario"]["spectrum"] == "german-low" and doc["scenario"]["seed"] == 1
    assert doc["passive_rms"] and all(np.isfinite(v) for v in doc["passive_rms"].values())


# -- frf ------------------------------------------------------------------------------------------
def test_frf_json():
    doc = ok_json("frf", "--points", 50)
    assert doc["schema"] == "railride.frf/1"
    assert doc["settings"]["rails"] == list(FRF_PATTERNS)
    f = np.array(doc["frequency_hz"])
    assert len(f) == 50 and f[0] == 0.1 and f[-1] == 30.0 and np.all(np.diff(np.log(f)) > 0)
    assert set(doc["responses"]) == set(FRF_PATTERNS)
    for pattern in FRF_PATTERNS:
        assert list(doc["responses"][pattern]) == list(FRF_MAGNITUDES)
        assert all(len(v) == 50 for v in doc["responses"][pattern].values())
        assert list(doc["peaks"][pattern]) == list(FRF_MAGNITUDES)
    inphase, anti = doc["responses"]["in-phase"], doc["responses"]["anti-phase"]
    # at low frequency the carbody follows in-phase rails: 1 m per m
    assert inphase["bounce_m_per_m"][0] == pytest.approx(1.0, rel=0.01)
    # a symmetric car: in-phase rails do not roll it, anti-phase rails do not bounce or pitch it
    assert max(inphase["roll_rad_per_m"]) == 0 and max(anti["bounce_m_per_m"]) == 0
    assert doc["peaks"]["anti-phase"]["bounce_m_per_m"]["frequency_hz"] is None
    assert doc["peaks"]["anti-phase"]["roll_deg_per_m"]["frequency_hz"] > 0
    deg = np.degrees(inphase["pitch_rad_per_m"])
    assert np.allclose(deg, inphase["pitch_deg_per_m"])
    acc = np.array(inphase["acceleration_m_s2_per_m"])
    assert np.allclose(acc, (2 * np.pi * f) ** 2 * np.array(inphase["bounce_m_per_m"]))
    assert [m["label"] for m in doc["modes"]][:3] == ["carbody roll", "carbody bounce", "carbody pitch"]


def test_frf_one_pattern_and_table():
    doc = ok_json("frf", "--rails", "anti-phase", "--points", 5, "--speed", 30)
    assert list(doc["responses"]) == ["anti-phase"] and doc["settings"]["speed_m_s"] == 30.0
    table = ok("frf", "--points", 20).stdout
    assert "Peaks of the carbody frequency responses" in table and "not excited" in table
    assert "Modes of the passive vehicle" in table and "carbody bounce" in table


def test_frf_out_and_csv(tmp_path):
    out = tmp_path / "frf"
    result = ok("frf", "--points", 40, "--out", out, "--format", "csv")
    assert sorted(p.name for p in out.iterdir()) == sorted(FRF_FILES)
    assert is_png(out / "frf.png")
    frame = pd.read_csv(out / "frf.csv")
    assert len(frame) == 80 and list(frame["pattern"].unique()) == list(FRF_PATTERNS)
    assert {"bounce_phase_deg", "roll_deg_per_m", "acceleration_phase_deg"} <= set(frame.columns)
    assert frame.filter(like="phase_deg").abs().max().max() <= 180
    assert result.stdout == (out / "frf.csv").read_text()
    modes = pd.read_csv(out / "modes.csv")
    assert list(modes.columns) == ["mode", "label", "frequency_hz", "damped_frequency_hz", "damping_ratio"]
    assert list(modes["mode"]) == list(range(1, 10))
    assert json.loads((out / "frf.json").read_text())["settings"]["points"] == 40


@pytest.mark.parametrize(
    "args, fragment",
    [
        (("--rails", "diagonal"), "--rails"),
        (("--fmin", 0), "--fmin"),
        (("--fmin", 5, "--fmax", 2), "--fmax = 2 Hz"),
        (("--points", 1), "--points"),
        (("--speed", -1), "--speed"),
    ],
)
def test_frf_bad_input(args, fragment, tmp_path):
    assert_input_error(run("frf", *args, "--out", tmp_path / "x"), fragment)
    assert not (tmp_path / "x").exists()


# -- compare --out: PSD; sweep --out: the plot ---------------------------------------------------
def test_compare_writes_the_acceleration_psd(tmp_path):
    out = tmp_path / "cmp"
    # from 2 s on, past the sine's entry taper: Parseval below needs a steady signal
    ok("compare", "--controllers", "pid", "--duration", 6, "--window", "2:6", "--out", out)
    assert sorted(p.name for p in out.iterdir()) == sorted(COMPARE_FILES)
    assert {"psd.png", "psd.csv"} <= set(COMPARE_FILES)
    assert is_png(out / "psd.png")
    psd = pd.read_csv(out / "psd.csv")
    assert list(psd.columns) == ["frequency_hz", "passive", "pid"]
    f = psd["frequency_hz"].values
    # the sine at 55.56 / 60 Hz: one segment of the 3 whole periods in the 4 s window, bins f0 / 3
    f0, n = 55.56 / 60, round(3 * 1000 * 60 / 55.56)
    assert f[0] == 0 and np.allclose(np.diff(f), 1000 / n) and 1000 / n == pytest.approx(f0 / 3, rel=1e-3)
    assert f[-1] == pytest.approx(500.0) and abs(f[np.argmax(psd["passive"])] - f0) <= f[1]
    assert (psd[["passive", "pid"]].values >= 0).all()
    # Parseval: the PSD integrates to the variance of the acceleration over that segment
    runs = pd.read_csv(out / "compare.csv")
    for name in ("passive", "pid"):
        part = runs[runs["controller"] == name].tail(n)
        variance = part["carbody_acceleration"].var()
        assert psd[name].sum() * f[1] == pytest.approx(variance, rel=0.1)


def test_sweep_writes_the_plot_for_one_numeric_axis(tmp_path):
    out = tmp_path / "speeds"
    result = ok("sweep", "--speed", "20:40:3", "--duration", 1, "--out", out)
    assert "sweep.png" in result.stderr
    # comfort is on by default: its plot comes with the RMS one
    assert sorted(p.name for p in out.iterdir()) == ["comfort.png", "runs.csv", "sweep.json", "sweep.png"]
    assert is_png(out / "sweep.png")
    # none with several values: no plot, and a line that says why
    other = tmp_path / "grid"
    result = ok("sweep", "--duration", 1, "--out", other)
    assert sorted(p.name for p in other.iterdir()) == ["runs.csv", "sweep.json"]
    assert "note: no figure" in result.stderr


def test_a_measured_line_runs_from_start(tmp_path):
    """--start M runs a measured profile's section from s = M on: simulate, compare and study give
    the run of `railride.scenario("file:...", start=M)`, which is the line shifted by M (the
    section's RMS differs from the whole line's); a scenario that is not a file, a negative start,
    and a league table are refused (status 2) before any run."""
    import numpy as np
    import railride as rr

    s = np.arange(0.0, 800.25, 0.25)
    zl, zr, _, _ = rr.scenario("fra4", seed=3).track.evaluate(s)
    path = tmp_path / "line.csv"
    pd.DataFrame({"s": s, "z_L": zl, "z_R": zr}).to_csv(path, index=False)
    line = f"file:{path}"
    direct = rr.simulate(rr.scenario(line, start=160.0, speed=40.0, duration=2.0)).metrics()
    want = float(direct.sel(response="acceleration_m_s2", statistic="rms"))
    whole = rr.simulate(rr.scenario(line, speed=40.0, duration=2.0)).metrics()
    assert abs(float(whole.sel(response="acceleration_m_s2", statistic="rms")) - want) > 1e-3 * want
    doc = ok_json("simulate", "--scenario", line, "--start", 160, "--speed", 40, "--duration", 2)
    assert doc["metrics"]["acceleration_m_s2"]["rms"] == pytest.approx(want, rel=1e-12)
    doc = ok_json("compare", "--scenario", line, "--start", 160, "--speed", 40, "--duration", 2,
                  "--controllers", "passive")  # fmt: skip
    passive = next(r for r in doc["controllers"] if r["name"] == "passive")
    assert passive["metrics"]["acceleration_m_s2"]["rms"] == pytest.approx(want, rel=1e-12)
    doc = ok_json("study", "--scenario", line, "--start", 160, "--speed", 40, "--duration", 2,
                  "--controllers", "passive")  # fmt: skip
    assert doc["settings"]["start_m"] == 160.0
    mean = next(g for g in doc["results"] if g["controller"] == "passive")["metrics"]["acceleration_m_s2_rms"]["mean"]
    assert mean == pytest.approx(want, rel=1e-12)
    assert_input_error(run("simulate", "--scenario", "fra4", "--start", 160), "--start = 160", "file:PATH")
    assert_input_error(run("compare", "--scenario", line, "--start", -5), "--start = -5", ">= 0")
    assert_input_error(run("compare", "--scenario", line, "--start", 160, "--speed", "30,40"), "--start")
