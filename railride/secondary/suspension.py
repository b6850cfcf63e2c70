"""What sits in the secondary suspension: the `Suspension` value.

Three kinds (`KINDS`):

* ``passive``: the vehicle's viscous secondary dampers c_sz (or a `dampers.Viscous` in their
  place);
* ``semi-active``: four MR dampers (`dampers.BoucWen`, `dampers.Spencer`) at a constant
  command voltage (open loop), or under an outer loop (`railride.secondary.control`: PID, SAS;
  `railride.secondary.controllers`: skyhook, groundhook, hybrid, clipped-optimal) whose demand the
  outer loop's voltage law turns into voltages (the paper's force-tracking inner loop, eq.
  12-14, on-off or clipped);
* ``ideal``: an ideal device under an outer loop (`dampers.Ideal`: the ideal actuator
  "ideal", force = demand; the ideal semi-active damper "ideal-damper"), with no inner loop
  and no voltage.

Simulation, comparison, sweeps and tuning all describe a run's secondary this way;
`Suspension.named` is the one place that turns a suspension name (`NAMES`: "passive", "mr",
the outer loops of `control.CONTROLLERS`, "passive-on", "passive-off") and a `GainSet` into
outer and inner loops.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass
from typing import Any

from railride.errors import InputError
from railride.secondary import dampers
from railride.engine import layout
from railride import validation
from railride.secondary.control import CONSTANT_VOLTAGE, CONTROLLERS, LABELS, GainSet, InnerLoop, SensorNoise
from railride.defaults import DEFAULT_DAMPER
from railride.secondary.faults import check_faults

#: the kinds of suspension, see `Suspension.kind`
KINDS = ("passive", "semi-active", "ideal")
#: the names `Suspension.named` knows: passive, MR dampers at a constant voltage, the outer loops,
#: the MR dampers at their highest and lowest voltage (passive-on, passive-off)
NAMES = ("passive", "mr", *CONTROLLERS[1:])


def damper_model(damper, damper_scale: float = 1.0):
    """The damper ``damper``, a name (`railride.secondary.dampers.preset`) or a model of
    `railride.secondary.dampers` (a user's own Bouc-Wen or Spencer damper), with its force capacity
    times ``damper_scale``; a scale other than 1 for an ideal device is an InputError (it has
    none). The one place a damper argument is resolved: every function that takes a damper
    name takes a model too."""
    scale = dampers.check_scale("damper_scale", damper_scale)
    if isinstance(damper, str):
        model = dampers.preset(damper)
    elif isinstance(damper, (dampers.Viscous, dampers.BoucWen, dampers.Ideal)):  # Spencer is a BoucWen
        model = damper
    else:
        raise InputError(
            f"damper = {damper!r}: must be a name ({', '.join(dampers.NAMES)}) or a model from "
            "railride.secondary.dampers"
        )
    if scale == 1.0:
        return model
    if model.law == dampers.LAW_IDEAL:
        raise InputError(
            f"damper_scale = {scale:g}: {dampers.ideal_words(model.model)} follows the demand and has no force "
            "capacity to scale (leave damper_scale at 1)"
        )
    if not hasattr(model, "scaled"):
        raise InputError(f"damper_scale = {scale:g}: a {model.model} damper has no force capacity to scale")
    return model.scaled(scale)


def damper_record(damper):
    """A damper argument as the records of results hold it: the name as given, or the model's
    record (``to_dict()``) for a model."""
    return damper if damper is None or isinstance(damper, str) else damper.to_dict()


def damper_label(damper) -> str:
    """A damper argument in a table's column: the name as given, else the model's preset name or
    its model name ("bouc-wen")."""
    return damper if isinstance(damper, str) else _damper_name(damper)


@functools.lru_cache(maxsize=1)
def _shipped_gains() -> GainSet:
    """The shipped gains, read once (every sweep case without a gain set asks for them)."""
    return GainSet.default()


def _damper_name(model) -> str:
    """A damper model by its preset name, else its model name ("bouc-wen" for a scaled one)."""
    return model.to_dict()["preset"] or model.model


def _model(damper):
    """A damper model from a name or a model; None stays None (the passive dashpots)."""
    if damper is None:
        return None
    if isinstance(damper, (str, dampers.Viscous, dampers.BoucWen, dampers.Ideal)):
        return damper_model(damper)
    raise InputError(
        f"damper = {damper!r}: must be None (passive), a name "
        f"({', '.join(dampers.NAMES)}) or a model from railride.secondary.dampers"
    )


@dataclass(frozen=True)
class Suspension:
    """The secondary vertical suspension of a run, checked at construction.

    ``damper``: None (the passive viscous dampers c_sz), a damper model from `railride.secondary.dampers`
    or its name (stored as the model). ``voltage`` [V]: the constant command of MR dampers in
    open loop (default their v_min, "passive-off"; the coils start there). ``controller``: the
    outer loop (`control.PID`, `control.SAS`, `control.ZeroDemand` for a closed loop with no
    outer loop; anything with ``gains(vehicle)``, ``name`` and ``to_dict()``); it makes the
    loop closed. ``inner``: the MR dampers' force-tracking loop (`control.InnerLoop`, default
    the shipped gains). ``sensor_noise``: `control.SensorNoise` on the controller's
    measurements. ``damper_scale``: the factor `semi_active` and `named` applied to the preset
    they were given by name, kept for the records of results (`damper_name`); it is not part of
    the value (a suspension equals one given the scaled model itself). Use the constructors
    `passive`, `semi_active`, `ideal` and `named`.

    Refused with a ValueError naming the field: a voltage with a controller, or without MR
    dampers; a controller on the viscous dampers or on none; an ideal device without a controller or with
    an inner loop; an inner loop or sensor noise without a controller; a voltage outside the
    damper's range. ``delay``: the controller's computation and communication delay in
    controller periods (1, the default: a demand takes effect one period after its sample;
    up to `railride.engine.layout.MAX_DELAY`; `with_delay`). ``faults``: dampers that fail during the
    run (`railride.secondary.faults.DamperFault`, or their text such as "1R-off" or "2L-on@2.5";
    `with_faults`), checked against the damper. ``sensing``: what the controller measures
    (`railride.secondary.sensing.Accelerometers`, `with_sensing`; None, the default: the exact states).
    """

    damper: Any = None
    voltage: float | None = None
    controller: Any = None
    inner: InnerLoop | None = None
    sensor_noise: SensorNoise | None = None
    damper_scale: float = dataclasses.field(default=1.0, compare=False, repr=False)
    faults: tuple = ()
    delay: int = 1
    sensing: Any = None

    def __post_init__(self):
        model = _model(self.damper)
        object.__setattr__(self, "damper", model)
        object.__setattr__(self, "faults", check_faults(self.faults, model))
        what = "controller periods from a sample of the states to its demand taking effect"
        object.__setattr__(self, "delay", validation.integer("delay", self.delay, 1, layout.MAX_DELAY, what))
        if self.delay != 1 and self.controller is None:
            raise InputError(f"delay = {self.delay}: applies to a closed loop only (give controller= as well)")
        if self.sensing is not None:
            from railride.secondary.sensing import Accelerometers

            if not isinstance(self.sensing, Accelerometers):
                raise InputError(
                    f"sensing = {self.sensing!r}: must be a railride.secondary.sensing.Accelerometers, or None"
                )
            if self.controller is None:
                raise InputError("sensing applies to a closed loop only (give controller= as well)")
            if self.sensor_noise is not None:
                raise InputError(
                    "sensing with sensor_noise: the accelerometers have their own noise; give one or the other"
                )
        object.__setattr__(self, "damper_scale", dampers.check_scale("damper_scale", self.damper_scale))
        c = self.controller
        missing = [] if c is None else [a for a in ("gains", "name", "to_dict") if not hasattr(c, a)]
        if missing:  # the interface of an outer loop of one's own, checked before any run
            raise InputError(
                f"controller = {c!r}: must be an outer loop from railride.secondary.control (PID, SAS, ZeroDemand) "
                "or railride.secondary.controllers, or one of your own with gains(vehicle), name and to_dict(); "
                f"this one has no {', '.join(missing)}"
            )
        if c is not None and getattr(c, "voltage_law", "tracking") not in dampers.VOLTAGE_LAWS:
            raise InputError(
                f"controller {c.name!r} voltage_law = {c.voltage_law!r}: allowed {', '.join(dampers.VOLTAGE_LAWS)}"
            )
        if self.inner is not None and not isinstance(self.inner, InnerLoop):
            raise InputError(f"inner = {self.inner!r}: must be a railride.secondary.control.InnerLoop")
        if self.sensor_noise is not None and not isinstance(self.sensor_noise, SensorNoise):
            raise InputError(f"sensor_noise = {self.sensor_noise!r}: must be a railride.secondary.control.SensorNoise")
        ideal = model is not None and model.law == dampers.LAW_IDEAL
        if c is None:
            for name in ("inner", "sensor_noise"):
                if getattr(self, name) is not None:
                    raise InputError(f"{name} applies to a closed loop only: give controller= as well")
            if ideal:
                raise InputError(
                    f"damper = {model.model!r}: {dampers.ideal_words(model.model)} follows an outer loop's "
                    "demand and needs controller= (PID or SAS); it has no voltage to set"
                    + (f" (got voltage = {self.voltage!r})" if self.voltage is not None else "")
                )
            if model is None or model.law == dampers.LAW_VISCOUS:
                if self.voltage is not None:
                    raise InputError(
                        f"voltage = {self.voltage!r}: applies to MR dampers only, give "
                        "damper= as well (the passive suspension has no command)"
                    )
                return
            voltage = model.v_min if self.voltage is None else self.voltage
            object.__setattr__(self, "voltage", model.check_voltage(voltage))
            return
        if self.voltage is not None:
            raise InputError(
                f"voltage = {self.voltage!r} with controller = {c.name!r}: give either "
                "voltage (open loop) or controller (closed loop), not both"
            )
        if model is None:
            raise InputError(
                f"controller = {c.name!r} with damper = None: a closed loop needs MR "
                "dampers or an ideal device (Suspension.semi_active or Suspension.ideal)"
            )
        if model.law == dampers.LAW_VISCOUS:
            raise InputError(
                f"controller = {c.name!r}: a controller needs MR dampers or the ideal "
                "actuator (a viscous damper has no command)"
            )
        if ideal:
            if self.inner is not None:
                raise InputError(
                    f"inner = {self.inner!r}: the ideal devices apply the demand themselves and have no inner loop"
                )
        elif self.inner is None:
            object.__setattr__(self, "inner", _shipped_gains().inner)

    def with_delay(self, periods: int) -> "Suspension":
        """This closed loop with a computation and communication delay of ``periods``
        controller periods (1: the demand takes effect one period after its sample)."""
        return dataclasses.replace(self, delay=periods)

    def with_sensing(self, sensing) -> "Suspension":
        """This closed loop measuring through ``sensing`` (`railride.secondary.sensing.Accelerometers`; None:
        the exact states) in place of the exact carbody states."""
        return dataclasses.replace(self, sensing=sensing)

    def with_faults(self, faults) -> "Suspension":
        """This suspension with ``faults`` (`railride.secondary.faults.DamperFault`, their text such as
        "1R-off", "2L-on@2.5", or a sequence of them) in place of its own."""
        return dataclasses.replace(self, faults=faults)

    # -- constructors --------------------------------------------------------------------------
    @classmethod
    def passive(cls, damper=None) -> "Suspension":
        """The passive viscous secondary dampers: the vehicle's c_sz, or ``damper`` (a
        `dampers.Viscous`) in their place."""
        if damper is not None and not isinstance(damper, dampers.Viscous):
            raise InputError(
                f"damper = {damper!r}: the passive suspension takes a "
                "railride.secondary.dampers.Viscous or None (the vehicle's c_sz)"
            )
        return cls(damper)

    @classmethod
    def semi_active(
        cls,
        damper=DEFAULT_DAMPER,
        voltage=None,
        controller=None,
        inner=None,
        sensor_noise=None,
        damper_scale: float = 1.0,
    ) -> "Suspension":
        """MR dampers (a name of `dampers.PRESETS` or a `BoucWen` / `Spencer` model, scaled by
        ``damper_scale``, `BoucWen.scaled`) at the constant ``voltage`` [V]
        (default v_min), or closed by ``controller`` and the inner loop ``inner`` (default the
        shipped gains), the controller seeing ``sensor_noise``."""
        model = damper_model(damper, damper_scale)  # a name or a model, scaled
        if model is None or model.law not in (dampers.LAW_BOUC_WEN, dampers.LAW_SPENCER):
            raise InputError(
                f"damper = {damper!r}: a semi-active suspension has MR dampers ("
                f"{', '.join(dampers.PRESETS)} or a BoucWen / Spencer model); the "
                "ideal devices are Suspension.ideal, the dashpots Suspension.passive"
            )
        return cls(model, voltage, controller, inner, sensor_noise, damper_scale)

    @classmethod
    def ideal(cls, controller, dissipative: bool = False, sensor_noise=None) -> "Suspension":
        """An ideal device under ``controller``: the ideal actuator (force = demand), or with
        ``dissipative`` the ideal semi-active damper (the demand where it dissipates, else 0)."""
        if controller is None:
            raise InputError(
                "controller = None: an ideal device applies an outer loop's demand; "
                "give one (PID, SAS, or ZeroDemand for none)"
            )
        if not isinstance(dissipative, bool):
            raise InputError(f"dissipative = {dissipative!r}: must be True or False")
        return cls(dampers.IDEAL_DAMPER if dissipative else dampers.IDEAL, None, controller, None, sensor_noise)

    @classmethod
    def named(
        cls,
        name: str,
        gains: GainSet | None = None,
        damper=DEFAULT_DAMPER,
        damper_scale: float = 1.0,
        voltage=None,
        sensor_noise=None,
    ) -> "Suspension":
        """The suspension the package calls ``name`` (`NAMES`): "passive"; "mr", the MR
        ``damper`` (a name, scaled by ``damper_scale``) at the constant ``voltage``;
        "passive-on" / "passive-off", the same at its v_max / v_min; or an outer loop of
        ``gains`` (default the shipped `GainSet.default`) with its inner loop on the MR dampers,
        or on the ideal device when ``damper`` is "ideal" or "ideal-damper". ``damper`` is not
        used by "passive", but must be a known name; a scale other than 1 there is refused, as
        is a voltage with a controller or with passive-on / passive-off (their name sets it),
        and an ideal device with mr, passive-on or passive-off (it has no voltage)."""
        if not isinstance(name, str) or name not in NAMES:
            raise InputError(f"suspension = {name!r}; allowed: {', '.join(NAMES)}")
        if gains is not None:  # a GainSet, or what names one (a shipped set, a gains file)
            gains = GainSet.of(gains)
        model = damper_model(damper, 1.0)  # an unknown name fails here, for passive too
        if name == "passive":
            scale = dampers.check_scale("damper_scale", damper_scale)
            if scale != 1.0:
                raise InputError(
                    f"damper_scale = {scale:g}: the passive viscous dampers have no force "
                    "capacity to scale; it applies to MR dampers only"
                )
            if voltage is not None:
                raise InputError(
                    f"voltage = {voltage!r}: applies to suspension 'mr' only (the passive suspension has no command)"
                )
            return cls(None, None, None, None, sensor_noise)
        if (name == "mr" or name in CONSTANT_VOLTAGE) and model.law == dampers.LAW_IDEAL:
            raise InputError(
                f"damper = {damper!r} with suspension {name!r}: {dampers.ideal_words(model.model)} follows a "
                "controller's demand and has no constant voltage; it needs a controller (a suspension "
                "named after one, e.g. 'sas-attitude'), as railride compare --damper ideal and railride "
                "sweep --damper ideal run it"
            )
        model = damper_model(damper, damper_scale)
        scale = float(damper_scale)
        if name == "mr":
            return cls(model, voltage, None, None, sensor_noise, scale)
        if name in CONSTANT_VOLTAGE:
            if voltage is not None:
                raise InputError(
                    f"voltage = {voltage!r} with suspension {name!r}: its voltage is the damper's "
                    f"{CONSTANT_VOLTAGE[name]}; give a voltage with suspension 'mr'"
                )
            return cls(model, getattr(model, CONSTANT_VOLTAGE[name]), None, None, sensor_noise, scale)
        gains = _shipped_gains() if gains is None else gains
        controller = gains.controller(name)
        if model.law == dampers.LAW_IDEAL:
            return cls(model, voltage, controller, None, sensor_noise, scale)
        return cls(model, voltage, controller, gains.inner, sensor_noise, scale)

    # -- what it is ----------------------------------------------------------------------------
    @property
    def kind(self) -> str:
        """ "passive", "semi-active" or "ideal" (`KINDS`)."""
        if self.damper is None or self.damper.law == dampers.LAW_VISCOUS:
            return "passive"
        return "ideal" if self.damper.law == dampers.LAW_IDEAL else "semi-active"

    @property
    def closed_loop(self) -> bool:
        """Whether an outer loop sets the demand."""
        return self.controller is not None

    @property
    def name(self) -> str:
        """The name as `named` spells it: passive, mr, or the outer loop's name."""
        if self.closed_loop:
            return self.controller.name
        return "passive" if self.kind == "passive" else "mr"

    @property
    def damper_name(self) -> str | None:
        """The damper by the name it was given: the preset (`dampers.NAMES`) that, scaled by
        `damper_scale`, is the model; else the model's name ("bouc-wen"); None when passive
        on the vehicle's c_sz."""
        if self.damper is None:
            return None
        if self.damper_scale != 1.0:
            for name, preset in dampers.PRESETS.items():
                if preset.scaled(self.damper_scale) == self.damper:
                    return name
        return _damper_name(self.damper)

    @property
    def label(self) -> str:
        """A short text for tables and plots."""
        if self.kind == "passive":
            return "Passive"
        if not self.closed_loop:
            return f"{_damper_name(self.damper)} MR dampers at {self.voltage:g} V"
        text = LABELS.get(self.name) or str(getattr(self.controller, "label", None) or self.name)
        return text if self.kind == "semi-active" else f"{text} ({self.damper.model})"

    def describe(self) -> str:
        """What sits in the secondary, in words (the ``suspension`` attribute of a Dataset)."""
        if self.damper is None:
            return "passive viscous secondary dampers"
        if self.kind == "ideal":
            return "ideal secondary force actuators (force = held demand), closed loop"
        if not self.closed_loop:
            return f"{self.damper.model} secondary dampers at constant command voltage"
        return f"{self.damper.model} secondary dampers, closed loop"

    def to_dict(self) -> dict:
        """The JSON record of the suspension: kind, name, the damper model, voltage, outer and
        inner loop gains, sensor noise (None where it has none)."""
        c = self.controller
        return {
            "kind": self.kind,
            "name": self.name,
            "label": self.label,
            "damper": None if self.damper is None else self.damper.to_dict(),
            "voltage_v": self.voltage,
            "controller": None if c is None else {"name": c.name, "gains": c.to_dict()},
            "inner_loop": None if self.inner is None else self.inner.to_dict(),
            "sensor_noise": None if self.sensor_noise is None else dataclasses.asdict(self.sensor_noise),
            **({"faults": [f.label for f in self.faults]} if self.faults else {}),
            **({"delay_periods": self.delay} if self.delay != 1 else {}),
            **({"sensing": self.sensing.to_dict()} if self.sensing is not None else {}),
        }


def batch_conflict(suspensions) -> str | None:
    """Why ``suspensions`` cannot run as one batch, or None if they can: a batch shares one
    damper model, inner loop and sensor noise, and is all open or all closed loop (the
    voltages and the outer loops may differ)."""

    def shown(field, value):  # a damper by its preset name or model, the rest as they print
        if field == "damper" and value is not None:
            return repr(_damper_name(value))
        return repr(value)

    first = suspensions[0]
    for i, s in enumerate(suspensions[1:], start=1):
        if s is first:  # a batch often repeats one suspension
            continue
        for field in ("damper", "closed_loop", "inner", "sensor_noise", "sensing"):
            a, b = getattr(first, field), getattr(s, field)
            if a != b:
                return (
                    f"a batch of suspensions shares one damper model, inner loop and sensor "
                    f"noise, and is all open or all closed loop; suspension {i} has {field} = "
                    f"{shown(field, b)}, suspension 0 has {shown(field, a)}: run them separately"
                )
    return None
