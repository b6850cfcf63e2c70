"""The ride in service: where a design is given each speed and load's share of the time in
service (`railride.studies.design.service_shares`), each law's RMS responses over that service,
as a passenger rides them, beside passive's.

A ratio averaged over the points (the design's score) says how much better a law is on
average; it does not say how the ride is over a day of service, which the slow, smooth points
weigh as much as the fast, rough ones. The service RMS does: the square root of the mean
square over the held-out runs at each speed and load, weighted by the point's share (every run
lasts the same time, so this is the RMS over the time in service)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from railride.studies.objectives import RATIO_NAMES, RMS_COLUMNS

#: how the sentence shows each response: its word, the factor to its unit and the unit
_SHOWN = {
    "acceleration_m_s2_rms": ("acceleration", 1.0, "m/s2"),
    "displacement_m_rms": ("displacement", 1e3, "mm"),
    "pitch_deg_rms": ("pitch", 1.0, "deg"),
    "roll_deg_rms": ("roll", 1.0, "deg"),
}


def service_rms(runs: pd.DataFrame, service: dict, laws) -> dict:
    """Per law of ``laws`` and passive: {response column: RMS over the time in service}, from
    the held-out ``runs`` (a design's `runs`: ``controller``, ``speed_m_s``, ``load``,
    ``diverged_at_s`` and the RMS columns) and ``service`` ({(speed, load): share}). A law with
    a point where no run finished (all diverged) has None: its service is not known."""
    out: dict[str, dict | None] = {}
    finished = runs[~np.isfinite(runs["diverged_at_s"].to_numpy(dtype=float))]
    groups = dict(list(finished.groupby(["controller", "speed_m_s", "load"])))
    for law in ("passive", *laws):
        total = dict.fromkeys(RMS_COLUMNS, 0.0)
        parts = [(share, groups.get((law, speed, load))) for (speed, load), share in service.items()]
        known = [(share, part) for share, part in parts if part is not None and not part.empty]
        if len(known) < len(parts):
            out[law] = None
            continue
        for share, part in known:
            for column in RMS_COLUMNS:
                total[column] += share * float(np.mean(part[column].to_numpy(dtype=float) ** 2))
        out[law] = {c: math.sqrt(v) for c, v in total.items()}
    return out


def ranking_entries(rms: dict, law: str) -> dict:
    """What a ranking entry records of ``law``'s service (`service_rms`' ``rms``): per response
    its RMS in service, passive's and their ratio; empty where either is not known."""
    own, passive = rms.get(law), rms.get("passive")
    if own is None or passive is None:
        return {}
    return {
        "service_rms": {
            c: {"value": own[c], "passive": passive[c], "ratio": own[c] / passive[c] if passive[c] > 0 else None}
            for c in RMS_COLUMNS
        }
    }


def service_sentence(entry: dict, label: str, kept_passive: bool = False) -> str:
    """One sentence of a ranking entry's service RMS (`ranking_entries`), or "" without one;
    ``kept_passive``: the design keeps passive, which the sentence then weighs against where
    the law's service RMS is below passive's in every response."""
    rms = entry.get("service_rms")
    if not rms:
        return ""
    parts = []
    for column, word in zip(RMS_COLUMNS, RATIO_NAMES):
        name, factor, unit = _SHOWN.get(column, (word, 1.0, ""))
        r = rms[column]
        ratio = f" (x{r['ratio']:.3f})" if r["ratio"] is not None else ""
        parts.append(f"{name} {factor * r['value']:.3g} against passive's {factor * r['passive']:.3g} {unit}{ratio}")
    text = (
        f"Over the time in service (the held-out runs' mean squares weighted by each speed and load's share), "
        f"{label}'s RMS responses are: " + "; ".join(parts) + "."
    )
    ratios = [rms[c]["ratio"] for c in RMS_COLUMNS]
    if kept_passive and all(r is not None and r < 1.0 for r in ratios):
        text += (
            f" So by the ride in service {label} is better than passive in every response, while the score keeps "
            "passive: the score weighs each speed and load's ratios by its share, the ride in service its mean "
            "squares, where the rougher points count for more."
        )
    return text
