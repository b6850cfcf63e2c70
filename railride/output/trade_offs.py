"""The trade-offs of a controller comparison in words: one line per pair of suspensions where one
wins a response by losing another (`railride.studies.comparison.Comparison.trade_offs`), shared by
the command line and the HTML report so that both say the same thing."""

from __future__ import annotations

#: the responses' names in the sentences, keyed as in the comparison's metrics
RESPONSE_WORDS = {
    "acceleration_m_s2": "acceleration",
    "displacement_m": "displacement",
    "pitch_deg": "pitch",
    "roll_deg": "roll",
}


def trade_off_lines(doc: dict) -> list[str]:
    """One line per trade-off of a comparison's ``to_dict()``: what a controller loses for what
    it wins, against passive and against each other controller."""
    labels = {r["name"]: r["label"] for r in doc["controllers"]}
    lines = []
    for t in doc.get("trade_offs", []):
        if not t["worse_on"]:
            continue
        a, b = labels[t["controller"]], labels.get(t["than"], t["than"])
        better = ", ".join(RESPONSE_WORDS.get(r, r) for r in t["better_on"])
        worse = ", ".join(RESPONSE_WORDS.get(r, r) for r in t["worse_on"])
        if better:
            lines.append(f"trade-off: {a} beats {b} on {better} but is worse on {worse}")
        else:  # not a trade: one is better wherever they differ
            lines.append(f"no trade-off: {b} beats {a} on {worse} and is worse on nothing")
    return lines
