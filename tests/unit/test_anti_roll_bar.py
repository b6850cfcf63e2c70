"""The anti-roll bar (one per bogie: a torsion spring k_ar on theta_c - theta_bi, no damping)
against hand formulas of the static roll and the carbody roll frequency.

Notation of docs/model.md: carbody roll theta_c (DOF 2), bogie rolls theta_b1, theta_b2 (DOFs 5,
8). Per bogie, the secondary's vertical springs resist the relative roll theta_c - theta_bi with
2 k_sz d_s^2 and the bar adds k_ar; the two lateral springs (deflection h_cs theta_c + h_ts
theta_bi, the paper's model) hold the carbody's roll against the ground with 2 k_sy h_cs^2.
"""

from __future__ import annotations

import numpy as np
import pytest

from railride.model.params import VehicleParams
from railride.model.vehicle import Vehicle

P = VehicleParams.preset("paper")
ROLL_C, ROLL_B1, ROLL_B2 = 2, 5, 8
MOMENT = 1.0e4  # N m on the carbody in roll

pytestmark = pytest.mark.filterwarnings("ignore::railride.model.plausible.PlausibilityWarning")


def test_the_paper_has_no_bar_and_keeps_its_36_elements():
    v = Vehicle(P)
    assert P.k_ar == 0.0
    assert len(v.elements) == 36
    assert not [el for el in v.elements if el.group == "anti_roll_bar"]
    # an explicit k_ar = 0 is the same vehicle, bit for bit
    same = Vehicle(P.replace(k_ar=0.0))
    for name in ("K", "C", "C0", "K_w", "C_w", "T"):
        assert np.array_equal(getattr(v, name), getattr(same, name)), name


def test_a_bar_adds_one_element_per_bogie_and_only_its_roll_stiffness():
    k_ar = 9.4e5
    bare, barred = Vehicle(P), Vehicle(P.replace(k_ar=k_ar))
    bars = [el for el in barred.elements if el.group == "anti_roll_bar"]
    assert len(bars) == 2 and len(barred.elements) == 38
    assert all(el.k == k_ar and el.c == 0.0 and not el.e.any() for el in bars)
    # k_ar (theta_c - theta_bi)^2 / 2 for each bogie, by hand
    expected = np.zeros((9, 9))
    for b in (ROLL_B1, ROLL_B2):
        expected[ROLL_C, ROLL_C] += k_ar
        expected[b, b] += k_ar
        expected[ROLL_C, b] = expected[b, ROLL_C] = -k_ar
    assert np.allclose(barred.K - bare.K, expected, rtol=0, atol=1e-9 * k_ar)
    for name in ("C", "C0", "K_w", "C_w", "T"):  # no damping, no rail input, no secondary force
        assert np.array_equal(getattr(barred, name), getattr(bare, name)), name


@pytest.mark.parametrize("k_ar", [0.0, 5e5, 9.4e5, 2.5e6])
def test_static_carbody_roll_with_the_bogies_held(k_ar):
    # Bogies and rails held still: the carbody rolls by M / K_roll with
    # K_roll = 4 k_sz d_s^2 + 4 k_sy h_cs^2 + 2 k_ar (two bars in parallel with the springs).
    p = P.replace(k_ar=k_ar)
    K = Vehicle(p).K[:3, :3]
    q = np.linalg.solve(K, [0.0, 0.0, MOMENT])
    hand = MOMENT / (4 * p.k_sz * p.d_s**2 + 4 * p.k_sy * p.h_cs**2 + 2 * k_ar)
    assert q[ROLL_C] == pytest.approx(hand, rel=1e-12)
    assert abs(q[0]) < 1e-15 and abs(q[1]) < 1e-15  # a pure roll moment neither lifts nor pitches


@pytest.mark.parametrize("k_ar", [0.0, 5e5, 2.5e6])
def test_static_carbody_roll_with_the_bar_in_series_with_the_bogie(k_ar):
    # Bogies free, rails held, the lateral secondary springs made negligible (their deflection
    # h_cs theta_c + h_ts theta_b ties both bodies to the ground): each bogie takes M/2 through
    # its secondary springs and bar in parallel, k_rel = 2 k_sz d_s^2 + k_ar, which passes it to
    # the rails through the primary, k_bg = 4 k_pz d_p^2 + 4 k_py h_tp^2. In series:
    # theta_b = (M/2) / k_bg and theta_c = (M/2) (1/k_rel + 1/k_bg).
    p = P.replace(k_ar=k_ar, k_sy=1e-6)
    f = np.zeros(9)
    f[ROLL_C] = MOMENT
    q = np.linalg.solve(Vehicle(p).K, f)
    k_rel = 2 * p.k_sz * p.d_s**2 + k_ar
    k_bg = 4 * p.k_pz * p.d_p**2 + 4 * p.k_py * p.h_tp**2
    assert q[ROLL_B1] == pytest.approx(MOMENT / 2 / k_bg, rel=1e-9)
    assert q[ROLL_B2] == pytest.approx(MOMENT / 2 / k_bg, rel=1e-9)
    assert q[ROLL_C] == pytest.approx(MOMENT / 2 * (1 / k_rel + 1 / k_bg), rel=1e-9)


def test_the_carbody_roll_frequency_rises_with_the_bar_as_the_hand_formula_says():
    # On a primary 1000 times stiffer the bogies stay level, so the carbody rolls alone:
    # omega^2 = (4 k_sz d_s^2 + 4 k_sy h_cs^2 + 2 k_ar) / I_cx, and the bar adds no damping,
    # so the modal damping stays c_roll = 4 c_sz d_s^2 + 4 c_sy h_cs^2.
    stiff = P.replace(k_pz=P.k_pz * 1e3, k_px=P.k_px * 1e3, k_py=P.k_py * 1e3)
    found = []
    for k_ar in (0.0, 2.5e5, 9.4e5, 2.5e6, 5e6):
        p = stiff.replace(k_ar=k_ar)
        roll = next(m for m in Vehicle(p).modes() if m.label == "carbody roll")
        omega = np.sqrt((4 * p.k_sz * p.d_s**2 + 4 * p.k_sy * p.h_cs**2 + 2 * k_ar) / p.I_cx)
        zeta = (4 * p.c_sz * p.d_s**2 + 4 * p.c_sy * p.h_cs**2) / (2 * p.I_cx * omega)
        assert roll.frequency_hz == pytest.approx(omega / (2 * np.pi), rel=1e-3), k_ar
        assert roll.damping_ratio == pytest.approx(zeta, rel=1e-3), k_ar
        found.append(roll.frequency_hz)
    assert found == sorted(found) and found[-1] > 2 * found[0]
