"""`railride.analysis.spectra.comparison_psd` on made-up signals of known content: a periodic
track's spectrum resolves its input (one Hann segment of whole periods), any other track's is
Welch's with 4 s segments; the titles say which, with the bin width."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from railride.analysis.labels import psd_title
from railride.analysis.psd_plan import PSD_MIN_PERIODS, periodic_input_hz, psd_plan
from railride.analysis.spectra import comparison_psd

SPEED, WAVELENGTH = 55.56, 60.0  # the paper's sine: 0.926 Hz
F0 = SPEED / WAVELENGTH
FS = 1000.0


def made_up(signal, scenario: dict, duration: float = 10.0) -> xr.Dataset:
    """A combined comparison Dataset of one suspension whose carbody acceleration is ``signal(t)``."""
    t = np.round(np.arange(0.0, duration + 0.5 / FS, 1 / FS), 9)
    ds = xr.Dataset(
        {"carbody_acceleration": (("controller", "time"), signal(t)[None, :])},
        coords={"controller": ["passive"], "time": t},
    )
    ds.attrs["settings"] = json.dumps({"scenario": scenario})
    return ds


SINE = {"name": "paper-sine", "profile": "sine", "speed_m_s": SPEED, "wavelength_m": WAVELENGTH}
RANDOM = {"name": "fra4", "profile": "random", "speed_m_s": SPEED, "spectrum": "fra4"}


def sine(t, amplitude=0.6):
    return amplitude * np.sin(2 * np.pi * F0 * t + 0.3)


def test_the_paper_sine_is_resolved_within_one_bin_and_keeps_its_power():
    """Amplitude 0.6 m/s^2 at 0.926 Hz (mean square 0.18), with a third harmonic of 0.1: the
    peak is within one bin of f0, the bins are at most f0 / 5, and the PSD integrated over the
    peak gives the sine's mean square 0.6^2 / 2 (Parseval), the whole spectrum 0.18 + 0.005."""
    ds = made_up(lambda t: sine(t) + 0.1 * np.sin(2 * np.pi * 3 * F0 * t), SINE)
    for window in (None, (2.0, 10.0)):
        psd = comparison_psd(ds, window)
        f, p = psd["frequency_hz"].values, psd["passive"].values
        df = f[1] - f[0]
        assert psd.attrs["method"] == "periodic" and psd.attrs["periods"] >= PSD_MIN_PERIODS
        assert df <= F0 / PSD_MIN_PERIODS and np.isclose(df, psd.attrs["bin_hz"])
        assert abs(f[np.argmax(p)] - F0) <= df
        near = np.abs(f - F0) <= 2.5 * df  # Hann: the line and its two neighbours
        assert np.sum(p[near]) * df == pytest.approx(0.6**2 / 2, rel=1e-3)
        assert np.sum(p) * df == pytest.approx(0.6**2 / 2 + 0.1**2 / 2, rel=1e-3)
        third = np.abs(f - 3 * F0) <= 2.5 * df
        assert np.sum(p[third]) * df == pytest.approx(0.1**2 / 2, rel=1e-2)
    # 10 s hold 9 periods of 1.08 s: the last nine, bins f0 / 9
    assert comparison_psd(ds).attrs["periods"] == 9
    assert comparison_psd(ds).attrs["bin_hz"] == pytest.approx(F0 / 9, rel=1e-3)


def test_a_random_track_keeps_welch_with_4_s_segments():
    rng = np.random.default_rng(1)
    ds = made_up(lambda t: rng.normal(size=t.size), RANDOM, duration=20.0)
    psd = comparison_psd(ds)
    assert psd.attrs["method"] == "welch" and psd.attrs["bin_hz"] == pytest.approx(0.25)
    assert psd["frequency_hz"].values[1] == pytest.approx(0.25)
    # white noise of unit variance: a flat one-sided density of 2 / fs
    assert np.median(psd["passive"].values[1:-1]) == pytest.approx(2 / FS, rel=0.1)


def test_short_windows():
    """Fewer than five periods: the whole periods there are, said to be coarser; less than one:
    Welch over the whole window."""
    ds = made_up(sine, SINE)
    four = psd_plan(ds, (5.5, 10.0))
    assert four["method"] == "periodic" and four["periods"] == 4 and "coarser than f/5" in four["text"]
    short = psd_plan(ds, (9.5, 10.0))
    assert short["method"] == "welch" and short["bin_hz"] == pytest.approx(FS / 501)


def test_the_input_frequency_comes_from_the_recorded_scenario():
    assert periodic_input_hz(made_up(sine, SINE)) == pytest.approx(0.926)
    assert periodic_input_hz(made_up(sine, RANDOM)) is None
    assert periodic_input_hz(made_up(sine, {"name": "bump", "profile": "cosine-bump"})) is None
    bare = made_up(sine, SINE)
    bare.attrs.pop("settings")
    assert periodic_input_hz(bare) is None  # nothing recorded: not known to be periodic


def test_the_titles_say_how_with_the_bin_width():
    from matplotlib.figure import Figure

    from railride.plots.comparison import plot_comparison_psd

    ds = made_up(sine, SINE)
    title = " ".join(psd_title(ds, (2.0, 10.0), 4.0).split())
    assert "2-10 s" in title and "the last 7 whole periods of the 0.926 Hz input" in title
    assert f"{F0 / 7:.3g} Hz bins" in title
    welch = " ".join(psd_title(made_up(sine, RANDOM), None, 4.0).split())
    assert "0.25 Hz bins: Welch, 4 s Hann segments, 50 % overlap" in welch
    fig = plot_comparison_psd(comparison_psd(ds))
    assert isinstance(fig, Figure) and "0.103 Hz bins" in " ".join(fig._suptitle.get_text().split())
