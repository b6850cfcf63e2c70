"""The JSON output schemas (docs/schemas/*.json, JSON Schema draft 2020-12): every schema name the
package writes has its file, and a real document of each, made by a short run through the library,
validates against it."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

jsonschema = pytest.importorskip("jsonschema")

import railride as rr  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCHEMAS = ROOT / "docs" / "schemas"
PACKAGE = ROOT / "railride"
#: ``SCHEMA = "railride.sweep/1"``, ``SCHEMA_DAMPER = ...``, and a document's literal ``"schema": "..."``
NAME = re.compile(r"""(?:\bSCHEMA\w*\s*=\s*|["']schema["']\s*:\s*)["'](railride\.[\w-]+/\d+)["']""")
SHORT = {"duration": 0.5}


def schema_path(name: str) -> Path:
    return SCHEMAS / f"{name.replace('/', '-')}.json"


def names_in_package() -> set[str]:
    return {m for path in PACKAGE.rglob("*.py") for m in NAME.findall(path.read_text(encoding="utf-8"))}


def check(doc: dict, name: str) -> None:
    """``doc`` as JSON would carry it validates against the schema of ``name``, which it names."""
    doc = json.loads(json.dumps(doc, default=str))
    assert doc["schema"] == name
    schema = json.loads(schema_path(name).read_text(encoding="utf-8"))
    jsonschema.validate(doc, schema, cls=jsonschema.Draft202012Validator)


def test_every_schema_name_in_the_package_has_its_file():
    names = names_in_package()
    assert len(names) >= 12, names
    missing = sorted(n for n in names if not schema_path(n).is_file())
    assert not missing, f"no schema file in docs/schemas for {missing}"


@pytest.mark.parametrize("path", sorted(SCHEMAS.glob("*.json")), ids=lambda p: p.stem)
def test_each_schema_file_is_a_valid_schema_that_names_its_document(path):
    schema = json.loads(path.read_text(encoding="utf-8"))
    jsonschema.Draft202012Validator.check_schema(schema)
    name = schema["title"]
    assert path.name == f"{name.replace('/', '-')}.json"
    assert schema["$id"] == path.name
    assert schema["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert schema["properties"]["schema"] == {"const": name}
    assert "schema" in schema["required"]
    assert name in names_in_package(), f"{name}: no producer in railride/"


def test_a_document_of_another_kind_or_with_a_key_missing_is_rejected():
    doc = rr.frequency_responses(points=8).to_dict()
    check(doc, "railride.frf/1")
    with pytest.raises(jsonschema.ValidationError):
        check({**doc, "unknown_key": 1}, "railride.frf/1")
    with pytest.raises(jsonschema.ValidationError):
        check({k: v for k, v in doc.items() if k != "modes"}, "railride.frf/1")


# -- a real document of each kind ------------------------------------------------------------------
def test_comparison():
    check(
        rr.compare(rr.scenario("paper-sine", duration=1.0), controllers=["pid"], bounds=False).to_dict(),
        "railride.comparison/1",
    )


def test_comparison_with_comfort_and_bounds():
    check(rr.compare(rr.scenario("paper-sine", duration=1.0), comfort=True).to_dict(), "railride.comparison/1")


def test_simulation():
    result = rr.simulate(rr.scenario("paper-sine", duration=0.5))
    check(result.to_dict(), "railride.simulation/1")
    controlled = rr.simulate(rr.scenario("fra4", duration=0.5), None, rr.Suspension.named("pid"))
    check(controlled.to_dict(comfort=True, vehicle={"vehicle_params_file": "car.toml"}), "railride.simulation/1")


def test_frf():
    check(rr.frequency_responses(points=64).to_dict(), "railride.frf/1")


def test_modes():
    from railride.frequency.frf import modes

    check(modes().to_dict(), "railride.modes/1")
    check(modes("crh380a", load=1.3).to_dict(), "railride.modes/1")  # ten modes: its carbody bends


def test_damper_and_tracking():
    from railride.run import rig

    check(rig.cycles("railway", 0.01, 2.0, [0.0, 2.25], n_cycles=2).to_dict(), "railride.damper/1")
    check(rig.track(n_cycles=2).to_dict(), "railride.tracking/1")


def test_league():
    from railride.studies.league import league

    table = league(["paper-sine", "fra4"], [30.0], track_seeds=[0], controllers=["pid"], duration=0.5)
    check(table.to_dict(), "railride.league/1")


def test_optimise_and_sensitivity():
    from railride.studies.optimise import optimise, sensitivity

    found = optimise(
        ("attitude.kd_z",), suspension="sas-attitude", scenario_options=SHORT, popsize=2, maxiter=1, seed=1
    )
    check(found.to_dict(), "railride.optimise/1")
    indices = sensitivity(("attitude.kd_z", "ride.kp_1R"), suspension="sas-attitude", scenario_options=SHORT, n=2)
    check(indices.to_dict(), "railride.sensitivity/1")


def test_pareto():
    check(rr.pareto("pid", n_samples=2, seed=3, scenario_options=SHORT).to_dict(), "railride.pareto/1")


def test_ride_spectrum():
    from railride.frequency.ride_spectrum import ride_spectrum

    doc = ride_spectrum("fra4", points=64, gains=rr.GainSet.default()).to_dict()
    assert "gains_mismatch" in doc["settings"]  # the paper set was tuned on paper-sine
    check(doc, "railride.ride-spectrum/1")
    robust = ride_spectrum("fra4", points=64).to_dict()  # the robust set, taken on random track
    assert robust["settings"]["gains_source"].endswith("robust_gains.toml")
    check(robust, "railride.ride-spectrum/1")
    check(ride_spectrum("fra4", points=64, controllers="passive").to_dict(), "railride.ride-spectrum/1")


def test_linear():
    from railride.frequency.linear import linear_model

    check(linear_model(None, rr.Suspension.named("pid", damper="ideal")).to_dict(), "railride.linear/1")


def test_study():
    result = rr.study(["pid"], loads=[1.0], faults=["none", "1R-off"], track_seeds=[0], speeds=[40.0], duration=0.5)
    check(result.to_dict(), "railride.study/1")


def test_design():
    result = rr.design(
        ["pid"],
        tracks=["fra4"],
        speeds=[40.0],
        loads=[1.0],
        train_seeds=[0],
        test_seeds=[1],
        duration=0.5,
        budget=13,
        values=3,
    )
    check(result.to_dict(), "railride.design/1")


def test_sweep_and_the_file_its_save_writes(tmp_path):
    from railride.studies.grid import grid

    result = rr.run_sweep(grid(["passive", "pid"], speed=[30.0], duration=0.5))
    check(result.to_dict(), "railride.sweep/1")
    facts = {"runs_evaluated": 2, "runs_per_second": 1.0, "wall_time_s": 2.0, "executor": None}
    result.save(tmp_path, extra=facts)
    check(json.loads((tmp_path / "sweep.json").read_text(encoding="utf-8")), "railride.sweep/1")


def test_tune():
    result = rr.tune(("pid",), scenario_options=SHORT, n_values=3, budget=5)
    check(result.to_dict(), "railride.tune/3")
