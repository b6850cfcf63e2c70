"""Regression tests from a hostile-user audit of the command line: inputs that once ran with
another meaning, or failed only after the work."""

import pytest
from clihelp import assert_input_error, run


@pytest.mark.parametrize(
    "command",
    [
        ("study",),
        ("sweep", "--suspension", "passive", "--speed", "30"),
        ("tune", "--controllers", "pid"),
        ("design",),
        ("pareto",),
        ("simulate",),
        ("compare",),
    ],
    ids=lambda c: c[0],
)
def test_duration_0_is_refused_everywhere(command):
    # study once ran its default 10 s and recorded 0
    assert_input_error(run(*command, "--duration", "0"), "duration = 0.0", "> 0")
