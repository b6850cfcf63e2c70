"""What the tests of the gains records share (test_study_gains_record, test_results_gains_record):
a tuning's [provenance], a GainSet that such a tuning found, the packaged gains files as TOML
reads them without railride, and the check of a document against its JSON schema."""

from __future__ import annotations

import dataclasses
import json
import tomllib
from importlib import resources
from pathlib import Path

from railride.secondary.control import GainSet

SCHEMAS = Path(__file__).resolve().parents[2] / "docs" / "schemas"
#: the [provenance] of a tuning, as `railride tune` writes one (its date as text, as JSON holds it)
PROVENANCE = {
    "method": "railride tune (one-at-a-time sensitivity study, equal budget per law)",
    "date": "2026-11-26T10:00:00Z",
    "objective": "mean of the four RMS ratios to passive",
    "controllers": ["pid"],
    "budget": 5,
    "start_gains": "railride/data/gains.toml",
}
#: the value the "tuning" changed
TUNED_KP = 123456.5


def tuned_gains(source: str) -> GainSet:
    """The shipped gains with pid.kp changed to `TUNED_KP`, named ``source``, and a provenance
    that says a tuning found them."""
    changed = GainSet.default().apply({"pid.kp": TUNED_KP})
    assert changed.value("pid.kp") == TUNED_KP
    return dataclasses.replace(changed, source=source, provenance=PROVENANCE)


def packaged(name: str = "gains.toml") -> dict:
    """A packaged gains file (railride/data/NAME) as TOML reads it, without railride."""
    return tomllib.loads(resources.files("railride").joinpath(f"data/{name}").read_text(encoding="utf-8"))


def pid_values(data: dict, **changes) -> dict:
    """What the PID law reads of a gains file's tables (the inner loop and [pid]), with ``changes``."""
    values = {f"inner.{k}": float(v) for k, v in data["inner"].items()}
    values.update({f"pid.{k}": float(v) for k, v in data["pid"].items()})
    return {**values, **changes}


def as_validated_json(doc: dict, name: str) -> dict:
    """``doc`` as its JSON file holds it, after checking it against docs/schemas/NAME.json."""
    import jsonschema

    doc = json.loads(json.dumps(doc, allow_nan=False))
    schema = json.loads((SCHEMAS / f"{name}.json").read_text(encoding="utf-8"))
    jsonschema.validate(doc, schema, cls=jsonschema.Draft202012Validator)
    return doc
