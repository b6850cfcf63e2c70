"""Realistic sensing: what a controller on a vehicle measures in place of the exact states
(docs/control.md, Sensing).

`Accelerometers` is four vertical accelerometers at the carbody corners (over the secondary
suspension), each with white noise, a bias and a first-order anti-alias filter, sampled at the
controller rate, and the estimator railride uses with them: band-limited ("pseudo")
integration, as is usual for skyhook damping on rail vehicles. Each corner's acceleration
passes twice through s / (s + w)^2, a high-pass then a leaky integral with the corner frequency
``cutoff_hz``: the first pass gives the corner's velocity, the second its displacement, with
the bias and the slow drift of a plain integral removed. The four corners' estimates become the
carbody's heave, pitch and roll by the least-squares inverse of the corner geometry. Below
about ``cutoff_hz`` the estimates fade out (they are high-passed): that is the price of
integrating a biased, noisy signal.

The compiled engine runs the sensors and the estimator (`railride.engine.kernels.run_batch`); here
they are described and checked, and their settings packed for it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from railride.errors import InputError
from railride.engine import layout
from railride.model import plausible
from railride.validation import validate_fields


def _meta(unit: str, doc: str, rule: str) -> dict:
    return {"unit": unit, "doc": doc, "rule": rule}


@dataclass(frozen=True)
class Accelerometers:
    """Four vertical accelerometers at the carbody corners and the band-limited integration
    that estimates the states from them. Defaults: a railway-grade MEMS accelerometer sampled at
    the controller rate (0.03 m/s^2 RMS noise per sample: about 300 ug/sqrt(Hz) over a 100 Hz
    band; a bias of 0.02 m/s^2, 2 mg), and an estimator corner at 0.1 Hz, below the carbody
    modes (0.76-0.98 Hz for the paper's vehicle)."""

    noise: float = field(
        default=0.03, metadata=_meta("m/s^2", "white noise of each sample (standard deviation)", "nonnegative")
    )
    bias: float = field(default=0.02, metadata=_meta("m/s^2", "constant bias of each accelerometer", "finite"))
    antialias_hz: float = field(default=100.0, metadata=_meta("Hz", "anti-alias filter corner frequency", "positive"))
    cutoff_hz: float = field(default=0.1, metadata=_meta("Hz", "band-limited integration corner frequency", "positive"))
    seed: int = field(default=0, metadata=_meta("-", "seed of the noise generator", "seed"))

    def __post_init__(self):
        validate_fields(self, "accelerometer", plausible.ACCELEROMETERS)  # the seed as int, never through a float

    def to_dict(self) -> dict:
        return {"kind": "accelerometers", **dataclasses.asdict(self)}

    def check(self, control_rate: float, dt: float) -> None:
        """The filter must be resolved by the step, and sampled below its Nyquist limit."""
        if 2 * math.pi * self.antialias_hz * dt > 0.5:
            raise InputError(
                f"accelerometer antialias_hz = {self.antialias_hz:g} Hz: too fast for dt = {dt:g} s "
                f"(2 pi f dt must be <= 0.5; at most {0.5 / (2 * math.pi * dt):.4g} Hz)"
            )
        if not self.cutoff_hz < control_rate / 10:
            raise InputError(
                f"accelerometer cutoff_hz = {self.cutoff_hz:g} Hz: must be below a tenth of the "
                f"controller rate ({control_rate:g} Hz)"
            )

    def pack(self, carbody_map: np.ndarray) -> np.ndarray:
        """The engine's settings row (`railride.engine.layout.SENSING_COLS`) for a vehicle whose
        corner geometry is ``carbody_map`` (T_c, 3 x 4: heave, pitch, roll forces from corner
        forces; a corner's displacement is T_c^T q_c)."""
        row = np.zeros(layout.SENSING_COLS)
        row[layout.S_ON] = 1.0
        row[layout.S_W_AA] = 2 * math.pi * self.antialias_hz
        row[layout.S_W_C] = 2 * math.pi * self.cutoff_hz
        row[layout.S_BIAS : layout.S_BIAS + layout.N_CORNER] = self.bias
        # q_c from the corner displacements z = T_c^T q_c: the least-squares inverse
        row[layout.S_MAP :] = np.linalg.solve(carbody_map @ carbody_map.T, carbody_map).ravel()
        return row

    def samples(self, n: int) -> np.ndarray:
        """(n, 4) noise of the four accelerometers at n controller samples."""
        return np.random.default_rng(self.seed).standard_normal((n, 4)) * self.noise


#: what a controller can measure: the exact states, or the carbody accelerometers
SENSING = ("ideal", "accelerometers")


def reads_bogies(G) -> bool:
    """Whether an outer loop's gain G (4 x 6 on the carbody states, or 4 x 2n on (q, q'))
    reads a bogie state, which the carbody accelerometers cannot give."""
    G = np.asarray(G, dtype=float)
    if G.shape not in ((4, 2 * layout.N_RIGID), (4, 2 * layout.N_DOF)):
        return False
    n = G.shape[1] // 2  # the vehicle's (q, q') or the engine's: the bogies are DOFs 3 to 8 in both
    return bool(np.any(G[:, 3:9] != 0.0) or np.any(G[:, n + 3 : n + 9] != 0.0))
