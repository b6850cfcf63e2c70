"""railride's vehicle as an FMU, driven by a controller outside it: the paper's vehicle with its MR
dampers exported as an FMI 2.0 co-simulation FMU, stepped every 1 ms through FMPy by a Python
SAS (attitude) that reads the carbody's states and sets the four force demands, with railride's
inner loop inside the FMU. The same run by railride.simulate beside it: the two agree to
rounding, so a controller designed in Simulink or Python on this FMU sees railride's vehicle.

    python examples/fmu_cosimulation.py [--out DIR]

Writes vehicle.fmu and cosimulation.csv into DIR. Needs FMPy (pip install fmpy) and a C compiler.
"""

import argparse
import csv
import tempfile
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

import railride as rr

DURATION = 3.0  # s
PERIOD = 1e-3  # s: the controller's period and the communication step
CORNERS = ("1R", "1L", "2R", "2L")
SHOWN = ("carbody_bounce", "carbody_pitch", "carbody_roll", "carbody_acceleration")


def sas_attitude(gains):
    """The SAS (attitude) law as the matrices railride steps it with: the corner demands
    f_d = G m + H xi from the measured (q, q') m and the integrals xi of the carbody's bounce, pitch
    and roll (docs/control.md), so that both runs share one controller."""
    from railride.model.track import scenario
    from railride.run.checks import check

    plan = check(scenario("paper-sine", duration=DURATION), None, rr.Suspension.named("sas-attitude", gains))
    return plan.gm[0], plan.hm[0]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None, help="folder for the output files (default: temporary)")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="railride-"))
    out.mkdir(parents=True, exist_ok=True)

    path = str(rr.export_fmu(out / "vehicle.fmu", "paper", damper="railway"))
    md = read_model_description(path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    dofs = [v.name.removeprefix("initial_") for v in md.modelVariables if v.name.startswith("initial_")][:9]
    states = [vr[d] for d in dofs] + [vr[f"{d}_velocity"] for d in dofs]
    gains = rr.GainSet.default()
    gm, hm = sas_attitude(gains)
    half = gm.shape[1] // 2  # the engine's (q, q') columns of the gain matrix

    unzipped = extract(path)
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="vehicle")  # fmt: skip
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    sc = rr.scenario("paper-sine", duration=DURATION)
    fmu.setReal([vr["speed"]], [sc.speed])  # the paper's sine inside the FMU (scenario 1)
    fmu.setInteger([vr["inner_loop"]], [1])  # force demands in, railride's tracking inner loop inside
    fmu.setReal([vr["inner_B"], vr["inner_G"]], [gains.inner.B, gains.inner.G])
    fmu.exitInitializationMode()
    rows, held, integral = [], np.zeros(4), np.zeros(3)
    steps = int(round(DURATION / PERIOD))
    for k in range(steps + 1):
        s = np.array(fmu.getReal(states))
        measured = np.zeros(gm.shape[1])
        measured[:9], measured[half : half + 9] = s[:9], s[9:]
        fmu.setReal([vr[f"force_demand_{c}"] for c in CORNERS], list(held))  # one period late, as railride
        rows.append([k * PERIOD, *fmu.getReal([vr[n] for n in SHOWN])])
        integral += PERIOD * measured[:3]
        held = gm @ measured + hm @ integral
        if k < steps:
            fmu.doStep(k * PERIOD, PERIOD)
    fmu.terminate()
    fmu.freeInstance()

    got = np.array(rows)
    ref = rr.simulate(sc, suspension=rr.Suspension.named("sas-attitude", gains),
                      solver=rr.SolverSettings(method="rk4")).dataset  # fmt: skip
    with open(out / "cosimulation.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time_s", *(f"fmu_{n}" for n in SHOWN), *(f"railride_{n}" for n in SHOWN)])
        for i, row in enumerate(rows):
            w.writerow([*row, *(float(ref[n].values[i]) for n in SHOWN)])
    print(f"{'response':<24}{'FMU RMS':>12}{'railride RMS':>14}{'largest difference / largest value':>38}")
    for j, n in enumerate(SHOWN):
        a, b = got[:, j + 1], ref[n].values
        rms = lambda x: float(np.sqrt(np.mean(x**2)))  # noqa: E731
        print(f"{n:<24}{rms(a):>12.5g}{rms(b):>14.5g}{np.max(np.abs(a - b)) / np.max(np.abs(b)):>38.1e}")
    print(f"\nwrote {out / 'vehicle.fmu'} and {out / 'cosimulation.csv'}")


if __name__ == "__main__":
    main()
