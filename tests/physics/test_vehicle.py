"""The assembled vehicle against hand-derived limits and invariants."""

import numpy as np
import pytest

from railride.model.params import VehicleParams
from railride.model.vehicle import Vehicle

P = VehicleParams.preset("paper")


def test_matrices_are_symmetric_and_definite():
    v = Vehicle(P)
    for m in (v.M, v.K, v.C, v.C0):
        assert np.allclose(m, m.T, rtol=0, atol=1e-9 * np.abs(m).max())
    assert np.linalg.eigvalsh(v.K).min() > 0  # held to the rails: no rigid-body mode
    assert np.linalg.eigvalsh(v.C).min() > -1e-9 * np.abs(v.C).max()
    assert np.linalg.eigvalsh(v.C0).min() > -1e-9 * np.abs(v.C0).max()


def test_rigid_heave_with_the_rails_loads_no_element():
    v = Vehicle(P)
    q = np.array([1.0, 0, 0, 1.0, 0, 0, 1.0, 0, 0])
    w = np.ones(8)
    assert np.abs(v.K @ q + v.K_w @ w).max() < 1e-6
    assert np.abs(v.C @ q + v.C_w @ w).max() < 1e-6
    assert v.elements  # the loop below checks something
    for el in v.elements:
        assert abs(el.a @ q + el.e @ w) < 1e-12, el.name


def test_secondary_force_map_has_the_carbody_rows_of_the_geometry():
    v = Vehicle(P)
    assert np.allclose(v.T[0], [1, 1, 1, 1])
    assert np.allclose(v.T[1], [-P.l, -P.l, P.l, P.l])
    assert np.allclose(v.T[2], [-P.d_s, P.d_s, -P.d_s, P.d_s])
    # the front bogie takes the reaction of corners 1R, 1L only
    assert np.allclose(v.T[3], [-1, -1, 0, 0]) and np.allclose(v.T[6], [0, 0, -1, -1])


def _freqs(v):
    return {m.label: m for m in v.modes()}


def _stiff_primary_carbody(p):
    """Hand formulas (omega^2, modal damping, inertia) of the carbody on a rigid primary.

    With the bogies locked to level rails the carbody is one body on the secondary: four
    vertical springs at (+-l, +-d_s), and per bogie two lateral springs (one each side, the
    paper's 2 k_sy) acting on roll through h_cs and two longitudinal ones (2 k_sx) on pitch.
    So K_roll = 4 k_sz d_s^2 + 4 k_sy h_cs^2 and K_pitch = 4 k_sz l^2 + 4 k_sx h_cs^2.
    """
    return {
        "carbody bounce": (4 * p.k_sz / p.m_c, 4 * p.c_sz, p.m_c),
        "carbody pitch": (
            (4 * p.k_sz * p.l**2 + 4 * p.k_sx * p.h_cs**2) / p.I_cy,
            4 * p.c_sz * p.l**2 + 4 * p.c_sx * p.h_cs**2,
            p.I_cy,
        ),
        "carbody roll": (
            (4 * p.k_sz * p.d_s**2 + 4 * p.k_sy * p.h_cs**2) / p.I_cx,
            4 * p.c_sz * p.d_s**2 + 4 * p.c_sy * p.h_cs**2,
            p.I_cx,
        ),
    }


def test_carbody_modes_match_hand_formulas_on_a_stiff_primary():
    # Bogies locked to level rails: the carbody is a single body on the secondary springs.
    p = P.replace(k_pz=P.k_pz * 1e3, k_px=P.k_px * 1e3, k_py=P.k_py * 1e3)
    modes = _freqs(Vehicle(p))
    hand = _stiff_primary_carbody(p)
    for label, (w2, c, inertia) in hand.items():
        omega = np.sqrt(w2)
        zeta = c / (2 * inertia * omega)
        mode = modes[label]
        assert mode.frequency_hz == pytest.approx(omega / (2 * np.pi), rel=1e-3), label
        assert mode.damping_ratio == pytest.approx(zeta, rel=1e-3), label
        assert mode.damped_frequency_hz == pytest.approx(omega * np.sqrt(1 - zeta**2) / (2 * np.pi), rel=2e-3), label


def test_lateral_and_longitudinal_springs_count_twice_per_bogie():
    # The element count must not silently change again: the carbody roll and pitch
    # frequencies on a rigid primary are checked with the lateral and longitudinal springs made
    # ten times stiffer, where they carry most of the roll stiffness (one per bogie instead of
    # two would put the roll frequency 25 % low here), and the table holds four of each.
    p = P.replace(k_pz=P.k_pz * 1e4, k_px=P.k_px * 1e4, k_py=P.k_py * 1e4, k_sx=P.k_sx * 10, k_sy=P.k_sy * 10)
    v = Vehicle(p)
    modes = _freqs(v)
    for label in ("carbody pitch", "carbody roll"):
        w2 = _stiff_primary_carbody(p)[label][0]
        assert modes[label].frequency_hz == pytest.approx(np.sqrt(w2) / (2 * np.pi), rel=2e-4), label
    groups = [el.group for el in v.elements]
    assert groups.count("secondary_lateral") == 4 and groups.count("secondary_longitudinal") == 4
    assert len(v.elements) == 36


def test_paper_carbody_modes_are_within_a_few_percent_of_the_stiff_primary_formulas():
    p = P
    modes = _freqs(Vehicle(p))
    assert modes["carbody bounce"].frequency_hz == pytest.approx(np.sqrt(4 * p.k_sz / p.m_c) / (2 * np.pi), rel=0.03)
    assert modes["carbody roll"].frequency_hz == pytest.approx(
        np.sqrt((4 * p.k_sz * p.d_s**2 + 4 * p.k_sy * p.h_cs**2) / p.I_cx) / (2 * np.pi), rel=0.03
    )


def test_bogie_modes_match_hand_formulas_under_a_fixed_carbody():
    # A carbody a million times heavier stays still: each bogie is a body between the rails
    # (primary) and a fixed carbody (secondary).
    p = P.replace(m_c=P.m_c * 1e6, I_cx=P.I_cx * 1e6, I_cy=P.I_cy * 1e6)
    hand = {
        "bounce": (4 * p.k_pz + 2 * p.k_sz) / p.m_b,
        "pitch": (4 * p.k_pz * p.b**2 + 4 * p.k_px * p.h_tp**2 + 2 * p.k_sx * p.h_ts**2) / p.I_by,
        "roll": (4 * p.k_pz * p.d_p**2 + 4 * p.k_py * p.h_tp**2 + 2 * p.k_sz * p.d_s**2 + 2 * p.k_sy * p.h_ts**2)
        / p.I_bx,
    }
    modes = Vehicle(p).modes()
    for motion, w2 in hand.items():
        found = [
            m.frequency_hz
            for m in modes
            if m.label.startswith("bogie") and motion in m.label or m.label.endswith(f"bogie {motion}")
        ]
        assert len(found) == 2, (motion, [m.label for m in modes])
        for f in found:
            assert f == pytest.approx(np.sqrt(w2) / (2 * np.pi), rel=1e-4), motion


def test_modes_are_labelled_and_sorted():
    modes = Vehicle(P).modes()
    assert len(modes) == 9
    freqs = [m.frequency_hz for m in modes]
    assert freqs == sorted(freqs)
    assert {m.label for m in modes[:3]} == {"carbody bounce", "carbody pitch", "carbody roll"}
    for m in modes:
        assert 0 < m.damping_ratio < 1 and 0 < m.damped_frequency_hz < m.frequency_hz


def test_in_phase_rails_lift_the_body_one_to_one_at_low_frequency():
    f, V = 1e-4, 55.56
    frf = Vehicle(P).frequency_response([f, 1e-3], speed=V, rails="in-phase")
    h = frf["carbody_bounce"].values[0]
    assert abs(abs(h) - 1) < 1e-6
    # phase: the time the track takes from wheelset 1 to the carbody centre, (l + b) / V
    assert np.angle(h) == pytest.approx(-2 * np.pi * f * (P.l + P.b) / V, rel=1e-3)
    assert abs(abs(frf["front_bogie_bounce"].values[0]) - 1) < 1e-6
    # pitch comes only from the front bogie leading the rear by 2l/V: it vanishes like f
    pitch = np.abs(frf["carbody_pitch"].values)
    assert pitch[0] < 1e-4 and pitch[1] / pitch[0] == pytest.approx(10, rel=1e-2)
    assert np.abs(frf["carbody_roll"].values).max() < 1e-12  # symmetric input, no roll


def _static_roll_gain(p):
    """Carbody roll / wheelset cross-level angle under a static anti-phase rail input.

    By symmetry both bogies roll alike (theta_b); per bogie (two lateral springs, one each side)
    and for the carbody's share of one bogie:
      [4 k_pz d_p^2 + 4 k_py h_tp^2 + 2 k_sz d_s^2 + 2 k_sy h_ts^2] theta_b
        + (2 k_sy h_cs h_ts - 2 k_sz d_s^2) theta_c = (4 k_pz d_p^2 - 4 k_py h_tp h_wp) theta_w
      (2 k_sz d_s^2 + 2 k_sy h_cs^2) theta_c + (2 k_sy h_cs h_ts - 2 k_sz d_s^2) theta_b = 0
    """
    a11 = 4 * p.k_pz * p.d_p**2 + 4 * p.k_py * p.h_tp**2 + 2 * p.k_sz * p.d_s**2 + 2 * p.k_sy * p.h_ts**2
    a12 = 2 * p.k_sy * p.h_cs * p.h_ts - 2 * p.k_sz * p.d_s**2
    a22 = 2 * p.k_sz * p.d_s**2 + 2 * p.k_sy * p.h_cs**2
    rhs = 4 * p.k_pz * p.d_p**2 - 4 * p.k_py * p.h_tp * p.h_wp
    theta_b, theta_c = np.linalg.solve([[a11, a12], [a12, a22]], [rhs, 0.0])
    return theta_c


def test_anti_phase_rails_roll_the_body_by_the_static_gain():
    frf = Vehicle(P).frequency_response(1e-4, speed=55.56, rails="anti-phase")
    cross_level_per_m = 1.0 / P.a  # (z_L - z_R) / (2a) for z_L = 1, z_R = -1
    gain = frf["carbody_roll"].values[0] / cross_level_per_m
    assert gain.real == pytest.approx(_static_roll_gain(P), rel=1e-6)
    assert abs(frf["carbody_bounce"].values[0]) < 1e-9
    # with the paper's values the lateral springs, which act through roll only, hold the
    # carbody back to about 43 % of the cross-level angle
    assert 0.38 < gain.real < 0.48


def test_anti_phase_rails_roll_the_body_by_the_cross_level_when_lateral_springs_vanish():
    p = P.replace(k_sy=P.k_sy * 1e-9, k_py=P.k_py * 1e-9)
    frf = Vehicle(p).frequency_response(1e-5, speed=55.56, rails="anti-phase")
    assert frf["carbody_roll"].values[0].real == pytest.approx(1.0 / p.a, rel=1e-6)


def test_frequency_response_rejects_bad_input():
    v = Vehicle(P)
    with pytest.raises(ValueError, match="speed"):
        v.frequency_response(1.0, speed=-1)
    with pytest.raises(ValueError, match="frequency"):
        v.frequency_response([np.nan], speed=10)
    with pytest.raises(ValueError, match="rails"):
        v.frequency_response(1.0, speed=10, rails="diagonal")


def test_a_payload_lowers_the_carbody_modes_by_the_square_root_of_the_load_factor():
    # on a stiff primary the carbody rides on the secondary alone: every carbody mode's stiffness
    # stays and its inertia grows by the load factor, so its frequency falls by sqrt(load)
    p = P.replace(k_pz=P.k_pz * 1e3, k_px=P.k_px * 1e3, k_py=P.k_py * 1e3)
    empty, laden = _freqs(Vehicle(p)), _freqs(Vehicle(p.loaded(1.3)))
    for label in ("carbody bounce", "carbody pitch", "carbody roll"):
        assert laden[label].frequency_hz == pytest.approx(empty[label].frequency_hz / np.sqrt(1.3), rel=1e-3), label
    loaded = P.loaded(1.3)
    assert (loaded.m_c, loaded.I_cx, loaded.I_cy) == pytest.approx((1.3 * P.m_c, 1.3 * P.I_cx, 1.3 * P.I_cy))
    assert loaded.replace(m_c=P.m_c, I_cx=P.I_cx, I_cy=P.I_cy, I_cz=P.I_cz) == P  # nothing else changed
    for bad in (0, -1.0, float("nan"), "heavy"):
        with pytest.raises(ValueError, match="load = .*: must be a finite number > 0"):
            P.loaded(bad)
