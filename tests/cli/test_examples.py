"""The scripts in examples/ run as a user would run them (python examples/x.py --out DIR) and
print their summary."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def run_example(name: str, out: Path, *args: str) -> str:
    """Run examples/<name>.py from the repository root; return its standard output."""
    proc = subprocess.run(
        [sys.executable, f"examples/{name}.py", "--out", str(out), *args],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, f"{name} failed:\n{proc.stdout}\n{proc.stderr}"
    return proc.stdout


@pytest.mark.parametrize(
    "name",
    [
        "paper_comparison",
        "speed_sweep_random_track",
        "custom_vehicle",
        "damper_size",
        "flexible_carbody",
        "robust_gains",
        "roll_cost",
        "fmu_cosimulation",
    ],
)
def test_example_has_a_docstring_and_uses_no_private_names(name):
    text = (ROOT / "examples" / f"{name}.py").read_text()
    assert text.startswith('"""')
    assert not re.search(r"\brailride(\.\w+)*\._", text)
    assert not re.search(r"import _|\._[a-z]", text)


def test_paper_comparison(tmp_path):
    out = run_example("paper_comparison", tmp_path / "cmp")
    # the table: one reduction per controller on each response, as "( 16.8%)"
    assert re.search(r"^acceleration\s+\d\.\d+(\s+\d\.\d+\s+\(\s*-?\d+\.\d%\)){3}$", out, re.M)
    assert "ideal-damper" in out and "Trade-offs" in out
    assert "tuned on this same track (in-sample)" in out
    assert (tmp_path / "cmp" / "comparison.json").is_file()


def test_speed_sweep_random_track(tmp_path):
    out = run_example("speed_sweep_random_track", tmp_path / "sweep")
    for v in (20, 30, 40, 50, 60):
        assert re.search(rf"^\s+{v}\s+\d\.\d{{4}}\s+\d\.\d{{4}}\s+-?\d+\.\d%$", out, re.M), v
    assert (tmp_path / "sweep" / "rms_vs_speed.png").stat().st_size > 0
    assert (tmp_path / "sweep" / "sweep.csv").is_file()


def test_custom_vehicle(tmp_path):
    out = run_example("custom_vehicle", tmp_path / "veh")
    assert "k_sz 290000 -> 200000" in out
    assert re.search(r"^carbody bounce\s+0\.\d{3}\s+\d\.\d{3}\s+0\.\d{3}\s+\d\.\d{3}$", out, re.M)
    assert re.search(r"^acceleration \[m/s\^2\]\s+\d\.\d+ \(", out, re.M)
    assert (tmp_path / "veh" / "custom_vehicle.toml").is_file()


def test_damper_size(tmp_path):
    out = run_example("damper_size", tmp_path / "size")
    for name in ("railway x 0.5", "railway x 1", "railway x 2", "railway x 4", "ideal-damper", "ideal"):
        assert re.search(
            rf"^{re.escape(name)}\s+(\d\.\d{{3}}\s+){{4}}\d\.\d{{3}}$|^{re.escape(name)}\s+diverged", out, re.M
        ), name
    assert "Best MR size here" in out
    assert (tmp_path / "size" / "damper_size.csv").is_file()


def test_flexible_carbody(tmp_path):
    out = run_example("flexible_carbody", tmp_path / "flex", "--seeds", "1", "--duration", "10")
    assert re.search(r"^\| passive \| 0\.\d{3} \| 0\.\d{3} \(\d\.\d\dx\) \|", out, re.M)
    assert (tmp_path / "flex" / "flexible_carbody.csv").is_file()


def test_robust_gains(tmp_path):
    out = run_example("robust_gains", tmp_path / "rg", "--seeds", "1", "--duration", "4")
    assert out.startswith("gains: robust; mean RMS ratio to passive over 2 held-out runs")
    assert re.search(r"^\| clipped-optimal \| \d\.\d{3} \| \d+ m/s, load 1(\.3)? \|", out, re.M)
    assert "no mean ratio above 1 anywhere:" in out
    assert (tmp_path / "rg" / "robust_gains.csv").is_file()


@pytest.mark.slow
def test_roll_cost(tmp_path):
    run_example("roll_cost", tmp_path / "roll")
    assert (tmp_path / "roll" / "remedy.csv").is_file()


def test_readme_python_block_runs():
    # the README's Python example, as a user would paste it; the tuning line (30 s) is left out,
    # tune() has its own tests
    text = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    code = text.split("```python", 1)[1].split("```", 1)[0]
    kept = "\n".join(line for line in code.splitlines() if "rr.tune(" not in line)
    assert "rr.compare(" in kept and "rr.simulate(" in kept
    exec(compile(kept, "README.md", "exec"), {})


def test_fmu_cosimulation(tmp_path):
    pytest.importorskip("fmpy")
    out = run_example("fmu_cosimulation", tmp_path / "fmu")
    for name in ("carbody_bounce", "carbody_pitch", "carbody_roll", "carbody_acceleration"):
        match = re.search(rf"^{name}\s+\S+\s+\S+\s+(\S+)$", out, re.M)
        assert match and float(match.group(1)) < 1e-6, out
    assert (tmp_path / "fmu" / "vehicle.fmu").is_file() and (tmp_path / "fmu" / "cosimulation.csv").is_file()
