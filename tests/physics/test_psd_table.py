"""A user's own track spectrum (psd:PATH, railride.model.psd_table): a table of a standard
spectrum gives that spectrum's realisation, converging as the square of the table's spacing
(log-log interpolation); a power law's realisation has the variance of its integral; the units
of the two abscissae agree; bad tables are refused naming the row."""

from __future__ import annotations

import numpy as np
import pytest

from railride.errors import InputError
from railride.model.irregularity import spectrum
from railride.model.track import scenario


def _table(path, rows: int, per_cycle: bool = False, cross: bool = True):
    """fra4 tabulated at ``rows`` log-spaced wavenumbers over 0.5-200 m of wavelength."""
    W = np.geomspace(2 * np.pi / 200, 2 * np.pi / 0.5, rows)
    f = 2 * np.pi if per_cycle else 1.0  # cycles per metre: W / 2 pi, PSD per (1/m) = 2 pi x per (rad/m)
    head = "spatial_frequency_per_m" if per_cycle else "wavenumber_rad_per_m"
    lines = [f"# fra4, {rows} rows", f"{head},vertical" + (",cross_level" if cross else "")]
    for w, v, x in zip(W, spectrum("fra4", W), spectrum("fra4", W, "cross-level")):
        lines.append(f"{float(w / f)!r},{float(v * f)!r}" + (f",{float(x * f)!r}" if cross else ""))
    path.write_text("\n".join(lines) + "\n")
    return f"psd:{path}"


def _samples(name: str):
    return scenario(name, seed=3, speed=30.0, duration=5.0).track.samples()


def test_a_table_of_a_standard_spectrum_converges_to_its_realisation(tmp_path):
    """The same seed draws the same phases, so only the amplitudes differ: by the table's
    log-log interpolation error, which falls as the square of its spacing."""
    _, zv, zx = _samples("fra4")
    errors = []
    for rows in (50, 100, 200):
        _, tv, tx = _samples(_table(tmp_path / f"t{rows}.csv", rows))
        errors.append((np.abs(tv - zv).max() / np.abs(zv).max(), np.abs(tx - zx).max() / np.abs(zx).max()))
    assert errors[-1][0] < 3e-5 and errors[-1][1] < 1e-4, errors
    for coarse, fine in zip(errors, errors[1:]):
        for a, b in zip(coarse, fine):
            assert 2.5 < a / b < 6.0, errors  # second order: 4 per halving


def test_spatial_frequency_and_wavenumber_tables_are_the_same_spectrum(tmp_path):
    _, a, ax = _samples(_table(tmp_path / "rad.csv", 100))
    _, b, bx = _samples(_table(tmp_path / "cyc.csv", 100, per_cycle=True))
    np.testing.assert_allclose(b, a, rtol=0, atol=1e-12 * np.abs(a).max())
    np.testing.assert_allclose(bx, ax, rtol=0, atol=1e-12 * np.abs(ax).max())


def test_a_power_law_realisation_has_the_variance_of_its_integral(tmp_path):
    """S = A / W^2 over W1..W2 (two rows: log-log is exact) has variance A (1/W1 - 1/W2). The
    realisation's harmonics, at W_k = k dW on its period (2000 m here), each of variance
    S(W_k) dW, give the Riemann sum of it exactly (Parseval), which is within 3 % of the
    integral at this dW. Without a cross-level column the two rails are one profile."""
    A, lo, hi = 1e-7, 1.0, 100.0
    W1, W2 = 2 * np.pi / hi, 2 * np.pi / lo
    path = tmp_path / "power.csv"
    rows = [(W1 / 2, A / (W1 / 2) ** 2), (W2 * 2, A / (W2 * 2) ** 2)]
    path.write_text("wavenumber_rad_per_m,vertical\n" + "".join(f"{w!r},{s!r}\n" for w, s in rows))
    sc = scenario(f"psd:{path}", seed=0, speed=30.0, duration=5.0)
    s, zv, zx = sc.track.samples()
    dW = 2 * np.pi / 2000.0
    k = np.arange(1, 4001)
    W = k * dW
    W = W[(W >= W1 * (1 - 1e-12)) & (W <= W2 * (1 + 1e-12))]
    assert np.var(zv) == pytest.approx(np.sum(A / W**2) * dW, rel=1e-9)
    assert np.var(zv) == pytest.approx(A * (1 / W1 - 1 / W2), rel=0.03)
    assert not zx.any()
    zl, zr = sc.track._evaluate(np.linspace(30.0, 150.0, 500))[:2]
    np.testing.assert_array_equal(zl, zr)
    assert sc.describe()["spectrum_sha256"] and sc.describe()["spectrum"] == f"psd:{path}"


@pytest.mark.parametrize(
    "text, fragments",
    [
        ("", ("empty",)),
        ("omega,vertical\n1,1\n2,1\n", ("header 'omega,vertical'", "wavenumber_rad_per_m or spatial_frequency_per_m")),
        ("wavenumber_rad_per_m,vertical\n1,1e-6\n", ("1 row(s); a spectrum needs at least two",)),
        ("wavenumber_rad_per_m,vertical\n1,1e-6\n0.5,1e-6\n", ("row 3", "must rise strictly")),
        ("wavenumber_rad_per_m,vertical\n1,1e-6\n2,0\n", ("row 3", "finite number > 0")),
        ("wavenumber_rad_per_m,vertical\n1,1e-6\n2,lots\n", ("row 3 = '2,lots': not numbers",)),
        ("wavenumber_rad_per_m,vertical,cross_level\n1,1e-6\n", ("row 2 has 2 values, the header 3",)),
    ],
)
def test_a_bad_table_is_refused_naming_the_row(text, fragments, tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        scenario(f"psd:{path}", speed=30.0, duration=1.0)
    assert str(err.value).startswith(f"scenario 'psd:{path}': "), str(err.value)
    for fragment in fragments:
        assert fragment in str(err.value), str(err.value)


def test_a_band_beyond_the_table_is_refused_not_extrapolated(tmp_path):
    name = _table(tmp_path / "t.csv", 50)
    with pytest.raises(InputError, match=r"wavelength band \[0.2, 100\] m: beyond the 0.5 to 200 m"):
        scenario(name, min_wavelength=0.2, speed=30.0, duration=1.0)
    with pytest.raises(InputError, match="no such spectrum table"):
        scenario(f"psd:{tmp_path / 'gone.csv'}")
    with pytest.raises(InputError, match="a folder, not a spectrum table"):
        scenario(f"psd:{tmp_path}")
    with pytest.raises(InputError, match="needs a path"):
        scenario("psd:")


def test_an_edited_table_is_another_spectrum(tmp_path):
    """The realisations are kept for the next runs by their settings and the table's contents:
    a run after the file changed reads the new spectrum, not the old realisation."""
    path = tmp_path / "t.csv"
    name = _table(path, 50)
    before = _samples(name)[1]
    lines = path.read_text().splitlines()
    rows = [line.split(",") for line in lines[2:]]
    path.write_text("\n".join(lines[:2] + [f"{w},{4 * float(v)!r},{4 * float(x)!r}" for w, v, x in rows]) + "\n")
    after = _samples(name)[1]  # 4 x the PSD: 2 x the amplitude
    np.testing.assert_allclose(after, 2 * before, rtol=0, atol=1e-12 * np.abs(before).max())


def test_the_record_keeps_the_spectrum_not_the_files_bytes(tmp_path):
    """The SHA-256 a result records is of the values read: a comment or another way of writing
    the same numbers leaves it; another value changes it."""
    from railride.model import psd_table

    path = tmp_path / "t.csv"
    path.write_text("wavenumber_rad_per_m,vertical\n0.05,1e-4\n10,1e-9\n")
    first = psd_table.table(f"psd:{path}").sha256
    path.write_text("# the same spectrum\nwavenumber_rad_per_m,vertical\n5e-2,0.0001\n10.0,1.0e-9\n")
    assert psd_table.table(f"psd:{path}").sha256 == first
    path.write_text("wavenumber_rad_per_m,vertical\n0.05,2e-4\n10,1e-9\n")
    assert psd_table.table(f"psd:{path}").sha256 != first
