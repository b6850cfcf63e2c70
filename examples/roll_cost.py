"""Why the MR dampers cost carbody roll on random track, and a roll-aware demand that removes
the cost (docs/results.md, "The roll cost of the MR dampers, traced").

    python examples/roll_cost.py [--out DIR]

Five tables, each a measurement that separates the candidate causes: (1) constant voltage
against passive and viscous dampers, (2) the Bouc-Wen pre-yield stiffness against its yield
force, (3) the track input's amplitude and components, (4) the closed loops with the roll part
of their demand removed and on the ideal damper, (5) the remedy, a roll skyhook added to each
law's demand, its one gain tuned on training track and judged on held-out track. Every run is
seeded; RMS over 2-12 s of a 12 s run; ratios are to passive on the same track. About 45 s
on one core. Writes one CSV per table into DIR.
"""

import argparse
import csv
import json
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.signal import butter, sosfiltfilt

import railride as rr
from railride.model.track import MeasuredTrack
from railride.secondary.controllers import Skyhook

RESPONSES = ("acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg")
SPEEDS = (30.0, 45.0, 60.0)
DURATION, WINDOW = 12.0, (2.0, 12.0)
PARAMS = rr.VehicleParams.preset("paper")
GAINS = rr.GainSet.default()  # the shipped (paper-sine) gains, named so the run does not depend on defaults
RAILWAY = rr.dampers.preset("railway")
LAWS = ("pid", "sas-attitude", "sas-attitude-ride", "skyhook", "skyhook-on-off", "hybrid", "clipped-optimal")
#: corner pattern of a roll moment (corners 1R, 1L, 2R, 2L), unit length
ROLL = np.array([-1.0, 1.0, -1.0, 1.0]) / 2.0
CHUNK = 16  # suspensions per batch


# -- the runs ----------------------------------------------------------------------------------
def track(seed, speed, name="fra4", crosslevel=1.0, vertical=1.0):
    """A random track with its vertical profile and cross-level scaled apart: the realisation
    sampled every 2 cm into a measured profile (PCHIP reproduces the run of the random track)."""
    base = rr.scenario(name, seed=seed, speed=speed, duration=DURATION)
    if crosslevel == 1.0 and vertical == 1.0:
        return base
    s = np.arange(0.0, speed * DURATION + 5.0, 0.02)
    z_l, z_r, _, _ = base.track.evaluate(s)
    mean, half = (z_l + z_r) / 2, (z_l - z_r) / 2
    rails = MeasuredTrack(s, vertical * mean + crosslevel * half, vertical * mean - crosslevel * half, source="split")
    return rr.Scenario(rails, speed, DURATION, name=f"{name}-split")


def measure(result, damper=None):
    """Per sample: the four RMS responses, the damper force RMS [N], the RMS carbody roll [deg]
    below the track's band (under 0.8 V / 100 m, where the random track has no input: only a
    nonlinear suspension puts roll there) and, for MR dampers, the fraction of time in the
    pre-yield range and the mean coil voltage [V]."""
    rms = result.metrics(window=WINDOW).sel(statistic="rms").transpose(..., "response")
    rows = np.atleast_2d(rms.sel(response=list(RESPONSES)).values)
    full = result.dataset
    speed = json.loads(str(np.atleast_1d(full["scenario"].values)[0]))["speed_m_s"]
    low = butter(4, 0.8 * speed / 100.0, fs=1.0 / float(full.time[1] - full.time[0]), output="sos")
    roll = np.degrees(sosfiltfilt(low, full["carbody_roll"].values.reshape(len(rows), -1), axis=-1))
    keep = (full.time.values >= WINDOW[0]) & (full.time.values <= WINDOW[1])
    ds = full.sel(time=slice(*WINDOW))
    f = ds["secondary_damper_force"].values.reshape(len(rows), -1, 4)
    out = [
        {"ratios": r, "force": float(np.sqrt(np.mean(fi**2))), "low": float(np.sqrt(np.mean(lo[keep] ** 2)))}
        for r, fi, lo in zip(rows, f, roll)
    ]
    if damper is not None and "damper_hysteretic_z" in ds:
        z = ds["damper_hysteretic_z"].values.reshape(len(out), -1, 4)
        xd = ds["secondary_deflection_velocity"].values.reshape(z.shape)
        u = ds["damper_voltage"].values.reshape(z.shape)
        # pre-yield: tangent dz/dx above half its value A at z = 0 (Bouc-Wen, n = 1)
        dzdx = damper.A - damper.gamma * np.sign(xd) * z - damper.beta * np.abs(z)
        for o, dz, uu in zip(out, dzdx, u):
            o["preyield"], o["voltage"] = float(np.mean(dz > damper.A / 2)), float(uu.mean())
    return out


def runs(scenario, suspensions, params=PARAMS, damper=None):
    """The runs of ``suspensions`` on ``scenario`` (one batch), their RMS divided by passive's."""
    passive = measure(rr.simulate(scenario, params))[0]
    suspensions = list(suspensions)
    out = []
    for i in range(0, len(suspensions), CHUNK):  # chunks bound the memory of a batch's histories
        out += measure(rr.simulate(scenario, params, suspensions[i : i + CHUNK]), damper)
    for o in out:
        o["ratios"] = o["ratios"] / passive["ratios"]
    return out, passive


def mr(voltage, damper=RAILWAY):
    return rr.Suspension.semi_active(damper, voltage=voltage)


def closed(controller, ideal=False):
    if ideal:
        return rr.Suspension.ideal(controller, dissipative=True)
    return rr.Suspension.semi_active(RAILWAY, controller=controller, inner=GAINS.inner)


# -- outer loops changed by a projection or an added term (anything with gains, name, to_dict) --
@dataclass(frozen=True)
class Changed:
    """``law`` with its demand projected (``keep`` "no-roll": the left/right-antisymmetric part
    removed) and ``extra``'s demand added (a law on the carbody states)."""

    law: Any
    keep: str = "all"
    extra: Any = None

    @property
    def name(self):
        return self.law.name

    @property
    def voltage_law(self):
        return getattr(self.law, "voltage_law", "tracking")

    def gains(self, vehicle):
        G, H = self.law.gains(vehicle)
        n = vehicle.M.shape[0]
        G = _full(G, n)
        if self.keep == "no-roll":
            P = np.eye(4) - np.outer(ROLL, ROLL)
            G, H = P @ G, P @ H
        if self.extra is not None:
            G2, H2 = self.extra.gains(vehicle)
            G, H = G + _full(G2, n), H + H2
        return G, H

    def to_dict(self):
        extra = None if self.extra is None else self.extra.to_dict()
        return {"law": self.law.to_dict(), "keep": self.keep, "extra": extra}


def _full(G, n):
    """A 4 x 6 gain on the carbody states as the 4 x 2n gain on (q, q')."""
    if G.shape[1] == 2 * n:
        return G
    out = np.zeros((4, 2 * n))
    out[:, :3], out[:, n : n + 3] = G[:, :3], G[:, 3:]
    return out


def roll_skyhook(law, c_theta):
    """``law`` plus a roll skyhook: a roll moment -c_theta theta_c' spread over the corners by
    the decoupling transformation (equal and opposite at left and right)."""
    return law if c_theta == 0 else Changed(law, extra=Skyhook(c_z=0.0, c_phi=0.0, c_theta=c_theta))


# -- the tables ---------------------------------------------------------------------------------
def show(title, header, rows, out, name):
    print(f"\n{title}")
    widths = [max(len(str(h)), *(len(str(r[i])) for r in rows)) for i, h in enumerate(header)]
    print("  ".join(str(h).rjust(w) for h, w in zip(header, widths)))
    for r in rows:
        print("  ".join(str(v).rjust(w) for v, w in zip(r, widths)))
    with open(out / f"{name}.csv", "w", newline="") as fh:
        csv.writer(fh).writerows([header, *rows])


def f2(x):
    return f"{x:.2f}"


def table_voltage(out):
    """(1) Constant voltage: the roll cost grows with the voltage; a viscous damper with the same
    or a larger RMS force costs far less roll."""
    cases = [(seed, v) for seed in (0, 1) for v in SPEEDS]
    volts = (0.0, 0.5, 1.0, 1.5, 2.25)
    acc = {k: [] for k in ("passive", *volts, "visc 0.5", "visc 2", "visc 4")}
    modes = []
    for seed, v in cases:
        sc = track(seed, v)
        res, passive = runs(sc, [mr(u) for u in volts], damper=RAILWAY)
        acc["passive"].append({**passive, "ratios": np.ones(4)})
        for u, r in zip(volts, res):
            acc[u].append(r)
        for k in (0.5, 2, 4):  # one batch shares one damper model: a run per dashpot
            acc[f"visc {k:g}"] += runs(sc, [rr.Suspension.passive(rr.dampers.Viscous(c=k * PARAMS.c_sz))])[0]
        p = rr.simulate(sc, PARAMS).dataset.sel(time=slice(*WINDOW))
        # the carbody's motion at the dampers, per mode [mm]: bounce, l pitch, d_s roll
        modes.append(
            [1e3 * np.sqrt(np.mean(p[c].values ** 2)) * k for c, k in
             (("carbody_bounce", 1.0), ("carbody_pitch", PARAMS.l), ("carbody_roll", PARAMS.d_s))]
            + [passive["ratios"][3]]
        )  # fmt: skip
    rows = []
    for k, rs in acc.items():
        ratios = np.array([r["ratios"] for r in rs])
        label = k if k == "passive" else f"viscous {k.split()[1]} c_sz" if isinstance(k, str) else f"MR {k:g} V"
        pre = f2(np.mean([r["preyield"] for r in rs])) if "preyield" in rs[0] else "-"
        rows.append(
            [label, f"{np.mean([r['force'] for r in rs]) / 1e3:.1f}", f2(ratios[:, 3].mean()),
             f"{ratios[:, 3].min():.2f}-{ratios[:, 3].max():.2f}", *map(f2, ratios[:, :3].mean(axis=0)),
             f"{np.mean([r['low'] for r in rs]):.4f}", pre]
        )  # fmt: skip
    header = ["damper", "F RMS kN", "roll", "roll min-max", "acc", "bounce", "pitch", "roll < band deg", "pre-yield"]
    show("(1) fra4 seeds 0-1 at 30/45/60 m/s: RMS ratio to passive (mean of 6)", header, rows, out, "voltage")
    m = np.mean(modes, axis=0)
    print(f"passive carbody motion at the dampers [mm RMS]: bounce {m[0]:.1f}, pitch {m[1]:.1f}, roll {m[2]:.2f}")
    print(f"passive carbody roll: {m[3]:.4f} deg RMS")


def table_bouc_wen(out):
    """(2) At 1 V: the pre-yield stiffness alpha A and the yield force alpha A / (gamma + beta)
    changed apart (A, gamma, beta scaled). The roll cost follows the yield force."""
    stiff, yield_ = (0.1, 1.0, 10.0), (0.25, 0.5, 1.0, 2.0)
    rows = []
    for k in stiff:
        row = [f"pre-yield stiffness x {k:g}"]
        for f in yield_:
            d = RAILWAY.replace(A=RAILWAY.A * k, gamma=RAILWAY.gamma * k / f, beta=RAILWAY.beta * k / f)
            rs = [runs(track(0, v), [mr(1.0, d)], damper=d)[0][0] for v in SPEEDS]
            roll = np.mean([r["ratios"][3] for r in rs])
            row.append(f"{roll:.2f} ({np.mean([r['preyield'] for r in rs]):.2f})")
        rows.append(row)
    header = ["", *(f"yield force x {f:g}" for f in yield_)]
    show("(2) fra4 seed 0 at 30/45/60 m/s, 1 V: roll ratio (fraction of time pre-yield)", header, rows, out, "bouc_wen")


def table_input(out):
    """(3) The input's amplitude and components: a linear element costs the same ratio at every
    amplitude, a force that does not scale with the motion does not."""
    variants = [
        ("fra4", {}, PARAMS),
        ("cross-level only", {"vertical": 0.0}, PARAMS),
        ("cross-level x 0.25", {"crosslevel": 0.25}, PARAMS),
        ("cross-level x 4", {"crosslevel": 4.0}, PARAMS),
        ("vertical x 0.25", {"vertical": 0.25}, PARAMS),
        ("vertical x 4", {"vertical": 4.0}, PARAMS),
        ("fra4, vehicle k_sy x 0.1", {}, PARAMS.replace(k_sy=0.1 * PARAMS.k_sy)),
    ]
    volts = (0.0, 1.0, 2.25)
    rows = []
    for label, scale, params in variants:
        rolls = np.array(
            [[r["ratios"][3] for r in runs(track(s, v, **scale), [mr(u) for u in volts], params)[0]]
             for s in (0, 1) for v in SPEEDS]
        )  # fmt: skip
        rows.append([label, *map(f2, rolls.mean(axis=0))])
    header = ["input", *(f"roll {u:g} V" for u in volts)]
    show("(3) fra4 seeds 0-1 at 30/45/60 m/s: roll ratio to passive on the same input", header, rows, out, "input")


def table_closed(out):
    """(4) Closed loops: the roll part of the demand removed, the same demand on the ideal
    semi-active damper."""
    cases = [track(s, v) for s in (0, 1) for v in SPEEDS]
    acc = {law: [] for law in LAWS}
    for sc in cases:
        laws = [GAINS.controller(n) for n in LAWS]
        mrs, _ = runs(sc, [closed(c) for c in laws] + [closed(Changed(c, "no-roll")) for c in laws], damper=RAILWAY)
        ideal, _ = runs(sc, [closed(c, ideal=True) for c in laws])
        for i, n in enumerate(LAWS):
            acc[n].append((mrs[i], mrs[i + len(LAWS)], ideal[i]))
    rows = []
    for n, rs in acc.items():
        rows.append(
            [n, f2(np.mean([a["voltage"] for a, _, _ in rs])), f2(np.mean([a["ratios"][0] for a, _, _ in rs])),
             f2(np.mean([a["ratios"][3] for a, _, _ in rs])), f2(np.mean([b["ratios"][3] for _, b, _ in rs])),
             f2(np.mean([c["ratios"][3] for _, _, c in rs]))]
        )  # fmt: skip
    header = ["law", "mean V", "acc", "roll", "roll, no roll demand", "roll, ideal damper"]
    show("(4) fra4 seeds 0-1 at 30/45/60 m/s, shipped gains: RMS ratio to passive", header, rows, out, "closed")


def ratios_of(cases, suspensions_of):
    """Mean ratios over ``cases`` for each list entry of suspensions_of(); (n, cases, 4)."""
    per = []
    for sc in cases:
        res, _ = runs(sc, suspensions_of())
        per.append([r["ratios"] for r in res])
    return np.array(per).transpose(1, 0, 2)


def table_remedy(out):
    """(5) A roll skyhook added to each law's demand: its gain c_theta chosen per law on training
    track by the shipped gains' objective (minimax: the worst of the four mean ratios), then
    judged on held-out track seeds and on paper-sine."""
    grid = (0.0, 1e6, 2e6, 4e6, 8e6, 16e6, 32e6)  # N m s/rad
    train = [track(0, v, name) for name in ("fra4", "fra5") for v in SPEEDS]
    held = [track(s, v, name) for name in ("fra4", "fra5") for v in SPEEDS for s in range(100, 105)]
    laws = {n: GAINS.controller(n) for n in LAWS}
    t = ratios_of(train, lambda: [closed(roll_skyhook(c, ct)) for c in laws.values() for ct in grid])
    t = t.mean(axis=1).reshape(len(LAWS), len(grid), 4)
    pick = {n: grid[int(np.argmin(t[i].max(axis=1)))] for i, n in enumerate(LAWS)}
    rows = [[n, *(f"{w:.2f}/{r:.2f}" for w, r in zip(t[i].max(axis=1), t[i][:, 3]))] for i, n in enumerate(LAWS)]
    header = ["law", *(f"c_theta {ct / 1e6:g}" for ct in grid)]
    title = "(5a) training: fra4 and fra5 seed 0 at 30/45/60 m/s: worst/roll mean ratio per c_theta [MN m s/rad]"
    show(title, header, rows, out, "remedy_training")
    h = ratios_of(held, lambda: [closed(roll_skyhook(c, ct)) for n, c in laws.items() for ct in (0.0, pick[n])])
    h = h.reshape(len(LAWS), 2, len(held), 4)
    sine = rr.scenario("paper-sine", duration=DURATION)  # the shipped gains' own track
    s = ratios_of([sine], lambda: [closed(roll_skyhook(c, ct)) for n, c in laws.items() for ct in (0.0, pick[n])])
    s = s.reshape(len(LAWS), 2, 4)
    rows = []
    for i, n in enumerate(LAWS):
        for j, tag in enumerate(("as shipped", f"+ roll skyhook {pick[n] / 1e6:g} MN m s/rad")):
            m = h[i, j].mean(axis=0)
            rows.append(
                [n, tag, *map(f2, m), f"{int((h[i, j][:, 3] > 1).sum())}/{len(held)}", f2(m.max()),
                 " / ".join(f2(x) for x in s[i, j])]
            )  # fmt: skip
    header = ["law", "demand", "acc", "bounce", "pitch", "roll", "roll > passive", "worst", "paper-sine a/b/p/r"]
    title = "(5b) held out: fra4 and fra5 seeds 100-104 at 30/45/60 m/s (30 tracks), mean RMS ratio to passive"
    show(title, header, rows, out, "remedy")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=Path, default=None, help="folder for the output files (default: a temporary folder)"
    )
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="railride-"))
    out.mkdir(parents=True, exist_ok=True)
    table_voltage(out)
    table_bouc_wen(out)
    table_input(out)
    table_closed(out)
    table_remedy(out)
    print(f"\nWrote the tables as CSV into {out}")


if __name__ == "__main__":
    main()
