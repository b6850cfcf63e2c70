"""The base of every rail profile (`RailProfile`: heights and slopes along the track, level
before s = 0) and the plausible ranges their settings obey (docs/model.md, Track input). The
profiles themselves and the scenarios are in `railride.model.track`, the random irregularity in
`railride.model.irregularity`."""

from __future__ import annotations

import math
from abc import ABC, abstractmethod

import numpy as np

from railride.errors import InputError
from railride import validation

#: nodes per shortest feature (wavelength, bump length) in the stepper's table
NODES_PER_FEATURE = 200
MAX_TABLE_NODES = 2_000_000
#: plausible ranges (docs/model.md, Plausible ranges): a rail a metre out of line is no track the
#: vehicle could run on, and 200 m/s is above the rail speed record (159.7 m/s); beyond these the
#: run diverges or means nothing, so they are input errors rather than a "diverged" at run time
MAX_RAIL_AMPLITUDE = 1.0  # m, sine amplitude and bump height
MAX_SPEED = 200.0  # m/s
MAX_RAIL_PHASE = 360.0  # deg, either way
MAX_WAVELENGTH = 1.0e5  # m, a sine's wavelength and a bump's length
#: the longest random track a run may cover [m]: the Trans-Siberian line is 9.3e6 m; ten times it
#: leaves any real journey inside (its realisation's size is limited by memory besides)
MAX_RANDOM_LENGTH = 1.0e8


def _check(name: str, value, rule: str, allowed: str) -> float:
    return validation.number(name, value, rule, allowed=allowed)


def _within(name: str, value: float, bound: float, unit: str, why: str) -> float:
    """``value`` when |value| <= ``bound``, else a ValueError naming the field and the range."""
    if abs(value) > bound:
        raise InputError(
            f"{name} = {value:.4g} {unit}: outside the plausible range -{bound:g} to {bound:g} {unit} ({why})"
        )
    return value


class RailProfile(ABC):
    """Left and right rail heights along the track."""

    @abstractmethod
    def _evaluate(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """z_L, z_R, dz_L/ds, dz_R/ds at s >= 0."""

    @abstractmethod
    def table_spacing(self) -> float:
        """The node spacing ds [m] that resolves this profile in the stepper's table."""

    @abstractmethod
    def describe(self) -> dict:
        """Settings that define the profile, for the record kept with results."""

    def end(self) -> float:
        """Last s [m] at which the profile is defined (inf if everywhere)."""
        return math.inf

    def evaluate(self, s) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """z_L, z_R [m] and their slopes dz_L/ds, dz_R/ds [-] at positions s [m]; 0 for s < 0."""
        s = np.asarray(s, dtype=float)
        out = [np.zeros_like(s) for _ in range(4)]
        on = s > 0  # s = 0 itself still belongs to the level track
        if np.any(on):
            for o, v in zip(out, self._evaluate(s[on])):
                o[on] = v
        return tuple(out)
