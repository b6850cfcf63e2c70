"""Plausible ranges of the vehicle and controller inputs: the one table of them, each parameter
class hands its own table to the field checks (`railride.validation.validate_fields`); the
vehicle's is rendered into docs/cli.md, Sizes and plausible ranges (`railride.model.params.ranges_markdown`).

Each input has an error range and, for the vehicle, a narrower typical range:

* outside the error range the value is no body, spring, damper or sensor at all (a carbody of a
  milligram, a spring a hundred times stiffer than the wheel-rail contact, sensor noise larger
  than the quantity it measures): a ValueError naming the field, the value and the range;
* inside it but outside the typical range (a vehicle parameter only) the value is possible but
  not a full-size rail vehicle: a scale model on a roller rig, a limit study (a rigid primary,
  a carbody held still). The run goes on and a `PlausibilityWarning` says so; the command line
  prints it on stderr, the frequency responses record it in their document.

Gains and sensor settings have error ranges only: they are the user's design variables, which a
tuning study moves by factors of 30, so that a warning per candidate would say nothing.
"""

from __future__ import annotations

from railride.validation import PlausibilityWarning as PlausibilityWarning, Range, atypical, shown

# -- the vehicle ---------------------------------------------------------------------------------
_MASS = "a body of less than a gram or more than a billion tonnes carries no suspension"
_INERTIA = "the mass ranges times radii of gyration from 3 cm to 10 m"
_STIFF = "softer than 1e-6 N/m is no spring; 1e11 N/m is 100 times the wheel-rail contact, two bodies made one"
_DAMP = "1e9 N s/m resists 1 m/s with 1e9 N, 10,000 times any rail damper"
_LONG = "from 1 mm to 100 m: a 200 m carbody or a 1 mm wheelbase is no rail vehicle"
_WIDE = "from 1 mm to 10 m: the widest gauge ever laid is 2.14 m"

VEHICLE: dict[str, Range] = {
    "m_c": Range(1e-3, 1e12, _MASS, (5e3, 1.5e5)),
    "m_b": Range(1e-3, 1e12, _MASS, (5e2, 2e4)),
    "I_cx": Range(1e-6, 1e14, _INERTIA, (1e3, 1e6)),
    "I_cy": Range(1e-6, 1e14, _INERTIA, (5e4, 3e7)),
    "I_cz": Range(1e-6, 1e14, _INERTIA, (5e4, 3e7)),
    "I_bx": Range(1e-6, 1e14, _INERTIA, (1e2, 5e4)),
    "I_by": Range(1e-6, 1e14, _INERTIA, (1e2, 5e4)),
    "I_bz": Range(1e-6, 1e14, _INERTIA, (1e2, 5e4)),
    **{k: Range(1e-6, 1e11, _STIFF, (1e5, 5e7)) for k in ("k_px", "k_py", "k_pz")},
    **{k: Range(0.0, 1e9, _DAMP, (0.0, 2e5)) for k in ("c_px", "c_py", "c_pz")},
    **{k: Range(1e-6, 1e11, _STIFF, (1e4, 5e6)) for k in ("k_sx", "k_sy", "k_sz")},
    # yaw dampers act longitudinally between bogie and carbody: up to about 2 MN s/m
    **{k: Range(0.0, 1e9, _DAMP, (0.0, 2e6)) for k in ("c_sx", "c_sy", "c_sz")},
    "l": Range(1e-3, 100.0, _LONG, (2.0, 15.0)),
    "b": Range(1e-3, 100.0, _LONG, (0.5, 2.0)),
    **{k: Range(1e-3, 10.0, _WIDE, (0.4, 1.5)) for k in ("d_s", "d_p", "a")},
    "h_cs": Range(1e-3, 10.0, _WIDE, (0.3, 3.0)),
    **{k: Range(1e-3, 10.0, _WIDE, (0.02, 1.0)) for k in ("h_ts", "h_tp", "h_wp")},
    # an anti-roll bar: 0 (none) to about 5 MN m/rad on the stiffest tilting and high-speed cars
    "k_ar": Range(0.0, 1e11, _STIFF, (0.0, 1e7)),
    "z_stop": Range(1e-4, 10.0, "from 0.1 mm to 10 m: the secondary of a rail vehicle travels tens of mm", (0.01, 0.2)),
    "k_stop": Range(0.0, 1e11, _STIFF, (0.0, 5e7)),
    # the carbody's bending mode: passenger cars are 10 to 30 m long and bend first at 7-15 Hz
    # (Zhou et al., Proc. IMechE F 223, 2009: 8-12 Hz typical); EI of a few 1e9 N m^2
    "L_c": Range(1e-3, 100.0, _LONG, (8.0, 35.0)),
    "f_bend": Range(
        1e-2, 1e3, "from 0.01 Hz, no carbody at all, to 1 kHz, a carbody as rigid as its bogies' wheelsets", (5.0, 25.0)
    ),
    "EI_c": Range(
        1e-3,
        1e14,
        "from a plastic strip's bending stiffness to 10,000 times a carbody's (about 1e9 to 1e10 N m^2)",
        (1e8, 1e11),
    ),
    "zeta_bend": Range(
        0.0, 1.0, "1 is critical damping: a carbody's structure damps its bending by 1-5 %", (0.005, 0.1)
    ),
}

# -- controllers and sensors ---------------------------------------------------------------------
_GAIN = (
    "1e14 demands 1e11 N for a millimetre (or a mrad, mm/s, mrad/s): no damper or actuator gives "
    "it; the shipped gains are 1e3 to 1e8"
)
_GAIN_RANGE = Range(0.0, 1e14, _GAIN)
_WEIGHT = "the square of the gains' bound: the LQR gain grows as the root of the weight"
_INNER = "the voltage is clipped to the damper's 0-10 V: beyond 1000 the loop is a switch already"
SENSOR_NOISE_WHY = "noise larger than the whole range of the quantity is no measurement"

INNER_LOOP: dict[str, Range] = {k: Range(0.0, 1e3, _INNER) for k in ("B", "G")}
PID: dict[str, Range] = {k: _GAIN_RANGE for k in ("kp", "ki", "kd")}
ATTITUDE: dict[str, Range] = {k: _GAIN_RANGE for k in ("kp_z", "kd_z", "kp_phi", "kd_phi", "kp_theta", "kd_theta")}
RIDE: dict[str, Range] = {f"{g}_{c}": _GAIN_RANGE for g in ("kp", "kd") for c in ("1R", "1L", "2R", "2L")}
SKYHOOK: dict[str, Range] = {k: _GAIN_RANGE for k in ("c_z", "c_phi", "c_theta")}
GROUNDHOOK: dict[str, Range] = {"c_g": _GAIN_RANGE}
HYBRID: dict[str, Range] = {k: _GAIN_RANGE for k in ("c_z", "c_phi", "c_theta", "c_g")}
CLIPPED_OPTIMAL: dict[str, Range] = {
    **{k: Range(0.0, 1e28, _WEIGHT) for k in ("q_z", "q_phi", "q_theta", "qd_z", "qd_phi", "qd_theta")},
    "r": Range(1e-12, 1e12, "only the ratios of the weights to r matter; past 1e12 they lose their digits"),
}
SENSOR_NOISE: dict[str, Range] = {
    "displacement": Range(0.0, 0.1, SENSOR_NOISE_WHY + ": the secondary suspension's travel is under 0.1 m"),
    "angle": Range(0.0, 0.1, SENSOR_NOISE_WHY + ": carbody pitch and roll are milliradians"),
    "velocity": Range(0.0, 1.0, SENSOR_NOISE_WHY + ": carbody heave velocities are cm/s"),
    "angular_rate": Range(0.0, 1.0, SENSOR_NOISE_WHY + ": carbody pitch and roll rates are mrad/s"),
}
ACCELEROMETERS: dict[str, Range] = {
    "noise": Range(0.0, 10.0, "1 g of noise per sample: 300 times a railway MEMS accelerometer's"),
    "bias": Range(-10.0, 10.0, "a bias of 1 g is a sensor mounted on its side, not a bias"),
    "antialias_hz": Range(1.0, 1e6, "below 1 Hz the filter removes the carbody modes it is there to measure"),
    "cutoff_hz": Range(1e-3, 1e6, "below 1 mHz the integral drifts with the bias for minutes"),
}

#: the factor on a damper's force capacity (`railride.secondary.suspension.damper_model`)
DAMPER_SCALE = Range(0.01, 100.0, "a hundredth to a hundred times the railway damper: 0.1 kN to 1 MN")


def notes(params, what: str = "vehicle parameter") -> list[str]:
    """The warnings of vehicle parameters ``params``: one line per field outside its typical
    range, and the `rigid_note` of a carbody length without a bending frequency."""
    rigid = rigid_note(params)
    return atypical(params, VEHICLE, what) + ([rigid] if rigid else [])


def rigid_note(params) -> str | None:
    """The note of vehicle parameters given a carbody length ``L_c`` but no bending frequency
    (neither ``f_bend`` nor ``EI_c``): the carbody runs rigid; None for any other."""
    if getattr(params, "L_c", None) is None or params.f_bend is not None or params.EI_c is not None:
        return None
    return (
        f"vehicle parameter 'L_c' = {shown(params.L_c)} m (carbody length) is given without 'f_bend' or 'EI_c': "
        "the carbody runs rigid; give one of them for its bending mode"
    )
