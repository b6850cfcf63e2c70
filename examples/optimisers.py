"""The two optimisers of `railride design` on equal budgets: the paper's one-at-a-time
sensitivity study and differential evolution (Storn and Price 1997, SciPy's vectorised
`differential_evolution`), each law tuned with the same budget of gain sets on the same training
set, both judged on the same held-out seeds (docs/tuning.md, "Two optimisers on equal budgets").

    python examples/optimisers.py                 # the default design, twice (about 35 min on 2 cores)
    python examples/optimisers.py --quick         # one track, speed and load, 2 s runs (a minute)
    python examples/optimisers.py --out DIR       # also each design's folder (design.json, gains.toml, ...)

Prints, per law, each optimiser's held-out score (the design's ranking score: the objective of the
mean RMS ratios to passive, its worst over the speeds and loads; lower is better), its objective
on the training set, the gain sets it scored and the training runs in its run table; then each
optimiser's wall time (tuning: from the start to its last step; the whole design) and runs.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import railride as rr
from railride.studies.sweep import RunTable

#: the reduced design of --quick: every law, one track, speed and load, 2 s of track a run
QUICK = dict(
    tracks=["fra4"],
    speeds=[50.0],
    loads=[1.0],
    train_seeds=[1, 2],
    test_seeds=[100, 101, 102],
    duration=2.0,
    budget=130,
)


def run(optimiser: str, settings: dict, out: Path | None, seed: int) -> dict:
    """One design with ``optimiser``, in a run table of its own; its result and times."""
    stamps: list[float] = []
    table = RunTable(out / optimiser / "runs.csv") if out is not None else RunTable()
    t0 = time.perf_counter()
    result = rr.design(
        optimiser=optimiser,
        optimiser_seed=seed,
        table=table,
        log=lambda text: stamps.append(time.perf_counter()),
        **settings,
    )
    wall = time.perf_counter() - t0
    table.close()
    if out is not None:
        result.save(out / optimiser)
    return {"result": result, "wall_s": wall, "tuning_s": (stamps[-1] - t0) if stamps else float("nan")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a reduced design (one track, speed and load, 2 s)")
    parser.add_argument("--controllers", default="all", help="the laws, comma-separated, or all")
    parser.add_argument("--seed", type=int, default=0, help="the seed of the evolution")
    parser.add_argument("--out", type=Path, default=None, help="write each design's folder under DIR")
    args = parser.parse_args()
    settings = dict(QUICK) if args.quick else {}
    if args.controllers != "all":
        settings["controllers"] = [c.strip() for c in args.controllers.split(",")]
    runs = {name: run(name, settings, args.out, args.seed) for name in ("sensitivity", "evolution")}

    first = runs["sensitivity"]["result"]
    s = first.settings
    print(
        f"Tracks {', '.join(s['tracks'])} at {', '.join(f'{v:g}' for v in s['speeds_m_s'])} m/s, loads "
        f"{', '.join(f'{x:g}' for x in s['loads'])}, {s['duration_s']:g} s a run; trained on seeds "
        f"{', '.join(map(str, s['train_seeds']))} ({s['training_runs_per_gain_set']} runs per gain set), at most "
        f"{s['budget']} gain sets per law; judged on seeds {', '.join(map(str, s['test_seeds']))}."
    )
    print()
    head = f"{'law':<20} {'held-out score':>22} {'training J':>20} {'gain sets':>14} {'training runs':>16}  better"
    print(head)
    pair = (("sens.", 10), ("evol.", 11), ("sens.", 9), ("evol.", 10), ("sens.", 6), ("evol.", 7), ("sens.", 7))
    print(f"{'':<20} " + " ".join(f"{t:>{w}}" for t, w in pair) + f" {'evol.':>8}")
    wins = {"sensitivity": 0, "evolution": 0}
    for law in s["controllers"]:
        cells = {}
        for name, r in runs.items():
            res = r["result"]
            score = next(x["score"] for x in res.ranking if x["controller"] == law)
            study = next(st for st in res.tuning.studies if st.controller == law)
            rows = res.tuning.runs
            training = int((rows["suspension"] == law).sum())
            cells[name] = (score, study.objective, study.runs, training)
        (a, ja, na, ra), (b, jb, nb, rb) = cells["sensitivity"], cells["evolution"]
        better = "evolution" if b < a else ("sensitivity" if a < b else "tie")
        if better in wins:
            wins[better] += 1
        print(f"{law:<20} {a:>10.4f} {b:>11.4f} {ja:>9.4f} {jb:>10.4f} {na:>6} {nb:>7} {ra:>7} {rb:>8}  {better}")
    print()
    for name, r in runs.items():
        res = r["result"]
        print(
            f"{name:<12} tuning {r['tuning_s']:7.1f} s, design {r['wall_s']:7.1f} s; "
            f"{res.settings['training_runs']} training and {res.settings['judging_runs']} held-out runs; "
            f"recommended {res.recommended}"
        )
    print(f"lower held-out score: evolution for {wins['evolution']} laws, sensitivity for {wins['sensitivity']}")


if __name__ == "__main__":
    main()
