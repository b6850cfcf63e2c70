"""A measured profile's CSV as a recording car writes it: millimetres said in the header are
read as millimetres (a unit it does not know is refused, naming the column), and a profile that
starts off level is warned of, since the vehicle, at rest on level track, meets a step there."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import railride as rr
from railride.errors import InputError
from railride.validation import PlausibilityWarning

S = np.arange(0.0, 700.0, 0.25)
Z = 0.003 * np.sin(2 * np.pi * S / 25.0)


def _write(path, header, factor, offset=0.0):
    rows = "".join(
        f"{float(factor * s)!r},{float(factor * (z + offset))!r},{float(factor * 0.8 * z)!r}\n" for s, z in zip(S, Z)
    )
    path.write_text(header + "\n" + rows)
    return path


def test_millimetres_in_the_header_are_read_as_millimetres(tmp_path):
    metres = rr.scenario(f"file:{_write(tmp_path / 'm.csv', 's [m],z_L [m],z_R [m]', 1.0)}")
    mm = rr.scenario(f"file:{_write(tmp_path / 'mm.csv', 's [mm],z_L [mm],z_R [mm]', 1e3)}")
    at = np.linspace(0.0, 390.0, 777)
    for a, b in zip(metres.track._evaluate(at)[:2], mm.track._evaluate(at)[:2]):
        np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-15)
    assert np.max(np.abs(mm.track._evaluate(at)[0])) == pytest.approx(0.003, rel=1e-3)  # 3 mm, not 3 m


def test_a_unit_it_does_not_know_is_refused_naming_the_column(tmp_path):
    path = _write(tmp_path / "km.csv", "s [km],z_L,z_R", 1.0)
    with pytest.raises(InputError, match=r"column 's \[km\]' is in 'km'; allowed units: m or mm"):
        rr.scenario(f"file:{path}")


def test_a_profile_that_starts_off_level_is_warned_of_and_a_section_is_not(tmp_path):
    path = _write(tmp_path / "offset.csv", "s,z_L,z_R", 1.0, offset=0.004)
    with pytest.warns(PlausibilityWarning, match=r"starts at z_L = 4 mm, z_R = 0 mm at s = 0, not level"):
        rr.scenario(f"file:{path}")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rr.scenario(f"file:{path}", start=0.0)  # faded in over 20 m
        rr.scenario(f"file:{_write(tmp_path / 'level.csv', 's,z_L,z_R', 1.0)}")  # starts level
