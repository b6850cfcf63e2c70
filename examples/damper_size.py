"""How big a damper does the controller need? SAS (attitude+ride) with the shipped gains on
`paper-sine`, on the `railway` MR dampers scaled by 0.5, 1, 2 and 4, and on the two ideal
devices. For each: the worst of the four RMS ratios to passive (below 1: every response
better than passive).

    python examples/damper_size.py [--out DIR]

Writes damper_size.csv into DIR.
"""

import argparse
import csv
import math
import tempfile
from pathlib import Path

import railride as rr
from railride.secondary.control import GainSet

RESPONSES = ("acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg")
SCALES = (0.5, 1.0, 2.0, 4.0)


def rms_ratios(result, passive_rms):
    """RMS of each response over passive's: one number per response."""
    rms = result.metrics().sel(statistic="rms", response=list(RESPONSES)).values
    return rms / passive_rms


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=None, help="folder for the output files (default: a temporary folder)"
    )
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="railride-"))
    out.mkdir(parents=True, exist_ok=True)

    sc = rr.scenario("paper-sine")
    gains = GainSet.default()  # the shipped gains, tuned for the `railway` dampers at x 1
    passive = rr.simulate(sc).metrics().sel(statistic="rms", response=list(RESPONSES)).values

    rows = []
    # MR dampers: every force parameter scaled, so at the same motion and voltage the force is
    # k times as large (the force at 0 V grows with it too).
    for k in SCALES:
        res = rr.simulate(sc, suspension=rr.Suspension.named("sas-attitude-ride", gains, damper_scale=k))
        rows.append((f"railway x {k:g}", rms_ratios(res, passive), None))
    # The same gains on the ideal semi-active damper (demand where it dissipates, no limit)
    # and the ideal actuator (force = demand). These may diverge with gains tuned for an MR
    # damper: mark it instead of stopping.
    for name in ("ideal-damper", "ideal"):
        res = rr.simulate(
            sc, suspension=rr.Suspension.named("sas-attitude-ride", gains, damper=name), on_divergence="mark"
        )
        diverged = float(res.diverged_at[0])
        rows.append((name, rms_ratios(res, passive), None if math.isnan(diverged) else diverged))

    print("SAS (attitude+ride), shipped gains, paper-sine: RMS ratio to passive")
    print(f"{'damper':<16}{'acc':>7}{'disp':>7}{'pitch':>7}{'roll':>7}{'worst':>8}")
    for name, ratios, diverged in rows:
        if diverged is not None:
            print(f"{name:<16}diverged at {diverged:.2f} s")
            continue
        print(f"{name:<16}" + "".join(f"{r:>7.3f}" for r in ratios) + f"{ratios.max():>8.3f}")
    # Does a bigger MR damper keep improving the worst response?
    worst = [ratios.max() for name, ratios, _ in rows[: len(SCALES)]]
    best = min(range(len(SCALES)), key=lambda i: worst[i])
    keeps = all(b < a for a, b in zip(worst, worst[1:]))
    print(
        f"\nBest MR size here: railway x {SCALES[best]:g} (worst ratio {worst[best]:.3f}); "
        + (
            "the worst ratio keeps falling with size."
            if keeps
            else "a bigger MR damper does not keep improving it with these gains."
        )
        + "\nSee docs/results.md, 'Damper authority', for the study with re-tuned gains."
    )

    with open(out / "damper_size.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["damper", *(f"{r}_rms_ratio" for r in RESPONSES), "worst", "diverged_at_s"])
        for name, ratios, diverged in rows:
            writer.writerow(
                [name, *(f"{r:.6g}" for r in ratios), f"{ratios.max():.6g}", "" if diverged is None else diverged]
            )
    print(f"Wrote {out / 'damper_size.csv'}")


if __name__ == "__main__":
    main()
