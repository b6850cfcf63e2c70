"""The paper's comparison on `paper-sine`: passive against PID, SAS (attitude) and
SAS (attitude+ride) on four MR dampers, beside the same gains on the ideal devices.

    python examples/paper_comparison.py [--out DIR]

Writes comparison.json (the `railride compare --format json` document) into DIR.
"""

import argparse
import json
import tempfile
from pathlib import Path

import railride as rr
from railride.secondary.control import LABELS

RESPONSES = ("acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg")
SHORT = {
    "acceleration_m_s2": "acceleration",
    "displacement_m": "displacement",
    "pitch_deg": "pitch",
    "roll_deg": "roll",
}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=None, help="folder for the output files (default: a temporary folder)"
    )
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="railride-"))
    out.mkdir(parents=True, exist_ok=True)

    # One call runs passive, the three controllers on the `railway` MR dampers and, because
    # bounds=True by default, the same gains on the ideal semi-active damper and the ideal
    # actuator.
    comparison = rr.compare(rr.scenario("paper-sine"))
    doc = comparison.to_dict()
    (out / "comparison.json").write_text(json.dumps(doc, indent=2))
    controlled = [n for n in comparison.names if n != "passive"]

    # RMS of each response, and its reduction against passive in %.
    rms = comparison.metrics.sel(statistic="rms")
    red = comparison.reductions.sel(statistic="rms")
    print("RMS reduction against passive on paper-sine (MR dampers, shipped gains)")
    print(f"{'response':<14}{'passive RMS':>13}" + "".join(f"{LABELS[n]:>21}" for n in controlled))
    for r in RESPONSES:
        cells = "".join(
            f"{float(rms.sel(controller=n, response=r)):>12.4g} ({float(red.sel(controller=n, response=r)):5.1f}%)"
            for n in controlled
        )
        print(f"{SHORT[r]:<14}{float(rms.sel(controller='passive', response=r)):>13.4g}{cells}")

    # The same control laws and gains on the two ideal devices: what the MR dampers leave out.
    print("\nThe same gains on ideal devices: RMS reduction % (acc / disp / pitch / roll)")
    for device, runs in doc["bounds"].items():
        for name in controlled:
            run = runs[name]
            if run["diverged_at_s"] is not None:
                text = f"diverged at {run['diverged_at_s']:.2f} s"
            else:
                text = " / ".join(f"{run['reduction_percent'][r]:5.1f}" for r in RESPONSES)
            print(f"  {device:<13}{LABELS[name]:<22}{text}")

    # Where one suspension wins a response by losing another.
    print("\nTrade-offs")
    for t in comparison.trade_offs():
        if not t["worse_on"]:
            print(
                f"  {LABELS[t['controller']]} is at least as good as {LABELS.get(t['than'], t['than'])} "
                "on every response"
            )
        else:
            print(
                f"  {LABELS[t['controller']]} beats {LABELS.get(t['than'], t['than'])} on "
                f"{', '.join(SHORT[r] for r in t['better_on']) or 'nothing'}, "
                f"loses on {', '.join(SHORT[r] for r in t['worse_on'])}"
            )

    # The shipped gains were tuned on this track: the reductions above are in-sample.
    if comparison.in_sample:
        print(
            "\nNote: the shipped gains were tuned on this same track (in-sample); "
            "other track may tell another story (docs/results.md, 'Out of sample')."
        )
    else:
        print("\nThe gains were not tuned on this track (out of sample).")
    print(f"\nWrote {out / 'comparison.json'}")


if __name__ == "__main__":
    main()
