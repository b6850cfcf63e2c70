"""The vehicle as an FMI 2.0 co-simulation FMU with C sources (docs/fmu.md): `export_fmu`.

The FMU holds the vehicle railride steps (rigid, or with the carbody's first bending mode, from
the same element table), the secondary as chosen (the passive dashpots, Bouc-Wen MR dampers with
their hysteretic state and coil lag, or an ideal actuator taking force demands) with the bump
stops, and railride's fixed-step RK4 at its step dt, with the same sub-steps where the dampers'
states are stiff. Its sources are C (railride/data/fmu/railride_fmu.c and a header of the vehicle's
numbers written here), so that a user can build it for any platform; a binary for this one is built
at export with the system's C compiler.
"""

from __future__ import annotations

import hashlib
import math
import os
import platform
import shutil
import subprocess
import tempfile
import uuid
import zipfile
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from railride import arguments, validation
from railride.defaults import DEFAULT_DT
from railride.engine import layout
from railride.errors import InputError
from railride.model.params import resolve_vehicle
from railride.model.track import NODES_PER_FEATURE, RandomTrack, SineTrack, as_scenario
from railride.model.vehicle import CORNER_NAMES, RAILS, WHEELSETS, Vehicle
from railride.run.inputs import _system_arrays
from railride.secondary import dampers

#: the secondaries the C code implements: the passive dashpots, the Bouc-Wen MR damper presets
#: and the ideal actuator
SECONDARIES = ("passive", *(n for n, d in dampers.PRESETS.items() if d.law == dampers.LAW_BOUC_WEN), "ideal")
MODEL_IDENTIFIER = "railride_vehicle"
#: x of the floor points as multiples of the bogie semi-spacing l (front +), as `linear_model`
FLOOR_POINTS = {"centre": 0.0, "front": 1.0, "rear": -1.0}
#: FMI unit name -> (SI base exponents, factor), for <UnitDefinitions>
UNITS = {
    "m": ({"m": 1}, 1.0),
    "rad": ({"rad": 1}, 1.0),
    "deg": ({"rad": 1}, math.pi / 180.0),
    "s": ({"s": 1}, 1.0),
    "m/s": ({"m": 1, "s": -1}, 1.0),
    "rad/s": ({"rad": 1, "s": -1}, 1.0),
    "m/s2": ({"m": 1, "s": -2}, 1.0),
    "rad/s2": ({"rad": 1, "s": -2}, 1.0),
    "N": ({"kg": 1, "m": 1, "s": -2}, 1.0),
    "V": ({"kg": 1, "m": 2, "s": -3, "A": -1}, 1.0),
    "V/N": ({"m": 1, "s": -1, "A": -1}, 1.0),
}


#: the groups of variables the C code reads by their first value reference and their count
#: (RR_VR_<block>, RR_N_<block>; both 0 where an export has none)
BLOCKS = (
    *("DT", "SPEED", "AMPLITUDE", "WAVELENGTH", "RAIL_PHASE", "TAPER", "INITIAL_Q", "INITIAL_QD"),
    *("COMMAND", "FORCE_DEMAND", "INNER_B", "INNER_G", "RAIL_HEIGHT", "RAIL_RATE"),
    *("Q", "QD", "QDD", "FLOOR", "DEFLECTION", "DEFLECTION_RATE", "FORCE", "COIL", "HYSTERETIC", "CLEARANCE"),
    *("SCENARIO", "INNER_LOOP"),
)


@dataclass(frozen=True)
class Variable:
    """One FMU variable: its block (the C name of its group, `BLOCKS`), name,
    causality ("parameter", "input", "output"), unit, start value and description."""

    block: str
    name: str
    causality: str
    unit: str
    start: float | None
    description: str
    integer: bool = False


def _variables(vehicle: Vehicle, secondary: str, dt: float, sc) -> list[Variable]:
    """Every variable of the FMU in value-reference order: Reals, then Integers. ``sc``: the
    scenario the export starts with (None: the paper's sine at 40 m/s)."""
    sine = sc.track if sc is not None and isinstance(sc.track, SineTrack) else SineTrack()
    speed = 40.0 if sc is None else sc.speed
    names, units = vehicle.dof_names, vehicle.dof_units
    out = [
        Variable("DT", "dt", "parameter", "s", dt, "the fixed RK4 step; a communication step is a whole multiple"),
        Variable("SPEED", "speed", "parameter", "m/s", speed, "the vehicle's speed (scenarios 1 and 2)"),
        Variable("AMPLITUDE", "amplitude", "parameter", "m", sine.amplitude, "the sine's amplitude (scenario 1)"),
        Variable("WAVELENGTH", "wavelength", "parameter", "m", sine.wavelength, "the sine's wavelength (scenario 1)"),
        Variable("RAIL_PHASE", "rail_phase", "parameter", "deg", sine.rail_phase_deg, "the right rail's lag"),
        Variable("TAPER", "taper", "parameter", "", sine.taper, "the sine's entry taper, in wavelengths"),
    ]
    for i, (d, u) in enumerate(zip(names, units)):
        out.append(Variable("INITIAL_Q", f"initial_{d}", "parameter", u, 0.0, f"{d} at the start"))
    for i, (d, u) in enumerate(zip(names, units)):
        out.append(Variable("INITIAL_QD", f"initial_{d}_velocity", "parameter", f"{u}/s", 0.0, "at the start"))
    if secondary != "passive":
        what, unit = ("command voltage of the coil driver", "V") if secondary != "ideal" else ("force demand", "N")
        stem = "damper_command" if secondary != "ideal" else "force_demand"
        for k, c in enumerate(CORNER_NAMES):
            out.append(Variable("COMMAND", f"{stem}_{c}", "input", unit, 0.0, f"corner {c}: {what}"))
    if secondary not in ("passive", "ideal"):  # the inner loop, inside: force demands in, as railride's
        from railride.secondary.control import GainSet

        inner = GainSet.default().inner
        for k, c in enumerate(CORNER_NAMES):
            text = f"corner {c}: force demand on the carbody, for the inner loop (inner_loop 1-3)"
            out.append(Variable("FORCE_DEMAND", f"force_demand_{c}", "input", "N", 0.0, text))
        out.append(Variable("INNER_B", "inner_B", "parameter", "", inner.B, "the inner loop's weight of the force"))
        out.append(Variable("INNER_G", "inner_G", "parameter", "V/N", inner.G, "the inner loop's gain"))
    rails = [f"{w}{r}" for w in WHEELSETS for r in RAILS]
    for k, r in enumerate(rails):
        out.append(Variable("RAIL_HEIGHT", f"rail_height_{r}", "input", "m", 0.0, "scenario 0"))
    for k, r in enumerate(rails):
        out.append(Variable("RAIL_RATE", f"rail_rate_{r}", "input", "m/s", 0.0, "scenario 0"))
    for block, suffix, tail in (("Q", "", ""), ("QD", "_velocity", "/s"), ("QDD", "_acceleration", "/s2")):
        for i, (d, u) in enumerate(zip(names, units)):
            name = "carbody_acceleration" if f"{d}{suffix}" == "carbody_bounce_acceleration" else f"{d}{suffix}"
            out.append(Variable(block, name, "output", f"{u}{tail}", None, d))
    for k, p in enumerate(FLOOR_POINTS):
        text = f"vertical acceleration of the carbody floor at the {p}"
        out.append(Variable("FLOOR", f"floor_acceleration_{p}", "output", "m/s2", None, text))
    corner: list[tuple[str, str, str, str]] = [
        ("DEFLECTION", "secondary_deflection", "m", "secondary deflection, carbody minus bogie (extension +)"),
        ("DEFLECTION_RATE", "secondary_deflection_velocity", "m/s", "its rate"),
        ("FORCE", "secondary_damper_force", "N", "damper force on the carbody (up +), the bump stop not included"),
    ]
    if secondary not in ("passive", "ideal"):
        corner += [
            ("COIL", "damper_voltage", "V", "the coil voltage after the coil lag"),
            ("HYSTERETIC", "damper_hysteretic_z", "m", "the Bouc-Wen hysteretic variable z"),
        ]
    if vehicle.params.z_stop is not None and vehicle.params.k_stop > 0.0:
        corner += [("CLEARANCE", "secondary_clearance", "m", "travel left to the bump stop: z_stop - |deflection|")]
    for block, stem, unit, text in corner:
        for k, c in enumerate(CORNER_NAMES):
            out.append(Variable(block, f"{stem}_{c}", "output", unit, None, f"corner {c}: {text}"))
    text = "0: the rail inputs, carried on over a step with their rates; 1: the paper's sine"
    random = sc is not None and isinstance(sc.track, RandomTrack)
    if random:
        text += f"; 2: the random track of the export ({_track_words(sc.track)})"
    out.append(Variable("SCENARIO", "scenario", "parameter", "", 2 if random else 1, text, integer=True))
    if secondary not in ("passive", "ideal"):
        text = "0: the coil commands are the inputs; 1, 2, 3: the force demands, through railride's inner loop "
        text += "(tracking, on-off, clipped) at every step dt"
        out.append(Variable("INNER_LOOP", "inner_loop", "parameter", "", 0, text, integer=True))
    return out


def export_fmu(
    out,
    vehicle=None,
    *,
    params=None,
    load: float = 1.0,
    damper="railway",
    dt: float = DEFAULT_DT,
    scenario=None,
    binary: bool = True,
) -> Path:
    """Write the vehicle as an FMI 2.0 co-simulation FMU to ``out`` (a path ending in .fmu) and
    return it. ``vehicle`` (``params`` is an alias): a preset name, a parameters file or
    `VehicleParams` (default "paper"), with the load factor ``load``; ``damper``: the secondary,
    one of `SECONDARIES` ("passive": the vehicle's dashpots c_sz; an MR preset; "ideal": force
    inputs) or a Bouc-Wen MR damper of one's own (`railride.secondary.dampers.BoucWen`, as a
    damper file gives it, `railride.secondary.damper_file.load`); ``dt``: the FMU's fixed step
    [s]. ``scenario`` (a `Scenario` or a name, default the paper's sine at 40 m/s): the track
    the FMU starts with, its speed the default of the FMU's ``speed``; the paper's sine
    (scenario 1, its settings the defaults of the FMU's), or a random track, whose realisation
    the FMU carries (scenario 2, in its resources). ``binary``: also build this platform's
    binary with the C compiler (``CC``, else cc or gcc); False ships the sources alone. Every
    value is checked, and the compiler found, before anything is written."""
    path = Path(os.fspath(out)) if isinstance(out, (str, os.PathLike)) else None
    if path is None or path.suffix != ".fmu":
        shown = str(path) if path is not None else out
        raise InputError(f"out = {shown!r}: give the path of the FMU to write, ending in .fmu")
    validation.creatable(path, f"out = {str(path)!r}")
    if path.is_dir():  # the FMU replaces a file whole, never a folder
        raise InputError(f"out = {str(path)!r}: a folder; give the path of the FMU file to write, ending in .fmu")
    params_, record = resolve_vehicle(vehicle, params, load)
    secondary, model, label = _secondary(damper)
    dt = validation.number("dt", dt, "positive", "s")
    if dt > 1e-2:
        raise InputError(f"dt = {validation.shown(dt)} s: at most 0.01 s; railride's default is {DEFAULT_DT:g} s")
    sc = None if scenario is None else as_scenario(scenario)
    if sc is not None and not isinstance(sc.track, (SineTrack, RandomTrack)):
        raise InputError(
            f"scenario = {sc.name!r}: the FMU carries the paper's sine or a random track (fra1..fra6, german-low, "
            "german-high); give it other profiles through its rail inputs (scenario 0)"
        )
    binary = arguments.flag("binary", binary)
    compiler = _compiler() if binary else None
    car = Vehicle(params_)
    variables = _variables(car, secondary, dt, sc)
    track = sc.track if sc is not None and isinstance(sc.track, RandomTrack) else None
    header = _header(car, secondary, model, variables, dt) + _track_header(track)
    guid = str(uuid.uuid5(uuid.NAMESPACE_URL, "railride-fmu:" + hashlib.sha1(header.encode()).hexdigest()))
    header = f'#define RR_GUID "{{{guid}}}"\n' + header
    xml = _model_description(variables, guid, record, label, dt)
    source = resources.files("railride").joinpath("data/fmu/railride_fmu.c").read_text()
    with tempfile.TemporaryDirectory(prefix="railride-fmu-") as tmp:
        root = Path(tmp) / "fmu"
        (root / "sources").mkdir(parents=True)
        (root / "modelDescription.xml").write_text(xml)
        (root / "sources" / "railride_fmu.c").write_text(source)
        (root / "sources" / "model.h").write_text(header)
        if track is not None:
            (root / "resources").mkdir()
            (root / "resources" / "track.bin").write_bytes(_track_pieces(track))
        if compiler is not None:
            _build(compiler, root)
        path.parent.mkdir(parents=True, exist_ok=True)  # a new folder, as every command's --out makes one
        staged = path.with_name(f".{path.name}.{os.getpid()}.part")
        try:
            with zipfile.ZipFile(staged, "w", zipfile.ZIP_DEFLATED) as z:
                for f in sorted(root.rglob("*")):
                    if f.is_file():
                        z.write(f, f.relative_to(root).as_posix())
            os.replace(staged, path)
        finally:
            staged.unlink(missing_ok=True)
    return path


def _secondary(damper) -> tuple[str, object, str]:
    """(kind, model, name) of ``damper``: kind "passive", "ideal" or "mr" as the C code tells
    them apart, the MR damper's model (None for the others), and the name the FMU gives it."""
    if isinstance(damper, str) and damper in SECONDARIES:
        if damper in ("passive", "ideal"):
            return damper, None, damper
        return "mr", dampers.preset(damper), damper
    if getattr(damper, "law", None) == dampers.LAW_BOUC_WEN:  # one's own parameters
        return "mr", damper, dampers.record_name(damper.to_dict())
    shown = dampers.record_name(damper.to_dict()) if hasattr(damper, "to_dict") else damper
    raise InputError(
        f"damper = {shown!r}: the FMU's C code implements {', '.join(SECONDARIES)} and Bouc-Wen MR dampers of "
        "one's own (a damper file of model bouc-wen); the Spencer model and the ideal semi-active damper are not in it"
    )


def _track_words(track: RandomTrack) -> str:
    band = f"{track.min_wavelength:g}-{track.max_wavelength:g} m"
    return f"{track.name}, seed {track.seed}, {track.length:g} m, wavelengths {band}"


def _track_header(track: RandomTrack | None) -> str:
    """model.h's lines of the random track: whether there is one, and its input grid's spacing."""
    if track is None:
        return "#define RR_HAS_TRACK 0\n#define RR_TRACK_SPACING 1.0\n"
    return f"#define RR_HAS_TRACK 1\n#define RR_TRACK_SPACING {float(track.table_spacing())!r}\n"


def _track_pieces(track: RandomTrack) -> bytes:
    """resources/track.bin: the pieces n and the spacing, then the n x 4 coefficients of the left
    rail's cubic spline pieces (highest power first) and the right's, little-endian doubles."""
    s, _, _ = track.samples()
    left, right = (np.ascontiguousarray(spline.c.T) for spline in track.splines())
    n, ds = left.shape[0], float(s[1])  # the samples are k ds: s[1] is ds itself
    data = np.concatenate([[float(n), ds], left.ravel(), right.ravel()]).astype("<f8")
    return data.tobytes()


def _compiler() -> str:
    """The C compiler for this platform's binary: ``CC``, else cc, gcc or clang."""
    if _platform_folder() is None:
        raise InputError(
            f"binary: no FMU binary folder for {platform.system()} {platform.machine()} here; "
            "export the sources alone (binary=False, --sources-only) and build them there"
        )
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if name and shutil.which(name):
            return name
    raise InputError(
        "binary: no C compiler found (set CC, or install gcc or clang); "
        "or export the sources alone (binary=False, --sources-only)"
    )


def _platform_folder() -> str | None:
    system, machine = platform.system(), platform.machine().lower()
    if machine in ("x86_64", "amd64"):
        return {"Linux": "linux64", "Darwin": "darwin64"}.get(system)
    return None


def _build(compiler: str, root: Path) -> None:
    """The shared library binaries/<platform>/<model identifier> from the sources."""
    folder = root / "binaries" / str(_platform_folder())
    folder.mkdir(parents=True)
    suffix = ".dylib" if platform.system() == "Darwin" else ".so"
    target = folder / f"{MODEL_IDENTIFIER}{suffix}"
    cmd = [compiler, "-O2", "-shared", "-fPIC", "-fvisibility=hidden", "-o", str(target)]
    cmd += [str(root / "sources" / "railride_fmu.c"), "-lm"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:  # the sources are ours: a failure here is a bug, or a broken compiler
        raise RuntimeError(f"building the FMU's binary failed ({' '.join(cmd)}):\n{done.stderr[-2000:]}")


def _c_array(name: str, values: np.ndarray) -> str:
    """A static const double array in C, a row a line (an infinite value as 1e300)."""

    def row(v) -> str:
        return "{" + ", ".join(repr(float(x)) if math.isfinite(x) else "1e300" for x in np.ravel(v)) + "}"

    dims = "".join(f"[{n}]" for n in values.shape)
    body = row(values) if values.ndim == 1 else "{\n    " + ",\n    ".join(row(r) for r in values) + "}"
    return f"static const double {name}{dims} = {body};\n"


def _qdd_function(A: np.ndarray, Bw: np.ndarray, Bwd: np.ndarray) -> str:
    """rr_qdd(y, w, wd, qdd): q'' = Bw w + Bwd w' + A^T y written out with the nonzero entries
    alone (most are zero: a rail moves its bogie, a corner force two bodies), which makes the
    step about twice as fast as the full products."""
    lines = ["static void rr_qdd(const double *y, const double *w, const double *wd, double *qdd) {\n"]
    for i in range(A.shape[1]):
        terms = [f"{float(Bw[i, j])!r} * w[{j}]" for j in range(8) if Bw[i, j]]
        terms += [f"{float(Bwd[i, j])!r} * wd[{j}]" for j in range(8) if Bwd[i, j]]
        terms += [f"{float(A[j, i])!r} * y[{j}]" for j in range(A.shape[0]) if A[j, i]]
        lines.append(f"    qdd[{i}] = {' + '.join(terms) or '0.0'};\n")
    return "".join(lines) + "}\n"


def _header(car: Vehicle, secondary: str, model, variables: list[Variable], dt: float) -> str:
    """model.h: the vehicle's matrices at its own size, the damper (``model``, the MR damper's,
    None for the others) and the value references."""
    p, nd = car.params, car.n_dof
    system = _system_arrays(car, passive=secondary == "passive")
    E = layout.N_DOF  # the engine's size, which _system_arrays pads a rigid vehicle to
    rows = [*range(nd), *range(E, E + nd), *range(2 * E, 2 * E + 4)]
    A = system["A"][rows][:, :nd]
    floor = np.array([car.floor_point(share * p.l) for share in FLOOR_POINTS.values()])
    kinds = {"passive": 0, "ideal": 2}
    lines = [
        f"#define RR_N_DOF {nd}\n",
        "#define RR_SECONDARY_PASSIVE 0\n#define RR_SECONDARY_MR 1\n#define RR_SECONDARY_ACTUATOR 2\n",
        f"#define RR_SECONDARY {kinds.get(secondary, 1)}\n",
        _c_array("RR_T", system["TS"][:nd]),
        _c_array("RR_FLOOR", floor),
        _c_array("RR_LAG", np.asarray(car.wheelset_lag_distance, dtype=float)),
        f"#define RR_C_SEC {p.c_sz!r}\n",
        f"#define RR_Z_STOP {float(system['stops'][0]) if math.isfinite(system['stops'][0]) else 1e300!r}\n",
        f"#define RR_K_STOP {float(system['stops'][1])!r}\n",
        f"#define RR_SUBSTEP_DT_REF {layout.SUBSTEP_DT_REF!r}\n#define RR_SUBSTEP_LIMIT {layout.SUBSTEP_LIMIT!r}\n",
        f"#define RR_MAX_SUBSTEPS {layout.MAX_SUBSTEPS}\n",
        f"#define RR_NODES_PER_FEATURE {float(NODES_PER_FEATURE)!r}\n",
        _qdd_function(A, system["Bw"][:nd], system["Bwd"][:nd]),
    ]
    P = model.pack() if model is not None else np.zeros(layout.N_PACKED)
    for name, slot in (
        ("ALPHA_A", layout.P_ALPHA_A), ("ALPHA_B", layout.P_ALPHA_B), ("C0A", layout.P_C0A),
        ("C0B", layout.P_C0B), ("K0", layout.P_K0), ("A", layout.P_A), ("N", layout.P_N),
        ("GAMMA", layout.P_GAMMA), ("BETA", layout.P_BETA), ("ETA", layout.P_ETA), ("Z_BOUND", layout.P_Z_BOUND),
    ):  # fmt: skip
        lines.append(f"#define RR_BW_{name} {float(P[slot])!r}\n")
    lines.append(f"#define RR_V_MIN {float(P[layout.P_V_MIN])!r}\n#define RR_V_MAX {float(P[layout.P_V_MAX])!r}\n")
    reals = [v for v in variables if not v.integer]
    integers = [v for v in variables if v.integer]
    lines.append(f"#define RR_N_REAL {len(reals)}\n#define RR_N_INTEGER {len(integers)}\n")
    lines.append(f"#define RR_VR_INTEGER0 {len(reals)}\n")
    for block in BLOCKS:
        at = [i for i, v in enumerate(variables) if v.block == block]  # consecutive value references
        lines.append(f"#define RR_VR_{block} {at[0] if at else 0}\n#define RR_N_{block} {len(at)}\n")
    lines.append(_c_array("RR_START", np.array([v.start or 0.0 for v in reals])))
    starts = ", ".join(str(int(v.start or 0)) for v in integers)
    lines.append(f"static const int RR_START_INTEGER[{len(integers)}] = {{{starts}}};\n")
    kinds_ = "".join({"parameter": "p", "input": "i", "output": "o"}[v.causality] for v in variables)
    lines.append(f'static const char RR_CAUSALITY[] = "{kinds_}";\n')
    lines.append("static const char *const RR_NAMES[] = {" + ", ".join(f'"{v.name}"' for v in variables) + "};\n")
    lines.append(f"/* exported with dt = {dt!r} s */\n")
    return "".join(lines)


def _model_description(variables: list[Variable], guid: str, record: dict, secondary: str, dt: float) -> str:
    """modelDescription.xml: every variable with its unit and description, the outputs' structure."""
    from railride._version import __version__

    used = sorted({v.unit for v in variables if v.unit})
    units = []
    for u in used:
        base, factor = UNITS[u]
        attrs = " ".join(f'{k}="{e}"' for k, e in base.items()) + (f' factor="{factor!r}"' if factor != 1.0 else "")
        units.append(f'    <Unit name="{u}"><BaseUnit {attrs}/></Unit>')
    rows = []
    for vr, v in enumerate(variables):
        variability = "fixed" if v.causality == "parameter" else "continuous"
        if v.integer:
            variability = "fixed"
        initial = ' initial="exact"' if v.causality == "parameter" else ""
        kind = "Integer" if v.integer else "Real"
        start = f' start="{int(v.start) if v.integer else float(v.start)!r}"' if v.start is not None else ""
        unit = f' unit="{v.unit}"' if v.unit and not v.integer else ""
        rows.append(
            f'    <ScalarVariable name={quoteattr(v.name)} valueReference="{vr}" causality="{v.causality}" '
            f'variability="{variability}"{initial} description={quoteattr(v.description)}>'
            f"<{kind}{unit}{start}/></ScalarVariable>"
        )
    outputs = [i + 1 for i, v in enumerate(variables) if v.causality == "output"]
    unknowns = "\n".join(f'      <Unknown index="{i}"/>' for i in outputs)
    name = f"railride vehicle ({record['name']}, load {record['load']:g}), secondary {secondary}"
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        f'<fmiModelDescription fmiVersion="2.0" modelName={quoteattr(name)} guid="{{{guid}}}" '
        f'generationTool="railride {__version__}" variableNamingConvention="flat" numberOfEventIndicators="0" '
        f'description="a railway vehicle\'s vertical ride: railride.export_fmu (docs/fmu.md)">\n'
        f'  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" canHandleVariableCommunicationStepSize="true" '
        'canInterpolateInputs="false" canBeInstantiatedOnlyOncePerProcess="false" '
        'canNotUseMemoryManagementFunctions="true" '
        'canGetAndSetFMUstate="false" canSerializeFMUstate="false" providesDirectionalDerivative="false">\n'
        '    <SourceFiles><File name="railride_fmu.c"/></SourceFiles>\n  </CoSimulation>\n'
        "  <UnitDefinitions>\n" + "\n".join(units) + "\n  </UnitDefinitions>\n"
        f'  <DefaultExperiment startTime="0.0" stopTime="10.0" stepSize="{dt * max(1, round(1e-3 / dt))!r}"/>\n'
        "  <ModelVariables>\n" + "\n".join(rows) + "\n  </ModelVariables>\n"
        "  <ModelStructure>\n    <Outputs>\n" + unknowns + "\n    </Outputs>\n"
        "    <InitialUnknowns>\n" + unknowns + "\n    </InitialUnknowns>\n  </ModelStructure>\n"
        "</fmiModelDescription>\n"
    )
