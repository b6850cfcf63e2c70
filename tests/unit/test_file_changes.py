"""A track read from a file (a measured profile, file:PATH, or a spectrum table, psd:PATH) is
known by its values, not its path: a run table resumed after the file changed runs its runs
again, and gains tuned on the file say so when its values are no longer those they were tuned
on. A comment or another way of writing the same numbers changes nothing."""

from __future__ import annotations

import os

import numpy as np
import pytest

import railride as rr
from railride.model.irregularity import spectrum
from railride.secondary.control import GainSet
from railride.secondary.provenance import HELD_OUT, IN_SAMPLE, judged_on
from railride.studies.case import Case
from railride.studies.executors import RunTable
from railride.studies.sweep import run_cases
from railride.studies.tuning import tune

pytestmark = pytest.mark.filterwarnings("ignore::railride.errors.TuningWarning")  # the inner loop as it starts

S = np.arange(0.0, 200.0, 0.5)


def _profile(path, bump=0.0, comment=False):
    z = 0.004 * np.sin(2 * np.pi * S / 30.0)
    z[4] += bump  # at s = 2 m, which every run here crosses
    head = "# measured on the down line\n" if comment else ""
    # repr the first time, 17 significant digits the second: the same doubles, other text
    fmt = (lambda v: f"{float(v):.17g}") if comment else (lambda v: repr(float(v)))
    path.write_text(head + "s,z_L,z_R\n" + "".join(f"{fmt(a)},{fmt(b)},{fmt(0.9 * b)}\n" for a, b in zip(S, z)))
    _touch_later(path)
    return path


def _table(path, factor=1.0, comment=False):
    W = np.geomspace(2 * np.pi / 200, 2 * np.pi / 0.5, 60)
    rows = zip(W, factor * spectrum("fra4", W), spectrum("fra4", W, "cross-level"))
    head = "# fra4, tabulated\n" if comment else ""
    path.write_text(
        head
        + "wavenumber_rad_per_m,vertical,cross_level\n"
        + "".join(f"{float(w)!r},{float(v)!r},{float(x)!r}\n" for w, v, x in rows)
    )
    _touch_later(path)
    return path


def _touch_later(path):
    """A new modification time, as an edit some time later has (the files are read once per
    version, known by size and time; two writes within a clock tick would share one)."""
    stat = path.stat()
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9 + (hash(path.read_text()) % 10**6)))


@pytest.mark.parametrize("kind", ["file", "psd"])
def test_a_run_key_holds_the_files_values_not_its_path(tmp_path, kind):
    path = tmp_path / "line.csv"
    write = _profile if kind == "file" else _table
    write(path)
    name = f"{kind}:{path}"
    first = Case(name, {"duration": 0.2}, suspension="passive").key
    write(path, comment=True)  # the same values written otherwise
    assert Case(name, {"duration": 0.2}, suspension="passive").key == first
    write(path, **({"bump": 1e-3} if kind == "file" else {"factor": 2.0}))
    assert Case(name, {"duration": 0.2}, suspension="passive").key != first
    # a track of settings alone keys as before (no file, nothing added)
    assert "scenario_sha256" not in Case("fra4", {"seed": 1}).to_dict()


def test_a_resumed_run_table_runs_again_the_runs_of_a_changed_profile(tmp_path):
    path = _profile(tmp_path / "line.csv")

    def cases():  # made afresh, as a resumed study makes them (a case keeps its key once made)
        return [Case(f"file:{path}", {"duration": 0.2, "speed": v}, suspension="passive") for v in (30.0, 40.0)]

    table_path = tmp_path / "runs.csv"
    with RunTable(table_path) as table:
        before = run_cases(cases(), table=table)
    with RunTable(table_path, resume=True) as table:
        assert len(run_cases(cases(), table=table)) == 2 and len(table.done()) == 2  # nothing run again
    _profile(path, bump=0.01)  # a 10 mm step at s = 2 m
    with RunTable(table_path, resume=True) as table:
        after = run_cases(cases(), table=table)
        assert len(table.done()) == 4  # both runs again, beside the old file's
    for column in ("acceleration_m_s2_rms", "displacement_m_rms"):
        assert np.all(after[column].to_numpy() != before[column].to_numpy()), column


@pytest.fixture(scope="module")
def tuned_on_a_profile(tmp_path_factory):
    path = _profile(tmp_path_factory.mktemp("line") / "line.csv")
    res = tune(["pid"], budget=5, n_values=3, scenario=f"file:{path}", scenario_options={"duration": 0.5})
    return path, GainSet.from_toml(res.gains_toml(command="railride tune"), source="tuned.toml")


def test_gains_tuned_on_a_profile_that_changed_say_so(tuned_on_a_profile):
    path, gains = tuned_on_a_profile
    same = rr.scenario(f"file:{path}", duration=0.5).describe()
    assert gains.mismatch(None, same) is None
    assert judged_on(gains, same)[0] == IN_SAMPLE
    _profile(path, bump=1e-3)
    changed = rr.scenario(f"file:{path}", duration=0.5).describe()
    assert changed["profile_sha256"] != same["profile_sha256"]
    line = gains.mismatch(None, changed)
    assert line is not None and "(the measured profile changed since tuning)" in line
    kind, sentence = judged_on(gains, changed)
    assert kind == HELD_OUT and "changed since the gains were tuned on it" in sentence
    # gains tuned before profiles recorded their values are matched by path, as they were
    old = {k: v for k, v in changed.items() if k != "profile_sha256"}
    text = gains.to_toml().replace(f', profile_sha256 = "{same["profile_sha256"]}"', "")
    assert "profile_sha256" not in text
    assert judged_on(GainSet.from_toml(text), old)[0] == IN_SAMPLE
    assert judged_on(GainSet.from_toml(text), changed)[0] == IN_SAMPLE
    _profile(path)  # as tuned: the module's other tests see the file the gains were tuned on


def test_gains_tuned_on_a_spectrum_table_that_changed_say_so(tmp_path):
    path = _table(tmp_path / "line.csv")
    name = f"psd:{path}"
    res = tune(["pid"], budget=5, n_values=3, scenario=name, scenario_options={"duration": 0.5, "seed": 2})
    gains = GainSet.from_toml(res.gains_toml(command="railride tune"), source="tuned.toml")
    assert gains.mismatch(None, rr.scenario(name, duration=0.5, seed=2).describe()) is None
    _table(path, factor=2.0)
    line = gains.mismatch(None, rr.scenario(name, duration=0.5, seed=2).describe())
    assert line is not None and "(the spectrum table changed since tuning)" in line


def test_a_robust_tuning_on_a_spectrum_table_does_not_cover_the_table_edited(tmp_path):
    """Seeds 0 and 1 of a table cover any seed of it at the tuned speed, but not of the table
    with other values at the same path."""
    from railride.studies.tuning import tuning_set

    path = _table(tmp_path / "line.csv")
    name = f"psd:{path}"
    over = tuning_set(name, track_seeds=[0, 1], duration=0.5)
    res = tune(["pid"], over=over, budget=5, n_values=3)
    gains = GainSet.from_toml(res.gains_toml(), source="robust.toml")
    assert gains.mismatch(None, rr.scenario(name, duration=0.5, seed=7).describe()) is None
    copy = tmp_path / "copy.csv"  # the same values at another path: the same spectrum
    copy.write_bytes(path.read_bytes())
    assert gains.mismatch(None, rr.scenario(f"psd:{copy}", duration=0.5, seed=7).describe()) is None
    _table(path, factor=2.0)
    line = gains.mismatch(None, rr.scenario(name, duration=0.5, seed=7).describe())
    assert line is not None and "the spectrum table changed since tuning" in line


def test_a_profile_named_by_another_path_is_the_profile_the_gains_were_tuned_on(tuned_on_a_profile, tmp_path):
    """The same values read by another path (a relative and an absolute path, or a copy) are the
    same rail: in-sample, no mismatch; other values at another path are another line."""
    import shutil

    path, gains = tuned_on_a_profile
    copy = tmp_path / "elsewhere.csv"
    shutil.copy(path, copy)
    record = rr.scenario(f"file:{copy}", duration=0.5).describe()
    assert judged_on(gains, record)[0] == IN_SAMPLE
    assert gains.mismatch(None, record) is None
    _profile(copy, bump=1e-3)
    other = rr.scenario(f"file:{copy}", duration=0.5).describe()
    assert judged_on(gains, other)[0] == HELD_OUT
    assert f"track file:{copy}" in gains.mismatch(None, other)


def test_a_league_on_a_measured_profile_names_no_seeds_and_what_the_gains_were_tuned_on(tuned_on_a_profile):
    from clihelp import ok

    path, _ = tuned_on_a_profile
    result = ok("compare", "--scenario", f"file:{path}", "--speed", "20,30", "--duration", 0.3, "--controllers", "pid")
    text = " ".join(result.stdout.split())
    assert f"Mean over 2 cases: file:{path} at 20, 30 m/s." in text, text
    assert "random tracks" not in text
    assert "Gains tuned on: fra4, fra5 (seeds 1, 2, 3) at 30, 50, 70 m/s." in text  # the robust set, whole
