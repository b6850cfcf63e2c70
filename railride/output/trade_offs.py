"""The trade-offs of a controller comparison in words: one line per group of suspensions where one
wins a response by losing another (`railride.studies.comparison.Comparison.trade_offs`), shared by
the command line and the HTML report so that both say the same thing.

Pairs with the same winner and the same responses won, lost and level are one line, so that
eleven suspensions give a list one can read; responses within the comparison's level tolerance
are neither won nor lost. One line names the suspensions whose peak-to-peak values are above
passive's, and by how much; the last line states the tolerance."""

from __future__ import annotations

#: the responses' names in the sentences, keyed as in the comparison's metrics
RESPONSE_WORDS = {
    "acceleration_m_s2": "acceleration",
    "displacement_m": "displacement",
    "pitch_deg": "pitch",
    "roll_deg": "roll",
}


def _words(responses) -> str:
    return ", ".join(RESPONSE_WORDS.get(r, r) for r in responses)


def trade_off_lines(doc: dict) -> list[str]:
    """The trade-offs of a comparison's ``to_dict()`` in sentences: ``trade-off:`` where a
    suspension beats others on some responses and is worse on others, ``no trade-off:`` where
    one is better wherever they differ, ``level:`` where two differ on no response by more than
    the tolerance; then the tolerance itself. Empty when nothing is compared."""
    labels = {r["name"]: r["label"] for r in doc["controllers"]}
    groups: dict[tuple, list[str]] = {}
    level_pairs = []
    for t in doc.get("trade_offs", []):
        level = tuple(t.get("level_on", ()))
        better, worse = tuple(t["better_on"]), tuple(t["worse_on"])
        a, b = labels.get(t["controller"], t["controller"]), labels.get(t["than"], t["than"])
        if better and worse:
            groups.setdefault(("trade-off", a, better, worse, level), []).append(b)
        elif worse:  # not a trade: the other is better wherever they differ
            groups.setdefault(("no trade-off", b, worse, (), level), []).append(a)
        elif not better:
            level_pairs.append(f"{a} and {b}")
    lines = []
    for (kind, winner, won, lost, level), losers in groups.items():
        text = f"{kind}: {winner} beats {', '.join(losers)} on {_words(won)}"
        text += f" but is worse on {_words(lost)}" if kind == "trade-off" else " and is worse on nothing"
        lines.append(text + (f"; level on {_words(level)}" if level else ""))
    if level_pairs:
        lines.append(f"level on every response: {'; '.join(level_pairs)}")
    lines += _peak_lines(doc, labels)
    tol = doc.get("settings", {}).get("level_tolerance")
    if doc.get("trade_offs") and tol is not None:
        lines.append(
            f"(RMS and peak-to-peak values within {100 * tol:.3g} % of the larger count as level, "
            "neither better nor worse: --level-tolerance)"
        )
    return lines


def _peak_lines(doc: dict, labels: dict) -> list[str]:
    """One line on the peaks: the suspensions whose peak-to-peak is above passive's on some
    response, by how much (a law that lowers a response's RMS may raise its peaks); or that
    none is. Empty for a document without peak-to-peak trade-offs."""
    against = [t for t in doc.get("trade_offs", []) if t["than"] == "passive" and "ptp_worse_on" in t]
    if not against:
        return []
    ptp = {r["name"]: {k: v.get("ptp") for k, v in (r.get("metrics") or {}).items()} for r in doc["controllers"]}
    parts = []
    for t in against:
        if not t["ptp_worse_on"]:
            continue
        own, base = ptp.get(t["controller"], {}), ptp.get("passive", {})
        said = []
        for r in t["ptp_worse_on"]:
            x, b = own.get(r), base.get(r)
            rise = f" ({_percent(100 * (x - b) / b)})" if x is not None and b else ""
            said.append(RESPONSE_WORDS.get(r, r) + rise)
        parts.append(f"{labels.get(t['controller'], t['controller'])} on {', '.join(said)}")
    if not parts:
        return ["peak-to-peak: no suspension is worse than passive on any response"]
    return [f"peak-to-peak worse than passive: {'; '.join(parts)}"]


def _percent(p: float) -> str:
    return f"{p:+.3g} %" if abs(p) < 1000 else f"{p:+.0f} %"


def paper_ranking_text(ranking: dict) -> str:
    """The line on how this comparison's order of the paper's controllers agrees with Table 1
    (`Comparison.paper_ranking`): the responses ordered alike, those ordered otherwise with
    both orders, and the range of railride's reductions over the paper's."""
    from railride.secondary.control import LABELS

    responses = {r: v for r, v in ranking.items() if r != "reduction_ratio"}
    same = [RESPONSE_WORDS.get(r, r) for r, v in responses.items() if v["agrees"]]
    other = [
        f"{RESPONSE_WORDS.get(r, r)} (paper: {', '.join(LABELS[n] for n in v['paper'])}; here: "
        f"{', '.join(LABELS[n] for n in v['railride'])})"
        for r, v in responses.items()
        if not v["agrees"]
    ]
    parts = ([f"the same on {', '.join(same)}"] if same else []) + ([f"another on {'; '.join(other)}"] if other else [])
    lo, hi = ranking["reduction_ratio"]
    return (
        "Against the paper's order of its controllers by RMS reduction (best first, level within the tolerance): "
        + "; ".join(parts)
        + f". The reductions here are {lo:.2f} to {hi:.2f} times the paper's."
    )


#: a study's metrics in the sentences (`study_trade_off_lines`)
STUDY_WORDS = {f"{k}_rms": v for k, v in RESPONSE_WORDS.items()} | {"centre_N_MV_z": "N_MV,z"}


def study_trade_off_lines(entries: list[dict], level_percent: float) -> list[str]:
    """A study's trade-offs (`StudyResult.trade_offs`) in sentences: per controller, each set of
    metrics won and lost against passive on average, with the conditions (speed, load, and the
    stiffness, fault and delay where not the default) where it holds; then the level band."""
    from railride.secondary.control import LABELS

    groups: dict[tuple, list[str]] = {}
    for e in entries:
        if not (e["better_on"] and e["worse_on"]):
            continue
        where = [f"{e['speed_m_s']:g} m/s", f"load {e['load']:g}"]
        where += [] if e["stiffness"] == 1.0 else [f"k_sz x {e['stiffness']:g}"]
        where += [] if e["fault"] == "none" else [f"fault {e['fault']}"]
        where += [] if e["delay"] == 1 else [f"delay {e['delay']}"]
        key = (e["controller"], tuple(e["better_on"]), tuple(e["worse_on"]))
        groups.setdefault(key, []).append(", ".join(where))
    lines = []
    for (name, won, lost), where in groups.items():
        words = [STUDY_WORDS.get(m, m) for m in won], [STUDY_WORDS.get(m, m) for m in lost]
        lines.append(
            f"trade-off: {LABELS.get(name, name)} beats passive on {', '.join(words[0])} but is worse on "
            f"{', '.join(words[1])}, on average ({'; '.join(where)})"
        )
    if lines:
        lines.append(
            f"(a mean reduction within {level_percent:g} % of passive counts as level, neither better nor worse)"
        )
    return lines
