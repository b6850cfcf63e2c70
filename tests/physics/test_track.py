import numpy as np
import pytest

from railride.run.simulation import simulate
from railride.model.track import CosineBump, MeasuredTrack, Scenario, SineTrack, scenario, wheelset_input_table
from railride.model.vehicle import Vehicle


def test_sine_rails_follow_the_paper_formula():
    tr = SineTrack(amplitude=0.05, wavelength=60.0, rail_phase_deg=90.0, taper=0.0)
    s = np.linspace(0.1, 200, 1000)
    zl, zr, dzl, dzr = tr.evaluate(s)
    assert np.allclose(zl, 0.05 * np.sin(2 * np.pi * s / 60))
    assert np.allclose(zr, 0.05 * np.sin(2 * np.pi * s / 60 - np.pi / 2))
    # the right rail is the left rail a quarter wavelength later
    assert np.allclose(tr.evaluate(s + 15.0)[1], zl, atol=1e-15)
    # slopes are the derivative of the heights
    assert np.allclose(dzl[1:-1], np.gradient(zl, s)[1:-1], rtol=0, atol=1e-5)


def test_sine_enters_through_a_raised_cosine_taper_over_one_wavelength():
    tr = SineTrack(amplitude=0.05, wavelength=60.0, rail_phase_deg=90.0)
    plain = SineTrack(amplitude=0.05, wavelength=60.0, rail_phase_deg=90.0, taper=0.0)
    s = np.linspace(0.01, 180.0, 18000)
    zl, zr, dzl, dzr = tr.evaluate(s)
    pl, pr, _, _ = plain.evaluate(s)
    r = np.where(s < 60.0, np.sin(np.pi * s / 120.0) ** 2, 1.0)  # (1 - cos(pi s/L))/2
    assert np.allclose(zl, r * pl, rtol=0, atol=1e-15) and np.allclose(zr, r * pr, rtol=0, atol=1e-15)
    # no step: the right rail starts at 0, not at -A, and both heights and slopes are
    # continuous at s = 0 and at the end of the taper
    start = tr.evaluate(np.array([1e-6]))
    assert len(start) == 4 and all(abs(v[0]) < 1e-9 for v in start)
    for v in (zl, zr, dzl, dzr):
        assert np.abs(np.diff(v)).max() < 1e-4
    # slopes are the derivative of the heights, taper included
    assert np.allclose(dzr[1:-1], np.gradient(zr, s)[1:-1], rtol=0, atol=1e-6)
    with pytest.raises(ValueError, match="taper = -1"):
        SineTrack(taper=-1)
    with pytest.raises(ValueError, match="taper applies to paper-sine only"):
        scenario("bump", taper=1.0)


def test_every_profile_is_level_before_the_start():
    for tr in (SineTrack(), CosineBump(start=0.0)):
        out = tr.evaluate(np.array([-30.0, -1e-9, 0.0]))
        assert len(out) == 4 and all(np.all(o == 0) for o in out)


def test_cosine_bump_shape():
    b = CosineBump(height=-0.03, length=8.0, start=2.0, rails="right")
    zl, zr, dzl, dzr = b.evaluate(np.array([1.0, 2.0, 6.0, 10.0, 12.0]))
    assert np.all(zl == 0) and np.all(dzl == 0)
    assert np.allclose(zr, [0, 0, -0.03, 0, 0], atol=1e-15)
    assert np.allclose(dzr, 0, atol=1e-15)  # flat at both ends and at the crest


def _write_csv(path, s, zl, zr, header="s [m],z_L [m],z_R [m]"):
    rows = [header] + [f"{a:.17g},{b:.17g},{c:.17g}" for a, b, c in zip(s, zl, zr)]
    path.write_text("\n".join(rows) + "\n")
    return path


def test_measured_profile_reproduces_the_sine_it_was_sampled_from(tmp_path):
    sine = SineTrack(amplitude=0.05, wavelength=60.0, rail_phase_deg=0.0)
    s = np.arange(0.0, 600.25, 0.25)
    zl, zr, _, _ = sine.evaluate(s)
    path = _write_csv(tmp_path / "track.csv", s, zl, zr)
    meas = MeasuredTrack.from_csv(path)
    probe = np.linspace(1.0, 590.0, 777)
    assert np.abs(meas.evaluate(probe)[0] - sine.evaluate(probe)[0]).max() < 1e-4 * 0.05
    a = simulate(Scenario(sine, speed=55.56, duration=6.0)).metrics()
    b = simulate(scenario(f"file:{path}", duration=6.0)).metrics()
    assert np.allclose(a.values, b.values, rtol=1e-2)


def test_a_section_of_a_measured_profile_is_the_line_from_its_start_faded_in(tmp_path):
    """A section starting at 137.3 m (between samples) holds the line's heights from there on,
    past its 20 m fade-in exactly those of the whole profile at start + s, and starts level; a
    run on it is a run of the line's section. Outside the line, or on another track, refused."""
    sine = SineTrack(amplitude=0.05, wavelength=60.0, rail_phase_deg=90.0)
    s = np.arange(0.0, 600.25, 0.25)
    zl, zr, _, _ = sine.evaluate(s)
    whole = MeasuredTrack.from_csv(_write_csv(tmp_path / "line.csv", s, zl, zr))
    part = whole.section(137.3)
    probe = np.linspace(21.0, 400.0, 501)  # past the fade-in and the samples whose slopes it touches
    for k in (0, 1):
        assert np.abs(part.evaluate(probe)[k] - whole.evaluate(probe + 137.3)[k]).max() < 1e-9 * 0.05
    assert part.evaluate(np.array([1e-9]))[1][0] == pytest.approx(0.0, abs=1e-9)  # level at the start
    fade = part.evaluate(np.array([10.0]))[1][0] / whole.evaluate(np.array([147.3]))[1][0]
    assert fade == pytest.approx(0.5, rel=1e-2)  # the raised cosine at half its length (between samples)
    sc = scenario(f"file:{tmp_path / 'line.csv'}", start=137.3, speed=40.0, duration=2.0)
    assert sc.describe()["source"].endswith("line.csv from s = 137.3 m")
    with pytest.raises(ValueError, match="start = 700 m: outside the profile"):
        whole.section(700.0)
    with pytest.raises(ValueError, match="start = 10.0: applies to a measured profile"):
        scenario("fra4", start=10.0)


@pytest.mark.parametrize(
    "content, match",
    [
        ("s,z_L\n0,0\n1,0\n", "no column 'z_R'"),
        ("s,z_L,z_R\n0,0,0\n\n1,abc,0\n", "line 4.*'abc' is not a number"),
        ("s,z_L,z_R\n0,0,0\n2,0,0\n1,0,0\n", "increase strictly"),
        ("s,z_L,z_R\n5,0,0\n9,0,0\n", "must start at s <= 0"),
        ("s,z_L,z_R\n0,0,0\n1,nan,0\n", "non-finite"),
        ("s,z_L,z_R\n0,0,0\n", "at least 2 rows"),
        ("", "empty"),
        ("s,z_L,z_R\n0,0,0\n1,0\n", "line 3.*'<missing>'"),
    ],
)
def test_malformed_csv_gets_a_clear_error(tmp_path, content, match):
    path = tmp_path / "bad.csv"
    path.write_text(content)
    with pytest.raises(ValueError, match=match):
        MeasuredTrack.from_csv(path)


def test_missing_or_short_files_are_refused(tmp_path):
    with pytest.raises(ValueError, match="cannot read track file"):
        scenario(f"file:{tmp_path / 'none.csv'}")
    path = _write_csv(tmp_path / "short.csv", [0.0, 100.0], [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(ValueError, match="profile ends at s = 100"):
        scenario(f"file:{path}", speed=50.0, duration=10.0)
    assert scenario(f"file:{path}", speed=50.0, duration=2.0).track.end() == 100.0


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"speed": -3.0}, "speed = -3"),
        ({"speed": float("nan")}, "speed = nan"),
        ({"duration": 0.0}, "duration = 0"),
        ({"amplitude": -0.01}, "amplitude"),
        ({"wavelength": 0.0}, "wavelength"),
        ({"rail_phase": float("inf")}, "rail_phase"),
    ],
)
def test_bad_scenario_settings_name_the_setting(kwargs, match):
    with pytest.raises(ValueError, match=match):
        scenario("paper-sine", **kwargs)


def test_scenario_names_and_options():
    with pytest.raises(ValueError, match="unknown scenario 'sine'.*paper-sine"):
        scenario("sine")
    with pytest.raises(ValueError, match="rail_phase applies to paper-sine only"):
        scenario("bump", rail_phase=10.0)
    with pytest.raises(ValueError, match="cannot be set for a measured profile"):
        scenario("file:x.csv", amplitude=0.1)
    bump = scenario("bump", amplitude=-0.01, wavelength=5.0)
    assert bump.track.height == -0.01 and bump.track.length == 5.0
    sc = scenario()
    assert (sc.speed, sc.duration, sc.track.amplitude, sc.track.wavelength, sc.track.rail_phase_deg) == (
        55.56,
        10.0,
        0.05,
        60.0,
        90.0,
    )


def test_input_grid_falls_on_step_boundaries_and_ignores_step_halving():
    sc = scenario("paper-sine", duration=2.0)
    lag = Vehicle().wheelset_lag_distance
    tab1, itv1 = wheelset_input_table(sc, lag, 1e-4)
    tab2, itv2 = wheelset_input_table(sc, lag, 5e-5)
    assert itv1 == pytest.approx(itv2) and round(itv1 / 1e-4) == pytest.approx(itv1 / 1e-4)
    n = min(len(tab1), len(tab2))
    assert np.array_equal(tab1[:n], tab2[:n])
    # rail velocities are V dz/ds
    t = np.arange(len(tab1)) * itv1
    zl, _, dzl, _ = sc.track.evaluate(sc.speed * t - lag[2])
    assert np.allclose(tab1[:, 4], zl) and np.allclose(tab1[:, 12], sc.speed * dzl)
