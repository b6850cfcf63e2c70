"""The public API given values of the wrong type, or numbers at the ends of their range, one
argument at a time: every outcome is an `InputError` naming the argument, raised before any
vehicle is stepped, or a result. Never an AttributeError, TypeError or KeyError from deep inside.

The engine's first stage is replaced by one that raises `WorkStarted`, so that an argument that
passes every check costs nothing here, and one that is only checked once the runs have begun is
found: a value of the wrong type must be refused before that."""

import inspect
import math

import pytest

import railride as rr
from railride.errors import InputError
from railride.run import simulation


class WorkStarted(Exception):
    """The checks passed: the first run's inputs stage began."""


def _work(*args, **kwargs):
    raise WorkStarted


# cheap base calls: every other argument at a value that passes
SHORT = {"duration": 0.5}
CALLS = {
    "simulate": (rr.simulate, {"scenario": "paper-sine"}),
    "compare": (rr.compare, {"scenario": "paper-sine", "controllers": ("passive", "pid")}),
    "study": (rr.study, {"controllers": ("passive",), "track_seeds": (1,), "speeds": (40.0,), **SHORT}),
    "tune": (rr.tune, {"controllers": ("pid",), "budget": 20, "before_after": False}),
    "pareto": (rr.pareto, {"n_samples": 4}),
    "design": (rr.design, {"controllers": ("pid",), "budget": 20, "speeds": (40.0,), "loads": (1.0,), **SHORT}),
    "frequency_responses": (rr.frequency_responses, {"points": 20}),
    "scenario": (rr.scenario, {}),
    "SolverSettings": (rr.SolverSettings, {}),
    "Objective": (rr.Objective, {}),
    "Suspension.named": (rr.Suspension.named, {"name": "pid"}),
    "Suspension.semi_active": (rr.Suspension.semi_active, {}),
    "Vehicle": (rr.Vehicle, {}),
}
# arguments that take code or machinery, not values
SKIPPED = {"progress", "log", "executor", "table"}
# no argument of the API takes these: each must be refused before any work
GARBAGE = [object(), [object()], {"x": object()}, b"bytes", 1j]
# numbers at the ends of the range: refused, or taken (a result, or the checks passed)
NUMBERS = [math.nan, -math.inf, 1e308, 1e-308, -1, 0, True, 10**400]


def _arguments():
    for call, (fn, base) in CALLS.items():
        for name, p in inspect.signature(fn).parameters.items():
            if name in SKIPPED or name == "self" or p.kind in (p.VAR_POSITIONAL, p.VAR_KEYWORD):
                continue
            yield call, name


ARGUMENTS = list(_arguments())


def _outcome(call: str, name: str, value, monkeypatch):
    fn, base = CALLS[call]
    monkeypatch.setattr(simulation, "inputs", _work)
    kwargs = {**base, name: value}
    try:
        fn(**kwargs)
    except InputError as exc:
        return "refused", str(exc)
    except WorkStarted:
        return "started", ""
    return "result", ""


def test_every_public_call_has_arguments_to_try():
    assert len(ARGUMENTS) > 80 and {c for c, _ in ARGUMENTS} == set(CALLS)


@pytest.mark.parametrize(("call", "name"), ARGUMENTS, ids=[f"{c}-{n}" for c, n in ARGUMENTS])
def test_a_value_of_no_type_the_api_takes_is_refused_before_any_work(call, name, monkeypatch):
    for value in GARBAGE:
        kind, message = _outcome(call, name, value, monkeypatch)
        assert kind == "refused", f"{call}({name}={value!r}) was not refused: {kind}"
        assert message.strip() and "\n" not in message.strip(), message


@pytest.mark.parametrize(("call", "name"), ARGUMENTS, ids=[f"{c}-{n}" for c, n in ARGUMENTS])
def test_numbers_at_the_ends_of_the_range_are_refused_or_taken_never_a_crash(call, name, monkeypatch):
    for value in NUMBERS:
        kind, message = _outcome(call, name, value, monkeypatch)
        assert kind in ("refused", "started", "result")
        if kind == "refused":
            assert message.strip() and "\n" not in message.strip(), message
