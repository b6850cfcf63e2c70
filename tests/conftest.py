"""Shared test setup: the CLI helpers (tests/cli/clihelp.py) are importable from every folder.

The tests are split by what they check: unit/ (parameters, metrics, controllers, studies'
bookkeeping), physics/ (the model against analytic limits, invariants and a second method),
cli/ (the command line, the examples and the README)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent / "cli"))
