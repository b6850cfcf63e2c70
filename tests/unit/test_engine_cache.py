"""railride.engine.cache_guard: numba's cache of the engine is cleared when any engine source
changed (numba itself sees only the file that defines a kernel), and kept when none did."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys

import pytest

from railride.engine import cache_guard

#: numba's names for cached kernels of the engine, and files that are not the engine's
ENGINE_FILES = (
    "kernels.run_batch-350.py311.nbi",
    "kernels.run_batch-350.py311.1.nbc",
    "lanes.run_lanes-120.py311.nbi",
    "lanes.run_lanes-120.py311.1.nbc",
)
OTHERS = ("kernels.cpython-311.pyc", "elsewhere.f-1.py311.nbi")


@pytest.fixture
def engine(tmp_path):
    """A copy of the engine's sources and a cache folder with machine code in it."""
    src = tmp_path / "engine"
    shutil.copytree(cache_guard.ENGINE_DIR, src, ignore=shutil.ignore_patterns("__pycache__"))
    cache = tmp_path / "cache"
    _fill(cache)
    return src, cache


def _fill(cache):
    cache.mkdir(exist_ok=True)
    for name in ENGINE_FILES + OTHERS:
        (cache / name).write_bytes(b"machine code")


def _left(cache) -> set[str]:
    return {p.name for p in cache.iterdir()}


def test_a_stale_marker_clears_the_engines_machine_code(engine):
    src, cache = engine
    (cache / cache_guard.MARKER).write_text("0" * 64 + "\n")
    assert cache_guard.guard(str(src), str(cache)) == "cleared"
    assert _left(cache) == set(OTHERS) | {cache_guard.MARKER}
    assert (cache / cache_guard.MARKER).read_text().strip() == cache_guard.sources_hash(str(src))


def test_a_matching_marker_keeps_it(engine):
    src, cache = engine
    (cache / cache_guard.MARKER).write_text(cache_guard.sources_hash(str(src)) + "\n")
    assert cache_guard.guard(str(src), str(cache)) == "kept"
    assert _left(cache) == set(ENGINE_FILES + OTHERS) | {cache_guard.MARKER}


def test_an_edit_to_any_engine_file_clears_it(engine):
    src, cache = engine
    cache_guard.guard(str(src), str(cache))  # no marker yet: cleared, the hash stored
    _fill(cache)
    assert cache_guard.guard(str(src), str(cache)) == "kept"
    with open(src / "_simd.py", "a") as f:  # inlined into kernels.py: numba would not notice
        f.write("# an edit\n")
    assert cache_guard.guard(str(src), str(cache)) == "cleared"
    assert not set(ENGINE_FILES) & _left(cache)


def test_a_new_cache_folder_gets_the_hash_first(tmp_path):
    # the first process stores the hash before numba fills the folder, so the second keeps it
    cache = tmp_path / "new" / "__pycache__"
    assert cache_guard.guard(cache=str(cache)) == "cleared"
    _fill(cache)
    assert cache_guard.guard(cache=str(cache)) == "kept"


def test_an_unusable_cache_folder_is_no_error(tmp_path):
    blocked = tmp_path / "a-file"
    blocked.write_text("not a folder")
    assert cache_guard.guard(cache=str(blocked / "__pycache__")) == "skipped"


def test_the_cache_folder_follows_numba(monkeypatch, tmp_path):
    from numba.core import config

    monkeypatch.setattr(config, "CACHE_DIR", "")
    assert cache_guard.cache_dir() == os.path.join(cache_guard.ENGINE_DIR, "__pycache__")
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))
    assert os.path.dirname(cache_guard.cache_dir()) == str(tmp_path)


def _python(code: str, cache_root) -> str:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache_root))
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout


def test_importing_the_kernels_runs_the_guard(tmp_path):
    # numba's folder for the engine under NUMBA_CACHE_DIR, as a fresh process sees it
    folder = _python("from railride.engine import cache_guard; print(cache_guard.cache_dir())", tmp_path).strip()
    cache = tmp_path / os.path.basename(folder)
    assert str(cache) == folder
    _fill(cache)
    (cache / cache_guard.MARKER).write_text("stale\n")
    _python("import railride.engine.kernels", tmp_path)
    assert _left(cache) == set(OTHERS) | {cache_guard.MARKER}
    assert (cache / cache_guard.MARKER).read_text().strip() == cache_guard.sources_hash()
    _fill(cache)
    _python("import railride.engine.lanes", tmp_path)
    assert _left(cache) == set(ENGINE_FILES + OTHERS) | {cache_guard.MARKER}
