"""Shared test setup: the CLI helpers (tests/cli/clihelp.py) are importable from every folder.

The tests are split by what they check: unit/ (parameters, metrics, controllers, studies'
bookkeeping), physics/ (the model against analytic limits, invariants and a second method),
cli/ (the command line, the examples and the README).

The GPU kernel runs in numba's CUDA simulator (NUMBA_ENABLE_CUDASIM=1, set here before numba is
imported, and inherited by the commands the tests start) unless the environment sets it: with
NUMBA_ENABLE_CUDASIM=0 on a machine with a GPU the same tests run the kernel on the device."""

import os
import signal
import sys
from pathlib import Path

import pytest
from numba.core import config as _numba_config

# A shell that starts the tests in the background (`cmd &` in a script) hands them SIGINT
# ignored, and every command a test starts would inherit that, so the Ctrl-C tests would send a
# signal nobody hears: take Python's own handler back (a caught signal is reset to the default in
# a child, an ignored one is not)
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

os.environ.setdefault("NUMBA_ENABLE_CUDASIM", "1")
# pytest has imported numba already (the warning filters in pyproject.toml name its classes):
# have it read the environment again, before anything imports its CUDA target
_numba_config.reload_config()

sys.path.insert(0, str(Path(__file__).parent / "cli"))


@pytest.fixture(autouse=True)
def _default_limits():
    """`--max-memory` and `--max-steps` set process-wide limits as a command starts; a CLI test
    runs in this process, so put the defaults back for the tests after it."""
    yield
    from railride import limits

    limits.set_max_memory(None)
    limits.set_max_work(None)
