import math

import numpy as np
import pytest
import xarray as xr

from railride.analysis.metrics import parse_window, reduction, ride_metrics, to_dict


def _run(amplitudes, f=2.0, duration=4.0, rate=1000.0, offset=0.0):
    t = np.arange(int(duration * rate) + 1) / rate
    s = np.sin(2 * np.pi * f * t)
    acc, disp, pitch, roll = amplitudes
    return xr.Dataset(
        {
            "carbody_acceleration": ("time", acc * s),
            "carbody_bounce": ("time", disp * s + offset),
            "carbody_pitch": ("time", pitch * s),
            "carbody_roll": ("time", roll * s),
        },
        coords={"time": t},
    )


def test_rms_and_peak_to_peak_of_a_sine():
    m = ride_metrics(_run((0.3, 0.02, math.radians(1.0), math.radians(2.0))))
    d = to_dict(m)
    assert d["acceleration_m_s2"]["rms"] == pytest.approx(0.3 / math.sqrt(2), rel=1e-3)
    assert d["acceleration_m_s2"]["ptp"] == pytest.approx(0.6, rel=1e-6)
    assert d["displacement_m"]["rms"] == pytest.approx(0.02 / math.sqrt(2), rel=1e-3)
    assert d["pitch_deg"]["rms"] == pytest.approx(1.0 / math.sqrt(2), rel=1e-3)  # rad -> deg
    assert d["roll_deg"]["ptp"] == pytest.approx(4.0, rel=1e-6)


def test_rms_is_about_zero_not_about_the_mean():
    d = to_dict(ride_metrics(_run((1, 0.0, 0, 0), offset=0.01)))
    assert d["displacement_m"]["rms"] == pytest.approx(0.01)


def test_window_selects_a_time_range_and_is_checked():
    ds = _run((1, 1, 1, 1))
    ds["carbody_acceleration"] = ds["carbody_acceleration"] * (ds.time > 2.0)
    d = to_dict(ride_metrics(ds, window=(0.0, 1.5)))
    assert d["acceleration_m_s2"]["rms"] == 0
    assert parse_window("1:2") == (1.0, 2.0) and parse_window(":3")[0] == 0.0
    assert math.isinf(parse_window("2:")[1])
    assert to_dict(ride_metrics(ds, window=parse_window("2.5:")))["acceleration_m_s2"]["rms"] > 0
    for bad in ((3.0, 2.0), (-1.0, 2.0), (1.0, 9.0), (4.0, 4.0)):
        with pytest.raises(ValueError, match="window"):
            ride_metrics(ds, window=bad)
    for text in ("1-2", "a:b", "1:2:3"):
        with pytest.raises(ValueError, match="window"):
            parse_window(text)


def test_reduction_against_a_baseline():
    base = ride_metrics(_run((1.0, 1.0, 1.0, 1.0)))
    half = ride_metrics(_run((0.5, 0.75, 1.0, 1.2)))
    r = reduction(half, base).sel(statistic="rms").values
    assert np.allclose(r, [50.0, 25.0, 0.0, -20.0])


def test_nan_results_are_refused():
    ds = _run((1, 1, 1, 1))
    ds["carbody_roll"][5] = np.nan
    with pytest.raises(RuntimeError, match="not finite"):
        ride_metrics(ds)
