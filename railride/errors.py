"""The library's own exception types.

`InputError` is a `ValueError` (what every check raised before it had a type of its own, so
``except ValueError`` still catches it): what the user gave is wrong, an option, a field, a
value, a file. Every check in railride raises it, naming the option or field, the value and
what is allowed; the command line exits with status 2 for it. Any other exception that reaches
the command line is a bug in railride: one line that says so, status 1 (``railride --debug``
shows its traceback).

`DivergenceError` is a `RuntimeError` (what a diverged run raised before it had a type of its
own), so ``except RuntimeError`` still catches it. It is kept apart from the other runtime
errors because its cause is the inputs (gains, step, amplitude, speed), which the user can
change; the command line exits with status 2 for it, and with 1 only for internal faults.
"""

from __future__ import annotations


class InputError(ValueError):
    """What the user gave is wrong: an option, a field, a value or a file (the message names it,
    the value, and what is allowed)."""


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


class BackendWarning(UserWarning):
    """The backend asked for could not be used, and the run went on with another: for example
    "auto" with no GPU for a large batch (`railride.SolverSettings`). The command line shows it
    as one "warning:" line."""


class TuningWarning(UserWarning):
    """A tuning that leaves gains its result depends on at their start values: the inner loop
    of the MR dampers that a listed law drives, when "inner" is not listed
    (`railride.studies.tuning.tune`). The command line shows it as one "warning:" line."""
