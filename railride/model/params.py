"""Vehicle parameter sets: frozen, validated at construction, named presets, TOML round trip.

Symbols follow the appendix of Harun et al. (the paper; see docs/model.md, Parameters). Every
field carries its SI unit and the rule it must satisfy in its metadata;
`VehicleParams.describe()` lists them.
"""

from __future__ import annotations

import dataclasses
import warnings
import os
from dataclasses import MISSING, dataclass
from pathlib import Path

from railride.errors import InputError
from railride._io import atomic_write_text
from railride.model.plausible import VEHICLE, rigid_note
from railride.validation import param, parse_toml, rule_words, shown, validate_fields


@dataclass(frozen=True)
class VehicleParams:
    """Parameters of the 9-DOF vertical vehicle model (SI units, the paper's appendix).

    Suspension values are per element: one spring and one damper at each corner or axle box,
    as in the element table of docs/model.md, Equations.
    """

    m_c: float = param("kg", "carbody mass")
    m_b: float = param("kg", "bogie mass (each bogie)")
    I_cx: float = param("kg m^2", "carbody roll moment of inertia")
    I_cy: float = param("kg m^2", "carbody pitch moment of inertia")
    I_cz: float = param("kg m^2", "carbody yaw moment of inertia (not used by the vertical model)")
    I_bx: float = param("kg m^2", "bogie roll moment of inertia")
    I_by: float = param("kg m^2", "bogie pitch moment of inertia")
    I_bz: float = param("kg m^2", "bogie yaw moment of inertia (not used by the vertical model)")
    k_px: float = param("N/m", "primary longitudinal stiffness, per axle box")
    k_py: float = param("N/m", "primary lateral stiffness, per axle box")
    k_pz: float = param("N/m", "primary vertical stiffness, per axle box")
    c_px: float = param("N s/m", "primary longitudinal damping, per axle box", "nonnegative")
    c_py: float = param("N s/m", "primary lateral damping, per axle box", "nonnegative")
    c_pz: float = param("N s/m", "primary vertical damping, per axle box", "nonnegative")
    k_sx: float = param("N/m", "secondary longitudinal stiffness, per side of each bogie")
    k_sy: float = param("N/m", "secondary lateral stiffness, per side of each bogie")
    k_sz: float = param("N/m", "secondary vertical stiffness, per corner")
    c_sx: float = param("N s/m", "secondary longitudinal damping, per side of each bogie", "nonnegative")
    c_sy: float = param("N s/m", "secondary lateral damping, per side of each bogie", "nonnegative")
    c_sz: float = param("N s/m", "secondary vertical (passive) damping, per corner", "nonnegative")
    l: float = param("m", "half bogie-centre spacing")
    d_s: float = param("m", "half lateral spacing of the secondary suspension")
    d_p: float = param("m", "half lateral spacing of the primary suspension")
    a: float = param("m", "half wheel-rail contact spacing")
    b: float = param("m", "half wheelbase")
    h_cs: float = param("m", "carbody CG height above the secondary suspension")
    h_ts: float = param("m", "bogie CG depth below the secondary suspension")
    h_tp: float = param("m", "bogie CG height above the primary suspension")
    h_wp: float = param("m", "wheelset CG depth below the primary suspension")
    # -- beyond the paper's appendix: optional, a file without them keeps the paper's model --
    k_ar: float = param(
        "N m/rad", "anti-roll bar roll stiffness between the carbody and each bogie", "nonnegative", 0.0
    )
    z_stop: float | None = param(
        "m", "secondary vertical clearance to the bump stops, either way (none: no stops)", "positive", None
    )
    k_stop: float = param("N/m", "bump-stop stiffness beyond the clearance, per corner", "nonnegative", 0.0)
    # the carbody's first vertical bending mode (docs/model.md, Flexible carbody): none of
    # f_bend, EI_c keeps the carbody rigid (the paper's nine DOFs)
    L_c: float | None = param("m", "carbody length (for its bending mode; none: not given)", "positive", None)
    f_bend: float | None = param(
        "Hz",
        "first vertical bending frequency of the free carbody at this mass (none: a rigid carbody)",
        "positive",
        None,
    )
    EI_c: float | None = param(
        "N m^2", "carbody vertical bending stiffness, instead of f_bend (none: not given)", "positive", None
    )
    zeta_bend: float = param("1", "modal damping ratio of the carbody's bending mode", "nonnegative", 0.02)

    def __post_init__(self) -> None:
        validate_fields(self, "vehicle parameter", VEHICLE, then=self._check_wheelbase)

    def _check_wheelbase(self) -> None:
        if self.k_stop > 0.0 and self.z_stop is None:
            raise InputError(
                f"vehicle parameter 'k_stop' = {shown(self.k_stop)} (bump-stop stiffness, N/m): needs 'z_stop', "
                "the clearance to the stops (m, > 0)"
            )
        if not self.b < self.l:
            raise InputError(
                f"vehicle parameter 'b' = {shown(self.b)} (half wheelbase, m): must be below 'l' = {shown(self.l)} "
                "(half bogie-centre spacing, m): the two bogies' wheelsets would pass each other"
            )
        self._check_bending()

    def _check_bending(self) -> None:
        """The bending mode's fields together: flexible with L_c and exactly one of f_bend,
        EI_c; L_c beyond the outer wheelsets; L_c alone runs rigid and says so."""
        given = [n for n in ("f_bend", "EI_c") if getattr(self, n) is not None]
        if len(given) == 2:
            raise InputError(
                f"vehicle parameters 'f_bend' = {shown(self.f_bend)} Hz and 'EI_c' = {shown(self.EI_c)} N m^2: give "
                "one of them, the carbody's bending frequency or its bending stiffness, not both"
            )
        if given and self.L_c is None:
            raise InputError(
                f"vehicle parameter {given[0]!r} = {shown(getattr(self, given[0]))} needs 'L_c', the carbody "
                "length (m), for the carbody's bending mode"
            )
        if self.L_c is not None and not self.L_c > 2.0 * (self.l + self.b):
            raise InputError(
                f"vehicle parameter 'L_c' = {shown(self.L_c)} (carbody length, m): must exceed 2 (l + b) = "
                f"{shown(2.0 * (self.l + self.b))} m, the span of the outer wheelsets, which lie under the body"
            )
        if self.L_c is not None and not given:
            import warnings

            from railride.validation import PlausibilityWarning, caller_level

            note = rigid_note(self)
            if note is not None:
                warnings.warn(note, PlausibilityWarning, stacklevel=caller_level())

    @property
    def flexible(self) -> bool:
        """Whether the carbody bends (its first vertical bending mode, a tenth DOF): f_bend or
        EI_c given."""
        return self.f_bend is not None or self.EI_c is not None

    @property
    def bending_hz(self) -> float | None:
        """The first vertical bending frequency [Hz] of the free carbody at this mass: f_bend,
        or the free-free beam's from EI_c, m_c and L_c (`railride.model.beam`); None when rigid."""
        if self.f_bend is not None:
            return self.f_bend
        if self.EI_c is not None:
            from railride.model.beam import bending_frequency

            assert self.L_c is not None  # checked at construction: EI_c needs L_c
            return bending_frequency(self.EI_c, self.m_c, self.L_c)
        return None

    # -- presets --------------------------------------------------------------------------
    @classmethod
    def of(cls, value) -> "VehicleParams":
        """``value`` as parameters: None (the `paper` preset), a preset name, the path of a
        parameters file (`resolve`), or a VehicleParams."""
        if value is None or isinstance(value, (str, os.PathLike, VehicleParams)) or _vehicle_params(value):
            return cls.resolve(value, "params")[0]
        # a common slip: simulate(scenario, suspension) puts the suspension in params
        suspension = hasattr(value, "controller") and hasattr(value, "damper")  # a Suspension, not imported here
        hint = " (a Suspension is the third argument, suspension=)" if suspension else ""
        raise InputError(
            f"params = {value!r}: must be VehicleParams, a Vehicle, a preset name ({', '.join(PRESETS)}) or the path "
            f"of a parameters file (FILE.toml){hint}"
        )

    @classmethod
    def resolve(cls, value, field: str = "vehicle") -> tuple["VehicleParams", str | Path | None]:
        """(the parameters, where they came from) of ``value``: None (the `paper` preset), a
        preset name (one of `PRESETS`), the path of a parameters file (an os.PathLike, or a
        str that ends in ".toml" or names a file), VehicleParams (its preset's name if it is
        one, else None) or a `Vehicle` (its parameters). A str that is neither a preset nor a file: an InputError naming
        ``field`` (the argument or option), the presets and that a FILE.toml is accepted."""
        if value is None:
            value = "paper"
        if isinstance(value, str):
            if value in PRESETS:
                return PRESETS[value], value
            if value.endswith(".toml") or Path(value).is_file() or Path(value).is_dir():  # a folder: load says so
                return cls.load(Path(value)), Path(value)
            raise InputError(
                f"{field} = {value!r}: unknown vehicle preset, and no such file; allowed: a preset "
                f"({', '.join(PRESETS)}) or the path of a FILE.toml with a [vehicle] table"
            )
        if isinstance(value, os.PathLike):
            return cls.load(Path(value)), Path(value)
        if _vehicle_params(value):  # a Vehicle (railride.model.vehicle, above this module): its parameters
            value = value.params
        if isinstance(value, VehicleParams):
            return value, next((name for name, p in PRESETS.items() if p == value), None)
        raise InputError(
            f"{field} = {value!r}: must be VehicleParams, a Vehicle, a preset name "
            f"({', '.join(PRESETS)}) or the path of a parameters file (FILE.toml)"
        )

    @classmethod
    def preset(cls, name: str = "paper") -> "VehicleParams":
        """A named parameter set; see `PRESETS` for the names."""
        try:
            return PRESETS[name]
        except KeyError:
            raise InputError(f"unknown vehicle preset {name!r}; allowed: {', '.join(sorted(PRESETS))}") from None

    def replace(self, **changes: float) -> "VehicleParams":
        """A copy with some fields changed (validated like any new set)."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise InputError(
                f"unknown vehicle parameter(s) {', '.join(sorted(unknown))}; "
                f"allowed: {', '.join(f.name for f in dataclasses.fields(self))}"
            )
        return dataclasses.replace(self, **changes)

    def rigid(self) -> "VehicleParams":
        """The same vehicle with a rigid carbody (its bending mode off: no L_c, f_bend, EI_c); in a
        TOML file, ``rigid_carbody = true``."""
        return dataclasses.replace(self, L_c=None, f_bend=None, EI_c=None)

    def loaded(self, load: float) -> "VehicleParams":
        """The vehicle with a payload: the carbody's mass and moments of inertia times ``load``
        (the load factor, a finite number > 0: 1 the carbody as these parameters give it, 1.3 a
        crush-laden car with 30 % more mass). The payload is taken as spread like the carbody's
        own mass, so its radii of gyration stay; the bogies, wheelsets and suspensions stay as
        they are, and a controller keeps the gains it was given. A bending carbody keeps its
        bending stiffness: f_bend falls by 1/sqrt(load) (EI_c stays)."""
        from railride.validation import number

        factor = number("load", load, "positive", allowed="a finite number > 0 (the factor on the carbody mass)")
        carbody = ("m_c", "I_cx", "I_cy", "I_cz")
        changes = {n: factor * getattr(self, n) for n in carbody}
        if self.f_bend is not None:  # the same EI: the bending frequency falls as 1/sqrt(mass)
            changes["f_bend"] = self.f_bend / factor**0.5
        try:
            return self.replace(**changes)
        except InputError as exc:  # the factor is the user's input: name it, then the field it broke
            raise InputError(f"load = {factor:g}: the loaded carbody is no vehicle: {exc}") from None

    def load_changes(self, load: float, stiffness: float = 1.0) -> tuple:
        """The (field, value) changes of a payload (`loaded`) and of a secondary stiffness
        tolerance (k_sz times ``stiffness``, a finite number > 0: 0.9 and 1.1 for +-10 %), as a
        sweep's `Case.vehicle` holds them; none for factors of 1, so that the run keys of the
        nominal vehicle stay as they were."""
        from railride.validation import number

        changes: tuple = ()
        if load != 1.0:
            loaded = self.loaded(load)
            carbody = ("m_c", "I_cx", "I_cy", "I_cz") + (("f_bend",) if self.f_bend is not None else ())
            changes += tuple((n, getattr(loaded, n)) for n in carbody)
        k = number("stiffness", stiffness, "positive", allowed="a finite number > 0 (the factor on k_sz)")
        if k != 1.0:
            try:  # the factor is the user's input: name it, then the field it broke
                with warnings.catch_warnings():  # the run's own vehicle warns, once
                    warnings.simplefilter("ignore")
                    self.replace(k_sz=k * self.k_sz)
            except InputError as exc:
                raise InputError(f"stiffness = {k:g}: the secondary spring is no spring: {exc}") from None
            changes += (("k_sz", k * self.k_sz),)
        return changes

    def to_dict(self) -> dict[str, float]:
        return dataclasses.asdict(self)

    @classmethod
    def describe(cls) -> list[tuple[str, str, str, str]]:
        """(name, unit, meaning, rule) for every field."""
        return [
            (f.name, f.metadata["unit"], f.metadata["doc"], rule_words(f.metadata["rule"]))
            for f in dataclasses.fields(cls)
        ]

    # -- TOML -----------------------------------------------------------------------------
    def to_toml(self) -> str:
        """TOML text of all fields under ``[vehicle]``; `from_toml` reads it back exactly.

        Floats are written with ``repr``, the shortest text that parses back to the same
        double, so the round trip is lossless.
        """
        lines = ["# railride vehicle parameters (SI units)", "[vehicle]"]
        if not self.flexible:  # said, so that reading it back gives no warning of a rigid carbody
            lines.append("rigid_carbody = true  # the carbody does not bend (no L_c with f_bend or EI_c)")
        for name, unit, doc, _ in self.describe():
            value = getattr(self, name)
            if value is None:  # an element left out: TOML has no null
                lines.append(f"# {name} not set  # {unit}: {doc}")
                continue
            lines.append(f"{name} = {value!r}  # {unit}: {doc}")
        return "\n".join(lines) + "\n"

    def save(self, path: str | Path) -> None:
        atomic_write_text(Path(path), self.to_toml())

    @classmethod
    def from_toml(cls, text: str, source: str = "<string>") -> "VehicleParams":
        """Parse TOML with a ``[vehicle]`` table.

        The table either lists every field, or names a base with ``preset = "paper"`` and
        lists only the fields that differ from it.
        """
        data = parse_toml(text, source)
        table = data.get("vehicle")
        if not isinstance(table, dict):
            raise InputError(f"{source}: needs a [vehicle] table of parameters")
        table = dict(table)
        names = [f.name for f in dataclasses.fields(cls)]
        base_name = table.pop("preset", None)
        if base_name is not None and (not isinstance(base_name, str) or base_name not in PRESETS):
            raise InputError(
                f"{source}: [vehicle] preset = {shown(base_name)}: unknown vehicle preset; "
                f"allowed: {', '.join(sorted(PRESETS))}"
            )
        rigid = table.pop("rigid_carbody", None)  # a preset's flexible carbody switched off (None: not said)
        if rigid is not None and not isinstance(rigid, bool):
            raise InputError(f"{source}: [vehicle] rigid_carbody = {shown(rigid)}: must be true or false")
        frequency = [n for n in ("f_bend", "EI_c") if n in table]
        if rigid and frequency:  # L_c alone may stay: to_toml writes it with the switch for a rigid body
            raise InputError(
                f"{source}: [vehicle] rigid_carbody = true and {frequency[0]} = {shown(table[frequency[0]])}: give "
                "one of them, a rigid carbody or its bending mode, not both"
            )
        if rigid is False and not frequency and (base_name is None or not PRESETS[base_name].flexible):
            preset = "" if base_name is None else f" or its preset {base_name!r}"
            raise InputError(
                f"{source}: [vehicle] rigid_carbody = false, but the file{preset} gives the carbody no bending "
                "mode; give L_c with f_bend or EI_c, or leave rigid_carbody out"
            )
        unknown = sorted(set(table) - set(names))
        if unknown:
            raise InputError(
                f"{source}: unknown vehicle parameter(s) {', '.join(unknown)}; allowed: {', '.join(names)}"
            )
        if base_name is not None:
            base = PRESETS[base_name]
        else:
            missing = [f.name for f in dataclasses.fields(cls) if f.name not in table and f.default is MISSING]
            if missing:
                raise InputError(
                    f"{source}: missing vehicle parameter(s) {', '.join(missing)} "
                    '(list them all, or start from a base with preset = "paper")'
                )
        if rigid:
            table.update(L_c=None, f_bend=None, EI_c=None)
        elif base_name is None and not {"L_c", "f_bend", "EI_c"} & set(table):
            import warnings

            from railride.validation import PlausibilityWarning, caller_level

            warnings.warn(
                f"{source}: the file gives no bending mode of the carbody (L_c with f_bend or EI_c): it runs rigid",
                PlausibilityWarning,
                stacklevel=caller_level(),
            )
        try:
            return base.replace(**table) if base_name is not None else cls(**table)
        except ValueError as exc:  # the field's rule: name the file and table too
            raise InputError(f"{source}: [vehicle] {exc}") from None

    @classmethod
    def load(cls, path: str | Path) -> "VehicleParams":
        path = Path(path)
        if path.is_dir():  # reading it fails with an OS's own words ("Is a directory", "Permission denied")
            raise InputError(
                f"vehicle parameters {path}: a folder, not a vehicle file; give the path of a FILE.toml with a "
                "[vehicle] table"
            )
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as exc:
            raise InputError(f"cannot read vehicle parameters from {path}: {exc.strerror}") from None
        except UnicodeDecodeError:
            raise InputError(f"vehicle parameters file {path}: not a UTF-8 text TOML file") from None
        return cls.from_toml(text, source=str(path))


# -- the vehicle of a run, as its outputs record it ----------------------------------------------
def vehicle_argument(vehicle=None, params=None):
    """The vehicle given to a function that takes ``vehicle=`` and its alias ``params=``: the one
    given, None for neither; an InputError for both."""
    if vehicle is not None and params is not None:
        raise InputError("vehicle and params: give the vehicle once (params is an alias of vehicle)")
    return params if vehicle is None else vehicle


def vehicle_name(params: VehicleParams, source=None) -> str:
    """How the outputs name a vehicle: the preset's name, the parameters file's path, or
    "custom" for values that are no preset (``source`` as `VehicleParams.resolve` gives it)."""
    if source is not None:
        return str(source)
    return next((name for name, p in PRESETS.items() if p == params), "custom")


def vehicle_record(params: VehicleParams, source=None, load=1.0) -> dict:
    """The record of the vehicle that every output keeps (the JSON documents, the NetCDF
    attributes, the report, the tables' captions): ``name`` (`vehicle_name`), ``load`` (the
    load factor on the carbody's mass and inertias, `VehicleParams.loaded`; the list of them
    where a study runs several) and ``values`` (`to_dict` of ``params``, before the load)."""
    from railride.validation import number

    allowed = "a finite number > 0 (the factor on the carbody mass)"
    loads = [
        float(number("load", x, "positive", allowed=allowed))
        for x in (load if isinstance(load, (list, tuple)) else [load])
    ]
    if not loads:
        raise InputError("load: give at least one load factor")
    return {
        "name": vehicle_name(params, source),
        "load": loads[0] if len(loads) == 1 else loads,
        "values": params.to_dict(),
    }


def _vehicle_params(value) -> bool:
    """Whether ``value`` is a `railride.model.vehicle.Vehicle` (it holds its parameters)."""
    return not isinstance(value, VehicleParams) and isinstance(getattr(value, "params", None), VehicleParams)


def resolve_argument(vehicle=None, params=None, field: str = "vehicle") -> tuple[VehicleParams, str | Path | None]:
    """`VehicleParams.resolve` of a function's ``vehicle=`` or its alias ``params=``
    (`vehicle_argument`), its errors naming the one given (``field``: the name of ``vehicle``)."""
    return VehicleParams.resolve(vehicle_argument(vehicle, params), field if params is None else "params")


def resolve_vehicle(vehicle=None, params=None, load=1.0, field: str = "vehicle") -> tuple[VehicleParams, dict]:
    """(the vehicle to run, its `vehicle_record`) of a function's ``vehicle=`` (or its alias
    ``params=``: a preset name, a parameters file or VehicleParams, `VehicleParams.resolve`)
    and ``load`` factor: the edge where every study resolves its vehicle, once."""
    base, source = resolve_argument(vehicle, params, field)
    record = vehicle_record(base, source, load)
    return (base if record["load"] == 1.0 else base.loaded(record["load"])), record


def vehicle_text(record: dict) -> str:
    """One line of a table's caption from a `vehicle_record`: "vehicle: paper, load 1"."""
    load = record["load"]
    loads = f"loads {', '.join(f'{x:g}' for x in load)}" if isinstance(load, list) else f"load {load:g}"
    return f"vehicle: {record['name']}, {loads}"


#: The paper's appendix (Harun et al.), in SI units.
PAPER = VehicleParams(
    m_c=3.96e4,
    m_b=3.25e3,
    I_cx=8.85e4,
    I_cy=2.46e6,
    I_cz=2.5e6,
    I_bx=3.06e3,
    I_by=3.02e3,
    I_bz=4.27e3,
    k_px=4e6,
    k_py=3.25e6,
    k_pz=7e6,
    c_px=0.0,
    c_py=0.0,
    c_pz=1.5e4,
    k_sx=1.5e5,
    k_sy=1.5e5,
    k_sz=2.9e5,
    c_sx=0.0,
    c_sy=5e4,
    c_sz=8e4,
    l=9.0,
    d_s=1.0,
    d_p=1.0,
    a=1.0,
    b=1.25,
    h_cs=1.207,
    h_ts=0.217,
    h_tp=0.452,
    h_wp=0.18,
    # the paper gives no bump stops: travel is reported against an assumed clearance, with no
    # stop force, so that the paper's case stays the paper's model (docs/model.md, Presets)
    z_stop=0.08,
    k_stop=0.0,
)

#: The Manchester Benchmark passenger vehicle (Iwnicki, ed., "The Manchester Benchmarks for Rail
#: Vehicle Simulation", Supplement to Vehicle System Dynamics 31, 1999; Vehicle System Dynamics
#: 30, 1998). The source's values are marked; the rest are assumed (docs/model.md, Presets).
MANCHESTER_1 = VehicleParams(
    m_c=3.2e4,  # source
    m_b=2615.0,  # source (bogie frame)
    I_cx=5.68e4,  # source
    I_cy=1.97e6,  # source
    I_cz=1.97e6,  # assumed: as the pitch inertia (a long, slender body)
    I_bx=1722.0,  # source
    I_by=1476.0,  # source
    I_bz=3198.0,  # assumed: I_bx + I_by (a flat frame)
    k_px=3.0e7,  # assumed: stiff longitudinal wheelset guidance
    k_py=4.0e6,  # assumed
    k_pz=1.22e6,  # source (some copies print 1,200 kN/m)
    c_px=0.0,  # assumed: no longitudinal primary dampers
    c_py=0.0,  # assumed: no lateral primary dampers
    c_pz=4.0e3,  # source
    k_sx=1.6e5,  # source
    k_sy=1.6e5,  # source
    k_sz=4.3e5,  # source, per side of each bogie
    c_sx=0.0,  # assumed: no longitudinal dampers (yaw dampers act in yaw, not modelled)
    c_sy=3.0e4,  # assumed: a lateral damper per side
    c_sz=2.0e4,  # source, per side of each bogie
    l=9.5,  # source
    d_s=1.0,  # source
    d_p=1.0,  # source
    a=0.7465,  # assumed: half the 1.493 m contact spacing of standard gauge
    b=1.28,  # source
    h_cs=PAPER.h_cs,  # heights assumed: the paper's
    h_ts=PAPER.h_ts,
    h_tp=PAPER.h_tp,
    h_wp=PAPER.h_wp,
    k_ar=9.4e5,  # source, per bogie
    z_stop=0.04,  # assumed
    k_stop=2.0e6,  # assumed
    L_c=23.0,  # assumed: a 23 m coach body over the 19 m bogie spacing
    f_bend=10.0,  # assumed: the middle of the 8-12 Hz of passenger carbodies (Zhou et al. 2009)
    zeta_bend=0.02,  # assumed: 2 % modal damping
)

#: A CRH380A-type high-speed car: values as given for a CRH380A-type car in the published
#: high-speed vehicle-dynamics literature where marked "source", the others assumed
#: (docs/model.md, Presets).
CRH380A = VehicleParams(
    m_c=43862.5,  # source
    m_b=2400.0,  # source
    I_cx=1.094e5,  # source
    I_cy=1.654e6,  # source
    I_cz=1.654e6,  # assumed: as the pitch inertia
    I_bx=1944.0,  # source
    I_by=1314.0,  # source
    I_bz=3258.0,  # assumed: I_bx + I_by
    k_px=1.5e7,  # assumed
    k_py=6.0e6,  # assumed
    k_pz=1.176e6,  # source
    c_px=0.0,  # assumed
    c_py=0.0,  # assumed
    c_pz=1.0e4,  # assumed: a primary vertical damper per axle box
    k_sx=1.5e5,  # assumed: an air spring's shear stiffness
    k_sy=1.5e5,  # assumed
    k_sz=1.9e5,  # source, per side of each bogie (air spring)
    c_sx=0.0,  # assumed
    c_sy=3.0e4,  # assumed: a lateral damper per side
    c_sz=4.0e4,  # source, per side of each bogie
    l=8.75,  # source
    d_s=1.23,  # source
    d_p=1.0,  # source
    a=0.7465,  # assumed: standard gauge
    b=1.25,  # source
    h_cs=PAPER.h_cs,  # heights assumed: the paper's
    h_ts=PAPER.h_ts,
    h_tp=PAPER.h_tp,
    h_wp=PAPER.h_wp,
    k_ar=2.5e6,  # assumed: an air-spring car carries an anti-roll bar
    z_stop=0.04,  # assumed
    k_stop=2.0e6,  # assumed
    L_c=25.0,  # assumed: the 25 m of a CRH380A-type intermediate car
    f_bend=10.0,  # assumed: the middle of the 8-12 Hz of passenger carbodies (Zhou et al. 2009)
    zeta_bend=0.02,  # assumed: 2 % modal damping
)

PRESETS: dict[str, VehicleParams] = {"paper": PAPER, "manchester-1": MANCHESTER_1, "crh380a": CRH380A}

#: Where each preset's values come from, one line each (`railride vehicles`; docs/model.md, Presets).
PRESET_SOURCES: dict[str, str] = {
    "paper": "Harun et al., Application of Stability Augmentation System for Semi-active Railway Vehicle "
    "Secondary Vertical Suspension, appendix (bump stops assumed)",
    "manchester-1": "Manchester Benchmark passenger vehicle: Iwnicki (ed.), The Manchester Benchmarks for Rail "
    "Vehicle Simulation, Suppl. Vehicle System Dynamics 31, 1999 (yaw inertias, heights, primary "
    "lateral and longitudinal, a, stops assumed)",
    "crh380a": "CRH380A-type high-speed car: values as given for a CRH380A-type car in the published "
    "high-speed vehicle-dynamics literature; source values listed in docs/model.md, others assumed",
}


def ranges_markdown() -> str:
    """The docs' table of the vehicle's ranges (docs/cli.md, Sizes and plausible ranges)."""
    rows = ["| field | unit | typical (else a warning) | allowed (else an error) |", "|---|---|---|---|"]
    for name, unit, _, _ in VehicleParams.describe():
        r = VEHICLE[name]
        typical = f"{r.typical[0]:g} to {r.typical[1]:g}" if r.typical else "-"
        rows.append(f"| `{name}` | {unit} | {typical} | {r.low:g} to {r.high:g} |")
    return "\n".join(rows)
