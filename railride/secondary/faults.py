"""Damper faults: a secondary damper that fails during a run (docs/control.md, Faults).

A `DamperFault` names the corner (1R, 1L, 2R, 2L), the mode and the time it starts:

- ``off``: the coil driver fails, the command falls to v_min whatever the controller asks (the
  coil current decays with its time constant, and the damper gives its 0 V force);
- ``on``: the command is stuck at v_max (the stiffest damper the coil can make);
- ``disconnected``: the damper gives no force at all (a broken mount or rod).

``off`` and ``on`` need MR dampers (a coil to fail); ``disconnected`` applies to any damper
model the engine steps, MR, viscous or ideal, but not to the vehicle's own passive dampers,
which sit in its damping matrix (give `Suspension.passive(dampers.Viscous(c_sz))` instead).
The compiled engine applies them (`railride.engine.kernels.run_batch`); here they are checked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from railride.errors import InputError
from railride.secondary import dampers
from railride.engine import layout
from railride.validation import number, shown
from railride.model.vehicle import CORNER_NAMES

#: the fault modes, and their code in the compiled engine
FAULT_MODES = {"off": layout.FAULT_OFF, "on": layout.FAULT_ON, "disconnected": layout.FAULT_DISCONNECTED}


@dataclass(frozen=True)
class DamperFault:
    """The damper at ``corner`` fails in ``mode`` from ``time`` [s] on (0: from the start)."""

    corner: str
    mode: str
    time: float = 0.0

    def __post_init__(self):
        if self.corner not in CORNER_NAMES:
            raise InputError(f"fault corner = {self.corner!r}: allowed {', '.join(CORNER_NAMES)}")
        if self.mode not in FAULT_MODES:
            raise InputError(f"fault mode = {self.mode!r}: allowed {', '.join(FAULT_MODES)}")
        t = number("fault time", self.time, "nonnegative", "s")
        object.__setattr__(self, "time", t)

    @classmethod
    def parse(cls, text: str) -> "DamperFault":
        """``CORNER-MODE`` or ``CORNER-MODE@TIME`` (e.g. ``1R-off``, ``2L-on@2.5``)."""
        body, _, when = str(text).strip().partition("@")
        corner, _, mode = body.partition("-")
        if not corner or not mode:
            raise InputError(
                f"fault = {text!r}: expected CORNER-MODE[@TIME], e.g. 1R-off or 2L-on@2.5 "
                f"(corners {', '.join(CORNER_NAMES)}; modes {', '.join(FAULT_MODES)})"
            )
        time = 0.0
        if when:
            try:
                time = float(when)
            except ValueError:
                raise InputError(f"fault = {text!r}: the time after @ must be a number of seconds") from None
        return cls(corner, mode, time)

    @property
    def label(self) -> str:
        """The fault as `parse` reads it: ``1R-off`` or ``1R-off@2.5``."""
        return f"{self.corner}-{self.mode}" + (f"@{self.time:g}" if self.time else "")


def parse_faults(faults) -> tuple:
    """``faults`` (DamperFault or their text, e.g. "1R-off", or a sequence of them) as a tuple
    of `DamperFault` in corner order; one fault per corner."""
    if faults is None:
        return ()
    if isinstance(faults, (str, DamperFault)):
        faults = (faults,)
    from railride import arguments

    given = arguments.sequence("faults", faults, "allowed a fault (e.g. '1R-off@2'), a DamperFault or a list of them")
    bad = [f for f in given if not isinstance(f, (str, DamperFault))]
    if bad:
        raise InputError(f"faults: {bad[0]!r} is not a fault; allowed text such as '1R-off@2' or a DamperFault")
    out = [f if isinstance(f, DamperFault) else DamperFault.parse(f) for f in given]
    corners = [f.corner for f in out]
    twice = sorted({c for c in corners if corners.count(c) > 1})
    if twice:
        raise InputError(f"faults: corner {twice[0]} has more than one fault; give one per corner")
    return tuple(sorted(out, key=lambda f: CORNER_NAMES.index(f.corner)))


def check_faults(faults, model) -> tuple:
    """`parse_faults`, checked against the damper ``model`` of the suspension (None: the
    vehicle's passive dampers)."""
    out = parse_faults(faults)
    if out and model is None:
        raise InputError(
            "faults apply to the dampers the engine steps (MR, ideal, or a railride.secondary.dampers.Viscous); "
            "the vehicle's own passive dampers sit in its damping matrix"
        )
    coil = model is not None and model.law in (dampers.LAW_BOUC_WEN, dampers.LAW_SPENCER)
    for f in out:
        if f.mode != "disconnected" and not coil:
            raise InputError(
                f"fault {f.label!r}: 'off' and 'on' need MR dampers (a coil to fail); "
                f"damper {getattr(model, 'model', model)!r} can only be 'disconnected'"
            )
    return out


def fault_table(faults_per_sample, dt: float, duration: float):
    """The engine's (n, 8) int64 table: per sample the mode code of each corner (0: healthy),
    then the step each fault starts at. A fault at or after the end of the run is refused."""
    import numpy as np

    table = np.zeros((len(faults_per_sample), layout.N_FAULT_COLS), dtype=np.int64)
    for i, faults in enumerate(faults_per_sample):
        for f in faults:
            if not f.time < duration:
                raise InputError(
                    f"fault {f.label!r}: time = {shown(f.time)} s is not within the run (0 to {duration:g} s)"
                )
            c = CORNER_NAMES.index(f.corner)
            table[i, layout.F_MODE + c] = FAULT_MODES[f.mode]
            table[i, layout.F_STEP + c] = int(math.ceil(f.time / dt - 1e-9))
    return table


def degradation(faulted, healthy) -> dict:
    """How the ride degrades with the faults of ``faulted`` (a `railride.studies.comparison.Comparison`
    run with them) against ``healthy`` (the same without them): the faults, and per controller
    and response the RMS healthy and with the faults, the change in % ((faulted - healthy) /
    healthy x 100, + is worse), the reduction against the (healthy) passive suspension with
    healthy dampers and with the faults, and the responses that are worse than passive with the
    faults."""
    rms_f = faulted.metrics.sel(statistic="rms")
    rms_h = healthy.metrics.sel(statistic="rms")
    passive = rms_f.sel(controller="passive")
    out: dict = {"faults": faulted.settings.get("faults", []), "controllers": {}}
    for name in faulted.names:
        if name == "passive" or name not in healthy.names:
            continue
        row: dict = {
            "healthy_rms": {},
            "faulted_rms": {},
            "change_percent": {},
            "healthy_reduction_percent": {},
            "reduction_percent": {},
        }
        worse = []
        for r in rms_f.response.values:
            f, h, p = (
                float(a.sel(response=r)) for a in (rms_f.sel(controller=name), rms_h.sel(controller=name), passive)
            )
            row["healthy_rms"][str(r)], row["faulted_rms"][str(r)] = h, f
            row["change_percent"][str(r)] = (f - h) / h * 100.0 if h else None
            row["healthy_reduction_percent"][str(r)] = (p - h) / p * 100.0 if p else None
            row["reduction_percent"][str(r)] = (p - f) / p * 100.0 if p else None
            if f > p:
                worse.append(str(r))
        row["worse_than_passive"] = worse
        out["controllers"][name] = row
    return out
