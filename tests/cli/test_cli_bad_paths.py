"""Every check before any work: a command told to write where it cannot (an output folder under a
regular file, or in /proc, where nothing can be created) exits 2 with one line naming the option,
before it runs anything. "Before" is shown by the work itself: the engine's stages are replaced by
ones that fail the test if called (no timings; the settings are small so that a command that did
start would still end soon)."""

from __future__ import annotations

import pytest

from clihelp import assert_input_error, run

SHORT = ("--duration", "0.2", "--dt", "1e-3")
STORED = (*SHORT, "--output-rate", "100")

#: each command that writes files, on a tiny case: (its words, its options that name a place
#: to write and what each names: a folder, an HTML file, a model file)
WRITERS = {
    "simulate": (("simulate", *STORED), {"--out": "dir"}),
    "compare": (
        ("compare", *STORED, "--control-rate", "100", "--controllers", "pid"),
        {"--out": "dir", "--report": "html"},
    ),
    "report": (("report", *STORED, "--control-rate", "100", "--controllers", "pid"), {"--out": "html"}),
    "frf": (("frf", "--points", "16"), {"--out": "dir"}),
    "damper": (
        ("damper", "--cycles", "2", "--amplitude", "0.01", "--frequency", "2", "--voltage", "0"),
        {"--out": "dir"},
    ),
    "tracking": (("tracking", "--cycles", "2"), {"--out": "dir"}),
    "tune": (
        ("tune", *SHORT, "--controllers", "pid", "--values", "3", "--budget", "8", "--workers", "1"),
        {"--out": "dir", "--report": "html"},
    ),
    "pareto": (("pareto", *SHORT, "--samples", "4", "--workers", "1"), {"--out": "dir"}),
    "sweep": (("sweep", *SHORT, "--speed", "40,50", "--workers", "1"), {"--out": "dir", "--report": "html"}),
    "study": (
        ("study", *SHORT, "--track-seed", "0,1", "--controllers", "pid", "--workers", "1"),
        {"--out": "dir", "--report": "html"},
    ),
    "design": (
        (
            "design --controllers pid --track fra4 --speed 40 --load 1 --train-seeds 1 --test-seeds 2 "
            "--duration 0.2 --dt 1e-3 --budget 13 --values 3 --workers 1"
        ).split(),
        {"--out": "dir", "--report": "html"},
    ),
    "ride-spectrum": (
        ("ride-spectrum", "--points", "32", "--controllers", "passive"),
        {"--out": "dir", "--report": "html"},
    ),
    "state-space": (("state-space",), {"--out": "model"}),
    "fmu": (("fmu", "--damper", "passive"), {"--out": "fmu"}),
}

#: what each kind of place is called at the bad locations
NAMES = {"dir": "out", "html": "page.html", "model": "model.json", "fmu": "model.fmu"}


#: the modules that take the stages below by name when first imported: imported before the
#: stages are replaced, so that none keeps a replaced one after the test
USERS = (
    "railride.cli",
    "railride.engine.lanes",
    "railride.run.reduced",  # a sweep's metrics-only batches import it when they first run
    "railride.frequency.fmu",
    "railride.frequency.frf",
    "railride.frequency.ride_spectrum",
    "railride.run.rig",
    "railride.studies.comparison",
    "railride.studies.design",
    "railride.studies.pareto",
    "railride.studies.study",
    "railride.studies.sweep",
    "railride.studies.tuning",
)

#: (module, name) of each stage of work: the engine's stages and its entry points (also where a
#: module holds them under its own name), the damper rig's stepper, the frequency-domain models
#: and the FMU's build
STAGES = (
    ("railride.run.simulation", "inputs"),
    ("railride.run.simulation", "pack"),
    ("railride.run.simulation", "step"),
    ("railride.run.simulation", "run"),
    ("railride.run.simulation", "simulate"),
    ("railride.studies.comparison", "run_plan"),
    ("railride.studies.comparison", "simulate"),
    ("railride.engine.kernels", "run_parallel"),
    ("railride.frequency.frf", "frequency_responses"),
    ("railride.frequency.ride_spectrum", "ride_spectrum"),
    ("railride.frequency.ride_spectrum", "linear_model"),
    ("railride.frequency.linear", "linear_model"),
    ("railride.frequency.fmu", "_variables"),
    ("railride.frequency.fmu", "_build"),
)


@pytest.fixture
def no_work(monkeypatch):
    """Every stage of work fails the test if a command reaches it."""
    import importlib

    for module in USERS:
        importlib.import_module(module)

    def started(*args, **kwargs):
        raise AssertionError("work started")

    for module, name in STAGES:
        monkeypatch.setattr(importlib.import_module(module), name, started)


def _places(tmp_path, kind: str) -> dict[str, str]:
    """Bad places of ``kind``: under a regular file, in /proc (no folder can be created there)."""
    blocker = tmp_path / "file"
    blocker.write_text("a regular file\n")
    places = {"under a file": str(blocker / "sub" / NAMES[kind]), "in /proc": f"/proc/railride-x/{NAMES[kind]}"}
    if kind == "dir":
        places["a file"] = str(blocker)
    return places


WHERE = ("under a file", "in /proc", "a file")
CASES = [
    (name, option, where)
    for name, (_, options) in WRITERS.items()
    for option, kind in options.items()
    for where in WHERE
    if kind == "dir" or where != "a file"
]


@pytest.mark.parametrize("name, option, where", CASES, ids=[" ".join(case) for case in CASES])
def test_a_bad_place_to_write_is_refused_before_any_work(tmp_path, no_work, name, option, where):
    words, options = WRITERS[name]
    place = _places(tmp_path, options[option])[where]
    result = run(*words, option, place)
    assert_input_error(result, f"{option} = {place!r}")
    assert not (tmp_path / "file").is_dir()


def test_a_missing_folder_is_a_good_place_and_the_check_leaves_no_trace(tmp_path):
    # the writers make the missing folders on the way: only the nearest existing one is tried
    from railride.output.files import check_model_path, check_out_dir
    from railride.output.report import check_report_path

    check_out_dir(tmp_path / "new" / "out", "--out")
    check_out_dir(tmp_path, "--out")  # an existing folder: tried inside too
    check_report_path(tmp_path / "new" / "sub" / "page.html", "--report")
    check_model_path(tmp_path / "new" / "model.mat", "--out")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name", WRITERS)
def test_the_stages_replaced_are_the_work_of_each_command(tmp_path, no_work, name):
    # the control of the test above: with a good place, each command reaches a replaced stage
    words, options = WRITERS[name]
    result = run(*words, *(w for option, kind in options.items() for w in (option, tmp_path / NAMES[kind])))
    assert result.exit_code == 1 and "AssertionError: work started" in result.stderr, result.stderr
