"""A speed sweep on FRA class 4 random track: passive against SAS (attitude+ride) on MR
dampers: a grid of cases (`railride.studies.sweep.grid`) run by `railride.run_sweep`.

    python examples/speed_sweep_random_track.py [--out DIR]

Writes sweep.csv (one row per run) and rms_vs_speed.png into DIR.
"""

import argparse
import tempfile
from pathlib import Path

import matplotlib

import railride as rr
from railride.studies import sweep

matplotlib.use("Agg")  # no display needed: the plot goes to a file
import matplotlib.pyplot as plt  # after choosing the backend

SUSPENSIONS = {"passive": "Passive", "sas-attitude-ride": "SAS (attitude+ride)"}
SEED = 0  # the realisation of the random track: the same rails at every speed


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=None, help="folder for the output files (default: a temporary folder)"
    )
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="railride-"))
    out.mkdir(parents=True, exist_ok=True)
    duration = 10.0  # seconds per run
    speeds = [20.0, 30.0, 40.0, 50.0, 60.0]

    # Every combination of the axes: suspension x speed, on one realisation of the track.
    # run_sweep groups compatible cases into compiled batches.
    grid = sweep.grid(list(SUSPENSIONS), scenario="fra4", speed=speeds, track_seed=[SEED], duration=duration)
    result = rr.run_sweep(grid)
    table = result.to_pandas()  # one row per case, in the order of the grid
    table.to_csv(out / "sweep.csv", index=False)

    # RMS carbody acceleration per suspension, indexed by speed.
    acc = {s: table[table["suspension"] == s].set_index("speed_m_s")["acceleration_m_s2_rms"] for s in SUSPENSIONS}
    print(f"FRA class 4 random track (seed {SEED}), {duration:g} s per run: carbody acceleration RMS [m/s^2]")
    print(f"{'speed [m/s]':>12}{'passive':>10}{'SAS (att.+ride)':>17}{'reduction':>11}")
    for v in speeds:
        p, c = acc["passive"][v], acc["sas-attitude-ride"][v]
        print(f"{v:>12g}{p:>10.4f}{c:>17.4f}{(p - c) / p * 100:>10.1f}%")
    if result.diverged.any():
        print("Warning: some runs diverged (NaN metrics); see diverged_at_s in sweep.csv")

    # The plot: RMS acceleration against speed, one line per suspension.
    fig, ax = plt.subplots(figsize=(5, 3.5))
    for s, label in SUSPENSIONS.items():
        ax.plot(acc[s].index, acc[s].values, marker="o", label=label)
    ax.set_xlabel("speed [m/s]")
    ax.set_ylabel("carbody acceleration RMS [m/s$^2$]")
    ax.set_title(f"FRA class 4 track, seed {SEED}")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "rms_vs_speed.png", dpi=100)
    plt.close(fig)
    print(f"\nWrote {out / 'sweep.csv'} and {out / 'rms_vs_speed.png'}")


if __name__ == "__main__":
    main()
