"""`railride sweep --out`: a sweep over two axes writes its figure; one it cannot draw says why,
in one line."""

from __future__ import annotations

from clihelp import is_png, ok


def test_a_sweep_over_two_axes_writes_its_figure(tmp_path):
    out = tmp_path / "two"
    result = ok("sweep", "--speed", "20,40", "--wavelength", "30,60", "--duration", 0.2, "--no-comfort", "--out", out)
    assert sorted(p.name for p in out.iterdir()) == ["runs.csv", "sweep.json", "sweep.png"]
    assert is_png(out / "sweep.png")
    assert "note:" not in result.stderr


def test_a_sweep_over_three_axes_says_in_one_line_why_it_has_no_figure(tmp_path):
    out = tmp_path / "three"
    args = ("--speed", "20,40", "--wavelength", "30,60", "--amplitude", "0.01,0.02", "--duration", 0.2)
    result = ok("sweep", *args, "--no-comfort", "--out", out)
    assert sorted(p.name for p in out.iterdir()) == ["runs.csv", "sweep.json"]
    notes = [line for line in result.stderr.splitlines() if line.startswith("note:")]
    assert len(notes) == 1
    assert "3 axes" in notes[0] and "speed_m_s, wavelength_m, amplitude_m" in notes[0]
