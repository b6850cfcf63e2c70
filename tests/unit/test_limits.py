"""Sizes are estimated before anything large is allocated (railride.limits), wavelengths the
output cannot resolve are refused for every profile, and inputs outside the plausible ranges
are input errors."""

from __future__ import annotations

import math

import pytest

import railride as rr
from railride import limits
from railride.run import rig
from railride.frequency.frf import frequency_responses
from railride.analysis.metrics import parse_window
from railride.run.solver import SolverSettings
from railride.model.track import CosineBump, Scenario, SineTrack, scenario


def test_parse_size_reads_units_in_powers_of_1024():
    assert limits.parse_size("4G") == 4 * 1024**3
    assert limits.parse_size("512M") == 512 * 1024**2
    assert limits.parse_size("1.5GiB") == 3 * 1024**3 // 2
    assert limits.parse_size("2097152") == 2 * 1024**2
    for bad in ("abc", "4X", "-1G", "0", "inf"):
        with pytest.raises(ValueError, match="max_memory"):
            limits.parse_size(bad)


def test_the_limit_is_a_share_of_the_machine_and_restored_after_a_block():
    total = limits.machine_memory()
    assert total is None or limits.default_max_memory() == total // 2
    with limits.memory_limit("64M"):
        assert limits.max_memory() == 64 * 2**20
    assert limits.max_memory() == limits.default_max_memory()


@pytest.fixture
def no_work(monkeypatch):
    """Every compiled stepper, the damper rig's kernel, the exact stepper's matrix exponentials and
    the frequency response fail the test when entered: a refusal comes before any work (which is
    what makes it quick on any machine)."""
    import scipy.linalg

    from railride.engine import exact_kernels, kernels, lanes
    from railride.model.vehicle import Vehicle

    def worked(*args, **kwargs):
        raise AssertionError("the work began before the refusal")  # not a ValueError: pytest.raises lets it by

    for module, name in (
        (kernels, "run_parallel"),
        (exact_kernels, "exact_run"),
        (exact_kernels, "exact_closed_run"),
        (lanes, "run_parallel"),
        (scipy.linalg, "expm"),
    ):
        monkeypatch.setattr(module, name, worked)
    monkeypatch.setattr(Vehicle, "frequency_response", worked)


def _refused(fn, *fragments):
    """The ValueError of ``fn()``, holding every one of ``fragments`` (use with `no_work`)."""
    with pytest.raises(ValueError) as info:
        fn()
    for fragment in fragments:
        assert fragment in str(info.value), str(info.value)
    return str(info.value)


def test_a_billion_frf_points_are_refused_before_allocating(no_work):
    # beyond the bound on the count (a million), and a million beyond a small memory limit
    _refused(lambda: frequency_responses(points=10**9), "points = 1000000000", "<= 1000000")
    with limits.memory_limit("100M"):
        message = _refused(lambda: frequency_responses(points=10**6), "points", "fewer points", "--max-memory")
    assert "GiB" in message or "MiB" in message


def test_damper_rig_at_a_microhertz_or_a_billion_cycles_is_refused(no_work):
    _refused(lambda: rig.cycles("railway", 0.01, 1e-6, [1.0]), "4e+10 steps", "raise the frequency")
    _refused(lambda: rig.cycles("railway", 0.01, 1.0, [1.0], n_cycles=10**9), "1e+13 steps", "fewer cycles")


def test_a_picosecond_step_is_refused_with_what_the_run_would_need(no_work):
    # "auto" takes RK4 where the exact maps would not line up: refused for its work
    solver = SolverSettings(dt=1e-12)
    _refused(lambda: rr.simulate("paper-sine", solver=solver), "1e+13 sample-steps", "dt 1e-12 s")
    exact = SolverSettings(dt=1e-12, method="exact")  # the exact steps: for their tables' memory
    _refused(lambda: rr.simulate("paper-sine", solver=exact), "memory", "dt 1e-12 s")


def test_a_control_rate_slower_than_the_run_is_refused(no_work):
    solver = SolverSettings(control_rate=1e-300)
    pid = rr.Suspension.named("pid")
    _refused(lambda: rr.simulate("paper-sine", suspension=pid, solver=solver), "control_rate = 1e-300 Hz", "0.1 Hz")


def test_a_billion_tuning_candidates_are_refused(no_work):
    _refused(lambda: rr.tune(n_values=10**9, budget=10**9 + 2), "1000000000 candidate values")


def test_the_limit_refuses_and_admits_the_same_run():
    short = scenario("paper-sine", duration=1.0)
    with limits.memory_limit("1M"):
        # 1001 samples x 47 channels x 8 bytes alone are 0.36 MiB, the input tables more
        with pytest.raises(ValueError, match="limit of 1 MiB"):
            rr.simulate(short, solver=SolverSettings(output_rate=10000.0))
    with limits.memory_limit("256M"):
        assert math.isfinite(float(rr.simulate(short).metrics().sel(response="acceleration_m_s2", statistic="rms")))


@pytest.mark.parametrize(
    "track,field", [(SineTrack(wavelength=1e-6), "wavelength"), (CosineBump(length=0.01), "length")]
)
def test_wavelengths_the_output_cannot_resolve_are_refused_for_every_profile(track, field, no_work):
    # at 55.56 m/s and 1000 Hz (2.5 samples a cycle at least) the shortest is 2.5 x 55.56 / 1000 m
    message = _refused(lambda: rr.simulate(Scenario(track=track, speed=55.56)), f"{field} = ", "0.1389 m")
    assert "output_rate" in message


def test_a_wavelength_just_above_the_shortest_runs():
    result = rr.simulate(Scenario(track=SineTrack(wavelength=0.14), speed=55.56, duration=0.5))
    assert math.isfinite(float(result.metrics().max()))


@pytest.mark.parametrize(
    "make,fragment",
    [
        (lambda: SineTrack(amplitude=100.0), "amplitude = 100 m"),
        (lambda: SineTrack(rail_phase_deg=1e308), "rail_phase = 1e+308 deg"),
        (lambda: CosineBump(height=-3.0), "height = -3 m"),
        (lambda: Scenario(speed=1e5), "speed = 1e+05 m/s"),
    ],
)
def test_implausible_tracks_and_speeds_are_input_errors(make, fragment):
    with pytest.raises(ValueError, match="plausible") as info:
        make()
    assert fragment in str(info.value)


def test_plausible_edges_are_accepted():
    assert SineTrack(amplitude=1.0, rail_phase_deg=-360.0).amplitude == 1.0
    assert Scenario(speed=200.0).speed == 200.0


def test_the_window_is_finite():
    assert parse_window("2:") == (2.0, math.inf)  # an empty END: the end of the run
    for text in ("0:inf", "nan:5", "0:-inf"):
        with pytest.raises(ValueError, match="finite"):
            parse_window(text)


def test_a_run_of_a_hundred_billion_steps_is_refused_by_its_work_with_its_time(no_work):
    # memory does not stop it: the histories are strided to 10001 rows whatever dt is
    mr = rr.Suspension.semi_active("railway", voltage=1.0)
    message = _refused(
        lambda: rr.simulate("paper-sine", suspension=mr, solver=SolverSettings(dt=1e-10)),
        "1 x 1e+11 steps",
        "limit of 1e+10",
        "raise dt",
    )
    # 1e11 sample-steps at 4e6 a second: 25 000 s, 6.9 hours
    assert "about 6.9 h" in message


def test_the_work_limit_counts_samples_and_is_restored_after_a_block():
    short = scenario("paper-sine", duration=1.0)
    mr = [rr.Suspension.semi_active("railway", voltage=v) for v in (0.0, 1.0, 2.0)]
    assert limits.max_work() == limits.DEFAULT_MAX_WORK
    with limits.work_limit(2e6):  # 1 s at 1e-4 s is 1e4 steps a sample
        assert limits.max_work() == 2 * 10**6
        rr.simulate(short, suspension=mr)  # 3e4 sample-steps
        with pytest.raises(ValueError, match="3 runs of 1 s at dt 1e-06 s: 3 x 1e\\+06 steps = 3e\\+06"):
            rr.simulate(short, suspension=mr, solver=SolverSettings(dt=1e-6))
    assert limits.max_work() == limits.DEFAULT_MAX_WORK


def test_work_limits_and_durations_read_and_show_plainly():
    assert limits.parse_count("1e11") == 10**11 and limits.parse_count(10**7) == 10**7
    for bad in ("many", "1e3", "inf", "nan", True, 10**400, -5):
        with pytest.raises(ValueError, match="max_steps"):
            limits.parse_count(bad)
    assert limits.shown_duration(45) == "45 s"
    assert limits.shown_duration(3600 * 9.3) == "9.3 h"
    assert limits.shown_duration(86400 * 41) == "41 days"


def test_an_exact_run_whose_grids_never_line_up_is_refused_before_its_exponentials(no_work):
    # dt = 3e-9 s: 333 333 steps per output sample against 2**20 per input node, so the maps
    # would repeat only after a million output samples (minutes of matrix exponentials)
    _refused(
        lambda: rr.simulate("paper-sine", solver=SolverSettings(dt=3e-9, method="exact")),
        "1048576 step maps",
        "use method 'rk4', or 'auto', which takes RK4 there",
    )
