"""A study's size is refused before any work when it cannot fit: pareto's sample count, a sweep
grid's cartesian product (railride.limits' memory limit, counted before anything is made), and
state-space's one suspension (not "all", which the sibling ride-spectrum takes)."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

from railride import limits
from railride.cli import app
from railride.errors import InputError
from railride.studies.grid import grid, grid_size
from railride.studies.pareto import pareto

runner = CliRunner()


def _input_error(*args) -> str:
    """The one error line of a command that must exit 2 (an input error, no traceback)."""
    result = runner.invoke(app, [str(a) for a in args])
    assert result.exit_code == 2, (result.exit_code, result.output)
    assert isinstance(result.exception, SystemExit)
    assert "Traceback" not in result.output and "a bug in railride" not in result.output
    return result.stderr.strip().splitlines()[-1]


@pytest.mark.parametrize("name", ["all", "passive,pid"])
def test_state_space_takes_one_suspension(name):
    # "all" crashed unpacking several suspensions into one ("a bug in railride", exit 1)
    line = _input_error("state-space", "--suspension", name)
    assert f"--suspension = {name!r}" in line and "one suspension" in line
    assert "passive, plant, pid" in line and "or all" not in line


def test_pareto_samples_past_the_memory_are_refused_first():
    # 2**30 samples failed allocating the Sobol' sample (MemoryError, "a bug in railride")
    with limits.memory_limit("64G"), pytest.raises(InputError, match=r"n_samples = 1073741824: .* memory"):
        pareto(n_samples=2**30, scenario_options={"duration": 0.05}, progress=False)
    line = _input_error("pareto", "--duration", 0.05, "--samples", 2**30, "--max-memory", "64G")
    assert "--samples = 1073741824" in line and "memory" in line and "--max-memory" in line


def test_pareto_samples_past_sobol_are_refused():
    # past 2**30 scipy's Sobol' sequence has no more points (2**62 failed as "array is too big")
    with pytest.raises(InputError, match=r"n_samples = 4611686018427387904: at most 2\*\*30"):
        pareto(n_samples=2**62, scenario_options={"duration": 0.05}, progress=False)


def test_grid_product_past_the_memory_is_refused_before_it_is_built():
    # each axis alone passes; their product (1089 cases of about 1 kB) is past a 1 MiB limit
    values = dict(speed=[10 + i for i in range(33)], amplitude=[0.01 + 0.001 * i for i in range(33)], duration=0.05)
    with limits.memory_limit("1M"), pytest.raises(InputError, match=r"a grid of 1089 runs \(33 speed x 33 amplitude"):
        grid("passive", **values)
    assert len(grid("passive", **values)) == 1089  # the default limit holds it
    line = _input_error(
        "sweep", "--duration", 0.05, "--speed", "10:42:33", "--amplitude", "0.01:0.042:33", "--max-memory", "1M"
    )
    assert "a grid of 1089 runs (33 --speed x 33 --amplitude x 1 --suspension)" in line and "--max-memory" in line


def test_grid_size_counts_the_cases_grid_makes():
    g = grid(
        ["passive", "mr", "passive-on", "pid", "sas-attitude"],
        speed=[40, 50],
        duration=0.05,
        voltage=[0, 1, 2],
        damper_scale=[0.5, 1],
        gains={"pid.kp": [1, 2, 3]},
        noise=[1e-4, 1e-4, 1e-3, 1e-3],
        seed=[0, 1],
    )
    axes = [(kw, column, list(values)) for kw, column, values in g.axes]
    gains = [(n, list(vs)) for n, vs in g.gains]
    assert grid_size(axes, list(g.suspensions), g.damper_scales, g.voltages, gains, g.seeds) == len(g)
    assert grid_size(axes, ["passive"], None, None, [], None) == 2
