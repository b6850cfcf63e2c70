"""A command whose --out already holds files it did not write says so, in one line naming whose
results they are; a folder of its own, or its own earlier results, say nothing."""

from __future__ import annotations

import json

from clihelp import run

from railride.cli._folders import SCHEMA_COMMANDS, others_note

NOTE = "also holds"


def test_a_second_command_in_the_same_folder_says_whose_results_are_there(tmp_path):
    out = tmp_path / "run"
    first = run("compare", "--duration", 1, "--out", out)
    assert first.exit_code == 0, first.stderr
    assert NOTE not in first.stderr  # a new folder
    second = run("simulate", "--duration", 1, "--out", out)
    assert second.exit_code == 0, second.stderr
    lines = [line for line in second.stderr.splitlines() if NOTE in line]
    assert len(lines) == 1, second.stderr
    assert "the results of railride compare" in lines[0] and "compare.json" in lines[0]
    assert (out / "compare.json").exists()  # left as it was


def test_the_same_command_again_says_nothing(tmp_path):
    out = tmp_path / "run"
    for _ in range(2):
        result = run("simulate", "--duration", 1, "--out", out)
        assert result.exit_code == 0, result.stderr
        assert NOTE not in result.stderr


def test_the_note_tells_an_earlier_run_from_another_command(tmp_path):
    (tmp_path / "old.json").write_text(json.dumps({"schema": "railride.simulation/1"}))
    (tmp_path / "new.json").write_text(json.dumps({"schema": "railride.simulation/1"}))
    (tmp_path / "runs.csv").write_text("run\n")  # the run table --resume continues: not another's
    (tmp_path / ".hidden").write_text("")
    note = others_note(tmp_path, {"old.json", "runs.csv", ".hidden"} - {".hidden"}, [tmp_path / "new.json"])
    assert note is not None and "1 file(s)" in note and "an earlier run of railride simulate" in note
    assert others_note(tmp_path, {"runs.csv"}, [tmp_path / "new.json"]) is None
    (tmp_path / "notes.txt").write_text("mine")
    note = others_note(tmp_path, {"notes.txt"}, [tmp_path / "new.json"])
    assert note is not None and "not railride results" in note


def test_every_schema_the_package_writes_has_its_command():
    from pathlib import Path
    import re

    import railride

    root = Path(railride.__file__).parent
    written = set()
    for path in root.rglob("*.py"):
        written |= set(re.findall(r'"(railride\.[a-z-]+)/\d+"', path.read_text(encoding="utf-8")))
    assert written and written <= set(SCHEMA_COMMANDS), written - set(SCHEMA_COMMANDS)
