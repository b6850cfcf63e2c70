"""What a design study returns (`railride.studies.design.design`): `DesignResult`, the ranking of
the laws on held-out track (`rank`) and the recommendation in words built from it (`recommend`).

`DesignResult` follows the result protocol: `to_dict` (design.json, schema ``railride.design/1``),
`to_pandas` (design.csv: per law, speed, load and metric the held-out statistics), `plot`
(design.png: the RMS ratios to passive against speed with their 5-95 % bands), `save` (those
files, design_costs.png (each law's score against its damper force), the held-out runs as
design_runs.csv and the tuned gains as gains.toml, all or nothing); `report_contents` (the HTML
report).
"""

from __future__ import annotations

import json
import textwrap
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from railride.analysis.costs import COST_COLUMNS
from railride.analysis.metrics import RESPONSES
from railride.plots import PNG_DPI, FigureOptions
from railride.secondary.control import LABELS
from railride.studies.objectives import PEAK_COLUMN, RATIO_NAMES, TRAVEL_COLUMN, Objective
from railride.studies.design_service import service_sentence

#: the schema of `DesignResult.to_dict` (design.json)
SCHEMA = "railride.design/1"
#: the RMS responses, as the run table names them
RMS_COLUMNS = tuple(f"{r}_rms" for r in RESPONSES)
#: the comfort indices a design reports: EN 12299's N_MV (its vertical term) and Sperling's Wz
#: at the carbody's centre, front and rear floor points, and ISO 2631's Wk-weighted RMS
#: acceleration at the centre
COMFORT_METRICS = (
    "centre_N_MV_z",
    "centre_Wz",
    "centre_aw_Wk",
    "front_N_MV_z",
    "front_Wz",
    "rear_N_MV_z",
    "rear_Wz",
)
#: the peaks a design reports beside the RMS: the carbody's peak-to-peak vertical acceleration
PEAK_METRICS = ("acceleration_m_s2_ptp",)
#: every metric of a held-out run that a design summarises: responses, peaks, comfort, costs
METRICS = (*RMS_COLUMNS, *PEAK_METRICS, *COMFORT_METRICS, *COST_COLUMNS)
#: the band of the statistics
PERCENTILES = (5.0, 95.0)
#: the statistics of a metric, as `to_pandas` and the JSON name them
STATISTICS = ("mean", "p5", "p95", "ratio_mean", "ratio_p5", "ratio_p95")


def _finite(value) -> float | None:
    value = float(value)
    return value if np.isfinite(value) else None


def _label(name: str) -> str:
    return LABELS.get(name, name)


def _at(speed: float, load: float) -> str:
    return f"{speed:g} m/s, load {load:g}"


@dataclass(frozen=True, eq=False)
class DesignResult:
    """The result of `railride.design`. ``summary``: per law (passive first), speed, load and
    metric (`METRICS`, then ``score``, the objective of a run's RMS ratios) the held-out runs
    that did not diverge (``n``), the ``mean``, ``p5`` and ``p95`` of the value and
    ``ratio_mean``, ``ratio_p5`` and ``ratio_p95`` of its ratio to passive on the same run.
    ``runs``: one row per held-out run (law, track, seed, speed, load, metrics, ratios,
    ``score``, ``diverged_at_s``). ``ranking``: the laws, best first (`rank`); ``points``: per
    speed and load, each law's score and what no law improves; ``recommendation``: the words
    (`recommend`); ``diverged``: the laws that diverged, in tuning or judging, and where;
    ``tuning``: the `railride.studies.tune_result.TuneResult` of the training set (its gains:
    ``gains``); ``settings``: every input, the vehicle's record, the versions. ``references``:
    each law's score with the same gains on the ideal devices; ``fault``: the two leading laws
    with a failed damper (`railride.studies.design_probes`)."""

    summary: pd.DataFrame
    runs: pd.DataFrame = field(repr=False)
    ranking: list = field(default_factory=list)
    points: list = field(default_factory=list)
    recommendation: str = ""
    diverged: list = field(default_factory=list)
    tuning: Any = field(default=None, repr=False)
    settings: dict = field(default_factory=dict)
    date: str | None = None
    references: dict = field(default_factory=dict)
    fault: dict | None = None

    @property
    def gains(self):
        """The tuned gains (`GainSet`): every law's, and the inner loop's where it was tuned."""
        return self.tuning.gains

    @property
    def recommended(self) -> str | None:
        """The law ranked first; "passive" where its score is worse than passive's by the same
        objective (`passive_wins`); None when no law could be ranked (every one diverged)."""
        first = self.ranking[0] if self.ranking else None
        if first is None or not first["ranked"]:
            return None
        infeasible = (self.settings.get("objective") or {}).get("infeasible") or {}
        keep = passive_wins(first, self.points, infeasible.get("offset"))
        return "passive" if keep is not None else first["controller"]

    def table(self, metric: str) -> pd.DataFrame:
        """One metric's rows of `summary`, indexed by law, speed and load."""
        part = self.summary[self.summary["metric"] == metric]
        return part.set_index(["controller", "speed_m_s", "load"])

    def report_contents(self):
        """What this result shows in its HTML report (`railride.output.report.write_report`)."""
        from railride.output.report import design_contents

        return design_contents(self)

    def to_dict(self) -> dict:
        """The ``railride.design/1`` document (docs/schemas/railride.design-1.json)."""
        from railride._version import __version__, versions
        from railride.secondary.control import GainSet

        results = []
        for (name, v, load), part in self.summary.groupby(["controller", "speed_m_s", "load"], sort=False):
            metrics = {str(row["metric"]): {k: _finite(row[k]) for k in STATISTICS} for _, row in part.iterrows()}
            results.append(
                {
                    "controller": str(name),
                    "speed_m_s": float(v),
                    "load": float(load),
                    "n": int(part["n"].iloc[0]),
                    "metrics": metrics,
                }
            )
        tuning = self.tuning
        return {
            "schema": SCHEMA,
            "railride_version": __version__,
            "versions": versions(),
            "date": self.date,
            "settings": self.settings,
            "percentiles": list(PERCENTILES),
            "results": results,
            "points": [_plain(p) for p in self.points],
            "ranking": [_plain(r) for r in self.ranking],
            "recommendation": {"controller": self.recommended, "text": self.recommendation},
            "diverged": self.diverged,
            "references": _plain(self.references),
            "fault": _plain(self.fault),
            "tuning": {
                "objective": tuning.objective.describe(),
                "studies": [s.to_dict() for s in tuning.studies],
            },
            "gains": {t: self.gains.table(t).to_dict() for t in GainSet.TABLES},
            "runs": {"training": int(self.settings.get("training_runs", 0)), "judging": int(len(self.runs))},
        }

    def gains_toml(self, command: str | None = None) -> str:
        """The tuned gains as a gains file: a header that says how the design chose and judged
        them, then the tuning's file with its [provenance] (`TuneResult.gains_toml`: the
        training set, the vehicle, the objective, each law's study)."""
        s = self.settings
        tracks = ", ".join(s["tracks"])
        lines = [
            "# railride design: these gains were tuned on the training set in [provenance] and judged on",
            f"# held-out seeds {', '.join(map(str, s['test_seeds']))} of {tracks} (never used in tuning).",
            *([f"# command: {command}"] if command is not None else []),
            *textwrap.wrap("recommendation: " + self.recommendation, 98, initial_indent="# ", subsequent_indent="#   "),
            "",
        ]
        ranked = [r for r in self.ranking if r["ranked"]]
        design = [
            "",
            "# how the design judged them: the held-out seeds, the laws in their order, each one's score",
            "[provenance.design]",
            f"test_seeds = {json.dumps(list(s['test_seeds']))}",
            f"tracks = {json.dumps(list(s['tracks']))}",
            f"speeds_m_s = {json.dumps(list(s['speeds_m_s']))}",
            f"loads = {json.dumps(list(s['loads']))}",
            f"optimiser = {json.dumps(optimiser_text(s))}",
            f"recommended = {json.dumps(self.recommended or '')}",
            f"ranking = {json.dumps([r['controller'] for r in ranked])}",
            "scores = {" + ", ".join(f"{json.dumps(r['controller'])} = {float(r['score'])!r}" for r in ranked) + "}",
            "",
        ]
        return "\n".join(lines) + self.tuning.gains_toml().rstrip("\n") + "\n" + "\n".join(design)

    def to_pandas(self) -> pd.DataFrame:
        """The summary: one row per law, speed, load and metric (design.csv)."""
        return self.summary.copy()

    def plot(self, ax=None):
        """The four RMS ratios to passive against speed, per law and load, with the held-out
        5-95 % band (`railride.plots.design.plot_design`). ``ax``: four Axes, or None for a new
        figure. Returns the figure."""
        from railride.plots.design import plot_design

        return plot_design(self, ax=ax)

    def save(
        self,
        folder,
        command: str | None = None,
        *,
        extra: dict | None = None,
        figure_formats=("png",),
        dpi: float = PNG_DPI,
    ) -> list:
        """design.json (`to_dict`, then the entries of ``extra``), design.csv (`to_pandas`),
        design_runs.csv (``runs``), gains.toml (`gains_toml` with ``command``) and design.png
        (`plot`; in each of ``figure_formats``) into ``folder``, all or nothing (other files,
        such as the run table runs.csv, stay). Returns the paths."""
        from railride.output.files import write_design_outputs

        doc = {**self.to_dict(), **(extra or {})}
        figures = FigureOptions(figure_formats, dpi)
        return write_design_outputs(self, folder, doc, self.gains_toml(command), figures=figures)


def optimiser_text(settings: dict) -> str:
    """How a design's gains were tuned, in a few words (its ``settings["optimiser"]``)."""
    o = settings.get("optimiser") or {"name": "sensitivity"}
    if o["name"] == "evolution":
        return f"differential evolution over all of a law's gains at once (SciPy, seed {o['seed']})"
    return "the one-at-a-time sensitivity study (the paper's)"


def _plain(value):
    """A record with NaN and inf as None, tuples as lists (JSON)."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return _finite(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


# -- the ranking -----------------------------------------------------------------------------------
def _point_score(by: pd.DataFrame, objective: Objective, law: str, speed: float, load: float) -> float:
    """A law's score at a speed and load: ``objective`` of its mean ratios to passive over the
    held-out runs there, its bounds (peak, travel) checked on the 95th percentiles (a bound
    holds where 95 % of the held-out runs keep it); NaN where a value is missing."""
    try:
        ratios = {c: by.loc[(law, speed, load, c), "ratio_mean"] for c in objective.columns if c != PEAK_COLUMN}
        if objective.peak_bound is not None:
            ratios[PEAK_COLUMN] = by.loc[(law, speed, load, PEAK_COLUMN), "ratio_p95"]
        travel = by.loc[(law, speed, load, TRAVEL_COLUMN), "p95"] if objective.needs_costs else None
    except KeyError:
        return np.nan
    values = [*ratios.values(), *([] if travel is None else [travel])]
    if not np.isfinite(np.asarray(values, dtype=float)).all():
        return np.nan
    return float(objective.of_ratios({k: np.float64(x) for k, x in ratios.items()}, travel))


def over_points(values, shares=None, offset=None) -> float:
    """A score over the speeds and loads from its ``values`` at each: the largest, or with
    ``shares`` (time in service, one per value) their weighted mean, except where a value breaks
    the objective's constraints (at or above its infeasible ``offset``): a constraint holds at
    every point, so the largest. inf where a value is not finite (a run diverged)."""
    x = np.asarray(values, dtype=float)
    if not np.isfinite(x).all():
        return float(np.inf)
    if shares is None or (offset is not None and x.max() >= offset):
        return float(x.max())
    return float(np.dot(x, shares) / np.sum(shares))


def law_score(points: list, key, offset=None) -> float | None:
    """``key``'s score over the ``points`` (`over_points`: weighted by their ``share`` where they
    have one); ``key``: a law's name (its ``scores``) or "passive" (``passive_score``). None where
    a point has none."""
    values = [p.get("passive_score") if key == "passive" else p["scores"].get(key) for p in points]
    if not values or any(v is None for v in values):
        return None
    shares = [p["share"] for p in points] if all("share" in p for p in points) else None
    return over_points(values, shares, offset)


def rank(summary: pd.DataFrame, objective: Objective, laws, diverged=(), service=None) -> tuple[list, list]:
    """The laws ranked on held-out track, and the speeds and loads.

    At each speed and load (a point) a law's score is ``objective`` of its mean ratios to
    passive there (for minimax: its worst mean RMS ratio over the four responses; its bounds on
    the 95th percentiles, `_point_score`); a law's score is its largest over the points, at
    ``worst_at``, or with ``service`` ({(speed, load): share of time in service}, each point's
    ``share``) the weighted mean of its scores (`over_points`), its largest kept as
    ``worst_score``. The laws that did not diverge (``ranked``)
    come first, best score first; the ``diverged`` follow. Each point lists every law's score,
    the best ranked law (``best``) and the responses that no ranked law improves on average
    (``no_law_beats_passive``, with the best ratio there and its law). Returns (ranking,
    points)."""
    ratios = summary[summary["metric"].isin(RMS_COLUMNS)]
    mean = ratios.pivot_table(
        index=["controller", "speed_m_s", "load"], columns="metric", values="ratio_mean", dropna=False
    ).reindex(columns=list(RMS_COLUMNS))
    keys = list(dict.fromkeys(zip(summary["speed_m_s"], summary["load"])))
    ranked = [n for n in laws if n not in diverged]
    by = summary.set_index(["controller", "speed_m_s", "load", "metric"])
    points: list[dict[str, Any]] = []
    for v, load in keys:
        scores = {n: _point_score(by, objective, n, v, load) for n in laws}
        finite = [n for n in ranked if np.isfinite(scores[n])]
        best = min(finite, key=lambda n: scores[n]) if finite else None
        none = []
        for col, word in zip(RMS_COLUMNS, RATIO_NAMES):
            values = {
                n: float(mean.loc[(n, v, load), col])
                for n in ranked
                if (n, v, load) in mean.index and np.isfinite(mean.loc[(n, v, load), col])
            }
            if values and min(values.values()) >= 1.0:
                top = min(values, key=lambda n: values[n])
                none.append({"response": word, "best_ratio": values[top], "best_controller": top})
        points.append(
            {
                "speed_m_s": float(v),
                "load": float(load),
                "scores": scores,
                "best": best,
                "no_law_beats_passive": none,
                # passive by the same objective: ratios of 1, its own travel against a travel bound
                "passive_score": _plain(_point_score(by, objective, "passive", v, load)),
                **({"share": service[(float(v), float(load))]} if service is not None else {}),
            }
        )
    ranking = []
    for n in laws:
        per = [(p["scores"][n], p) for p in points]
        bad = [p for s, p in per if not np.isfinite(s)]
        worst = bad[0] if bad else max(per, key=lambda sp: sp[0])[1]
        score = law_score(points, n, objective.constraint_offset)
        score = np.inf if bad or score is None else score
        ranking.append(
            {
                "controller": n,
                "score": score,
                **({"worst_score": max(s for s, _ in per)} if service is not None else {}),
                "worst_at": {"speed_m_s": worst["speed_m_s"], "load": worst["load"]},
                "best_at": [{"speed_m_s": p["speed_m_s"], "load": p["load"]} for p in points if p["best"] == n],
                "ranked": n not in diverged and bool(np.isfinite(score)),
            }
        )
    ranking.sort(key=lambda r: (not r["ranked"], r["score"] if np.isfinite(r["score"]) else np.inf))
    for k, r in enumerate(ranking, 1):
        r["rank"] = k if r["ranked"] else None
    return ranking, points


# -- the recommendation ----------------------------------------------------------------------------
def recommend(ranking, points, summary: pd.DataFrame, runs: pd.DataFrame, objective, settings, diverged) -> str:
    """The recommendation in a few sentences, each one a number of the ranking or the summary:
    the law ranked first and its score; the responses it makes worse than passive on average,
    and where; where another law scores better; what it gives up to the other ranked laws
    (`_trade_offs`); how sure (whether the held-out 5-95 % bands of
    the per-run scores of it and the runner-up overlap, and how many runs it wins run by run);
    where no law beats passive; the laws that diverged."""
    ok = [r for r in ranking if r["ranked"]]
    n = len(settings["tracks"]) * len(settings["test_seeds"])
    seeds = ", ".join(map(str, settings["test_seeds"]))
    held = (
        f"{n} held-out run{'s' * (n != 1)} per law, speed and load ({', '.join(settings['tracks'])}, "
        f"seed{'s' * (len(settings['test_seeds']) != 1)} {seeds}; never used in tuning)"
    )
    out = []
    if not ok:
        out.append("No law can be recommended: every law diverged in tuning or on held-out track.")
    else:
        best = ok[0]
        name, score, w = best["controller"], best["score"], best["worst_at"]
        keep = passive_wins(best, points, objective.constraint_offset)
        service = settings.get("service")
        if objective.kind == "minimax":
            point = "its worst mean RMS ratio to passive over the four responses"
        elif objective.needs_comfort:
            index = "N_MV,z" if objective.kind == "n_mv" else "Wz"
            point = f"its worst mean {index} ratio to passive over the floor points"
        else:
            point = f"its score ({objective.kind} of the mean RMS ratios to passive)"
        if service:  # the points weighted by their time in service: the score is their mean
            what = (
                f"{point} at each speed and load, averaged with their shares of the time in service "
                f"({service_text(service)}), is"
            )
            worst = f"worst {score_text(best['worst_score'], objective)} at {_at(w['speed_m_s'], w['load'])}"
        elif objective.kind == "minimax" or objective.needs_comfort:
            what = f"{point}, at any speed and load, is"
        else:
            what = f"its largest score ({objective.kind} of the mean RMS ratios to passive) over the speeds and loads"
            what += " is"
        if keep is not None:  # by the design's own objective, passive is better than every law
            at = f"in service ({worst})" if service else f"at worst (at {_at(w['speed_m_s'], w['load'])})"
            out.append(
                f"Recommended: keep passive. By this objective no law beats passive on held-out track: the best "
                f"law, {_label(name)}, scores {score_text(score, objective)} {at} on {held}, against passive's "
                f"{score_text(keep, objective)}."
            )
        else:
            at = worst if service else f"at {_at(w['speed_m_s'], w['load'])}"
            out.append(f"Recommended: {_label(name)}. On {held}, {what} {score_text(score, objective)} ({at}).")
        out.append(_worse_than_passive(name, summary))
        out.append(_wins(name, points))
        out.append(_trade_offs(name, ok, summary, service))
        out.append(service_sentence(best, _label(name), keep is not None))
        out.append(_sureness(best, ok[1] if len(ok) > 1 else None, points, summary, runs, objective))
        if objective.peak_bound is not None or objective.travel_bound is not None:
            out.append(
                "Constraints, on the 95th percentile of the held-out runs at each speed and load: "
                + _bounds_text(ok, objective)
            )
        if objective.kind == "minimax" and score >= 1.0 and keep is None:
            out.append(
                "No law keeps every RMS response better than passive on average at every speed and load; "
                "the recommended law is the one whose worst response is least worse."
            )
    out.append(_passive_unbeaten(points, bool(diverged)))
    for d in diverged:
        if d["controller"] == "passive":
            out.append(f"Passive diverged on {d['runs']} held-out run(s): those runs have no ratios.")
            continue
        first = d["where"][0] if d["where"] else None
        place = ""
        if first is not None:
            load = "" if first["load"] is None else f", load {first['load']:g}"
            place = (
                f", first on {first['track']} seed {first['track_seed']} at {first['speed_m_s']:g} m/s{load}, "
                f"t = {first['diverged_at_s']:.3g} s"
            )
        stage = "in tuning" if d["stage"] == "tuning" else "on held-out track"
        out.append(
            f"{_label(d['controller'])} diverged {stage} ({d['runs']} run{'s' * (d['runs'] != 1)}{place}) "
            "and is not ranked."
        )
    return " ".join(s for s in out if s)


def service_text(service: list) -> str:
    """The time in service in a few words: "30 m/s, load 1: 60 %; ..." (a design's record)."""
    return "; ".join(f"{_at(p['speed_m_s'], p['load'])}: {100 * p['share']:.3g} %" for p in service)


def score_text(score, objective, short: bool = False) -> str:
    """A score in words: the number, or where it breaks the objective's constraints (at or above
    its infeasible offset), "infeasible" and by how much it breaks them (the excess, summed over
    the constraints as fractions of each bound), which the raw score hides in its offset.
    ``objective``: an `Objective`, or its record's ``infeasible`` entry (a document's);
    ``short``: "infeasible (+excess)", for a table's cell."""
    if score is None:
        return "-"
    infeasible = objective.to_dict()["infeasible"] if isinstance(objective, Objective) else objective
    if not infeasible or not np.isfinite(score) or score < infeasible["offset"]:
        return f"{score:.3f}"
    excess = (score - infeasible["offset"]) / infeasible["scale"]
    return f"infeasible (+{excess:.3g})" if short else f"infeasible: over its constraints by {excess:.3g} of a bound"


def passive_wins(best: dict, points: list, offset: float | None = None) -> float | None:
    """Passive's score (over the speeds and loads as the laws', `law_score`, by the design's
    objective) where it is lower than ``best``'s, the ranked law's, by more than the level
    tolerance of a comparison; else None: a law that scores worse than passive is not
    recommended. ``offset``: the objective's `Objective.constraint_offset` (a broken constraint
    is not averaged away)."""
    from railride.studies.comparison import LEVEL_TOLERANCE, is_level

    own = law_score(points, "passive", offset)
    if own is None or not np.isfinite(own):
        return None
    if best["score"] > own and not is_level(best["score"], own, LEVEL_TOLERANCE):
        return float(own)
    return None


def _bounds_text(ok: list, objective) -> str:
    """Which ranked laws keep the bounds of ``objective`` (a score below the infeasible offset)."""
    from railride.studies.objectives import INFEASIBLE_OFFSET

    offset = objective.infeasible_offset or INFEASIBLE_OFFSET
    limits = []
    if objective.peak_bound is not None:
        limits.append(f"peak-to-peak acceleration <= {objective.peak_bound:g} x passive's")
    if objective.travel_bound is not None:
        limits.append(f"travel <= {objective.travel_bound * 1e3:g} mm")
    broke = [_label(r["controller"]) for r in ok if r["score"] >= offset]
    kept = len(ok) - len(broke)
    text = f"{' and '.join(limits)}; {kept} of {len(ok)} ranked laws keep them everywhere"
    return text + (f" ({', '.join(broke)} do not)." if broke else ".")


def _worse_than_passive(name: str, summary: pd.DataFrame) -> str:
    part = summary[(summary["controller"] == name) & summary["metric"].isin(RMS_COLUMNS)]
    worse: dict[str, list] = {}
    for _, row in part.iterrows():
        if np.isfinite(row["ratio_mean"]) and row["ratio_mean"] > 1.0:
            word = RATIO_NAMES[RMS_COLUMNS.index(row["metric"])]
            worse.setdefault(word, []).append(f"{_at(row['speed_m_s'], row['load'])} (x{row['ratio_mean']:.3f})")
    if not worse:
        return "It is better than passive on average in every RMS response at every speed and load."
    return (
        "On average it is worse than passive in " + "; ".join(f"{w} at {', '.join(p)}" for w, p in worse.items()) + "."
    )


def _trade_offs(name: str, ok: list, summary: pd.DataFrame, service=None) -> str:
    """What the recommended law gives up: the responses (RMS, and the peak-to-peak acceleration)
    on which another ranked law's mean ratio to passive, averaged over the speeds and loads
    (weighted by their time in service where ``service``, a design's record, gives it), is
    lower than its own by more than the level tolerance of a comparison; and its largest
    secondary travel against passive's."""
    from railride.studies.comparison import LEVEL_TOLERANCE, is_level

    if service:
        share = {(p["speed_m_s"], p["load"]): p["share"] for p in service}
        ratio = summary["ratio_mean"].to_numpy(dtype=float)
        weights = np.array([share[v, x] for v, x in zip(summary["speed_m_s"], summary["load"])])
        weights = np.where(np.isfinite(ratio), weights, 0.0)  # a point with no ratio counts for nothing, as in mean()
        weighted = summary.assign(w=weights, wr=np.where(weights > 0, ratio * weights, 0.0))
        sums = weighted.groupby(["controller", "metric"])[["wr", "w"]].sum()
        mean = sums["wr"] / sums["w"]
    else:
        mean = summary.groupby(["controller", "metric"])["ratio_mean"].mean()
    words = {**dict(zip(RMS_COLUMNS, RATIO_NAMES)), PEAK_COLUMN: "peak-to-peak acceleration"}
    lost = []
    for other in (r["controller"] for r in ok if r["controller"] != name):
        worse = []
        for metric, word in words.items():
            a, b = mean.get((name, metric)), mean.get((other, metric))
            if a is not None and b is not None and np.isfinite(a) and np.isfinite(b):
                if a > b and not is_level(a, b, LEVEL_TOLERANCE):
                    worse.append(f"{word} ({b:.3f} against its {a:.3f})")
        if worse:
            lost.append(f"to {_label(other)} on {', '.join(worse)}")
    over = "Averaged over the speeds and loads" + (" weighted by their time in service" if service else "")
    text = (
        f"{over} (mean ratios to passive), it loses " + "; ".join(lost) + "."
        if lost
        else f"{over}, no other ranked law is better on any RMS response or the peak-to-peak acceleration."
    )
    travel = mean.get((name, TRAVEL_COLUMN))
    if travel is not None and np.isfinite(travel) and not is_level(travel, 1.0, LEVEL_TOLERANCE):
        text += f" Its largest secondary travel is x{travel:.2f} passive's on average"
        # rattle space is a worst case: the speed and load where the travel grows most
        own = summary[(summary["controller"] == name) & (summary["metric"] == TRAVEL_COLUMN)]
        own = own[np.isfinite(own["ratio_mean"].to_numpy(dtype=float))]
        if len(own) > 1:
            top = own.loc[own["ratio_mean"].idxmax()]
            text += f", x{top['ratio_mean']:.2f} at {_at(top['speed_m_s'], top['load'])}, the most"
        text += "."
    return text


def _wins(name: str, points) -> str:
    lost = [p for p in points if p["best"] not in (None, name)]
    if not lost:
        return "It has the best score of the laws at every speed and load."
    where = "; ".join(
        f"{_label(p['best'])} at {_at(p['speed_m_s'], p['load'])} ({p['scores'][p['best']]:.3f} against its "
        f"{p['scores'][name]:.3f})"
        for p in lost
    )
    return f"It has the best score at {len(points) - len(lost)} of {len(points)} speeds and loads; it loses to {where}."


def _sureness(best: dict, runner: dict | None, points, summary: pd.DataFrame, runs: pd.DataFrame, objective) -> str:
    if runner is None:
        return "No other law was ranked: there is no runner-up to compare with."
    a, b = best["controller"], runner["controller"]
    band = summary[summary["metric"] == "score"].set_index(["controller", "speed_m_s", "load"])
    overlap = 0
    counts = sorted({int(band.loc[(x, p["speed_m_s"], p["load"]), "n"]) for x in (a, b) for p in points})
    n = counts[-1] if counts else 0
    runs_text = f"{n} run{'s' * (n != 1)}" if len(counts) < 2 else f"{counts[0]} to {n} runs"
    for p in points:
        key_a, key_b = (a, p["speed_m_s"], p["load"]), (b, p["speed_m_s"], p["load"])
        lo = max(band.loc[key_a, "p5"], band.loc[key_b, "p5"])
        hi = min(band.loc[key_a, "p95"], band.loc[key_b, "p95"])
        overlap += bool(lo <= hi)
    text = (
        f"Runner-up: {_label(b)} ({score_text(runner['score'], objective)}). The held-out 5-95 % bands of the "
        f"two laws' per-run scores (over {runs_text} each) overlap at {overlap} of {len(points)} speeds and loads"
    )
    if overlap == len(points):
        text += ": the spread over tracks is wider than the two laws' difference"
    elif overlap == 0:
        text += ": they are apart at every one"
    key = ["track", "track_seed", "speed_m_s", "load"]
    pair = runs[runs["controller"] == a].set_index(key)["score"].to_frame("a")
    pair = pair.join(runs[runs["controller"] == b].set_index(key)["score"].to_frame("b"))
    pair = pair[np.isfinite(pair["a"]) & np.isfinite(pair["b"])]
    wins, losses = int((pair["a"] < pair["b"]).sum()), int((pair["a"] > pair["b"]).sum())
    text += f"; run by run (the same track, speed and load) {_label(a)} scores lower in {wins} of {len(pair)}"
    if wins + losses == 0:
        return text + "."
    # the paired runs: a two-sided sign test of "either law as likely to score lower", ties left out
    from scipy.stats import binomtest

    p = float(binomtest(wins, wins + losses, 0.5).pvalue)
    verdict = "these runs separate the two" if p < 0.05 else "these runs do not tell that from chance"
    return text + f" (two-sided sign test over the runs that differ, p = {p:.2g}: {verdict}, at 5 %)."


def _passive_unbeaten(points, some_diverged: bool) -> str:
    laws = "law that did not diverge" if some_diverged else "law"
    by_response: dict[str, list] = {}
    for p in points:
        for item in p["no_law_beats_passive"]:
            by_response.setdefault(item["response"], []).append(
                f"{_at(p['speed_m_s'], p['load'])} (best x{item['best_ratio']:.3f}, {_label(item['best_controller'])})"
            )
    if not by_response:
        return f"At every speed and load, every RMS response has a {laws} better than passive on average."
    return (
        f"No {laws} is better than passive on average in "
        + "; ".join(f"{w} at {', '.join(where)}" for w, where in by_response.items())
        + "."
    )


# -- the laws that diverged (`railride.studies.design.design`) -----------------------------------
def seed_of(plan, row) -> int | None:
    """The design's seed of a run-table row: its track seed, or its measured section's index."""
    track = str(row["scenario"])
    if track in plan.sections:
        first, length = plan.sections[track]
        return int(round((float(row["scenario.start"]) - first) / length))
    seed = row.get("scenario.seed")
    return None if seed is None or seed != seed else int(seed)


#: the most places a law's divergence is listed at (the count is always given)
MAX_PLACES = 5


def diverged_laws(tuned, training: pd.DataFrame, runs: pd.DataFrame, plan) -> list[dict]:
    """The laws that diverged: in tuning, where the tuned gains' objective over the training
    runs is not finite (a training run with them diverged), with the training runs of that law
    that diverged; on held-out track, every law (or passive) with a held-out run that diverged.
    Each: controller, stage, the number of runs that diverged and up to `MAX_PLACES` of them
    (track, seed, speed, load where known, time)."""
    out = []
    for st in tuned.studies:
        if st.controller == "inner" or np.isfinite(st.objective):
            continue
        part = training[training["suspension"] == st.controller] if len(training) else training
        if len(part):
            part = part[np.isfinite(part["diverged_at_s"].astype(float))]
        places = [
            {
                "track": str(r["scenario"]),
                "track_seed": seed_of(plan, r),
                "speed_m_s": float(r["scenario.speed"]),
                "load": None,
                "diverged_at_s": float(r["diverged_at_s"]),
            }
            for _, r in part.head(MAX_PLACES).iterrows()
        ]
        out.append({"controller": st.controller, "stage": "tuning", "runs": int(len(part)), "where": places})
    bad = runs[np.isfinite(runs["diverged_at_s"])]
    for name, part in bad.groupby("controller", sort=False):
        places = [
            {
                "track": str(r.track),
                "track_seed": int(r.track_seed),
                "speed_m_s": float(r.speed_m_s),
                "load": float(r.load),
                "diverged_at_s": float(r.diverged_at_s),
            }
            for r in part.head(MAX_PLACES).itertuples()
        ]
        out.append({"controller": str(name), "stage": "judging", "runs": int(len(part)), "where": places})
    return out


def dumps(result: DesignResult) -> str:
    """The document as strict JSON (the command line's ``--format json``)."""
    return json.dumps(result.to_dict(), indent=2, allow_nan=False)
