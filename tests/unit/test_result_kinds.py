"""One name, one kind across the results (docs/architecture.md, the result protocol): a name
that two result types share is data on both (a field or a property, read as ``result.summary``)
or a method on both (called, ``result.by_speed()``), never a field on one and a method on the
other. The result types are found by scanning the package for classes with ``to_pandas``."""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import pkgutil
from collections import defaultdict
from functools import cached_property

import railride

#: names of two kinds, each on purpose (docs/architecture.md): `RideResult.metrics(window=)`
#: and `RideResult.comfort(window=, positions=, weightings=)` compute with options, as
#: `Tracking.metrics()` does, while a `Comparison` holds both computed for every controller
#: and `SweepResult.comfort` says whether its rows hold comfort
TWO_KINDS = {"metrics", "comfort"}


def _result_types() -> list[type]:
    found = []
    for info in pkgutil.walk_packages(railride.__path__, "railride."):
        if info.name.startswith(("railride.cli", "railride.__main__")):
            continue  # the command line holds no result type
        module = importlib.import_module(info.name)
        for value in vars(module).values():
            if inspect.isclass(value) and value.__module__ == info.name and "to_pandas" in vars(value):
                found.append(value)
    return found


def _kinds() -> dict[str, dict[str, str]]:
    """Per public name, per result type: "data" or "method"."""
    out: dict[str, dict[str, str]] = defaultdict(dict)
    for kind in _result_types():
        fields = {f.name for f in dataclasses.fields(kind)} if dataclasses.is_dataclass(kind) else set()
        names = fields | {n for n in dir(kind) if not n.startswith("_")}
        for name in names:
            value = inspect.getattr_static(kind, name, None)
            data = name in fields or isinstance(value, (property, cached_property)) or not callable(value)
            if isinstance(value, (classmethod, staticmethod)):
                data = False
            out[name][f"{kind.__module__}.{kind.__qualname__}"] = "data" if data else "method"
    return out


def test_the_scan_finds_the_result_types():
    names = {k.__qualname__ for k in _result_types()}
    assert {"StudyResult", "LeagueTable", "DesignResult", "SweepResult", "Comparison", "RideResult"} <= names


def test_a_name_two_results_share_is_of_one_kind():
    mixed = {name: by_type for name, by_type in _kinds().items() if len(set(by_type.values())) > 1}
    assert set(mixed) <= TWO_KINDS, {n: mixed[n] for n in set(mixed) - TWO_KINDS}


def test_the_tables_and_settings_of_the_results_are_data():
    kinds = _kinds()
    for name in ("summary", "settings", "cases", "ranking"):
        assert set(kinds[name].values()) == {"data"}, (name, kinds[name])
