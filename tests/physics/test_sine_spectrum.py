"""The acceleration spectrum of `railride compare` on the paper's sine resolves the sine: the
passive vehicle's carbody acceleration, a linear response to a 0.926 Hz input, is one line there,
and the spectrum's power around it is the variance of the signal it was taken from."""

from __future__ import annotations

import numpy as np
import pytest

from railride.analysis.psd_plan import PSD_MIN_PERIODS
from railride.analysis.spectra import comparison_psd
from railride.studies.comparison import compare


@pytest.mark.parametrize("window", [None, (2.0, 10.0)])
def test_the_paper_sine_spectrum_has_its_line_within_one_bin(window):
    ds = compare("paper-sine", controllers=["passive"], bounds=False).combined()
    f0 = 55.56 / 60.0  # speed / wavelength of the paper's sine
    psd = comparison_psd(ds, window)
    f, p = psd["frequency_hz"].values, psd["passive"].values
    df = f[1] - f[0]
    assert df <= f0 / PSD_MIN_PERIODS
    assert abs(f[np.argmax(p)] - f0) <= df
    # Parseval, against the time history itself: from 2 s on the vehicle is settled, and the
    # line (the Hann window spreads it over three bins) holds the variance of the segment
    if window is not None:
        t = ds["time"].values
        x = ds["carbody_acceleration"].sel(controller="passive").values[t >= psd.attrs["start_s"] - 1e-9]
        assert x.size == psd.attrs["samples"]
        near = np.abs(f - f0) <= 2.5 * df
        assert np.sum(p[near]) * df == pytest.approx(np.var(x), rel=0.01)
