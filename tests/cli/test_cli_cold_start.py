"""The first run after install says on stderr, in one line, that it compiles the stepper; later
runs say nothing extra. numba's compile event is raised by hand (a real cold compile takes tens
of seconds)."""

from __future__ import annotations

import pytest
from numba.core import event

import railride.studies.comparison
from railride.engine import kernels
from clihelp import ok

RUN = ("compare", "--duration", 1, "--controllers", "pid", "--no-bounds")
NOTE = "compiling the stepper once, about 40 s; later runs start at once"


@pytest.fixture
def cold(monkeypatch):
    """compare as on a fresh install: numba starts compiling the stepper during the runs."""
    real = railride.studies.comparison.compare

    def compare(*args, **kwargs):
        with event.trigger_event("numba:compile", data=dict(dispatcher=kernels.run_batch, args=(), return_type=None)):
            pass
        return real(*args, **kwargs)

    monkeypatch.setattr(railride.studies.comparison, "compare", compare)


def test_first_run_says_it_compiles(cold):
    result = ok(*RUN)  # stderr is not a terminal here: no bar, the line still shows
    assert result.stderr.splitlines() == [NOTE]
    assert "PID" in result.stdout


def test_later_runs_say_nothing():
    result = ok(*RUN)
    assert "compiling" not in result.stderr
