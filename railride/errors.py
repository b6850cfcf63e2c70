"""The library's own exception types.

`DivergenceError` is a `RuntimeError` (what a diverged run raised before it had a type of its
own), so ``except RuntimeError`` still catches it. It is kept apart from the other runtime
errors because its cause is the inputs (gains, step, amplitude, speed), which the user can
change; the command line exits with status 2 for it, and with 1 only for internal faults.
"""

from __future__ import annotations


class DivergenceError(RuntimeError):
    """A run diverged: a response left the allowed range or stopped being finite."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C during a long run (`railride.simulate` with a ``progress`` callback): a
    KeyboardInterrupt, so code that does not know this type stops as before, with what was
    computed up to the last finished chunk in ``result`` (a `RideResult` whose Dataset says
    ``partial`` in its attrs) and the time it reaches in ``until`` [s]; None when nothing
    useful was computed."""

    def __init__(self, result=None, until: float = 0.0):
        super().__init__("interrupted")
        self.result = result
        self.until = until
