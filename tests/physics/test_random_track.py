"""Random track irregularity from standard spectra."""

import numpy as np
import pytest
import scipy.signal
from scipy.integrate import quad

from railride.run.simulation import simulate
from railride.model.track import FRA_AV, RandomTrack, scenario, spectrum

BAND = (1.0, 100.0)  # m


@pytest.mark.parametrize("name", ["fra1", "fra4", "fra6", "german-low", "german-high"])
@pytest.mark.parametrize("component", ["vertical", "cross-level"])
def test_realisation_variance_equals_the_spectrum_over_the_band(name, component):
    tr = RandomTrack(name, seed=5, min_wavelength=BAND[0], max_wavelength=BAND[1], length=4000.0)
    s, zv, zx = tr.samples()
    z = zv if component == "vertical" else zx
    lo, hi = 2 * np.pi / BAND[1], 2 * np.pi / BAND[0]
    # a sum of harmonics over a whole period: the variance is exactly sum S(W_k) dW ...
    dW = 2 * np.pi / tr.length
    W = np.arange(1, int(hi / dW) + 2) * dW
    W = W[(W >= lo) & (W <= hi)]
    assert np.var(z) == pytest.approx(np.sum(spectrum(name, W, component)) * dW, rel=1e-9)
    # ... which is the integral of the one-sided target spectrum over the band
    target = quad(lambda w: spectrum(name, w, component), lo, hi, limit=400)[0]
    assert np.var(z) == pytest.approx(target, rel=0.02)


@pytest.mark.parametrize("name", ["fra4", "german-high"])
def test_welch_psd_of_a_realisation_follows_the_target(name):
    tr = RandomTrack(name, seed=11, length=8000.0)
    s, zv, _ = tr.samples()
    ds = s[1] - s[0]
    f, P = scipy.signal.welch(zv, fs=1.0 / ds, nperseg=2**14)  # one-sided, per (cycle/m)
    W, S_est = 2 * np.pi * f, P / (2 * np.pi)  # per (rad/m)
    inside = (W > 2 * np.pi / 60) & (W < 2 * np.pi / 2)
    ratio = S_est[inside] / spectrum(name, W[inside])
    assert np.median(ratio) == pytest.approx(1.0, rel=0.1)
    assert np.mean(np.log(ratio)) == pytest.approx(0.0, abs=0.15)


def test_classes_scale_with_their_roughness_constant():
    W = np.array([0.1, 0.5, 2.0])
    ratio = spectrum("fra6", W) / spectrum("fra4", W)
    assert np.allclose(ratio, FRA_AV[6] / FRA_AV[4])
    # vertical FRA spectra fall as Omega^-4 well above Omega_c
    assert spectrum("fra4", 20.0) / spectrum("fra4", 40.0) == pytest.approx(16, rel=0.01)
    assert np.all(spectrum("german-high", W) > spectrum("german-low", W))


def test_rails_are_the_profile_plus_and_minus_half_the_cross_level():
    tr = RandomTrack("fra4", seed=2)
    s = np.linspace(30.0, 500.0, 2000)  # past the lead-in
    zl, zr, _, _ = tr.evaluate(s)
    s_grid, zv, zx = tr.samples()
    assert np.allclose((zl + zr) / 2, np.interp(s, s_grid, zv), atol=2e-5)
    assert np.allclose(zl - zr, np.interp(s, s_grid, zx), atol=2e-5)
    assert np.all(np.abs(tr.evaluate(np.array([0.0, 1e-3]))[0]) < 1e-6)  # enters level track


def test_compiled_rails_are_scipys_splines_to_the_bit():
    # the input tables read the rails through a compiled evaluation (railride.engine.tables);
    # scipy's CubicSpline of the same samples is the second method, at random points, at every
    # breakpoint (the interval a point on one belongs to), at the ends and past the last one
    tr = RandomTrack("german-high", seed=8, length=600.0)
    sl, sr = tr.splines()
    rng = np.random.default_rng(3)
    s = np.concatenate([rng.uniform(0.0, tr.end(), 5000), sl.x, np.nextafter(sl.x, -1.0), [tr.end() + 0.3]])
    ours = tr._evaluate(s)
    assert all(np.array_equal(a, b) for a, b in zip(ours, (sl(s), sr(s), sl(s, 1), sr(s, 1))))


def test_rail_slopes_are_the_derivative_of_the_heights():
    tr = RandomTrack("fra4", seed=6)
    s, h = np.linspace(25.0, 400.0, 3001), 1e-4
    zl, zr, dzl, dzr = tr.evaluate(s)
    fd = [(a - b) / (2 * h) for a, b in zip(tr.evaluate(s + h)[:2], tr.evaluate(s - h)[:2])]
    scale = np.max(np.abs(dzl))
    assert np.max(np.abs(dzl - fd[0])) < 1e-5 * scale and np.max(np.abs(dzr - fd[1])) < 1e-5 * scale


def test_seeds_are_reproducible_and_distinct():
    a = RandomTrack("german-low", seed=1).samples()[1]
    b = RandomTrack("german-low", seed=1).samples()[1]
    c = RandomTrack("german-low", seed=2).samples()[1]
    assert np.array_equal(a, b) and not np.allclose(a, c)
    r1 = simulate(scenario("fra4", seed=4, duration=1.0)).metrics()
    r2 = simulate(scenario("fra4", seed=4, duration=1.0)).metrics()
    assert np.array_equal(r1.values, r2.values)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"name": "fra7"}, "unknown track spectrum 'fra7'"),
        ({"name": "fra4", "min_wavelength": -1.0}, "min_wavelength"),
        ({"name": "fra4", "min_wavelength": 50.0, "max_wavelength": 10.0}, "below max_wavelength"),
        ({"name": "fra4", "seed": -3}, "seed"),
    ],
)
def test_bad_random_track_settings(kwargs, match):
    with pytest.raises(ValueError, match=match):
        RandomTrack(**kwargs)


def test_a_band_the_output_rate_cannot_resolve_is_refused():
    sc = scenario("fra4", min_wavelength=0.1, duration=1.0)  # 556 Hz at 55.56 m/s
    with pytest.raises(ValueError, match="min_wavelength = 0.1 m .* output_rate"):
        simulate(sc)
    with pytest.raises(ValueError, match="seed applies to the random tracks"):
        scenario("paper-sine", seed=3)
    with pytest.raises(ValueError, match="unknown scenario"):
        scenario("fra9")


def test_rail_forcing_at_the_nodes_is_the_input_matrices_times_the_rails():
    # the compiled forcing table (railride.engine.tables.forcing_nodes) against NumPy's matrix
    # products of the same input table: (Bw w, Bw w', Bwd w, Bwd w') at every node
    from railride.model.params import VehicleParams
    from railride.model.track import wheelset_input_table
    from railride.run.inputs import _forcing_table, _system_arrays, _vehicle

    for preset in ("paper", "crh380a"):
        vehicle = _vehicle(VehicleParams.preset(preset))
        arrays = _system_arrays(vehicle)
        Bw, Bwd = arrays["Bw"], arrays["Bwd"]
        table, _ = wheelset_input_table(
            scenario("fra4", seed=3, speed=45.0, duration=2.0), vehicle.wheelset_lag_distance, 1e-4
        )
        w, wd = table[:, :8], table[:, 8:]
        expected = np.hstack([w @ Bw.T, wd @ Bw.T, w @ Bwd.T, wd @ Bwd.T])
        got = _forcing_table(table, Bw, Bwd)
        assert got.shape == expected.shape and np.abs(expected).max() > 0
        assert np.max(np.abs(got - expected)) <= 1e-14 * np.abs(expected).max()
