"""`ProcessExecutor`: a study's chunks on worker processes give the rows the local executor gives,
and the command line takes --processes N."""

import pytest
from clihelp import assert_input_error, ok_json, run

from railride.studies.executors import ProcessExecutor
from railride.studies.study import study


def test_worker_processes_give_the_rows_of_the_local_executor():
    kw = dict(track_seeds=[0, 1], speeds=[30.0, 50.0], loads=[1.0], faults=["none"], duration=1.0)
    local = study(["pid", "skyhook"], **kw)
    pool = ProcessExecutor(2)
    try:
        apart = study(["pid", "skyhook"], executor=pool, **kw)
    finally:
        pool.close()
    # each run is computed alike in its chunk, whichever process: the same numbers, bit for bit
    assert local.to_pandas().equals(apart.to_pandas())


def test_processes_on_the_command_line():
    doc = ok_json("study", "--processes", "2", "--duration", "1", "--track-seed", "0", "--controllers", "pid")
    assert doc["executor"] == {"type": "processes", "processes": 2}
    assert_input_error(run("study", "--processes", "0"), "--processes = 0", ">= 1")
    assert_input_error(run("study", "--processes", "2", "--workers", "1"), "--processes with --workers")


@pytest.mark.parametrize("command", ["sweep", "tune", "pareto", "design"])
def test_every_study_command_takes_processes(command):
    assert_input_error(run(command, "--processes", "-1"), "--processes = -1")
