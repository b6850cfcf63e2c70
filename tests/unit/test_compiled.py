"""railride.engine.compiled: whether the stepper still needs compiling, and the watch on its compiles."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from numba.core import event

import railride as rr
from railride.engine import compiled, kernels, lanes, laws


def test_an_empty_cache_means_compiling(tmp_path):
    # a fresh process with an empty numba cache has no machine code to load
    code = "from railride import compiled; print(compiled.needs_compiling('run_batch'))"
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"


def test_a_stepper_that_ran_needs_no_compiling():
    rr.simulate(rr.scenario("paper-sine", duration=0.2), suspension=rr.Suspension.semi_active("railway", voltage=1.0))
    assert kernels.run_batch.signatures  # the run went through the stepper
    assert compiled.needs_compiling("run_batch") is False


def test_unknown_kernel_is_named():
    with pytest.raises(ValueError, match="kernel = 'stepper'.*run_batch"):
        compiled.needs_compiling("stepper")


def _compile_event(dispatcher):
    """What numba broadcasts when it starts compiling ``dispatcher`` (not on a cache load)."""
    return event.trigger_event("numba:compile", data=dict(dispatcher=dispatcher, args=(), return_type=None))


def test_watch_hears_the_stepper_compile_only():
    heard: list[str] = []
    with compiled.watch_compiles(heard.append):
        with _compile_event(laws.substeps):  # compiles in well under a second: unannounced
            pass
        with _compile_event(kernels.run_batch):
            pass
    with _compile_event(kernels.run_batch):  # after the block: nobody listens
        pass
    assert heard == ["run_batch"]
    assert compiled.compile_seconds("run_batch") > 1.0


def test_the_build_compiles_what_compare_and_studies_call():
    # setup.py compiles `build_cache`'s signatures into the wheel; if they drifted from the calls
    # the library makes (compare, and a study's batch), the first run after install would compile
    # again. Run those first, so the kernels hold the signatures of real calls; the build's must
    # add none (a drift compiles a second one here, which the check sees).
    rr.compare(rr.scenario("paper-sine", duration=0.3))
    sc = rr.scenario("paper-sine", duration=0.1)  # and a batch that fills the lane stepper, as studies do
    rr.simulate([sc] * lanes.LANES, None, rr.Suspension.named("pid"))
    rr.simulate(rr.scenario("fra4", duration=0.1))  # a random track's rails: its splines, compiled

    def home(name):
        return compiled._dispatcher(name)

    used = {name: set(home(name).signatures) for name in compiled._signatures()}
    assert used and all(used.values())  # compare went through every kernel the build compiles
    assert compiled.build_cache() == list(used)
    assert {name: set(home(name).signatures) for name in used} == used
