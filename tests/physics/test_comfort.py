"""Ride comfort (railride.analysis.comfort): the weightings against the published one-third-octave tables,
the digital filters against the analog weightings, and each index against a closed form."""

import json
import math
import warnings

import numpy as np
import pytest
import xarray as xr

from railride.analysis import comfort
from railride.analysis.comfort import (
    ShortRunWarning,
    comfort_class,
    comfort_intervals,
    floor_acceleration,
    mean_comfort_vertical,
    ride_comfort,
    sperling_wz,
    to_dict,
    vdv,
    weight,
    weighted_rms,
    weighting,
)

RATE = 1000.0  # railride's default output rate

# ISO 2631-1:1997 Table 3, weighting factors x 1000 at the nominal one-third-octave centres. The
# table is computed at the nominal centres (at the exact centres 10^(n/10) the filter is up to
# 1.4 % away) and rounded to three significant figures: tolerance 1 % of the table value.
TABLE3_WK = {
    0.5: 418,
    0.63: 459,
    0.8: 477,
    1: 482,
    1.25: 484,
    1.6: 494,
    2: 531,
    2.5: 631,
    3.15: 804,
    4: 967,
    5: 1039,
    6.3: 1054,
    8: 1036,
    10: 988,
    12.5: 902,
    16: 768,
    20: 636,
    25: 513,
    31.5: 405,
    40: 314,
    50: 246,
    63: 186,
    80: 132,
}
TABLE3_WD = {
    0.5: 853,
    0.63: 944,
    0.8: 992,
    1: 1011,
    1.25: 1008,
    1.6: 968,
    2: 890,
    2.5: 776,
    3.15: 642,
    4: 512,
    5: 409,
    6.3: 323,
    8: 253,
    10: 212,
    12.5: 161,
    16: 125,
    20: 100,
    25: 80,
    31.5: 63.2,
    40: 49.4,
    50: 38.8,
}
# ISO 2631-1 Table 4 (Wc, We) as transcribed in a public repository, not checked against the
# printed standard; a selection across the band.
TABLE4_WC = {0.5: 843, 1: 991, 2: 1012, 4: 1024, 6.3: 974, 10: 776, 16: 512, 31.5: 256, 80: 84.4}
TABLE4_WE = {0.5: 862, 1: 880, 2: 512, 4: 253, 6.3: 160, 10: 100, 16: 62.5, 31.5: 31.6, 80: 10.5}
TABLE_RTOL = 0.01

# The one table value that disagrees with the exact filter: Wd at 10 Hz prints 212, the filter
# gives 201.7 (-4.9 %). Its neighbours agree to 0.3 %, the curve falls as ~1/f there
# (253 * 8/10 = 202), and We at 5 Hz, the same curve an octave down, reads 202.
DISAGREES = {
    ("Wd", 10): "Table 3 prints 212, the exact Wd filter gives 201.7 (-4.9 %); "
    "likely a misprint for 202 (see docs/comfort.md)"
}


def _table_cases():
    for name, table in (("Wk", TABLE3_WK), ("Wd", TABLE3_WD), ("Wc", TABLE4_WC), ("We", TABLE4_WE)):
        for f, value in table.items():
            marks = [pytest.mark.xfail(strict=True, reason=DISAGREES[(name, f)])] if (name, f) in DISAGREES else []
            yield pytest.param(name, f, value, marks=marks, id=f"{name}-{f}Hz")


@pytest.mark.parametrize("name, f, value", list(_table_cases()))
def test_weighting_equals_the_iso_2631_1_table(name, f, value):
    assert weighting(name, f) * 1000 == pytest.approx(value, rel=TABLE_RTOL)


def test_wb_follows_its_asymptotes_not_2_56_times_them():
    # BS 6841 describes Wb by straight lines: 0.4 (0.5-2 Hz), f/5 (2-5 Hz), 1 (5-16 Hz), 16/f
    # (16-80 Hz). Away from the corners the filter is within 6 % of them; the low-frequency
    # level K (f5/f6)^2 = 1.024 * 0.39 = 0.4 would read 1.024 with the step normalised to 1 there
    for f, line in ((1.0, 0.4), (1.6, 0.4), (8.0, 1.0), (10.0, 1.0), (40.0, 0.4), (63.0, 16 / 63)):
        assert weighting("Wb", f) == pytest.approx(line, rel=0.08)


def test_iso_8041_wb_follows_the_same_asymptotes():
    # the ISO 8041 / ISO 2631-4 form of Wb (other Q values) lies on the same BS 6841 lines
    for f, line in ((1.0, 0.4), (1.6, 0.4), (8.0, 1.0), (10.0, 1.0), (40.0, 0.4), (63.0, 16 / 63)):
        assert weighting("Wb8041", f) == pytest.approx(line, rel=0.08)
    # and differs from the EN 12299 form by at most about 12 % (docs/comfort.md)
    f = np.logspace(0, np.log10(80), 50)
    assert np.max(np.abs(weighting("Wb8041", f) / weighting("Wb", f) - 1)) < 0.13


def test_weighting_is_vectorised_and_zero_at_dc():
    f = np.array([[0.0, 1.0], [4.0, 8.0]])
    w = weighting("Wk", f)
    assert w.shape == (2, 2) and w[0, 0] == 0.0
    assert w[1, 1] == pytest.approx(weighting("Wk", 8.0))


def _steady_amplitude(name, freqs, rate=RATE, settle=20.0, span=10.0):
    """Amplitude of each weighted unit sine once the filter's start transient has died out,
    over a whole number of periods."""
    t = np.arange(int((settle + span) * rate)) / rate
    x = np.sin(2 * np.pi * np.asarray(freqs)[:, None] * t)
    y = weight(name, x, rate)[:, int(settle * rate) :]
    return np.sqrt(2 * np.mean(y * y, axis=-1))


@pytest.mark.parametrize("name", ["Wk", "Wd", "Wb", "Wc", "We"])
def test_digital_filter_on_a_sine_gives_the_analog_gain(name):
    freqs = [0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 31.5, 50.0, 63.0]
    got = _steady_amplitude(name, freqs)
    assert got == pytest.approx(weighting(name, freqs), rel=0.01)


def test_digital_filter_at_the_lowest_accepted_rate():
    rate = comfort.min_rate_hz("Wk")
    assert rate == 500.0
    freqs = [1.0, 8.0, 31.5]
    assert _steady_amplitude("Wk", freqs, rate=rate) == pytest.approx(weighting("Wk", freqs), rel=0.01)


def _sine(amplitude, f, duration, rate=RATE):
    t = np.arange(int(round(duration * rate))) / rate
    return amplitude * np.sin(2 * np.pi * f * t)


@pytest.mark.parametrize("name, f", [("Wk", 1.0), ("Wk", 6.3), ("Wb", 4.0), ("Wb", 12.5)])
def test_weighted_rms_of_a_sine(name, f):
    A = 0.8
    x = _sine(A, f, 30.0)
    got = weighted_rms(x, RATE, weighting=name, window=(10.0, 30.0))
    assert got == pytest.approx(weighting(name, f) * A / math.sqrt(2), rel=1e-3)


def test_vdv_of_a_sine_over_whole_periods():
    A, f, T = 1.5, 4.0, 20.0
    x = _sine(A, f, 10.0 + T)
    got = vdv(x, RATE, window=(10.0, 10.0 + T))
    assert got == pytest.approx(weighting("Wk", f) * A * (3 * T / 8) ** 0.25, rel=1e-3)


def test_mean_comfort_of_a_stationary_sine():
    A, f = 0.3, 4.0
    x = _sine(A, f, 30.0)
    rms = comfort_intervals(x, RATE, window=(10.0, 30.0))
    assert rms.shape == (4,)
    expected = weighting("Wb", f) * A / math.sqrt(2)
    assert rms == pytest.approx(np.full(4, expected), rel=1e-3)
    assert mean_comfort_vertical(x, RATE, window=(10.0, 30.0)) == pytest.approx(6 * expected, rel=1e-3)


def test_mean_comfort_takes_the_95th_percentile_of_the_intervals():
    # five 5 s intervals with growing amplitude: the percentile interpolates between the two
    # largest RMS values
    amps = np.array([0.1, 0.2, 0.3, 0.4, 0.5])
    x = np.concatenate([_sine(a, 8.0, 5.0) for a in amps])
    rms = comfort_intervals(x, RATE)
    assert rms.shape == (5,)
    assert mean_comfort_vertical(x, RATE) == pytest.approx(6 * (rms[3] + 0.8 * (rms[4] - rms[3])))


def test_mean_comfort_of_a_run_shorter_than_5_s_uses_one_interval_and_warns():
    x = _sine(0.5, 5.0, 3.0)
    with pytest.warns(ShortRunWarning, match="5 s"):
        n = mean_comfort_vertical(x, RATE)
    assert n == pytest.approx(6 * weighted_rms(x, RATE, weighting="Wb"))


def test_comfort_scale():
    assert comfort_class(0.5) == "very comfortable"
    assert comfort_class(1.0) == "comfortable"
    assert comfort_class(3.9) == "medium"
    assert comfort_class(4.0) == "uncomfortable"
    assert comfort_class(5.0) == "very uncomfortable"
    with pytest.raises(ValueError):
        comfort_class(float("nan"))


def _wz_by_hand(a_m_s2, f):
    a = 100.0 * a_m_s2  # cm/s^2
    F = 0.325 * f**2 if f <= 5.9 else (400 / f**2 if f <= 20 else 1.0)
    return 0.896 * (a**3 * F / f) ** 0.1


def test_sperling_of_one_sine():
    A, f = 0.5, 2.0  # 50 cm/s^2 at 2 Hz: F = 0.325 * 4 = 1.3
    assert sperling_wz(_sine(A, f, 10.0), RATE) == pytest.approx(0.896 * (50**3 * 1.3 / 2) ** 0.1, rel=1e-9)


def test_sperling_of_two_sines_is_the_tenth_power_sum():
    x = _sine(0.5, 2.0, 10.0) + _sine(0.2, 8.0, 10.0)  # 8 Hz: F = 400 / 64
    expected = (_wz_by_hand(0.5, 2.0) ** 10 + _wz_by_hand(0.2, 8.0) ** 10) ** 0.1
    assert sperling_wz(x, RATE) == pytest.approx(expected, rel=1e-9)
    # and above 20 Hz the correction is 1
    assert sperling_wz(_sine(0.1, 25.0, 2.0), RATE) == pytest.approx(_wz_by_hand(0.1, 25.0), rel=1e-9)


def test_signal_functions_take_a_batch():
    # each row its own signal: the same sine at twice the amplitude gives twice the weighted
    # RMS and the mean comfort (linear in the signal) and 2^0.3 times Wz (a^3 under a tenth
    # power), and each row what the row alone gives
    x = np.stack([_sine(0.2, 4.0, 12.0), _sine(0.4, 4.0, 12.0)])
    indices = (
        (lambda s: weighted_rms(s, RATE, window=(6.0, 12.0)), 1.0),
        (lambda s: sperling_wz(s, RATE), 0.3),
        (lambda s: mean_comfort_vertical(s, RATE), 1.0),
    )
    for index, power in indices:
        batch = np.asarray(index(x))
        assert batch.shape == (2,) and batch[0] > 0
        assert batch[1] == pytest.approx(2**power * batch[0], rel=1e-9)
        assert batch == pytest.approx([float(index(x[0])), float(index(x[1]))], rel=1e-12)


# -- bad input ------------------------------------------------------------------------------------


def test_unknown_weighting_is_refused():
    with pytest.raises(ValueError, match="unknown frequency weighting 'Wx'.*Wk"):
        weighting("Wx", 1.0)
    with pytest.raises(ValueError, match="unknown frequency weighting"):
        weighted_rms(np.zeros(100), RATE, weighting="A")


@pytest.mark.parametrize("f", [-1.0, float("nan"), [1.0, -0.1], float("inf")])
def test_bad_frequencies_are_refused(f):
    with pytest.raises(ValueError, match="frequenc"):
        weighting("Wk", f)


def test_a_rate_too_low_for_the_weighting_is_refused():
    with pytest.raises(ValueError, match=r"rate_hz = 400 Hz.*f2 = 100 Hz.*500 Hz"):
        weight("Wk", np.zeros(100), 400.0)
    for rate in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="rate_hz"):
            weight("Wk", np.zeros(100), rate)


def test_bad_signals_and_windows_are_refused():
    with pytest.raises(ValueError, match="NaN"):
        weighted_rms(np.array([0.0, np.nan, 1.0]), RATE)
    with pytest.raises(ValueError, match="two samples"):
        vdv(np.zeros(1), RATE)
    with pytest.raises(ValueError, match="window"):
        weighted_rms(np.zeros(1000), RATE, window=(0.5, 2.0))  # the signal lasts 1 s
    with pytest.raises(ValueError, match="window"):
        sperling_wz(np.zeros(1000), RATE, window=(0.8, 0.2))


# -- on a carbody ---------------------------------------------------------------------------------

L = 9.0


def _run(duration=12.0, acc=(0.3, 1.5), pitch=(0.01, 0.9), rate=RATE):
    """A Dataset shaped like simulate's: carbody CG acceleration A sin(2 pi f t) and pitch
    velocity B sin(2 pi g t), so the pitch acceleration is 2 pi g B cos(2 pi g t)."""
    t = np.arange(int(duration * rate) + 1) / rate
    return xr.Dataset(
        {
            "carbody_acceleration": ("time", acc[0] * np.sin(2 * np.pi * acc[1] * t)),
            "carbody_pitch_velocity": ("time", pitch[0] * np.sin(2 * np.pi * pitch[1] * t)),
            "vehicle_params": ((), json.dumps({"l": L, "m_c": 3.4e4})),
        },
        coords={"time": t},
    )


def _pitch_acc(ds, pitch=(0.01, 0.9)):
    t = ds.time.values
    return 2 * np.pi * pitch[1] * pitch[0] * np.cos(2 * np.pi * pitch[1] * t)


def test_floor_acceleration_above_the_bogies():
    ds = _run()
    floor = floor_acceleration(ds)
    assert list(floor.position.values) == ["centre", "front", "rear"]
    assert list(floor.x_m.values) == [0.0, L, -L]
    a, phi2 = ds.carbody_acceleration.values, _pitch_acc(ds)
    assert np.array_equal(floor.sel(position="centre").values, a)
    # a point at x moves by z - x phi: the front (x = +l) by z - l phi
    expected = a - L * phi2
    err = np.abs(floor.sel(position="front").values - expected)
    # central difference inside, (omega h)^2 / 6 relative; second-order one-sided at the ends
    assert err[1:-1].max() < 1e-4 * np.abs(L * phi2).max()
    assert err.max() < 1e-3 * np.abs(L * phi2).max()


def test_ride_comfort_of_a_run():
    ds = _run()
    out = ride_comfort(ds)
    assert out.dims == ("position", "index")
    assert list(out["index"].values) == ["aw_Wk", "vdv_Wk", "aw_Wb", "vdv_Wb", "N_MV_z", "Wz"]
    assert list(out.unit.values) == ["m/s^2", "m/s^1.75", "m/s^2", "m/s^1.75", "1", "1"]
    a = ds.carbody_acceleration.values
    centre = out.sel(position="centre")
    assert float(centre.sel(index="aw_Wk")) == pytest.approx(weighted_rms(a, RATE))
    assert float(centre.sel(index="Wz")) == pytest.approx(sperling_wz(a, RATE))
    assert float(centre.sel(index="N_MV_z")) == pytest.approx(mean_comfort_vertical(a, RATE))
    assert out.attrs["n_intervals"] == 2
    front = a - L * _pitch_acc(ds)
    assert float(out.sel(position="front", index="vdv_Wb")) == pytest.approx(vdv(front, RATE, weighting="Wb"), rel=1e-4)
    d = to_dict(out)
    assert set(d) == {"centre", "front", "rear"} and set(d["rear"]) == set(out["index"].values)
    assert json.loads(json.dumps(out.to_dict()))["name"] == "ride_comfort"
    assert "lateral" in out.attrs["notes"]


def test_ride_comfort_prefers_a_pitch_acceleration_channel():
    ds = _run()
    exact = ds.assign(carbody_pitch_acceleration=("time", _pitch_acc(ds)))
    out = ride_comfort(exact)
    assert out.attrs["pitch_acceleration"] == "carbody_pitch_acceleration channel"
    front = ds.carbody_acceleration.values - L * _pitch_acc(ds)
    assert float(out.sel(position="front", index="aw_Wk")) == pytest.approx(weighted_rms(front, RATE), rel=1e-12)
    assert ride_comfort(ds).attrs["pitch_acceleration"].startswith("central difference")


def test_ride_comfort_positions_window_and_short_runs():
    ds = _run()
    out = ride_comfort(ds, positions={"seat_row_3": 4.5, "end": "rear"}, window=(2.0, 12.0), weightings=("Wk",))
    assert list(out.position.values) == ["seat_row_3", "end"]
    assert list(out.x_m.values) == [4.5, -L]
    assert list(out["index"].values) == ["aw_Wk", "vdv_Wk", "N_MV_z", "Wz"]
    a = ds.carbody_acceleration.values - 4.5 * _pitch_acc(ds)
    assert float(out.sel(position="seat_row_3", index="aw_Wk")) == pytest.approx(
        weighted_rms(a, RATE, window=(2.0, math.inf)), rel=1e-4
    )
    assert out.attrs["n_intervals"] == 2
    short = ride_comfort(_run(duration=3.0))
    assert short.attrs["n_intervals"] == 1 and "5 s" in short.attrs["notes"]
    with pytest.raises(ValueError, match="position 'middle'"):
        ride_comfort(ds, positions=("middle",))
    with pytest.raises(ValueError, match="window"):
        ride_comfort(ds, window=(5.0, 20.0))


def test_ride_comfort_of_a_batch_equals_the_single_runs():
    runs = [_run(acc=(0.3, 1.5)), _run(acc=(0.6, 4.0), pitch=(0.02, 1.1))]
    batch = xr.concat(runs, dim="sample").assign_coords(sample=[0, 1])
    out = ride_comfort(batch)
    assert out.dims == ("sample", "position", "index")
    for i, run in enumerate(runs):
        single = ride_comfort(run)
        assert np.allclose(out.isel(sample=i).values, single.values, rtol=1e-12, atol=0)
    with pytest.raises(ValueError, match="select a sample"):
        to_dict(out)


def test_ride_comfort_of_a_simulated_run():
    """On the paper's sine, once the start has died away, the floor moves as the frequency
    response at f = V / wavelength says (`Vehicle.frequency_response`, a second method): over
    whole periods each position's weighted RMS is |W(f)| A |H(f)| / sqrt(2) and its VDV
    |W(f)| A |H(f)| (3 T / 8)^(1/4) (measured within 1.1e-4)."""
    from railride.run.simulation import simulate
    from railride.model.track import scenario
    from railride.model.vehicle import Vehicle

    sc = scenario("paper-sine", duration=20.0)
    ds = simulate(sc).dataset
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = ride_comfort(ds)
    l = json.loads(str(ds.vehicle_params.values))["l"]
    assert list(out.x_m.values) == [0.0, l, -l]
    f = sc.speed / sc.track.wavelength
    span = 9 / f  # nine whole periods, from 10 s on
    steady = ride_comfort(ds, window=(10.0, 10.0 + span))
    rails = (1.0, np.exp(-1j * np.deg2rad(sc.track.rail_phase_deg)))
    frf = Vehicle().frequency_response([f], sc.speed, rails=rails)["floor_acceleration"]
    for position in ("centre", "front", "rear"):
        amplitude = sc.track.amplitude * abs(complex(frf.sel(position=position).values[0]))
        for w in ("Wk", "Wb"):
            got = steady.sel(position=position)
            expected = weighting(w, f) * amplitude
            assert float(got.sel(index=f"aw_{w}")) == pytest.approx(expected / math.sqrt(2), rel=1e-3), (position, w)
            assert float(got.sel(index=f"vdv_{w}")) == pytest.approx(expected * (3 * span / 8) ** 0.25, rel=1e-3)
