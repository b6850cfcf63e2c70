"""The result protocol: what every result of a library function offers (docs/architecture.md).

`simulate`, `compare`, `league`, `study`, `run_sweep`, `tune`, `pareto`, `optimise`,
`sensitivity`, `frequency_responses`, `ride_spectrum` and the damper rig's `cycles` and `track`
each return a frozen dataclass with

* ``to_dict()``: the JSON document (plain values, a versioned ``schema`` name);
* ``to_pandas()``: its main table, a DataFrame;
* ``plot(ax=None)``: its figure, drawn into the caller's Axes when given (some draw several
  panels and take that many Axes), returning the matplotlib Figure;
* ``save(folder, ...)``: its files (the JSON document, the main table as CSV where it has one,
  the figures), written all or nothing.

``isinstance(value, railride.Result)`` checks the four methods are there (not their
signatures). This module is on the ground floor: it imports nothing of railride.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable


@runtime_checkable
class Result(Protocol):
    """A result of a railride library function (`railride.Result`)."""

    def to_dict(self) -> dict:
        """The JSON document."""
        ...

    def to_pandas(self) -> Any:
        """The main table (a DataFrame)."""
        ...

    def plot(self, ax=None) -> Any:
        """The figure; into ``ax`` when given. Returns the matplotlib Figure."""
        ...

    def save(self, folder, *args: Any, **kwargs: Any) -> Any:
        """The files into ``folder``, all or nothing. Returns the written paths."""
        ...
