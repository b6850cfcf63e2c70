"""Lists on the command line: a name beside "all" is still checked, a range of one value keeps
its STOP, a value given twice is said, and a range's step that is not whole shows why."""

from __future__ import annotations

import pytest

from clihelp import assert_input_error, run

from railride.cli._parsing import value_list
from railride.errors import InputError


@pytest.mark.parametrize("command", ["compare", "tune", "study", "design"])
@pytest.mark.parametrize("controllers", ["all,foo", "foo,all"])
def test_an_unknown_controller_beside_all_is_refused_by_name(command, controllers, tmp_path):
    extra = ("--out", str(tmp_path / "d")) if command == "design" else ()
    assert_input_error(run(command, "--controllers", controllers, *extra), "--controllers", "'foo'")


def test_a_range_of_one_value_from_start_to_another_stop_is_refused():
    with pytest.raises(InputError, match=r"--speed = '10:20:1': COUNT = 1 gives START alone"):
        value_list("--speed", "10:20:1")
    assert value_list("--speed", "10:10:1") == [10.0]  # one value, START = STOP: nothing dropped
    assert value_list("--speed", "10:20:2") == [10.0, 20.0]


def test_a_step_that_is_not_whole_is_said_exactly():
    # (100000 - 0) / 99999 = 1.00001: four digits showed it as "1"; the step is said exactly
    with pytest.raises(InputError, match=r"the step \(STOP - START\) / \(COUNT - 1\) = 100000/99999 is not"):
        value_list("--track-seed", "0:100000:100000", integer=True)
    assert value_list("--track-seed", "0:10:6", integer=True) == [0, 2, 4, 6, 8, 10]


@pytest.mark.parametrize(
    ("args", "fragments"),
    [
        (("study", "--fault", "none,none"), ("--fault = none", "twice")),
        (("study", "--fault", "1R-off,none,1R-off"), ("--fault = 1R-off", "twice")),
        (("design", "--track", "fra4,fra4"), ("--track", "'fra4' is listed twice")),
        (("design", "--controllers", "pid,pid"), ("--controllers", "'pid' is listed twice")),
    ],
)
def test_a_name_given_twice_is_refused(args, fragments, tmp_path):
    extra = ("--out", str(tmp_path / "d")) if args[0] == "design" else ()
    assert_input_error(run(*args, *extra), *fragments)
