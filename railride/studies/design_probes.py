"""What a design runs beside its judging (docs/design.md, References and a fault): every law's
tuned gains on the two ideal devices, and the two leading laws with a failed damper.

- `references`: each law with the same gains on the ideal actuator (force = demand) and on the
  ideal semi-active damper (the demand where it dissipates, else 0), judged on the same held-out
  runs. They are references, not bounds: with the same gains the MR dampers can do better than
  either (their lag and hysteresis change the loop).
- `fault_check`: what would change the answer. The two leading laws run with the coil driver of
  one damper failed (`FAULT`, its command at v_min from the start) on the same held-out runs;
  the record says whether their order holds at every speed and load, and the sentence joins the
  recommendation.

Both take ``scores(laws=..., damper=..., faults=...)``, which judges laws on the plan's held-out
runs and returns the points of `railride.studies.design_result.rank`.
"""

from __future__ import annotations

import math

import numpy as np

#: the fault tried on the leading laws: the front right damper's coil driver fails from the start
#: (an MR damper then gives its 0 V force); a damper without a coil is disconnected instead
FAULT = "1R-off"
FAULT_NO_COIL = "1R-disconnected"
#: the devices of the references, by their damper name, and their words
DEVICES = {"ideal": "ideal actuator", "ideal-damper": "ideal semi-active damper"}


def _ideal(damper) -> bool:
    from railride.secondary import dampers
    from railride.secondary.suspension import damper_model

    return damper_model(damper, 1.0).law == dampers.LAW_IDEAL


def _worst(points: list, law: str, offset=None) -> float | None:
    """A law's score over the points as the ranking takes it (its largest, or its mean weighted
    by time in service: `law_score`), None where one is missing or not finite (it diverged)."""
    from railride.studies.design_result import law_score

    score = law_score(points, law, offset)
    return score if score is not None and np.isfinite(score) else None


def asks(plan, leaders: list) -> list[dict]:
    """The keyword arguments of every ``scores`` call that `references` and `fault_check` make,
    in their order: the design runs them all as one batch before either asks (a GPU then steps
    them in one call, not one a device and one for the fault)."""
    out = [] if _ideal(plan.damper) else [{"laws": tuple(plan.laws), "damper": device} for device in DEVICES]
    if leaders:
        out.append({"laws": tuple(leaders), "faults": (FAULT_NO_COIL if _ideal(plan.damper) else FAULT,)})
    return out


def references(plan, gains, scores) -> dict:
    """Per device of `DEVICES`, per law: its score with the design's tuned ``gains`` on that
    device (``score``, the largest over the speeds and loads, None where a run diverged) and its
    score at each (``points``). Empty where the design's own damper is an ideal device."""
    out = {}
    for ask in asks(plan, []):
        device = ask["damper"]
        points = scores(**ask)
        out[device] = {
            law: {
                "score": _worst(points, law, plan.objective.constraint_offset),
                "points": [
                    {"speed_m_s": p["speed_m_s"], "load": p["load"], "score": _plain(p["scores"].get(law))}
                    for p in points
                ],
            }
            for law in plan.laws
        }
    return out


def fault_check(plan, leaders: list, points: list, scores) -> dict | None:
    """The two leading laws (``leaders``, best first; their healthy ``points``) with `FAULT`:
    each law's worst score, healthy and faulted, the speeds and loads where their order holds
    and where it turns, and one sentence. None where fewer than one law was ranked."""
    from railride.secondary.control import LABELS

    if not leaders:
        return None
    ask = asks(plan, leaders)[-1]
    fault = ask["faults"][0]
    faulted = scores(**ask)
    offset = plan.objective.constraint_offset
    laws = {law: {"healthy": _worst(points, law, offset), "faulted": _worst(faulted, law, offset)} for law in leaders}
    over = "in service" if plan.service is not None else "at worst"
    label = {law: LABELS.get(law, law) for law in leaders}
    if fault == FAULT:
        text = f"With the coil driver of the front right damper failed from the start ({fault}: its command at v_min), "
    else:
        text = f"With the front right damper disconnected from the start ({fault}), "
    text += " and ".join(
        f"{label[law]} scores {_text(v['faulted'], plan.objective)} {over} "
        f"(healthy {_text(v['healthy'], plan.objective)})"
        for law, v in laws.items()
    )
    baseline = plan.objective.passive_score

    def beats(score) -> bool:
        return score is not None and score < baseline

    worse = [label[law] for law, v in laws.items() if beats(v["healthy"]) and not beats(v["faulted"])]
    never = [label[law] for law, v in laws.items() if not beats(v["healthy"]) and not beats(v["faulted"])]
    text += f" (passive {baseline:g})"
    # the scores are worst cases (beating passive at every point) or, with time in service, means
    where = "in service" if plan.service is not None else "everywhere"
    if worse:
        text += f"; {' and '.join(worse)} then no longer beat{'s' * (len(worse) == 1)} passive {where}"
    if never:
        text += f"; {' and '.join(never)} did not beat passive {where} healthy either"
    record = {"fault": fault, "laws": laws, "turns_at": []}
    if len(leaders) == 2:
        first, second = leaders
        turns = []
        for p in faulted:
            a, b = p["scores"].get(first), p["scores"].get(second)
            if a is None or b is None or not (np.isfinite(a) and np.isfinite(b)) or a > b:
                turns.append({"speed_m_s": p["speed_m_s"], "load": p["load"]})
        record["turns_at"] = turns
        if turns:
            where = "; ".join(f"{t['speed_m_s']:g} m/s, load {t['load']:g}" for t in turns)
            text += (
                f"; {label[second]} then scores better at {len(turns)} of {len(faulted)} speeds and loads ({where})."
            )
        else:
            text += f"; {label[first]} still scores better at every speed and load."
    else:
        text += "."
    record["text"] = text
    return record


def _plain(value) -> float | None:
    return float(value) if value is not None and math.isfinite(value) else None


def _text(value, objective) -> str:
    """A score as the ranking shows it: "infeasible (+excess)" where it breaks a constraint,
    not the offset that encodes it (`score_text`)."""
    from railride.studies.design_result import score_text

    return score_text(value, objective, short=True)
