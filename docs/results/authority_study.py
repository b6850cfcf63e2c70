"""How big a damper does the controller need? (docs/results.md, "Damper authority").

For each force scale of the `railway` MR dampers (every force parameter times the scale, so the
0 V force grows with it: `--damper-scale`), the controllers are re-tuned by `railride tune`'s
defaults (the inner loop, then each law alike from the neutral reference gains with the same
budget of runs, minimax objective; the inner phase tracks demands scaled alike), then judged on
`paper-sine`. A second series scales only the
field-dependent part (alpha_b, c0b) and keeps the 0 V force: the experiment that checks whether
the off-state force is what stops the larger dampers (these variants are registered as presets
in this script only). The same procedure and budget tune the two bounds:
the ideal semi-active damper (`ideal-damper`: the demand where it dissipates, no force where it
would push energy in) and the ideal actuator (`ideal`: the demand, always), without the inner
phase, which they do not have. A second table keeps the shipped gains (tuned at scale 1) and
only changes the damper. Writes authority.csv and authority.png next to this file.

    python docs/results/authority_study.py          # about 15-20 minutes on 2 cores
    python docs/results/authority_study.py --plot   # only redraw the figure from the CSV
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pandas as pd

from railride import dampers
from railride.secondary.control import GainSet
from railride.analysis.metrics import RESPONSES
from railride.studies.sweep import Case, run_cases
from railride.studies.tuning import tune

#: the paper's laws and the inner loop, each tuned alike (railride.studies.tuning)
PAPER_LAWS = ("inner", "pid", "sas-attitude", "sas-attitude-ride")

HERE = Path(__file__).parent
SCALES = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)
FIELD_SCALES = (2.0, 4.0, 8.0, 16.0)


def probe_variants() -> list[str]:
    """The two probes of what holds the field-scaled damper back: the x 16 field part with a coil
    100 times faster, with and without the hysteretic (Bouc-Wen) force. Without it the damper is
    a variable viscous one: alpha_b's force per volt replaced by 0.004 s x alpha_b of viscous
    damping per volt (a choice of range, not a fit), about 0.58 MN s/m at 2.25 V."""
    r = dampers.RAILWAY
    fast = r.replace(alpha_b=r.alpha_b * 16, c0b=r.c0b * 16, eta=5000.0)
    viscous = r.replace(alpha_a=0.0, alpha_b=0.0, c0b=r.c0b * 16 + r.alpha_b * 16 * 0.004, eta=5000.0)
    dampers.PRESETS["probe-fast-coil"] = fast
    dampers.PRESETS["probe-fast-coil-no-hysteresis"] = viscous
    return ["probe-fast-coil", "probe-fast-coil-no-hysteresis"]


def field_variant(k: float) -> str:
    """Register railway with its field-dependent force parameters times k, 0 V force kept."""
    name = f"railway-field-x{k:g}"
    r = dampers.RAILWAY
    dampers.PRESETS[name] = r.replace(alpha_b=r.alpha_b * k, c0b=r.c0b * k)
    return name


CONTROLLERS = ("pid", "sas-attitude", "sas-attitude-ride")


def ratios(gains: GainSet, damper: str, scale: float) -> dict:
    cases = [Case("paper-sine")] + [
        Case("paper-sine", suspension=c, damper=damper, damper_scale=scale) for c in CONTROLLERS
    ]
    rows = run_cases(cases, base_gains=gains)
    rms = rows[[f"{r}_rms" for r in RESPONSES]].to_numpy()
    return {c: rms[i + 1] / rms[0] for i, c in enumerate(CONTROLLERS)}


def main() -> None:
    records = []
    shipped = GainSet.default()
    devices = [("railway", s, s, PAPER_LAWS) for s in SCALES]
    devices += [(field_variant(k), 1.0, k, PAPER_LAWS) for k in FIELD_SCALES]
    devices += [(name, 1.0, 16.0, PAPER_LAWS) for name in probe_variants()]
    devices += [("ideal-damper", 1.0, 1.0, PAPER_LAWS[1:]), ("ideal", 1.0, 1.0, PAPER_LAWS[1:])]
    for damper, scale, factor, phases in devices:
        t0 = time.perf_counter()
        tuned = tune(phases, damper=damper, damper_scale=scale).gains
        series = "field" if damper.startswith("railway-field") else "probe" if damper.startswith("probe") else damper
        for gains_name, gains in (("tuned for this damper", tuned), ("shipped", shipped)):
            for c, r in ratios(gains, damper, scale).items():
                records.append(
                    {
                        "damper": damper,
                        "series": series,
                        "factor": factor,
                        "gains": gains_name,
                        "controller": c,
                        **{f"{k}_ratio": float(v) for k, v in zip(RESPONSES, r)},
                        "worst_ratio": float(r.max()),
                        "inner_G": gains.inner.G,
                    }
                )
        print(f"{damper} x{factor:g}: {time.perf_counter() - t0:.0f} s", file=sys.stderr)
    frame = pd.DataFrame.from_records(records)
    frame.to_csv(HERE / "authority.csv", index=False, float_format="%.5g")
    plot(frame)


def plot(frame: pd.DataFrame) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), sharey=True, constrained_layout=True)
    labels = {"pid": "PID", "sas-attitude": "SAS (attitude)", "sas-attitude-ride": "SAS (attitude+ride)"}
    for ax, c in zip(axes, CONTROLLERS):
        mine = frame[frame.controller == c]
        whole = mine[mine.series == "railway"]
        tuned = whole[whole.gains == "tuned for this damper"]
        ax.plot(tuned.factor, tuned.worst_ratio, "-o", label="whole damper x k, tuned for it")
        p = whole[whole.gains == "shipped"]
        ax.plot(p.factor, p.worst_ratio, "--s", ms=4, label="whole damper x k, shipped gains")
        one = tuned[tuned.factor == 1.0]
        field = pd.concat([one, mine[(mine.series == "field") & (mine.gains == "tuned for this damper")]])
        ax.plot(field.factor, field.worst_ratio, "-^", label="field part x k (0 V force kept), tuned")
        for damper, color in (("ideal-damper", "tab:purple"), ("ideal", "tab:red")):
            b = frame[(frame.controller == c) & (frame.damper == damper) & (frame.gains == "tuned for this damper")]
            ax.axhline(float(b.worst_ratio.iloc[0]), color=color, lw=1, label=f"{damper}, tuned for it")
        ax.axhline(1.0, color="k", lw=0.8)
        ax.set_xscale("log", base=2)
        ax.set_ylim(0.0, 1.6)
        ax.set_xlabel("force scale k (1 = railway: 1.7 kN at 0 V, 20 kN at 2.25 V)")
        ax.set_title(labels[c])
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("worst of the four RMS ratios to passive")
    axes[0].legend(fontsize=7)
    fig.suptitle(
        "Damper authority on paper-sine: each damper size tuned by railride tune's defaults "
        "(tuned and judged on the same track)",
        fontsize=10,
    )
    fig.savefig(HERE / "authority.png", dpi=110)


if __name__ == "__main__":
    if sys.argv[1:] == ["--plot"]:  # redraw from authority.csv
        plot(pd.read_csv(HERE / "authority.csv"))
    else:
        main()
