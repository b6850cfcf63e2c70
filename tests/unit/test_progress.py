"""Long library calls show their progress unless told not to: True (the default) shows it on
stderr after a delay, False says nothing, a callable receives the numbers."""

from __future__ import annotations

import io

import pytest

import railride as rr
from railride.errors import InputError
from railride.studies import progress as prog


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_resolve_maps_the_three_kinds():
    assert prog.resolve(False, "x") is None and prog.resolve(None, "x") is None
    mine = lambda *a: None  # noqa: E731
    assert prog.resolve(mine, "x") is mine
    assert isinstance(prog.resolve(True, "x"), prog.Shown)
    with pytest.raises(InputError, match="progress = 'yes'"):
        prog.resolve("yes", "x")


def test_a_short_call_says_nothing_and_a_long_one_a_line_now_and_then():
    clock, out = Clock(), io.StringIO()
    shown = prog.Shown("tuning", clock=clock, stream=out)
    shown(0, 40, 0.0)
    clock.t = prog.DELAY / 2
    shown(10, 40, 12.0)
    assert out.getvalue() == ""  # within the delay: silent
    clock.t = prog.DELAY + 0.1
    shown(20, 40, 12.5)
    assert out.getvalue() == "tuning: 20/40 runs, 12.5 runs/s (2 s)\n"
    clock.t += prog.EVERY / 2
    shown(30, 40, 12.5)
    assert out.getvalue().count("\n") == 1  # not before EVERY seconds
    clock.t += prog.EVERY
    shown(40, 40, 12.5)
    assert out.getvalue().splitlines()[-1].startswith("tuning: 40/40 runs")


def test_a_fraction_is_shown_in_percent():
    clock, out = Clock(), io.StringIO()
    shown = prog.Shown("compare", fraction=True, clock=clock, stream=out)
    clock.t = prog.DELAY
    shown(0.25)
    assert out.getvalue().startswith("compare: 25/100 %")


SC = rr.scenario("paper-sine", duration=0.5)


def test_a_study_shows_progress_by_default_and_not_when_told(monkeypatch, capsys):
    monkeypatch.setattr(prog, "DELAY", 0.0)
    rr.compare(SC, bounds=False)
    assert "compare:" in capsys.readouterr().err
    rr.compare(SC, bounds=False, progress=False)
    assert capsys.readouterr().err == ""
    seen = []
    rr.compare(SC, bounds=False, progress=seen.append)
    assert seen and seen[-1] == pytest.approx(1.0) and capsys.readouterr().err == ""


def test_every_long_call_takes_progress_and_shows_it_by_default():
    import inspect

    from railride.studies.league import league

    for f in (rr.compare, rr.design, rr.tune, rr.study, rr.pareto, rr.run_sweep, league):
        assert inspect.signature(f).parameters["progress"].default is True, f.__name__


def test_a_warning_inside_a_wrapped_study_points_at_the_callers_line():
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rr.tune(("pid",), scenario_options={"duration": 0.3}, n_values=3, budget=5, before_after=False)
    tuning = [w for w in caught if issubclass(w.category, rr.errors.TuningWarning)]
    assert tuning and all(w.filename == __file__ for w in tuning), [(w.filename, w.lineno) for w in tuning]


def test_ctrl_c_between_chunks_stops_the_run_with_what_it_has(monkeypatch):
    """A Ctrl-C that comes while the progress of a finished chunk is reported (before the next
    chunk starts) is a request to stop, as one during a chunk is: the run ends with its finished
    chunks (`Interrupted` holding them), not with a bare KeyboardInterrupt that loses them. Seen
    in CI: a Ctrl-C sent on the first progress line had come just before the second chunk."""
    import os
    import signal

    from railride.errors import Interrupted
    from railride.run import simulation

    if signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        pytest.skip("Python's own Ctrl-C handler is not in place here (the stop request is off then)")
    monkeypatch.setattr(simulation, "_CHUNK_WORK", 50)  # short chunks: 50 steps, then at most 4x the last
    calls = []

    def report(fraction):
        calls.append(fraction)
        if len(calls) == 2:  # between the second chunk and the third
            os.kill(os.getpid(), signal.SIGINT)

    try:
        rr.simulate(rr.scenario("paper-sine", duration=0.2), suspension=rr.Suspension.named("skyhook"), progress=report)
    except Interrupted as exc:
        stopped = exc
    except KeyboardInterrupt:  # caught here: left alone it would end the whole test session
        pytest.fail("a bare KeyboardInterrupt: the finished chunks were lost")
    else:
        pytest.fail("the run was not stopped")
    assert 0.0 < stopped.until < 0.2 and stopped.result is not None
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler  # given back
