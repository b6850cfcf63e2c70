"""Shared test setup: the CLI helpers (tests/cli/clihelp.py) are importable from every folder.

The tests are split by what they check: unit/ (parameters, metrics, controllers, studies'
bookkeeping), physics/ (the model against analytic limits, invariants and a second method),
cli/ (the command line, the examples and the README)."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent / "cli"))


@pytest.fixture(autouse=True)
def _default_limits():
    """`--max-memory` and `--max-steps` set process-wide limits as a command starts; a CLI test
    runs in this process, so put the defaults back for the tests after it."""
    yield
    from railride import limits

    limits.set_max_memory(None)
    limits.set_max_work(None)
