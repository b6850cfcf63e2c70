"""The flexible carbody: the free-free beam's first bending mode against beam theory, the
coupled vehicle against its limits, a rigid vehicle unchanged, the floor points and the input
rules (docs/model.md, Flexible carbody)."""

import json
import math
import warnings

import numpy as np
import pytest
import scipy.integrate
import scipy.optimize
import xarray as xr

from railride.analysis.comfort import floor_acceleration
from railride.errors import InputError
from railride.frequency.linear import linear_model
from railride.frequency.ride_spectrum import ride_spectrum
from railride.model import beam
from railride.model.modes import checked_modes
from railride.model.params import PRESETS, VehicleParams
from railride.model.plausible import PlausibilityWarning, notes
from railride.model.vehicle import DOF_NAMES, Vehicle

P = VehicleParams.preset("paper")
#: the paper's car with a 24 m body bending first at 10 Hz
F = P.replace(L_c=24.0, f_bend=10.0)
BEYOND = 0.5 - beam.node_fraction()  # the nodes' x / L from the centre


def _mode(vehicle: Vehicle, label: str):
    (found,) = [m for m in vehicle.modes() if m.label == label]
    return found


def _quiet(**changes) -> VehicleParams:
    """The paper's vehicle changed, its plausibility warnings (a limit study) silenced."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlausibilityWarning)
        return P.replace(**changes)


# -- the beam ------------------------------------------------------------------------------------
def test_beta_l_is_the_first_root_of_the_free_free_frequency_equation():
    root = scipy.optimize.brentq(beam.frequency_equation, 4.0, 5.0, xtol=1e-14)
    assert beam.BETA_L == pytest.approx(root, rel=1e-13)
    assert beam.BETA_L == pytest.approx(4.730040745, abs=1e-9)
    assert abs(beam.frequency_equation(beam.BETA_L)) < 1e-10


def test_the_mode_is_normalised_at_the_centre_symmetric_and_free_at_the_ends():
    L = 24.0
    assert beam.mode_shape(0.0, L) == 1.0
    x = np.linspace(0.0, L / 2, 7)
    assert np.allclose(beam.mode_shape(x, L), beam.mode_shape(-x, L), rtol=0, atol=1e-15)
    beta = beam.BETA_L / L
    # a free end carries no moment (phi'' = 0) and no shear (phi''' = 0): the shape's own
    # derivatives, the slope analytically and the rest by differences of it
    h = 1e-4
    end = L / 2

    def curvature(u):
        return (beam.mode_slope(u + h, L) - beam.mode_slope(u - h, L)) / (2 * h)

    assert abs(curvature(end)) < 1e-6 * beta**2
    shear = (curvature(end + h) - curvature(end - h)) / (2 * h)
    assert abs(shear) < 1e-4 * beta**3
    # and the beam's equation phi'''' = beta^4 phi inside it
    u, d = 2.0, 1e-2
    fourth = sum(c * beam.mode_shape(u + k * d, L) for k, c in zip(range(-2, 3), (1, -4, 6, -4, 1))) / d**4
    assert fourth == pytest.approx(beta**4 * beam.mode_shape(u, L), rel=1e-4)


def test_the_mode_is_orthogonal_to_the_free_beams_rigid_modes():
    L = 20.0
    mean, _ = scipy.integrate.quad(beam.mode_shape, -L / 2, L / 2, args=(L,), epsabs=1e-11, limit=200)
    moment, _ = scipy.integrate.quad(lambda x: x * beam.mode_shape(x, L), -L / 2, L / 2, epsabs=1e-11, limit=200)
    assert abs(mean) < 1e-10 * L and abs(moment) < 1e-10 * L**2  # int phi dx = int x phi dx = 0


def test_the_nodes_lie_0_224_l_from_each_end():
    assert beam.node_fraction() == pytest.approx(0.2242, abs=5e-5)
    L = 24.0
    for x in (BEYOND * L, -BEYOND * L):
        assert abs(beam.mode_shape(x, L)) < 1e-12
    assert beam.mode_shape(0.99 * BEYOND * L, L) > 0 > beam.mode_shape(1.01 * BEYOND * L, L)


def test_the_modal_mass_factor_is_the_mean_square_of_the_shape():
    L = 26.0
    square, _ = scipy.integrate.quad(lambda x: beam.mode_shape(x, L) ** 2, -L / 2, L / 2, epsabs=1e-12)
    assert beam.modal_mass_factor() == pytest.approx(square / L, rel=1e-12)


def test_the_frequency_and_the_bending_stiffness_are_each_others_inverse():
    m, L, EI = 4.0e4, 25.0, 5.0e9
    f = beam.bending_frequency(EI, m, L)
    assert f == pytest.approx(4.730040745**2 / (2 * math.pi) * math.sqrt(EI / (m * L**3)), rel=1e-9)
    assert beam.bending_stiffness(f, m, L) == pytest.approx(EI, rel=1e-12)


def test_a_point_beyond_the_beam_is_refused():
    with pytest.raises(ValueError, match="must lie on the beam"):
        beam.mode_shape(12.5, 24.0)


# -- the vehicle ---------------------------------------------------------------------------------
def _by_hand(p: VehicleParams, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """(K, K_w) of the rigid vehicle, kind "k", or (C, C_w), kind "c", from the equations of
    motion written out entry by entry (q = z_c, phi_c, theta_c, then each bogie's z, phi,
    theta; a point at (x, y) of a body moves z - x phi + y theta; w = z_L, z_R of wheelsets 1-4).

    Per bogie at x_b = +-l: two secondary vertical springs at (x_b, +-d_s), two lateral (roll,
    arms h_cs above and h_ts below) and two longitudinal (pitch, same arms); four primary
    vertical at (+-b, +-d_p) on wheelsets that follow their rails (z_w + y theta_w, theta_w =
    (z_L - z_R) / 2a), four primary longitudinal and four lateral (arm h_tp on the bogie, h_wp
    on the wheelset's roll); an anti-roll bar k_ar on theta_c - theta_b."""
    sz, sx, sy, pz, px, py = (getattr(p, f"{kind}_{n}") for n in ("sz", "sx", "sy", "pz", "px", "py"))
    ar = p.k_ar if kind == "k" else 0.0  # the bar has no damping
    l, b, d_s, d_p, a = p.l, p.b, p.d_s, p.d_p, p.a
    h_cs, h_ts, h_tp, h_wp = p.h_cs, p.h_ts, p.h_tp, p.h_wp
    K, K_w = np.zeros((9, 9)), np.zeros((9, 8))
    K[0, 0] = 4 * sz
    K[1, 1] = 4 * sz * l**2 + 4 * sx * h_cs**2
    K[2, 2] = 4 * sz * d_s**2 + 4 * sy * h_cs**2 + 2 * ar
    for o, x_b, wheelsets in ((3, l, (0, 1)), (6, -l, (2, 3))):
        K[o, o] = 2 * sz + 4 * pz
        K[o + 1, o + 1] = 4 * pz * b**2 + 4 * px * h_tp**2 + 2 * sx * h_ts**2
        K[o + 2, o + 2] = 4 * pz * d_p**2 + 4 * py * h_tp**2 + 2 * sz * d_s**2 + 2 * sy * h_ts**2 + ar
        K[0, o] = K[o, 0] = -2 * sz
        K[1, o] = K[o, 1] = 2 * sz * x_b
        K[1, o + 1] = K[o + 1, 1] = 2 * sx * h_cs * h_ts
        K[2, o + 2] = K[o + 2, 2] = 2 * sy * h_cs * h_ts - 2 * sz * d_s**2 - ar
        for j, x_w in zip(wheelsets, (b, -b)):
            roll = (py * h_tp * h_wp - pz * d_p**2) / a
            K_w[o, 2 * j : 2 * j + 2] = -pz
            K_w[o + 1, 2 * j : 2 * j + 2] = pz * x_w
            K_w[o + 2, 2 * j : 2 * j + 2] = roll, -roll
    return K, K_w


def test_a_rigid_vehicle_keeps_its_nine_dofs_and_its_matrices():
    v = Vehicle(P)
    assert not P.flexible and P.bending_hz is None
    assert v.n_dof == 9 and v.dof_names == DOF_NAMES
    assert len(v.elements) == 36 and all(el.a.shape == (9,) for el in v.elements)
    assert not [el for el in v.elements if el.group == "carbody_bending"]
    # the matrices as they always were: the equations of motion written out DOF by DOF
    # (`_by_hand`), not the sum over the element table the code assembles them by; for every
    # preset's rigid carbody, the anti-roll bars of two of them included
    for name, params in PRESETS.items():
        rigid = Vehicle(params.rigid())
        for kind, (matrix, rails) in (("k", (rigid.K, rigid.K_w)), ("c", (rigid.C, rigid.C_w))):
            want, want_w = _by_hand(params, kind)
            assert np.allclose(matrix, want, rtol=0, atol=1e-12 * np.abs(want).max()), (name, kind)
            assert np.allclose(rails, want_w, rtol=0, atol=1e-12 * np.abs(want_w).max()), (name, kind)
    assert np.array_equal(v.M, np.diag([P.m_c, P.I_cy, P.I_cx, P.m_b, P.I_by, P.I_bx, P.m_b, P.I_by, P.I_bx]))
    assert v.state_matrix.shape == (18, 18) and len(v.modes()) == 9
    # a flexible one adds a row and a column and leaves the rigid blocks as they were
    f = Vehicle(F)
    for name in ("M", "K", "C", "C0"):
        assert np.allclose(getattr(f, name)[:9, :9], getattr(v, name), rtol=1e-15, atol=0), name
    for name in ("K_w", "C_w", "T"):
        assert np.allclose(getattr(f, name)[:9], getattr(v, name), rtol=1e-15, atol=0), name


def test_the_flexible_vehicle_has_the_bending_as_its_tenth_dof():
    v = Vehicle(F)
    mu = beam.modal_mass_factor()
    assert v.n_dof == 10 and v.dof_names == (*DOF_NAMES, "carbody_bending")
    assert v.M[9, 9] == pytest.approx(mu * F.m_c, rel=1e-15)
    for m in (v.M, v.K, v.C, v.C0):
        assert m.shape == (10, 10) and np.allclose(m, m.T, rtol=0, atol=1e-9 * np.abs(m).max())
    assert v.K_w.shape == (10, 8) and v.C_w.shape == (10, 8) and v.T.shape == (10, 4)
    assert v.state_matrix.shape == (20, 20)
    assert np.linalg.eigvalsh(v.K).min() > 0
    (bending,) = [el for el in v.elements if el.group == "carbody_bending"]
    omega = 2 * math.pi * 10.0
    assert bending.name == "carbody bending" and np.array_equal(bending.a, np.eye(10)[9])
    assert bending.k == pytest.approx(mu * F.m_c * omega**2, rel=1e-14)
    assert bending.c == pytest.approx(2 * 0.02 * omega * mu * F.m_c, rel=1e-14)
    # the secondary's corners sit at x = +-l on the bending mode; the bending leaves the rails alone
    phi_l = beam.mode_shape(F.l, F.L_c)
    assert np.allclose(v.T[9], [phi_l] * 4, rtol=1e-15)
    assert not np.any(v.K_w[9]) and not np.any(v.C_w[9])


def test_the_bending_mode_tends_to_the_free_beams_as_the_secondary_goes():
    for p in (F, F.replace(f_bend=None, EI_c=5.0e9)):
        loose = _quiet(**{**{k: getattr(p, k) for k in ("L_c", "f_bend", "EI_c")}, "k_sz": 1e-3, "c_sz": 0.0})
        v = Vehicle(loose)
        mode = _mode(v, "carbody bending")
        expected = 10.0 if p.f_bend else 4.730040745**2 / (2 * math.pi) * math.sqrt(5.0e9 / (P.m_c * 24.0**3))
        assert loose.bending_hz == pytest.approx(expected, rel=1e-9)
        assert mode.frequency_hz == pytest.approx(expected, rel=1e-6)
        assert mode.damping_ratio == pytest.approx(0.02, rel=1e-6)  # the modal damping alone
    # on its suspension the secondary springs stiffen it: a little above the free carbody's
    on = _mode(Vehicle(F), "carbody bending")
    assert 10.0 < on.frequency_hz < 10.5 and on.damping_ratio > 0.02


def test_a_payload_keeps_the_bending_stiffness():
    heavy = F.loaded(1.3)
    assert heavy.f_bend == pytest.approx(10.0 / math.sqrt(1.3), rel=1e-15)
    EI = beam.bending_stiffness(10.0, F.m_c, F.L_c)
    given = F.replace(f_bend=None, EI_c=EI)
    assert given.bending_hz == pytest.approx(10.0, rel=1e-12)
    assert given.loaded(1.3).EI_c == EI
    assert given.loaded(1.3).bending_hz == pytest.approx(heavy.f_bend, rel=1e-12)


def test_the_floor_point_adds_the_bending_at_its_x():
    rigid, flexible = Vehicle(P), Vehicle(F)
    assert np.array_equal(rigid.floor_point(3.0, 0.5), [1.0, -3.0, 0.5, 0, 0, 0, 0, 0, 0])
    a = flexible.floor_point(3.0, 0.5)
    assert np.array_equal(a[:9], rigid.floor_point(3.0, 0.5)) and a[9] == beam.mode_shape(3.0, 24.0)
    assert flexible.floor_point(0.0)[9] == 1.0
    with pytest.raises(InputError, match=r"x = 12.5 m: .*within \+-L_c/2 = 12.0 m"):
        flexible.floor_point(12.5)


def test_the_centre_floor_resonates_at_the_bending_frequency_where_the_rigid_car_does_not():
    # 30 m/s: neither the wheelbase (2b) nor the bogie spacing (2l) filters 10 Hz out
    f = np.linspace(6.0, 14.0, 161)
    flexible = Vehicle(F).frequency_response(f, 30.0, "in-phase")
    rigid = Vehicle(P).frequency_response(f, 30.0, "in-phase")
    centre = np.abs(flexible["floor_acceleration"].sel(position="centre").values)
    peak = f[np.argmax(centre)]
    assert peak == pytest.approx(_mode(Vehicle(F), "carbody bending").damped_frequency_hz, rel=0.03)
    at = np.argmin(np.abs(f - peak))
    rigid_centre = np.abs(rigid["floor_acceleration"].sel(position="centre").values)
    assert centre[at] > 5 * rigid_centre[at]
    # the rigid car's centre floor is its CG; the flexible car's CG does not bend
    assert np.allclose(rigid_centre, np.abs(rigid["carbody_acceleration"].values), rtol=1e-12)
    assert np.abs(flexible["carbody_acceleration"].values)[at] < 0.2 * centre[at]
    assert "carbody_bending" in flexible and "carbody_bending" not in rigid


def test_the_modal_table_has_a_carbody_bending_mode():
    found = checked_modes(Vehicle(F))
    assert len(found) == 10 and [m.label for m in found].count("carbody bending") == 1
    assert len(checked_modes(Vehicle(P))) == 9


# -- the frequency domain ------------------------------------------------------------------------
def test_the_state_space_model_names_the_bending_and_its_floor_points_carry_it():
    model = linear_model(F)
    assert model.states[9] == "carbody_bending" and model.states[19] == "carbody_bending_rate"
    assert model.units["carbody_bending"] == "m" and "carbody_bending_acceleration" in model.outputs
    assert np.allclose(np.sort_complex(model.poles()), np.sort_complex(np.linalg.eigvals(Vehicle(F).state_matrix)))
    # the centre floor of the state-space model against the vehicle's frequency response
    f = np.array([2.0, 10.0])
    v = Vehicle(F)
    G = model.frequency_response(f)
    lag = np.exp(-2j * np.pi * f[:, None] * v.wheelset_lag_distance / 30.0)  # (2, 4)
    u = np.zeros((2, 20), complex)
    u[:, 0:8:2], u[:, 1:8:2] = lag, lag
    u[:, 8:16] = 2j * np.pi * f[:, None] * u[:, 0:8]
    y = np.einsum("foi,fi->fo", G, u)
    expected = v.frequency_response(f, 30.0, "in-phase")["floor_acceleration"].sel(position="centre").values
    assert np.allclose(y[:, model.index("outputs", "floor_acceleration_centre")], expected, rtol=1e-9)
    assert linear_model(P).states == (*DOF_NAMES, *(f"{d}_rate" for d in DOF_NAMES))


def test_the_ride_spectrum_of_the_flexible_car_raises_its_centre_floor():
    kwargs = dict(points=300, controllers=("passive", "sas-attitude"))
    flexible = ride_spectrum("fra4", vehicle=F, **kwargs)
    rigid = ride_spectrum("fra4", vehicle=P, **kwargs)
    centre = "floor_acceleration_centre"
    assert np.all(flexible.rms.sel(response=centre).values > rigid.rms.sel(response=centre).values)
    psd = flexible.psd[centre].sel(suspension="passive")
    band = psd.where((psd.frequency > 8) & (psd.frequency < 13), drop=True)
    assert float(band.max()) > 3 * float(rigid.psd[centre].sel(suspension="passive").interp(frequency=band.idxmax()))


# -- the floor in the time domain ----------------------------------------------------------------
def _dataset(params: VehicleParams, bending: bool) -> xr.Dataset:
    t = np.arange(0.0, 1.0, 1e-3)
    ds = xr.Dataset(
        {
            "carbody_acceleration": ("time", np.sin(2 * np.pi * t)),
            "carbody_pitch_acceleration": ("time", 0.1 * np.cos(2 * np.pi * t)),
            "vehicle_params": ((), json.dumps(params.to_dict())),
        },
        coords={"time": t},
    )
    if bending:
        ds["carbody_bending_acceleration"] = ("time", 0.5 * np.sin(20 * np.pi * t))
        ds["carbody_bending"] = ("time", -0.5 / (20 * np.pi) ** 2 * np.sin(20 * np.pi * t))
    return ds


def test_the_floor_acceleration_adds_the_bending_at_each_point():
    ds = _dataset(F, bending=True)
    floor = floor_acceleration(ds, {"centre": 0.0, "front": "front", "node": BEYOND * 24.0, "end": 12.0})
    rigid = ds["carbody_acceleration"] - floor["x_m"] * ds["carbody_pitch_acceleration"]
    for name, phi in (("centre", 1.0), ("front", beam.mode_shape(F.l, 24.0)), ("node", 0.0), ("end", -1.6452)):
        expected = rigid.sel(position=name) + phi * ds["carbody_bending_acceleration"]
        assert np.allclose(floor.sel(position=name), expected, rtol=0, atol=2e-4 if name == "end" else 1e-12), name
    with pytest.raises(InputError, match=r"beyond the bending carbody's ends, \+-L_c/2 = 12.0 m"):
        floor_acceleration(ds, {"out": 13.0})
    # a rigid carbody's run, and one whose channel holds zeros, are the rigid floor
    plain = floor_acceleration(_dataset(P, bending=False), {"front": "front"})
    assert np.array_equal(plain.sel(position="front"), rigid.sel(position="front"))
    zeros = _dataset(P, bending=True)
    zeros["carbody_bending_acceleration"] = zeros["carbody_bending_acceleration"] * 0.0
    assert np.array_equal(floor_acceleration(zeros, {"front": "front"}), plain)


# -- the input rules -----------------------------------------------------------------------------
def test_a_bending_frequency_at_or_below_the_carbody_modes_is_refused():
    with pytest.raises(InputError, match=r"'f_bend' = 0.9 Hz: .*the highest, carbody pitch, is at 0.978[0-9]* Hz"):
        Vehicle(_quiet(L_c=24.0, f_bend=0.9))
    EI = beam.bending_stiffness(0.5, P.m_c, 24.0)
    with pytest.raises(InputError, match=r"'EI_c' = .* N m\^2 \(a bending frequency of 0.5 Hz\): .*carbody pitch"):
        Vehicle(_quiet(L_c=24.0, EI_c=EI))


def test_the_bending_fields_go_together():
    with pytest.raises(InputError, match=r"'f_bend' = 10.0 Hz and 'EI_c' = 5e\+09 N m\^2: give one"):
        P.replace(L_c=24.0, f_bend=10.0, EI_c=5e9)
    for field, value in (("f_bend", 10.0), ("EI_c", 5e9)):
        with pytest.raises(InputError, match=rf"{field!r} = .* needs 'L_c', the carbody length"):
            P.replace(**{field: value})
    with pytest.raises(InputError, match=r"'L_c' = 20.0 \(carbody length, m\): must exceed 2 \(l \+ b\) = 20.5 m"):
        P.replace(L_c=20.0, f_bend=10.0)
    with pytest.raises(InputError, match=r"'zeta_bend' = 2.0 .*must be between 0 and 1"):
        F.replace(zeta_bend=2.0)


def test_a_length_without_a_frequency_runs_rigid_and_says_so():
    rigid = r"'L_c' = 24.0 m .*without 'f_bend' or 'EI_c': the carbody runs rigid"
    with pytest.warns(PlausibilityWarning, match=rigid):
        p = P.replace(L_c=24.0)
    assert not p.flexible and Vehicle(p).n_dof == 9
    assert any("runs rigid" in n for n in notes(p)) and not notes(F)


def test_the_toml_round_trip_keeps_the_bending_and_a_file_without_it_is_rigid():
    assert VehicleParams.from_toml(F.to_toml()) == F
    text = P.to_toml()
    assert "# f_bend not set" in text and "# L_c not set" in text
    assert VehicleParams.from_toml(text) == P
    # a file of before the bending mode: no bending entries, no rigid_carbody switch: rigid, said
    old = "\n".join(
        line
        for line in text.splitlines()
        if not line.startswith(("# L_c", "# f_bend", "# EI_c", "zeta_bend", "rigid_carbody"))
    )
    with pytest.warns(PlausibilityWarning, match="gives no bending mode of the carbody"):
        assert not VehicleParams.from_toml(old).flexible
    assert VehicleParams.from_toml('[vehicle]\npreset = "paper"\nL_c = 24.0\nf_bend = 10.0\n') == F
