"""Tuning objectives: one number from the four RMS ratios to passive (docs/tuning.md, Objectives).

r_k = RMS_k / RMS_k(passive) for k = acceleration, displacement, pitch, roll. ``sum``,
``weighted``, ``minimax`` or ``constrained``, plus an optional penalty on ratios above 1; a run
that diverged scores +inf. `Objective.describe` states an objective in full, and every output
of a study prints that statement. `DEFAULT_OBJECTIVE` is the one home of the default.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from railride.defaults import DEFAULT_OBJECTIVE_KIND
from railride.errors import InputError
from railride.analysis.metrics import RESPONSES

#: the objectives, in the order the docs list them
OBJECTIVE_KINDS = ("sum", "weighted", "minimax", "constrained", "n_mv", "sperling")
#: the comfort objectives: kind -> the comfort index whose worst ratio to passive over the floor
#: points is J (EN 12299's N_MV vertical term; Sperling's ride index Wz, EN 12299 annex)
COMFORT_KINDS = {"n_mv": "N_MV_z", "sperling": "Wz"}
#: the floor points a comfort objective looks at (`railride.analysis.comfort.FLOOR`)
FLOOR_POINTS = ("centre", "front", "rear")
#: the run-table columns: the four RMS responses, in the order of the ratios, and the peak
RMS_COLUMNS = tuple(f"{r}_rms" for r in RESPONSES)
PEAK_COLUMN = "acceleration_m_s2_ptp"
TRAVEL_COLUMN = "travel_max_m"
#: the ratios' names in the order of the weights
RATIO_NAMES = ("acceleration", "displacement", "pitch", "roll")
#: constrained: an infeasible candidate scores INFEASIBLE_OFFSET + INFEASIBLE_SCALE x excess;
#: the offset rises (by powers of ten) above the largest J a feasible candidate can have
INFEASIBLE_OFFSET = 1000.0
INFEASIBLE_SCALE = 1000.0
#: the smallest bound on the secondary travel [m]: below it the excess of any real travel over it
#: overflows the infeasible score (1e-308 m)
MIN_TRAVEL_BOUND = 1e-6


def _number(name: str, value, rule: str, ok) -> float:
    """``value`` as a float if it is a real number (not a bool, not text) passing ``ok``."""
    number = not isinstance(value, (bool, str, bytes))
    try:
        x = float(value) if number else math.nan
    except (TypeError, ValueError):
        x = math.nan
    except OverflowError:  # a whole number too large for a float
        x = math.inf
    if not (math.isfinite(x) and ok(x)):
        raise InputError(f"objective {name} = {value!r}: {rule}")
    return x


@dataclass(frozen=True)
class Objective:
    """A score J of a vehicle run from its RMS ratios to passive, r_k = RMS_k / RMS_k(passive),
    k = acceleration, displacement, pitch, roll; lower is better, J(passive) = 4 for the sums.

    ``kind``:

    * ``sum``: J = sum_k r_k;
    * ``weighted``: J = sum_k w_k r_k, ``weights`` four numbers >= 0, not all 0;
    * ``minimax``: J = max_k r_k, the worst ratio (candidates with the same worst ratio tie,
      whatever their other ratios);
    * ``constrained``: J = sum_k r_k if every r_k <= ``bound`` (> 0); otherwise the candidate
      is infeasible and J = offset + 1000 E, E = sum_k max(0, r_k - bound) its total excess, the
      offset 1000 (or the next power of ten above the largest J a feasible candidate can reach):
      every infeasible candidate ranks after every feasible one, and among themselves by E.

    * ``n_mv``: J = max_p N_MV,z(p) / N_MV,z(p, passive), the worst ratio of the vertical term
      of EN 12299's comfort index over the floor points p (centre, front, rear);
    * ``sperling``: the same with Sperling's ride index Wz.

    ``penalty`` (>= 0, default 0) adds penalty x sum_k max(0, r_k - 1) to every kind (to the
    feasible ones of ``constrained``). ``weights`` is for ``weighted`` only and ``bound`` for
    ``constrained`` only.

    Two constraints apply to any kind: ``peak_bound`` (> 0), the largest peak-to-peak carbody
    acceleration as a ratio to passive's, and ``travel_bound`` (> 0) [m], the largest secondary
    travel (for example the bump stops' clearance). A run that breaks one is infeasible and
    scores J = offset + 1000 E, E the sum of its excesses (the peak ratio above its bound; the
    travel above its bound, as a fraction of it), after every feasible run (`of_ratios`).
    `describe` is the statement printed with every result. `DEFAULT_OBJECTIVE` is the tuner's
    default; ``Objective()`` is the plain sum.
    """

    kind: str = "sum"
    weights: tuple | None = None  # acceleration, displacement, pitch, roll
    bound: float | None = None
    penalty: float = 0.0
    peak_bound: float | None = None
    travel_bound: float | None = None

    def __post_init__(self):
        if self.kind not in OBJECTIVE_KINDS:
            raise InputError(f"objective kind = {self.kind!r}: unknown; allowed: {', '.join(OBJECTIVE_KINDS)}")
        rule = "four numbers >= 0, not all 0 (acceleration, displacement, pitch, roll), for kind 'weighted'"
        if self.kind == "weighted":
            if self.weights is None:
                raise InputError(f"objective weights = None: {rule}")
            try:
                w = tuple(self.weights)
            except TypeError:
                raise InputError(f"objective weights = {self.weights!r}: {rule}") from None
            if len(w) != 4:
                raise InputError(f"objective weights = {self.weights!r}: {rule}")
            w = tuple(_number("weights", x, rule, lambda v: v >= 0) for x in w)
            if sum(w) == 0:
                raise InputError(f"objective weights = {self.weights!r}: {rule}")
            object.__setattr__(self, "weights", w)
        elif self.weights is not None:
            raise InputError(f"objective weights = {self.weights!r}: for kind 'weighted' only (kind is {self.kind!r})")
        if self.kind == "constrained":
            if self.bound is None:
                raise InputError(
                    "objective bound = None: kind 'constrained' needs a bound, a "
                    "finite number > 0 (the largest RMS ratio to passive allowed)"
                )
            object.__setattr__(
                self,
                "bound",
                _number(
                    "bound",
                    self.bound,
                    "a finite number > 0 (the largest RMS ratio to passive allowed)",
                    lambda v: v > 0,
                ),
            )
        elif self.bound is not None:
            raise InputError(f"objective bound = {self.bound!r}: for kind 'constrained' only (kind is {self.kind!r})")
        object.__setattr__(self, "penalty", _number("penalty", self.penalty, "a finite number >= 0", lambda v: v >= 0))
        for name, rule, least in (
            ("peak_bound", "a finite number > 0 (the largest peak-to-peak acceleration as a ratio to passive's)", 0.0),
            (
                "travel_bound",
                f"a finite number >= {MIN_TRAVEL_BOUND:g} [m] (the largest secondary travel; a micrometre is "
                "below any suspension's tolerances)",
                MIN_TRAVEL_BOUND,
            ),
        ):
            if getattr(self, name) is not None:
                value = _number(name, getattr(self, name), rule, lambda v, least=least: v > 0 and v >= least)
                object.__setattr__(self, name, value)
        if self.kind == "constrained" and not math.isfinite(self.feasible_max):
            raise InputError(
                f"objective bound = {self.bound!r} with penalty = {self.penalty!r}: "
                "too large to rank infeasible candidates after feasible ones"
            )

    @property
    def needs_comfort(self) -> bool:
        """Whether J needs the runs' comfort indices (a comfort kind)."""
        return self.kind in COMFORT_KINDS

    @property
    def needs_costs(self) -> bool:
        """Whether J needs what the runs ask of their dampers (the travel constraint)."""
        return self.travel_bound is not None

    @property
    def columns(self) -> tuple:
        """The run-table columns whose ratios to passive J reads (the travel is read as it is)."""
        comfort = tuple(f"{p}_{COMFORT_KINDS[self.kind]}" for p in FLOOR_POINTS) if self.needs_comfort else ()
        return (*RMS_COLUMNS, *comfort, *((PEAK_COLUMN,) if self.peak_bound is not None else ()))

    @property
    def passive_score(self) -> float:
        """J of passive itself: every ratio 1 (4 for the sums, 1 for minimax and comfort)."""
        ones = {c: np.float64(1.0) for c in self.columns}
        return float(self.of_ratios(ones, self.travel_bound))

    def of_runs(self, runs, passive) -> np.ndarray:
        """J of each run of ``runs`` (a table with the run-table columns, `columns` and for
        the travel constraint `TRAVEL_COLUMN`) against ``passive`` (one row, or a table of as
        many rows: passive on the same tracks)."""
        cols = list(self.columns)
        base = np.asarray(passive[cols], dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.asarray(runs[cols], dtype=float) / base
        ratios = dict(zip(cols, np.moveaxis(ratio, -1, 0)))
        travel = np.asarray(runs[TRAVEL_COLUMN], dtype=float) if self.needs_costs else None
        return self.of_ratios(ratios, travel)

    def of_ratios(self, ratios, travel=None) -> np.ndarray:
        """J from ratios to passive by run-table column (a mapping of arrays: `columns`) and,
        for the travel constraint, the largest travel [m]: the kind's J, then the constraints
        (an infeasible run scores `infeasible_offset` + 1000 x its excess)."""
        r = np.stack([np.asarray(ratios[c], dtype=float) for c in RMS_COLUMNS], axis=-1)
        if self.needs_comfort:
            comfort = np.stack([np.asarray(ratios[f"{p}_{COMFORT_KINDS[self.kind]}"], float) for p in FLOOR_POINTS], -1)
            j = comfort.max(axis=-1)
            if self.penalty:
                j = j + self.penalty * np.clip(r - 1.0, 0.0, None).sum(axis=-1)
            j = np.where(np.isnan(r).any(axis=-1) | np.isnan(comfort).any(axis=-1), np.inf, j)
        else:
            j = self.score(r)
        excess = np.zeros(np.shape(j))
        if self.peak_bound is not None:
            excess = excess + np.clip(np.asarray(ratios[PEAK_COLUMN], dtype=float) - self.peak_bound, 0.0, None)
        if self.travel_bound is not None:
            travel = np.asarray(travel, dtype=float)
            excess = excess + np.clip(travel / self.travel_bound - 1.0, 0.0, None)
        if self.peak_bound is not None or self.travel_bound is not None:
            offset = self.infeasible_offset or INFEASIBLE_OFFSET
            j = np.where(np.isfinite(j) & (excess > 0), offset + INFEASIBLE_SCALE * excess, j)
        return j

    @property
    def feasible_max(self) -> float:
        """constrained: the largest J a feasible candidate can have (every r_k at the bound)."""
        if self.kind != "constrained":
            return math.inf
        bound = self.bound
        assert bound is not None  # a constrained objective has one, checked at construction
        return 4.0 * bound + 4.0 * self.penalty * max(0.0, bound - 1.0)

    @property
    def infeasible_offset(self) -> float | None:
        """constrained: the J of an infeasible candidate with a vanishing excess (None for the
        other kinds): INFEASIBLE_OFFSET, or the next power of ten above `feasible_max`."""
        if self.kind != "constrained":
            return None
        offset = INFEASIBLE_OFFSET
        while offset <= self.feasible_max:
            offset *= 10.0
        return offset

    @property
    def constraint_offset(self) -> float | None:
        """The score at and above which a run breaks a constraint of this objective (the
        constrained kind's bound, ``peak_bound``, ``travel_bound``); None where it has none."""
        if self.kind != "constrained" and self.peak_bound is None and self.travel_bound is None:
            return None
        return self.infeasible_offset or INFEASIBLE_OFFSET

    def score(self, ratio) -> np.ndarray:
        """J of RMS ratios to passive, ``ratio`` (..., 4). A run that diverged has NaN ratios
        and scores +inf: after every run that did not."""
        if self.needs_comfort:
            raise InputError(f"objective {self.kind!r} scores comfort indices, not the RMS ratios: use of_runs")
        r = np.asarray(ratio, dtype=float)
        if r.shape[-1:] != (4,):
            raise InputError(f"ratios of shape {r.shape}: the last axis must hold the four responses")
        if self.kind == "weighted":
            assert self.weights is not None  # a weighted objective has them, checked at construction
            w = [float(x) for x in self.weights]
            # term by term: a run's J must not depend on how many runs share the call, and a
            # matrix product's BLAS sums a row in another order for another number of rows
            j = r[..., 0] * w[0] + r[..., 1] * w[1] + r[..., 2] * w[2] + r[..., 3] * w[3]
        elif self.kind == "minimax":
            j = r.max(axis=-1)
        else:
            j = r.sum(axis=-1)
        if self.penalty:
            j = j + self.penalty * np.clip(r - 1.0, 0.0, None).sum(axis=-1)
        if self.kind == "constrained":
            excess = np.clip(r - self.bound, 0.0, None).sum(axis=-1)
            j = np.where(excess > 0, self.infeasible_offset + INFEASIBLE_SCALE * excess, j)
        return np.where(np.isnan(r).any(axis=-1), np.inf, j)

    def __call__(self, rms: np.ndarray, passive: np.ndarray) -> np.ndarray:
        """J of RMS values (..., 4) against the passive RMS (4,)."""
        return self.score(np.asarray(rms, dtype=float) / np.asarray(passive, dtype=float))

    def describe(self) -> str:
        """The whole objective in one line: formula, weights, bound, penalty, infeasible rule."""
        r = "r_k = RMS_k / RMS_k(passive), k = acceleration, displacement, pitch, roll"
        if self.kind == "sum":
            text = f"sum: J = sum_k r_k (every weight 1), {r}"
        elif self.kind == "weighted":
            w = ", ".join(f"{n} {v:g}" for n, v in zip(RATIO_NAMES, self.weights or ()))
            text = f"weighted: J = sum_k w_k r_k, weights {w}, {r}"
        elif self.kind == "minimax":
            text = f"minimax: J = max_k r_k (the worst ratio; equal worst ratios tie), {r}"
        elif self.kind in COMFORT_KINDS:
            index = "N_MV,z (EN 12299, vertical term)" if self.kind == "n_mv" else "Sperling's Wz"
            text = (
                f"{self.kind}: J = max_p {COMFORT_KINDS[self.kind]}(p) / {COMFORT_KINDS[self.kind]}(p, passive), "
                f"the worst ratio of {index} over the floor points p = centre, front, rear"
            )
            if self.penalty:
                text += f", {r}"
        else:
            b = f"{self.bound:g}"
            text = (
                f"constrained: J = sum_k r_k subject to r_k <= {b} for every k, {r}; an "
                f"infeasible candidate scores J = {self.infeasible_offset:g} + "
                f"{INFEASIBLE_SCALE:g} x E, E = sum_k max(0, r_k - {b}), ranking it after "
                f"every feasible one (J <= {self.feasible_max:g}) and by its excess"
            )
        if self.penalty:
            text += f"; plus penalty {self.penalty:g} x sum_k max(0, r_k - 1)"
            if self.kind == "constrained":
                text += " on feasible candidates"
        limits = []
        if self.peak_bound is not None:
            limits.append(f"peak-to-peak carbody acceleration <= {self.peak_bound:g} x passive's")
        if self.travel_bound is not None:
            limits.append(f"secondary travel <= {self.travel_bound:g} m")
        if limits:
            offset = self.infeasible_offset or INFEASIBLE_OFFSET
            text += (
                f"; subject to {' and '.join(limits)} in every run: a run that breaks them scores "
                f"J = {offset:g} + {INFEASIBLE_SCALE:g} x its excess (peak ratio above its bound, travel "
                "above its bound as a fraction of it)"
            )
        return text + "; a run that diverged scores J = inf"

    def to_dict(self) -> dict:
        """Every setting of the objective and its statement (for JSON documents)."""
        return {
            "kind": self.kind,
            "weights": None if self.weights is None else dict(zip(RESPONSES, self.weights)),
            "bound": self.bound,
            "penalty": self.penalty,
            **({"peak_bound": self.peak_bound} if self.peak_bound is not None else {}),
            **({"travel_bound_m": self.travel_bound} if self.travel_bound is not None else {}),
            "infeasible": None
            if self.constraint_offset is None
            else {
                "offset": self.constraint_offset,
                "scale": INFEASIBLE_SCALE,
                "feasible_max": self.feasible_max if math.isfinite(self.feasible_max) else None,
            },
            "statement": self.describe(),
        }


#: the tuner's default objective (`tune`, `railride.studies.optimise`, `railride tune`)
DEFAULT_OBJECTIVE = Objective(kind=DEFAULT_OBJECTIVE_KIND)
