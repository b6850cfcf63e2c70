"""Robust tuning against tuning on one track, as run for docs/tuning.md (about 3 minutes on 2 cores).

SAS (attitude) tuned by the same study and budget (the inner loop, then 400 gain sets) on
`paper-sine` (the shipped gains) and on five FRA class 4 tracks at 45 m/s (seeds 0-4, the mean
of the minimax objective), both judged on ten tracks neither saw (seeds 10-19) at 30, 45 and
60 m/s, and on `paper-sine`.
"""

import numpy as np

from railride.studies.comparison import compare
from railride.secondary.control import GainSet
from railride.studies.study import study
from railride.model.track import scenario
from railride.studies.tuning import tune, tuning_set

RESPONSES = ["acceleration_m_s2_rms", "displacement_m_rms", "pitch_deg_rms", "roll_deg_rms"]

robust = tune(("inner", "sas-attitude"), over=tuning_set("fra4", track_seeds=range(5), speeds=[45.0])).gains
for label, gains in (("tuned on paper-sine (shipped)", GainSet.default()), ("tuned on fra4 seeds 0-4", robust)):
    res = study(["sas-attitude"], track_seeds=range(10, 20), speeds=[30.0, 45.0, 60.0], gains=gains)
    runs = res.cases[res.cases.controller == "sas-attitude"]
    print(f"{label}: reduction against passive on fra4 seeds 10-19 at 30, 45, 60 m/s, mean (5-95 %)")
    for m in [*RESPONSES, "centre_N_MV_z"]:
        x = runs[f"{m}_reduction"].to_numpy()
        print(f"  {m:24s} {x.mean():6.1f} ({np.percentile(x, 5):6.1f} to {np.percentile(x, 95):6.1f})")
    worst = (1 - runs[[f"{m}_reduction" for m in RESPONSES]] / 100).max(axis=1).to_numpy()
    lo, hi = np.percentile(worst, [5, 95])
    print(f"  worst RMS ratio per run  {worst.mean():.3f} ({lo:.3f} to {hi:.3f}), largest {worst.max():.3f}")
    red = compare(scenario("paper-sine"), controllers=["sas-attitude"], gains=gains, bounds=False).reductions
    r = red.sel(controller="sas-attitude", statistic="rms").values
    print(f"  paper-sine: {' / '.join(f'{v:.1f}' for v in r)} %, worst ratio {(1 - r / 100).max():.3f}")
