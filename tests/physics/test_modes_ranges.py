"""The modes of every vehicle the parameter ranges allow: finite numbers, resolved or marked not
resolved (docs/model.md, Modes and frequency response), and the paper's modes against a second
method (the general eigen-solver on M^-1 K and the QZ algorithm on the damped pencil)."""

import dataclasses
import json
import math
import warnings

import numpy as np
import pytest
import scipy.linalg

from railride.errors import InputError
from railride.model.modes import checked_modes, modes
from railride.model.params import PRESETS, VehicleParams
from railride.model.plausible import VEHICLE, PlausibilityWarning
from railride.model.vehicle import Vehicle

P = PRESETS["paper"]
#: the paper's fields (the optional ones, bump stops and bending, drawn apart below)
REQUIRED = [f.name for f in dataclasses.fields(VehicleParams) if f.default is dataclasses.MISSING]
#: the bump stops act in the time domain only: no mode sees them
BENDING = ("L_c", "f_bend", "zeta_bend")


def _log_uniform(rng, low: float, high: float) -> float:
    return float(math.exp(rng.uniform(math.log(low), math.log(high))))


def _value(rng, name: str, widen: float | None) -> float:
    """One field, log-uniform within its allowed range (``widen`` None) or within its typical
    range widened ``widen`` times each way (inside the allowed one); a damping of 0 one time
    in ten, since 0 is allowed and a log scale never reaches it."""
    r = VEHICLE[name]
    if r.low == 0.0 and rng.random() < 0.1:
        return 0.0
    if widen is None:
        low, high = r.low, r.high
    else:
        assert r.typical is not None
        low, high = r.typical[0] / widen, r.typical[1] * widen
        if low == 0.0:  # a damper's typical range starts at none
            low = r.typical[1] * 1e-4
    low = max(low, r.low, 1e-3 if r.low == 0.0 else 0.0)
    return _log_uniform(rng, low, min(high, r.high))


def _vehicle(rng, widen: float | None = None) -> Vehicle:
    """A vehicle drawn field by field (`_value`), with an anti-roll bar one time in three and a
    bending carbody one time in three; drawn again where the fields together are refused
    (b >= l, a carbody shorter than its wheelsets' span, a bending below the rigid modes)."""
    while True:
        values = {name: _value(rng, name, widen) for name in REQUIRED}
        if rng.random() < 1 / 3:
            values["k_ar"] = _value(rng, "k_ar", widen)
        if rng.random() < 1 / 3:
            values.update({name: _value(rng, name, widen) for name in BENDING})
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", PlausibilityWarning)
                return Vehicle(VehicleParams(**values))
        except InputError:
            continue


def _numbers(mode) -> tuple[float, float, float]:
    return mode.frequency_hz, mode.damped_frequency_hz, mode.damping_ratio


def test_every_vehicle_the_ranges_allow_has_finite_modes():
    """Drawn log-uniformly across the allowed ranges, about a quarter of the vehicles once had
    an infinite damping ratio: an overdamped pair whose slower root rounding put at or past 0.
    Now every number is finite and every mode an overdamped one (damped frequency 0) has a
    ratio >= 1; where a mode is not resolved, `checked_modes` (railride modes, frf) refuses
    the vehicle, else its document is strict JSON."""
    rng = np.random.default_rng(20240611)
    outcomes = {"refused": 0, "resolved": 0}
    for _ in range(300):
        vehicle = _vehicle(rng)
        found = vehicle.modes()
        assert len(found) == vehicle.n_dof
        for m in found:
            assert all(math.isfinite(x) and x >= 0.0 for x in _numbers(m)), (vehicle.params, m)
            if m.damped_frequency_hz == 0.0:
                assert m.damping_ratio >= 1.0 - 1e-12, (vehicle.params, m)
            elif m.resolved:
                assert m.damping_ratio <= 1.0 + 1e-12, (vehicle.params, m)
        if all(m.resolved for m in found):
            doc = modes(vehicle.params).to_dict()
            json.dumps(doc, allow_nan=False)  # never inf or NaN
            outcomes["resolved"] += 1
        else:
            with pytest.raises(InputError, match="cannot be computed in double precision"):
                checked_modes(vehicle)
            outcomes["refused"] += 1
    # the draw reaches both sides of the resolution
    assert outcomes["refused"] > 0 and outcomes["resolved"] > 0, outcomes


def test_vehicles_within_ten_times_the_typical_ranges_are_resolved():
    rng = np.random.default_rng(7)
    for _ in range(60):
        vehicle = _vehicle(rng, widen=10.0)
        found = checked_modes(vehicle)
        assert len(found) == vehicle.n_dof and all(m.resolved for m in found), vehicle.params


@pytest.mark.parametrize("name", list(PRESETS))
def test_the_undamped_frequencies_are_the_eigenvalues_of_the_inverse_mass_times_the_stiffness(name):
    # the general (nonsymmetric) solver on M^-1 K, not the symmetric-definite one modes() uses
    v = Vehicle(PRESETS[name])
    omega2 = np.sort(np.linalg.eigvals(np.linalg.solve(v.M, v.K)).real)
    found = np.array([(2 * np.pi * m.frequency_hz) ** 2 for m in v.modes()])
    np.testing.assert_allclose(found, omega2, rtol=1e-9)


@pytest.mark.parametrize("name", list(PRESETS))
def test_the_damped_modes_are_the_roots_of_the_quadratic_eigenproblem(name):
    """Each mode's damped frequency and ratio give back its pair of roots -zeta w +- i w_d of
    (lambda^2 M + lambda C + K) q = 0, solved here by the QZ algorithm on the pencil
    ([0 I; -K -C], [I 0; 0 M]) instead of the state matrix."""
    v = Vehicle(PRESETS[name])
    n = v.n_dof
    eye, zero = np.eye(n), np.zeros((n, n))
    roots = scipy.linalg.eig(np.block([[zero, eye], [-v.K, -v.C]]), np.block([[eye, zero], [zero, v.M]]))[0]
    upper = np.sort_complex(roots[roots.imag > 0])
    found = v.modes()
    assert len(found) == n
    assert all(0.0 < m.damping_ratio < 1.0 and m.resolved for m in found)  # all underdamped: complex pairs
    wd = np.array([2 * np.pi * m.damped_frequency_hz for m in found])
    zeta = np.array([m.damping_ratio for m in found])
    rebuilt = np.sort_complex(-zeta * wd / np.sqrt(1 - zeta**2) + 1j * wd)
    np.testing.assert_allclose(rebuilt, upper, rtol=1e-8)


@pytest.mark.filterwarnings("ignore::railride.model.plausible.PlausibilityWarning")
def test_an_overdamped_carbody_bounce_has_the_ratio_of_its_damper():
    # on a rigid primary the carbody bounces on 4 k_sz and 4 c_sz: c_sz three times critical
    # makes it a pair of real roots, whose ratio is the one degree of freedom's 4 c / (2 m w)
    p = P.replace(k_pz=P.k_pz * 1e3, k_px=P.k_px * 1e3, k_py=P.k_py * 1e3)
    omega = math.sqrt(4 * p.k_sz / p.m_c)
    p = p.replace(c_sz=3.0 * p.m_c * omega / 2)
    (bounce,) = [m for m in Vehicle(p).modes() if m.label == "carbody bounce"]
    assert bounce.damped_frequency_hz == 0.0 and bounce.resolved
    assert bounce.damping_ratio == pytest.approx(3.0, rel=1e-3)
    assert bounce.frequency_hz == pytest.approx(omega / (2 * np.pi), rel=1e-3)


@pytest.mark.filterwarnings("ignore::railride.model.plausible.PlausibilityWarning")
def test_slow_complex_pairs_of_a_stiff_vehicle_are_not_taken_for_real_roots():
    """A carbody of 1e-6 kg m^2 in roll puts one root at 6e11 1/s: a tolerance of 1e-9 times it
    took the other modes' complex pairs (|Im| near 100) for real roots and paired them into
    nonsense. Its roll is the body on the secondary under bogies that do not move."""
    p = P.replace(I_cx=1e-6, c_pz=0.0)
    found = {m.label: m for m in checked_modes(Vehicle(p))}
    roll = found.pop("carbody roll")
    stiffness = 4 * p.k_sz * p.d_s**2 + 4 * p.k_sy * p.h_cs**2
    damping = 4 * p.c_sz * p.d_s**2 + 4 * p.c_sy * p.h_cs**2
    omega = math.sqrt(stiffness / p.I_cx)
    assert roll.frequency_hz == pytest.approx(omega / (2 * np.pi), rel=1e-3)
    assert roll.damped_frequency_hz == 0.0  # overdamped, 2e5 times critical
    assert roll.damping_ratio == pytest.approx(damping / (2 * p.I_cx * omega), rel=1e-3)
    assert len(found) == 8
    assert all(0.0 <= m.damping_ratio < 1.0 and m.damped_frequency_hz > 0.0 for m in found.values())


@pytest.mark.filterwarnings("ignore::railride.model.plausible.PlausibilityWarning")
def test_a_slow_root_hidden_by_rounding_gives_a_finite_bound():
    # a 1e9 N s/m secondary on gram bogies: the bogies' roots near 1e12 1/s hide the carbody's
    # slow overdamped root (about k/c, 1e-4 1/s) in their rounding
    v = Vehicle(P.replace(c_sz=1e9, m_b=1e-3, I_bx=1e-6, I_by=1e-6))
    (bounce,) = [m for m in v.modes() if m.label == "carbody bounce"]
    assert not bounce.resolved and bounce.damped_frequency_hz == 0.0
    assert math.isfinite(bounce.damping_ratio) and bounce.damping_ratio >= 1.0
    with pytest.raises(InputError, match=r"mode \d \(carbody bounce\).*within the rounding"):
        checked_modes(v)
