"""A custom vehicle from a TOML file: the paper's vehicle with a softer secondary vertical
spring and a heavier carbody, its modes beside the paper's, and both on `paper-sine`
(passive suspension).

    python examples/custom_vehicle.py [--out DIR]

Writes custom_vehicle.toml (the input) and custom_vehicle_full.toml (every field) into DIR.
"""

import argparse
import tempfile
from pathlib import Path

import railride as rr

# A [vehicle] table may name a base preset and list only the fields that differ from it
# (docs/model.md, "Parameters"). SI units: N/m and kg.
TOML = """\
# The paper's vehicle with two changes
[vehicle]
preset = "paper"
k_sz = 2.0e5   # secondary vertical stiffness per corner, N/m (paper: 2.9e5)
m_c = 4.5e4    # carbody mass, kg (paper: 3.96e4)
"""

RESPONSES = {
    "acceleration_m_s2": "acceleration [m/s^2]",
    "displacement_m": "displacement [m]",
    "pitch_deg": "pitch [deg]",
    "roll_deg": "roll [deg]",
}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=None, help="folder for the output files (default: a temporary folder)"
    )
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="railride-"))
    out.mkdir(parents=True, exist_ok=True)

    # Write the TOML file and load it back, as a user would with their own file.
    path = out / "custom_vehicle.toml"
    path.write_text(TOML)
    paper = rr.VehicleParams.preset("paper")
    custom = rr.VehicleParams.load(path)
    custom.save(out / "custom_vehicle_full.toml")  # every field, for the record
    new = custom.to_dict()
    changed = {k: (v, new[k]) for k, v in paper.to_dict().items() if new[k] != v}
    print(f"Loaded {path}: " + ", ".join(f"{k} {a:g} -> {b:g}" for k, (a, b) in changed.items()))

    # Modes of both vehicles. They come sorted by frequency, and the order can change with the
    # parameters (here carbody bounce drops below roll), so pair them by label.
    modes_paper = rr.Vehicle(paper).modes()
    modes_custom = {m.label: m for m in rr.Vehicle(custom).modes()}
    print("\nModes of the passive vehicle: undamped frequency [Hz] and damping ratio")
    print(f"{'mode':<28}{'paper f':>9}{'zeta':>7}{'custom f':>11}{'zeta':>7}")
    for m in modes_paper:
        c = modes_custom.get(m.label)
        right = f"{c.frequency_hz:>11.3f}{c.damping_ratio:>7.3f}" if c else f"{'-':>11}{'-':>7}"
        print(f"{m.label:<28}{m.frequency_hz:>9.3f}{m.damping_ratio:>7.3f}{right}")

    # Both vehicles on the paper's sine track in one batch (a list of parameter sets runs
    # along a 'sample' dimension), passive suspension.
    result = rr.simulate(rr.scenario("paper-sine"), [paper, custom])
    metrics = result.metrics()  # (sample, response, statistic)
    print("\npaper-sine, passive suspension: RMS (peak-to-peak)")
    print(f"{'response':<24}{'paper':>21}{'custom':>21}")
    for r, label in RESPONSES.items():
        cells = "".join(
            f"{float(metrics.isel(sample=i).sel(response=r, statistic='rms')):>11.4g} "
            f"({float(metrics.isel(sample=i).sel(response=r, statistic='ptp')):7.4g})"
            for i in range(2)
        )
        print(f"{label:<24}{cells}")
    print(f"\nWrote {path} and {out / 'custom_vehicle_full.toml'}")


if __name__ == "__main__":
    main()
