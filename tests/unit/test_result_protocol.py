"""Every result of a library function follows one protocol (`railride.Result`, railride/results.py):
it is a `railride.Result`, a frozen dataclass, its `to_pandas` is a DataFrame, `save` writes its
JSON document (equal to `to_dict`) and its main table (equal to `to_pandas`, where it writes
one), and `plot` returns its figure, or draws into the Axes it is given and returns theirs.

Each result is made as cheaply as the public library allows (short runs, few points)."""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any, Callable, NamedTuple

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402
import pytest  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

import railride as rr  # noqa: E402

SHORT = {"duration": 0.5}


def _ride():
    return rr.simulate(rr.scenario("paper-sine", duration=1.0))


def _comparison():
    return rr.compare(rr.scenario("paper-sine", duration=1.0), controllers=["pid"], bounds=False)


def _league():
    from railride.studies.league import league

    return league(["paper-sine"], [30.0, 40.0], controllers=["pid"], duration=1.0)


def _study():
    return rr.study(["pid"], scenario="paper-sine", speeds=[30.0, 40.0], duration=1.0)


def _design():
    return rr.design(
        ["pid"],
        tracks=["fra4"],
        speeds=[40.0],
        loads=[1.0],
        train_seeds=[0],
        test_seeds=[1],
        duration=1.0,
        budget=13,
        values=3,
    )


def _sweep():
    return rr.run_sweep(rr.sweep.grid(["passive", "pid"], speed=[20.0, 40.0], duration=0.5))


def _tune():
    return rr.tune(("pid",), scenario_options=SHORT, n_values=3, budget=5, before_after=False)


def _pareto():
    return rr.pareto("sas-attitude", n_samples=2, seed=3, scenario_options=SHORT)


def _optimise():
    from railride.studies.optimise import optimise

    return optimise(("attitude.kd_z",), suspension="sas-attitude", scenario_options=SHORT, popsize=2, maxiter=1)


def _sensitivity():
    from railride.studies.optimise import sensitivity

    return sensitivity(("attitude.kd_z", "ride.kp_1R"), suspension="sas-attitude", scenario_options=SHORT, n=2)


def _frf():
    return rr.frequency_responses(points=20)


def _ride_spectrum():
    from railride.frequency.ride_spectrum import ride_spectrum

    return ride_spectrum("fra4", controllers=("passive", "pid"), points=64)


def _cycles():
    from railride.run import rig

    return rig.cycles("railway", 0.01, 2.0, [0.0, 2.25], n_cycles=2)


def _tracking():
    from railride.run import rig

    return rig.track(n_cycles=2)


def _tune_panels(result) -> int:
    return len(dict.fromkeys(c.parameter for c in result.curves))


def _study_panels(result) -> int:
    from railride.plots.study import DEFAULT_METRICS

    return len(DEFAULT_METRICS)


class Kind(NamedTuple):
    """How to make a result type and what its `save` writes: ``document`` (the JSON of
    `to_dict`), ``table`` (the CSV of `to_pandas`, None where it writes none) and whether that
    table has an index column; ``panels``: the Axes its `plot` takes (a count, or one from the
    result)."""

    name: str
    make: Callable[[], Any]
    document: str
    table: str | None
    panels: int | Callable[[Any], int]
    index: bool = False


KINDS = [
    Kind("RideResult", _ride, "metrics.json", "ride.csv", 4, index=True),
    # compare.csv holds the time histories; the metrics table of to_pandas has no file of its own
    Kind("Comparison", _comparison, "compare.json", None, 1),
    Kind("LeagueTable", _league, "league.json", "league.csv", 1),
    Kind("StudyResult", _study, "study.json", "study_summary.csv", _study_panels),
    Kind("DesignResult", _design, "design.json", "design.csv", 4),
    # sweep.json holds every row; the run table runs.csv is the sweep's, not save's
    Kind("SweepResult", _sweep, "sweep.json", None, 4),
    Kind("TuneResult", _tune, "tune.json", "curves.csv", _tune_panels),
    Kind("ParetoResult", _pareto, "pareto.json", "pareto.csv", 2),
    Kind("OptimiseResult", _optimise, "optimise.json", "optimise.csv", 1),
    Kind("SensitivityResult", _sensitivity, "sobol.json", "sobol.csv", 1),
    Kind("FrfResult", _frf, "frf.json", "frf.csv", 8),
    Kind("RideSpectrum", _ride_spectrum, "ride_spectrum.json", "ride_spectrum.csv", 3),
    Kind("Cycles", _cycles, "damper.json", "cycles.csv", 2),
    Kind("Tracking", _tracking, "tracking.json", "tracking.csv", 2, index=True),
]


def _same(saved, made, where="document") -> None:
    """``saved`` (read back from the file) equals ``made`` (to_dict through JSON), floats to
    rounding."""
    if isinstance(made, float) and isinstance(saved, (int, float)) and not isinstance(saved, bool):
        assert math.isclose(saved, made, rel_tol=1e-12, abs_tol=0.0) or saved == made, f"{where}: {saved} != {made}"
    elif isinstance(made, dict):
        assert isinstance(saved, dict) and list(saved) == list(made), f"{where}: keys {list(saved)} != {list(made)}"
        for k in made:
            _same(saved[k], made[k], f"{where}.{k}")
    elif isinstance(made, list):
        assert isinstance(saved, list) and len(saved) == len(made), f"{where}: {saved!r} != {made!r}"
        for i, (s, m) in enumerate(zip(saved, made)):
            _same(s, m, f"{where}[{i}]")
    else:
        assert saved == made and type(saved) is type(made), f"{where}: {saved!r} != {made!r}"


@pytest.mark.parametrize("kind", KINDS, ids=[k.name for k in KINDS])  # each a few seconds at most, compiled
def test_every_result_follows_the_protocol(kind, tmp_path):
    result = kind.make()
    try:
        # (1) it is a railride.Result, of the type the package names
        assert type(result).__name__ == kind.name
        assert isinstance(result, rr.Result)
        # (2) frozen: a dataclass whose fields cannot be assigned
        assert dataclasses.is_dataclass(result) and type(result).__dataclass_params__.frozen  # type: ignore[attr-defined]
        first = dataclasses.fields(result)[0].name
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(result, first, getattr(result, first))
        with pytest.raises(dataclasses.FrozenInstanceError):
            result.anything_else = 1
        # (3) its table
        frame = result.to_pandas()
        assert isinstance(frame, pd.DataFrame) and len(frame)
        # (4) its files: the JSON document is to_dict, the main table is to_pandas
        paths = result.save(tmp_path / "x")
        assert paths and all(p.exists() for p in paths)
        names = [p.name for p in paths]
        assert kind.document in names
        made = json.loads(json.dumps(result.to_dict(), default=str))
        _same(json.loads((tmp_path / "x" / kind.document).read_text()), made)
        if kind.table is not None:
            assert kind.table in names
            back = pd.read_csv(tmp_path / "x" / kind.table, index_col=0 if kind.index else None)
            missing = frame.where(frame.notna(), float("nan"))  # None (no track seed on a sine) is a blank cell
            pd.testing.assert_frame_equal(back, missing, check_dtype=False, check_exact=False, rtol=1e-12)
        # (5) its figure, new or in the caller's Axes
        fig = result.plot()
        assert isinstance(fig, Figure) and fig.axes
        count = kind.panels if isinstance(kind.panels, int) else kind.panels(result)
        mine = Figure()
        axes = mine.subplots(1, count, squeeze=False).ravel().tolist()
        assert result.plot(ax=axes[0] if count == 1 else axes) is mine
        assert all(a.figure is mine for a in axes) and any(a.has_data() for a in axes)
    finally:
        plt.close("all")


def test_every_result_type_is_checked():
    """The list above names every class of railride with the four methods of the protocol."""
    import ast
    from pathlib import Path

    package = Path(rr.__file__).parent
    found = set()
    for path in package.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef) and node.name != "Result":
                methods = {f.name for f in node.body if isinstance(f, ast.FunctionDef)}
                if {"to_dict", "to_pandas", "plot", "save"} <= methods:
                    found.add(node.name)
    assert found and found == {k.name for k in KINDS}
