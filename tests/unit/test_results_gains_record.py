"""Every result records the gains it ran as a study does (docs/json.md, The gains record): the
comparison, the sweep, the ride spectrum, the Pareto view and the global optimiser's results hold
``gains`` (the source as far as it is still true), ``gains_provenance`` and ``gains_values``
in their settings; those that vary gains say which (``gains_varied``). Each is checked against
the packaged gains file as TOML reads it, with the one value the "tuning" changed, and its JSON
against its schema."""

from __future__ import annotations

import pytest

import railride as rr
from railride.secondary.control import GainSet

pytest.importorskip("jsonschema")

from tuned_gains import PROVENANCE, TUNED_KP, as_validated_json, packaged, pid_values, tuned_gains  # noqa: E402

SHORT = {"duration": 0.5}
#: the file name the tuned gains claim
SOURCE = "tuned-for-this-test.toml"


def _pid_values(**changes) -> dict:
    """What the PID law reads of the shipped file, with ``changes``."""
    return pid_values(packaged(), **changes)


def _assert_tuned(settings: dict, controllers: dict, source_key: str = "gains") -> None:
    """``settings`` record the tuned gains: their name, their provenance and ``controllers``'s
    values ({name: expected values})."""
    assert settings[source_key] == SOURCE
    assert settings["gains_provenance"] == PROVENANCE
    assert settings["gains_values"] == controllers


@pytest.fixture(scope="module")
def tuned() -> GainSet:
    return tuned_gains(SOURCE)


def test_a_comparison_records_the_gains_it_ran(tuned):
    result = rr.compare(rr.scenario("paper-sine", **SHORT), controllers=["passive", "pid"], gains=tuned, bounds=False)
    doc = as_validated_json(result.to_dict(), "railride.comparison-1")
    _assert_tuned(doc["settings"], {"passive": {}, "pid": _pid_values(**{"pid.kp": TUNED_KP})})
    # the keys the document had before stay as they were
    assert doc["gains"]["source"] == SOURCE
    assert doc["gains"]["pid"]["kp"] == TUNED_KP
    assert doc["tuning"]["objective"] == PROVENANCE["objective"]


def test_a_comparison_of_changed_gains_never_names_their_file_alone():
    changed = GainSet.default().apply({"pid.kd": 12345.0})
    doc = rr.compare(rr.scenario("paper-sine", **SHORT), controllers=["pid"], gains=changed, bounds=False).to_dict()
    assert doc["gains"]["source"] == doc["settings"]["gains"] == "railride/data/gains.toml, changed: pid.kd"
    assert doc["settings"]["gains_provenance"] is None  # the file's provenance is not theirs
    assert doc["settings"]["gains_values"]["pid"] == _pid_values(**{"pid.kd": 12345.0})


def test_a_sweep_records_its_base_gains_and_the_gains_its_axes_vary(tuned):
    from railride.studies.grid import grid

    plain = rr.run_sweep(grid(["passive", "pid"], speed=[30.0], base_gains=tuned, **SHORT), progress=False)
    doc = as_validated_json(plain.to_dict(), "railride.sweep-1")
    _assert_tuned(doc["settings"], {"pid": _pid_values(**{"pid.kp": TUNED_KP})})
    assert doc["settings"]["gains_source"] == SOURCE  # the key of older files, the same source
    assert doc["settings"]["gains_varied"] == []

    kd = [1.0e4, 3.0e4]
    varied = rr.run_sweep(grid(["pid"], gains={"pid.kd": kd}, base_gains=tuned, **SHORT), progress=False)
    doc = as_validated_json(varied.to_dict(), "railride.sweep-1")
    # the base gains, the axis named; its values per run in the rows
    _assert_tuned(doc["settings"], {"pid": _pid_values(**{"pid.kp": TUNED_KP})})
    assert doc["settings"]["gains_varied"] == ["pid.kd"]
    assert sorted(row["pid.kd"] for row in doc["rows"] if row["suspension"] == "pid") == kd


def test_a_sweep_without_controllers_records_no_gains():
    from railride.studies.grid import grid

    settings = rr.run_sweep(grid(["passive"], speed=[30.0], **SHORT), progress=False).settings
    assert settings["gains"] is None and settings["gains_source"] is None
    assert settings["gains_provenance"] is None and settings["gains_values"] == {}


def test_a_ride_spectrum_records_the_gains_it_ran(tuned):
    from railride.frequency.ride_spectrum import ride_spectrum

    result = ride_spectrum("fra4", points=64, controllers=["passive", "pid"], gains=tuned)
    assert list(result.suspensions) == ["passive", "pid"]  # both ran
    doc = as_validated_json(result.to_dict(), "railride.ride-spectrum-1")
    _assert_tuned(doc["settings"], {"passive": {}, "pid": _pid_values(**{"pid.kp": TUNED_KP})}, "gains_source")
    assert doc["settings"]["gains"] == "given"  # the key of older files keeps its meaning


def test_a_pareto_view_records_its_base_gains_and_the_sampled_ones(tuned):
    result = rr.pareto("pid", n_samples=2, seed=3, scenario_options=SHORT, gains=tuned, parameters=["pid.kd"])
    doc = as_validated_json(result.to_dict(), "railride.pareto-1")
    expected = _pid_values(**{"pid.kp": TUNED_KP})
    _assert_tuned(doc["settings"], {"pid": expected})
    assert doc["settings"]["base_gains"] == SOURCE
    assert doc["settings"]["gains_varied"] == ["pid.kd"]
    assert doc["parameters"][0]["base"] == expected["pid.kd"]  # sample 0: the base gains


def test_the_optimiser_and_the_sensitivity_study_record_their_base_gains(tuned):
    from railride.studies.optimise import optimise, sensitivity

    found = optimise(("pid.kd",), suspension="pid", scenario_options=SHORT, gains=tuned, popsize=2, maxiter=1, seed=1)
    doc = as_validated_json(found.to_dict(), "railride.optimise-1")
    expected = {"pid": _pid_values(**{"pid.kp": TUNED_KP})}
    _assert_tuned(doc["settings"], expected)
    assert doc["settings"]["base_gains"] == SOURCE
    assert doc["settings"]["gains_varied"] == ["pid.kd"]
    assert doc["gains"]["pid"]["kp"] == TUNED_KP  # the search left kp at the base gains'

    # two parameters: SciPy's indices take at least two
    indices = sensitivity(("pid.kd", "pid.ki"), suspension="pid", scenario_options=SHORT, gains=tuned, n=2)
    doc = as_validated_json(indices.to_dict(), "railride.sensitivity-1")
    _assert_tuned(doc["settings"], expected)
    assert doc["settings"]["gains_varied"] == ["pid.kd", "pid.ki"]


def test_the_optimised_gains_never_claim_to_be_the_shipped_file():
    from railride.studies.optimise import optimise

    found = optimise(("pid.kd",), suspension="pid", scenario_options=SHORT, popsize=2, maxiter=1, seed=1)
    doc = found.to_dict()
    assert doc["settings"]["gains"] == doc["settings"]["base_gains"] == "railride/data/gains.toml"
    assert doc["gains"]["pid"]["kd"] != packaged()["pid"]["kd"]  # the search moved it
    assert doc["gains"]["source"] == "railride/data/gains.toml, changed: pid.kd"


def test_the_tuned_alike_line_says_why_each_study_stopped():
    """A study with a budget of 5 runs cannot converge in a pass of 3 gains x 4 values: it stops
    by its budget, and the line printed with the gains says so."""
    from railride.cli._render import alike_text

    res = rr.tune(("pid",), scenario_options={"duration": 0.5}, n_values=3, budget=5, before_after=False)
    study = next(s for s in res.studies if s.controller == "pid")
    assert study.runs <= 5 and study.stopped == "budget"
    line = alike_text({"budget": 5, "runs": {"pid": 5}, "stopped": {"pid": "budget"}})
    assert line.endswith("(runs used: pid 5). The study stopped when its budget ran out, before it converged.")
    mixed = alike_text({"budget": 5, "runs": {"a": 5, "b": 3}, "stopped": {"a": "budget", "b": "converged"}})
    assert mixed.endswith("a stopped when its budget ran out, before it converged; b converged.")
