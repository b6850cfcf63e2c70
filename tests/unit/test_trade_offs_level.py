"""Winners by the fourth digit: two RMS values within the level tolerance are level, neither
better nor worse, and the trade-off lines group pairs and state the tolerance."""

from __future__ import annotations

import pytest

import railride as rr
from railride.errors import InputError
from railride.output.trade_offs import trade_off_lines
from railride.studies.comparison import LEVEL_TOLERANCE, is_level


@pytest.mark.parametrize(
    ("x", "y", "tol", "level"),
    [
        (0.01275, 0.01276, 0.01, True),  # 0.08 %: the newcomer's case
        (1.0, 1.02, 0.01, False),  # 2 %
        (1.0, 1.0101, 0.01, True),  # 0.99 % of the larger
        (0.0, 0.0, 0.0, True),
        (1.0, 1.0 + 1e-15, 0.0, False),  # tolerance 0: any difference counts
        (float("nan"), 1.0, 0.5, False),
    ],
)
def test_level_is_relative_to_the_larger(x, y, tol, level):
    assert is_level(x, y, tol) is level
    assert is_level(y, x, tol) is level  # symmetric


@pytest.fixture(scope="module")
def paper():
    return rr.compare("paper-sine")


def test_the_paper_case_names_the_fourth_digit_level(paper):
    rms = paper.metrics.sel(statistic="rms")
    pair = next(t for t in paper.trade_offs() if t["controller"] == "sas-attitude" and t["than"] == "sas-attitude-ride")
    a = float(rms.sel(controller="sas-attitude", response="displacement_m"))
    b = float(rms.sel(controller="sas-attitude-ride", response="displacement_m"))
    assert a != b and abs(a - b) / max(a, b) < LEVEL_TOLERANCE  # they differ, by less than 1 %
    assert "displacement_m" in pair["level_on"]
    assert "displacement_m" not in pair["better_on"] + pair["worse_on"]
    # every response is in exactly one of the three lists, for every pair
    for t in paper.trade_offs():
        together = t["better_on"] + t["worse_on"] + t["level_on"]
        assert sorted(together) == sorted(str(r) for r in rms.response.values)
    assert paper.to_dict()["settings"]["level_tolerance"] == LEVEL_TOLERANCE


def test_tolerance_zero_splits_every_difference():
    strict = rr.compare("paper-sine", level_tolerance=0.0)
    rms = strict.metrics.sel(statistic="rms")
    for t in strict.trade_offs():
        a, b = rms.sel(controller=t["controller"]), rms.sel(controller=t["than"])
        for r in t["level_on"]:  # only exact ties are level
            assert float(a.sel(response=r)) == float(b.sel(response=r))
        for r in t["better_on"]:
            assert float(a.sel(response=r)) < float(b.sel(response=r))


@pytest.mark.parametrize("bad", [-0.1, 1.0, float("nan"), float("inf")])
def test_a_bad_tolerance_is_refused_before_any_run(bad):
    with pytest.raises(InputError, match="level_tolerance"):
        rr.compare("paper-sine", level_tolerance=bad)


def _doc(trade_offs, tol=0.01):
    names = {"passive": "Passive", "a": "A", "b": "B", "c": "C"}
    return {
        "controllers": [{"name": n, "label": lab} for n, lab in names.items()],
        "trade_offs": trade_offs,
        "settings": {"level_tolerance": tol},
    }


def _t(c, than, better=(), worse=(), level=()):
    return {"controller": c, "than": than, "better_on": list(better), "worse_on": list(worse), "level_on": list(level)}


def test_lines_group_pairs_with_the_same_sets_and_state_the_tolerance():
    acc, disp, pitch = "acceleration_m_s2", "displacement_m", "pitch_deg"
    lines = trade_off_lines(
        _doc(
            [
                _t("a", "passive", better=[acc, disp]),  # better everywhere: no line
                _t("a", "b", better=[pitch], worse=[acc]),
                _t("a", "c", better=[pitch], worse=[acc]),  # the same sets: joins the line above
                _t("b", "c", worse=[disp], level=[acc, pitch]),
                _t("c", "passive", level=[acc, disp, pitch]),
            ]
        )
    )
    assert lines == [
        "trade-off: A beats B, C on pitch but is worse on acceleration",
        "no trade-off: C beats B on displacement and is worse on nothing; level on acceleration, pitch",
        "level on every response: C and Passive",
        "(RMS and peak-to-peak values within 1 % of the larger count as level, neither better nor worse: "
        "--level-tolerance)",
    ]


def test_no_comparison_no_lines():
    assert trade_off_lines(_doc([])) == []


def test_peaks_above_passive_are_named_with_their_rise(paper):
    """The paper case's PID lowers every RMS but raises the peak-to-peak acceleration and roll:
    the peak line says so, with the rise read off the metrics."""
    ptp = paper.metrics.sel(statistic="ptp")
    doc = paper.to_dict()
    pid = next(t for t in doc["trade_offs"] if t["controller"] == "pid" and t["than"] == "passive")
    rises = {
        str(r): float(ptp.sel(controller="pid", response=r)) / float(ptp.sel(controller="passive", response=r)) - 1
        for r in ptp.response.values
    }
    assert sorted(pid["ptp_worse_on"]) == sorted(r for r, x in rises.items() if x > LEVEL_TOLERANCE)
    assert pid["ptp_worse_on"] and not pid["worse_on"]  # better RMS everywhere, worse peaks somewhere
    line = next(s for s in trade_off_lines(doc) if s.startswith("peak-to-peak worse than passive: "))
    assert f"PID on acceleration ({100 * rises['acceleration_m_s2']:+.3g} %)" in line


def test_no_peak_above_passive_says_so():
    acc = "acceleration_m_s2"
    doc = _doc([{**_t("a", "passive", better=[acc]), "ptp_better_on": [acc], "ptp_worse_on": [], "ptp_level_on": []}])
    assert "peak-to-peak: no suspension is worse than passive on any response" in trade_off_lines(doc)


def test_the_paper_case_says_where_its_order_agrees_with_table_1(paper):
    """docs/results.md: the ranking of the paper's three controllers is the paper's on
    acceleration, displacement and roll (SAS (attitude+ride) first, PID last; the two SAS level
    on displacement), PID's first on pitch, and the reductions are smaller than the paper's."""
    from railride.studies.comparison import PAPER_REDUCTION

    ranking = paper.to_dict()["paper_ranking"]
    assert [r for r in PAPER_REDUCTION if not ranking[r]["agrees"]] == ["pitch_deg"]
    assert ranking["pitch_deg"]["railride"][0] == "pid"
    red = paper.reductions.sel(statistic="rms")
    lo, hi = ranking["reduction_ratio"]
    for r, values in PAPER_REDUCTION.items():
        for law, published in values.items():
            assert lo - 1e-12 <= float(red.sel(controller=law, response=r)) / published <= hi + 1e-12
    assert 0 < lo < hi < 1  # every reduction here is smaller than the paper's
    assert "paper_ranking" not in rr.compare("paper-sine", controllers=("pid",), bounds=False).to_dict()
