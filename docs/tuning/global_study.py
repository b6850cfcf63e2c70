"""The global methods of docs/tuning.md, as run for the docs (about 4 minutes on 2 cores).

python docs/tuning/global_study.py      # writes docs/tuning/global.json
"""

import json
import time
from pathlib import Path

from railride.secondary.control import GainSet
from railride.studies.optimise import SAS_PARAMETERS, optimise, sensitivity
from railride.studies.sweep import Case, run_cases
from railride.studies.tuning import DEFAULT_OBJECTIVE

here = Path(__file__).parent
objective = DEFAULT_OBJECTIVE  # minimax: the objective the shipped gains were tuned with (railride tune)
shipped = GainSet.default()
t0 = time.perf_counter()
de = optimise(objective=objective, popsize=8, maxiter=25, seed=0)
t_de = time.perf_counter() - t0
t0 = time.perf_counter()
sobol = sensitivity(objective=objective, n=64, seed=0)
t_sobol = time.perf_counter() - t0
rows = run_cases(
    [
        Case(),
        Case(
            suspension="sas-attitude-ride",
            gains=tuple((p, de.gains.value(p)) for p in SAS_PARAMETERS),
        ),
        Case(suspension="sas-attitude-ride"),
    ]
)
resp = ["acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg"]
rms = {
    name: [float(rows.iloc[i][f"{r}_rms"]) for r in resp]
    for i, name in enumerate(("passive", "differential_evolution", "two_phase_study"))
}
out = {
    "objective": objective.to_dict(),
    "differential_evolution": {
        "objective": de.objective,
        "runs": de.n_runs,
        "generations": de.generations,
        "wall_time_s": t_de,
        "message": de.message,
        "gains": {p: float(10**x) for p, x in zip(de.parameters, de.log10_gains)},
    },
    "sobol": {"runs": sobol.n_runs, "n": 64, "wall_time_s": t_sobol, "indices": sobol.table()},
    "rms": rms,
}
(here / "global.json").write_text(json.dumps(out, indent=2) + "\n")
print(json.dumps({k: v for k, v in out.items() if k != "sobol"}, indent=1))
print(json.dumps(out["sobol"]["indices"], indent=1))
