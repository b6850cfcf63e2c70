"""A tuning that lists laws driving the MR dampers through the tracking inner loop, but not the
inner loop itself, says so: its B and G stay at the start values (one warning, and the record)."""

import warnings

import pytest

import railride as rr
from railride.errors import TuningWarning
from railride.run import simulation
from railride.studies.tuning import _inner_left_out


class Started(Exception):
    pass


def _started(*args, **kwargs):
    raise Started


def test_laws_on_the_inner_loop_without_it_warn_before_any_run(monkeypatch):
    monkeypatch.setattr(simulation, "inputs", _started)
    with pytest.warns(TuningWarning, match=r"the MR dampers of skyhook, hybrid follow it; list 'inner'"):
        with pytest.raises(Started):
            rr.tune(["skyhook", "hybrid"], budget=20)


@pytest.mark.parametrize(
    ("controllers", "damper"),
    [(["inner", "skyhook"], "railway"), (["skyhook-on-off", "clipped-optimal"], "railway"), (["skyhook"], "ideal")],
)
def test_no_warning_where_nothing_is_left_untuned(monkeypatch, controllers, damper):
    gains = rr.GainSet.default()
    assert _inner_left_out(tuple(controllers), gains, damper) is None
    monkeypatch.setattr(simulation, "inputs", _started)
    with warnings.catch_warnings():
        warnings.simplefilter("error", TuningWarning)
        with pytest.raises(Started):
            rr.tune(controllers, budget=20, damper=damper)


def test_the_note_is_kept_with_the_result():
    text = _inner_left_out(("pid",), rr.GainSet.default(), "railway")
    assert text is not None and "the MR dampers of pid follow it" in text and "B = " in text and "G = " in text
