"""The FMU's speed (railride.frequency.fmu): one communication step of 1 ms in C, and the same step
hosted by FMPy with a Python controller.

Run:  python benchmarks/bench_fmu.py [--steps 20000] [--damper railway]
Exports the paper's vehicle with ``--damper`` (MR dampers: the inner loop inside, tracking) on
the paper's sine at 55.56 m/s, dt = 1e-4 s, then
* in C: a driver written here (compiled with the system's cc) loads the FMU's binary, and times
  ``--steps`` calls of fmi2DoStep of 1 ms (10 RK4 steps each) after 1,000 untimed ones;
* through FMPy: 3,000 steps of 1 ms of the co-simulation loop of docs/fmu.md (read the states,
  a Python SAS (attitude) demand, set the inputs, fmi2DoStep).
Prints Markdown rows for docs/performance.md with the machine and the date. No test asserts timings.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

DRIVER = r"""
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
typedef void *(*inst_t)(const char *, int, const char *, const char *, const void *, int, int);
typedef int (*none_t)(void *);
typedef int (*setup_t)(void *, int, double, double, int, double);
typedef int (*step_t)(void *, double, double, int);
typedef int (*seti_t)(void *, const unsigned *, size_t, const int *);
typedef struct { void *logger, *alloc, *free_, *finished, *env; } callbacks;
static double now(void) { struct timespec t; clock_gettime(CLOCK_MONOTONIC, &t); return t.tv_sec + 1e-9 * t.tv_nsec; }
int main(int argc, char **argv) {
    void *lib = dlopen(argv[1], RTLD_NOW);
    long steps = atol(argv[3]), k;
    unsigned inner = (unsigned)atoi(argv[4]);
    int one = 1;
    callbacks cb = {0, (void *)calloc, (void *)free, 0, 0};
    void *c;
    double t0, t1, t = 0.0;
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 2; }
    c = ((inst_t)dlsym(lib, "fmi2Instantiate"))("x", 1, argv[2], "", &cb, 0, 0);
    if (!c) return 3;
    ((setup_t)dlsym(lib, "fmi2SetupExperiment"))(c, 0, 0.0, 0.0, 0, 0.0);
    ((none_t)dlsym(lib, "fmi2EnterInitializationMode"))(c);
    if (inner) ((seti_t)dlsym(lib, "fmi2SetInteger"))(c, &inner, 1, &one);
    ((none_t)dlsym(lib, "fmi2ExitInitializationMode"))(c);
    step_t step = (step_t)dlsym(lib, "fmi2DoStep");
    for (k = 0; k < 1000; k++, t += 1e-3) if (step(c, t, 1e-3, 1)) return 4;
    t0 = now();
    for (k = 0; k < steps; k++, t += 1e-3) if (step(c, t, 1e-3, 1)) return 4;
    t1 = now();
    printf("%.6g\n", (t1 - t0) / steps);
    return 0;
}
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--damper", default="railway")
    args = ap.parse_args()

    from fmpy import extract, read_model_description

    from railride.frequency.fmu import export_fmu

    where = f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, {datetime.date.today()}"
    with tempfile.TemporaryDirectory() as tmp:
        fmu = export_fmu(Path(tmp) / "v.fmu", damper=args.damper)
        md = read_model_description(str(fmu))
        unzipped = extract(str(fmu))
        lib = next(Path(unzipped, "binaries").rglob("*.so"))
        inner = next((v.valueReference for v in md.modelVariables if v.name == "inner_loop"), 0)
        driver = Path(tmp) / "driver"
        (Path(tmp) / "driver.c").write_text(DRIVER)
        subprocess.run(["cc", "-O2", "-o", str(driver), str(Path(tmp) / "driver.c"), "-ldl"], check=True)
        per_step = float(
            subprocess.run(
                [str(driver), str(lib), md.guid, str(args.steps), str(inner)],
                check=True,
                capture_output=True,
                text=True,
            ).stdout  # fmt: skip
        )
        takes_demands = any(v.name.startswith("force_demand_") for v in md.modelVariables)
        hosted = _fmpy_loop(str(fmu), md, unzipped) if takes_demands else None
        shutil.rmtree(unzipped, ignore_errors=True)
    print(f"| FMU ({args.damper}), one fmi2DoStep of 1 ms (10 RK4 steps of 1e-4 s), C driver | "
          f"{per_step * 1e6:.2f} us | {where} |")  # fmt: skip
    if hosted is not None:  # a secondary with demands to set (not the passive dashpots)
        print(f"| the same step in FMPy's co-simulation loop with a Python SAS (attitude) | "
              f"{hosted * 1e6:.0f} us | {where} |")  # fmt: skip


def _fmpy_loop(path: str, md, unzipped: str) -> float:
    """Seconds per 1 ms step of the co-simulation loop: states read, a Python SAS demand, inputs set."""
    from fmpy.fmi2 import FMU2Slave

    from railride.model.track import scenario
    from railride.run.checks import check
    from railride.secondary.suspension import Suspension

    vr = {v.name: v.valueReference for v in md.modelVariables}
    plan = check(scenario("paper-sine", duration=1.0), None, Suspension.named("sas-attitude"))
    gm, hm = plan.gm[0], plan.hm[0]
    dofs = [v.name for v in md.modelVariables if v.name.startswith("initial_") and not v.name.endswith("_velocity")]
    names = [d.removeprefix("initial_") for d in dofs]
    q_vr = [vr[n] for n in names] + [vr[f"{n}_velocity"] for n in names]
    fd_vr = [vr[k] for k in vr if k.startswith("force_demand_")]
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                    instanceName="bench")  # fmt: skip
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    if "inner_loop" in vr:
        fmu.setInteger([vr["inner_loop"]], [1])
    fmu.exitInitializationMode()
    n, nd = 3000, len(names)
    held, xi, meas = np.zeros(4), np.zeros(3), np.zeros(gm.shape[1])
    t0 = time.perf_counter()
    for k in range(n):
        s = fmu.getReal(q_vr)
        meas[:nd], meas[gm.shape[1] // 2 : gm.shape[1] // 2 + nd] = s[:nd], s[nd:]
        fmu.setReal(fd_vr, list(held))
        xi += 1e-3 * meas[:3]
        held = gm @ meas + hm @ xi
        fmu.doStep(k * 1e-3, 1e-3)
    took = (time.perf_counter() - t0) / n
    fmu.terminate()
    fmu.freeInstance()
    return took


if __name__ == "__main__":
    main()
