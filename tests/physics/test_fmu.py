"""The FMU (`railride.export_fmu`) is the same vehicle as railride's: FMPy hosts it, and its runs
are compared with `railride.simulate`'s, its linearisation at rest with `linear_model`'s matrices,
and its closed loop, stepped from Python as a co-simulation, with railride's own closed loop."""

import shutil
import zipfile

import numpy as np
import pytest

fmpy = pytest.importorskip("fmpy")
pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler to build the FMU")

from fmpy import extract, read_model_description  # noqa: E402
from fmpy.fmi2 import FMU2Slave  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from railride.errors import InputError  # noqa: E402
from railride.frequency.fmu import SECONDARIES, export_fmu  # noqa: E402
from railride.frequency.linear import linear_model  # noqa: E402
from railride.model.track import scenario  # noqa: E402
from railride.model.vehicle import CORNER_NAMES  # noqa: E402
from railride.run.checks import check  # noqa: E402
from railride.run.simulation import simulate  # noqa: E402
from railride.run.solver import SolverSettings  # noqa: E402
from railride.secondary import dampers  # noqa: E402
from railride.secondary.suspension import Suspension  # noqa: E402

RK4 = SolverSettings(method="rk4")
SINE = scenario("paper-sine", duration=2.0)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """Exports by (vehicle, damper), built once for the module."""
    folder, made = tmp_path_factory.mktemp("fmu"), {}

    def get(vehicle="paper", damper="railway"):
        if (vehicle, damper) not in made:
            made[vehicle, damper] = str(export_fmu(folder / f"{vehicle}-{damper}.fmu", vehicle, damper=damper))
        return made[vehicle, damper]

    return get


def _worst(fmu_rows, ds, names) -> float:
    """The largest difference of the FMU's outputs from railride's histories, over each history's
    largest value."""
    worst = 0.0
    for n in names:
        stem, _, corner = n.rpartition("_")
        ref = ds[stem].sel(corner=corner).values if corner in CORNER_NAMES else ds[n].values
        assert fmu_rows[n].shape == ref.shape and np.max(np.abs(ref)) > 0  # a history that moved
        worst = max(worst, float(np.max(np.abs(fmu_rows[n] - ref)) / np.max(np.abs(ref))))
    return worst


OUTPUTS = [
    "carbody_bounce",
    "carbody_pitch",
    "carbody_roll",
    "carbody_acceleration",
    "front_bogie_bounce",
    "rear_bogie_roll",
    "secondary_deflection_1R",
    "secondary_damper_force_2L",
]


@pytest.mark.parametrize(("vehicle", "damper"), [("paper", d) for d in SECONDARIES] + [("manchester-1", "railway")])
def test_fmpy_validates_the_fmu(fmus, vehicle, damper):
    assert validate_fmu(fmus(vehicle, damper)) == []


@pytest.mark.parametrize("vehicle", ["paper", "manchester-1"])
def test_a_passive_run_through_fmpy_is_railrides(fmus, vehicle):
    rows = fmpy.simulate_fmu(
        fmus(vehicle, "passive"), stop_time=SINE.duration, step_size=1e-3, output_interval=1e-3, output=OUTPUTS,
        start_values={"speed": SINE.speed},
    )  # fmt: skip
    for method in ("rk4", "auto"):  # RK4 alike, and the exact steps of the same inputs
        ds = simulate(SINE, vehicle, solver=SolverSettings(method=method)).dataset
        assert _worst(rows, ds, OUTPUTS) < 1e-6  # measured 1e-14 (the sine on railride's input grid)


def test_mr_dampers_at_a_constant_voltage_are_railrides(fmus):
    corners = [f"damper_command_{c}" for c in CORNER_NAMES]
    inputs = np.array([(0.0, *[1.5] * 4), (10.0, *[1.5] * 4)], dtype=[("time", float)] + [(c, float) for c in corners])
    names = [*OUTPUTS, "damper_voltage_1L", "damper_hysteretic_z_2R"]
    rows = fmpy.simulate_fmu(
        fmus(), stop_time=SINE.duration, step_size=1e-3, output_interval=1e-3, output=names, input=inputs,
        start_values={"speed": SINE.speed},
    )  # fmt: skip
    ds = simulate(SINE, suspension=Suspension.semi_active("railway", voltage=1.5), solver=RK4).dataset
    assert _worst(rows, ds, names) < 1e-6


def test_a_bouc_wen_damper_of_ones_own_in_the_fmu_is_railrides(tmp_path):
    """A damper file's parameters reach the C code: another exponent n (the C code's pow branch),
    other forces and rates, at a constant voltage, against railride's run of the same model."""
    own = dampers.preset("railway").replace(alpha_a=6.0e5, alpha_b=2.5e6, n=2.0, gamma=500.0, beta=200.0, eta=80.0)
    path = str(export_fmu(tmp_path / "own.fmu", damper=own))
    assert "secondary bouc-wen (own parameters)" in read_model_description(path).modelName
    corners = [f"damper_command_{c}" for c in CORNER_NAMES]
    inputs = np.array([(0.0, *[1.5] * 4), (10.0, *[1.5] * 4)], dtype=[("time", float)] + [(c, float) for c in corners])
    names = [*OUTPUTS, "damper_voltage_1L", "damper_hysteretic_z_2R"]
    rows = fmpy.simulate_fmu(
        path, stop_time=SINE.duration, step_size=1e-3, output_interval=1e-3, output=names, input=inputs,
        start_values={"speed": SINE.speed},
    )  # fmt: skip
    ds = simulate(SINE, suspension=Suspension.semi_active(own, voltage=1.5), solver=RK4).dataset
    assert _worst(rows, ds, names) < 1e-6
    railway = simulate(SINE, suspension=Suspension.semi_active("railway", voltage=1.5), solver=RK4).dataset
    assert _worst(rows, railway, ["secondary_damper_force_2L"]) > 1e-2  # another damper: not the preset's run


def _co_simulation(path, law, damper, duration=2.0):
    """The FMU stepped every 1 ms from Python, a controller computing the corner demands from the
    states it reads, with railride's one-period delay; the outputs at every step, and railride's
    own run of the same law."""
    sc = scenario("paper-sine", duration=duration)
    suspension = Suspension.named(law, damper=damper)
    plan = check(sc, None, suspension, RK4)
    gm, hm = plan.gm[0], plan.hm[0]  # the loop's gains on the engine's (q, q') and the integrals
    md = read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    dofs = [v.name.removeprefix("initial_") for v in md.modelVariables if v.name.startswith("initial_")][:9]
    states = [vr[d] for d in dofs] + [vr[f"{d}_velocity"] for d in dofs]
    demand = [vr[f"force_demand_{c}"] for c in CORNER_NAMES]
    unzipped = extract(path)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="co-simulation")  # fmt: skip
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([vr["speed"]], [sc.speed])
    if "inner_loop" in vr:  # railride's tracking law inside, every step dt
        fmu.setInteger([vr["inner_loop"]], [1])
        fmu.setReal([vr["inner_B"], vr["inner_G"]], [suspension.inner.B, suspension.inner.G])
    fmu.exitInitializationMode()
    rows, held, xi = [], np.zeros(4), np.zeros(3)
    half = gm.shape[1] // 2
    steps = int(round(duration * 1000))
    for k in range(steps + 1):  # a controller sample at every row, the last included, as railride's
        s = np.array(fmu.getReal(states))
        meas = np.zeros(gm.shape[1])
        meas[:9], meas[half : half + 9] = s[:9], s[9:]
        fmu.setReal(demand, list(held))  # the demand of the last sample: a one-period delay
        rows.append(fmu.getReal([vr[n] for n in OUTPUTS]))  # the forces and accelerations it feeds
        xi += 1e-3 * meas[:3]
        held = gm @ meas + hm @ xi
        if k < steps:
            fmu.doStep(k * 1e-3, 1e-3)
    fmu.terminate()
    fmu.freeInstance()
    shutil.rmtree(unzipped, ignore_errors=True)
    got = np.array(rows)
    ref = simulate(sc, suspension=suspension, solver=RK4).dataset
    return {n: got[:, j] for j, n in enumerate(OUTPUTS)}, ref


@pytest.mark.parametrize(("law", "damper"), [("sas-attitude", "railway"), ("skyhook", "ideal")])
def test_a_controller_stepping_the_fmu_is_railrides_closed_loop(fmus, law, damper):
    rows, ref = _co_simulation(fmus("paper", damper), law, damper)
    assert _worst(rows, ref, OUTPUTS) < 1e-6  # measured 1e-14


def _accelerations(path, start):
    """q'' at t = 0 (the outputs after the initialization) with the start values ``start``."""
    md = read_model_description(path)
    names = [v.name for v in md.modelVariables if v.causality == "output" and v.name.endswith("acceleration")]
    rows = fmpy.simulate_fmu(path, stop_time=1e-3, step_size=1e-3, output=names, start_values=start)
    return np.array([rows[n][0] for n in names if not n.startswith("floor_")])


@pytest.mark.parametrize(("damper", "secondary"), [("passive", "passive"), ("ideal", "plant")])
def test_the_fmus_linearisation_at_rest_is_the_state_space_model(fmus, damper, secondary):
    # the Jacobian of q'' by central differences of the FMU's own outputs, no derivative asked of it
    path = fmus("paper", damper)
    model = linear_model(suspension=secondary)
    nd = 9
    columns = {f"initial_{d}": j for j, d in enumerate(model.states[:nd])}
    columns |= {f"initial_{d}_velocity": nd + j for j, d in enumerate(model.states[:nd])}
    # the rails; and the corner forces where the FMU takes them (the actuator's force demands)
    inputs = {n: j for j, n in enumerate(model.inputs[:16])}
    if damper == "ideal":
        inputs |= {f"force_demand_{n.rsplit('_', 1)[1]}": 16 + k for k, n in enumerate(model.inputs[16:20])}
    base = {"scenario": 0}
    for name, j in {**columns, **inputs}.items():
        h = 1e-4 if not name.startswith("force_demand") else 1.0
        up = _accelerations(path, {**base, name: h})
        down = _accelerations(path, {**base, name: -h})
        got = (up - down) / (2 * h)
        want = (model.A[nd:, j] if name in columns else model.B[nd:, j])[: len(got)]
        assert np.allclose(got, want, rtol=1e-7, atol=1e-9 * max(1.0, np.max(np.abs(want)))), name


def _said(path, **kw) -> list[bytes]:
    """The FMU's log messages during an FMPy run that fails with fmi2Error."""
    said: list = []
    with pytest.raises(Exception, match=r"failed with status 3 \(error\)"):
        fmpy.simulate_fmu(path, logger=lambda *args: said.append(args[-1]), **kw)
    return said


def test_a_communication_step_that_is_not_a_multiple_of_dt_is_an_fmi_error(fmus):
    said = _said(fmus(), stop_time=0.01, step_size=1.5e-4, output_interval=1.5e-4)
    assert any(b"0.00015 s is not a whole multiple of the FMU's step dt = 0.0001 s" in m for m in said), said


def test_a_nan_input_is_an_fmi_error_with_a_message(fmus):
    inputs = np.array([(0.0, np.nan), (1.0, np.nan)], dtype=[("time", float), ("damper_command_1R", float)])
    said = _said(fmus(), stop_time=0.01, step_size=1e-3, output_interval=1e-3, input=inputs)
    assert any(b"damper_command_1R = nan: must be a finite number" in m for m in said), said


def test_bad_exports_are_input_errors_before_anything_is_written(tmp_path):
    with pytest.raises(InputError, match=r"damper = 'spencer1997': the FMU's C code implements passive, .*railway"):
        export_fmu(tmp_path / "a.fmu", damper="spencer1997")
    with pytest.raises(InputError, match=r"damper = 'spencer \(own parameters\)': .* the Spencer model"):
        export_fmu(tmp_path / "a.fmu", damper=dampers.preset("spencer1997").replace(c1a=1.0e5))
    with pytest.raises(InputError, match="ending in .fmu"):
        export_fmu(tmp_path / "a.zip")
    with pytest.raises(InputError, match="dt"):
        export_fmu(tmp_path / "a.fmu", dt=0.5)
    with pytest.raises(InputError, match="binary"):
        export_fmu(tmp_path / "a.fmu", binary="yes")
    assert list(tmp_path.iterdir()) == []


def test_the_sources_alone_compile_cleanly(tmp_path):
    import subprocess

    path = export_fmu(tmp_path / "v.fmu", "crh380a", binary=False)  # bump stops
    with zipfile.ZipFile(path) as z:
        names = z.namelist()
        z.extractall(tmp_path / "u")
    assert sorted(names) == ["modelDescription.xml", "sources/model.h", "sources/railride_fmu.c"]
    cmd = ["cc", "-std=c99", "-pedantic", "-Wall", "-Wextra", "-Werror", "-O2", "-shared", "-fPIC"]
    done = subprocess.run([*cmd, "-o", str(tmp_path / "x.so"), str(tmp_path / "u/sources/railride_fmu.c"), "-lm"],
                          capture_output=True, text=True)  # fmt: skip
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("damper", ["passive", "railway"])
def test_a_random_track_the_fmu_carries_is_railrides(tmp_path, damper):
    sc = scenario("fra4", seed=3, speed=45.0, duration=2.0)
    path = str(export_fmu(tmp_path / "r.fmu", damper=damper, scenario=sc))  # scenario 2 by default, at 45 m/s
    with zipfile.ZipFile(path) as z:
        assert "resources/track.bin" in z.namelist()
    names = [n for n in OUTPUTS if not n.startswith("secondary_damper_force") or damper != "railway"]
    corners = [f"damper_command_{c}" for c in CORNER_NAMES]
    v = 0.0 if damper == "passive" else 1.0
    inputs = np.array([(0.0, *[v] * 4), (10.0, *[v] * 4)], dtype=[("time", float)] + [(c, float) for c in corners])
    rows = fmpy.simulate_fmu(path, stop_time=sc.duration, step_size=1e-3, output_interval=1e-3, output=names,
                             input=inputs if damper != "passive" else None)  # fmt: skip
    suspension = None if damper == "passive" else Suspension.semi_active("railway", voltage=v)
    ds = simulate(sc, suspension=suspension, solver=RK4).dataset
    assert _worst(rows, ds, names) < 1e-6  # measured 1e-14: the same realisation on the same input grid


def test_the_fmu_takes_no_track_it_cannot_carry(tmp_path):
    with pytest.raises(InputError, match="scenario = 'bump': the FMU carries the paper's sine or a random track"):
        export_fmu(tmp_path / "b.fmu", scenario="bump")
    assert list(tmp_path.iterdir()) == []
