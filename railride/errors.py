"""The library's own exception types.

`DivergenceError` is a `RuntimeError` (what a diverged run raised before it had a type of its
own), so ``except RuntimeError`` still catches it. It is kept apart from the other runtime
errors because its cause is the inputs (gains, step, amplitude, speed), which the user can
change; the command line exits with status 2 for it, and with 1 only for internal faults.
"""

from __future__ import annotations


class DivergenceError(RuntimeError):
    """A run diverged: a response left the allowed range or stopped being finite."""
