"""`Comparison`, the result of `railride.compare`: the result protocol."""

import json

import matplotlib
import numpy as np
import pytest

import railride as rr
from railride.output.files import COMPARE_FILES

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def short():
    return rr.compare(rr.scenario("paper-sine", duration=2.0), controllers=["pid", "sas-attitude"])


def test_to_pandas_holds_every_metric_and_its_reduction(short):
    frame = short.to_pandas()
    assert len(frame) == 3 * 4 * 2  # suspensions x responses x statistics
    for (name, response, stat), row in frame.set_index(["controller", "response", "statistic"]).iterrows():
        assert row["value"] == float(short.metrics.sel(controller=name, response=response, statistic=stat))
        base = float(short.metrics.sel(controller="passive", response=response, statistic=stat))
        if name == "passive":
            assert np.isnan(row["reduction_percent"])
        else:
            assert row["reduction_percent"] == pytest.approx((base - row["value"]) / base * 100, rel=1e-12)


def test_plot_draws_into_the_given_axes(short):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    try:
        assert short.plot(ax=ax, response="pitch") is fig
        assert len(ax.lines) == 3  # one per suspension
    finally:
        plt.close(fig)  # pyplot's registry stays empty for the other tests
    assert short.plot().axes  # its own figure otherwise
    with pytest.raises(ValueError, match="response = 'yaw'"):
        short.plot(response="yaw")


def test_save_writes_the_compare_folder(short, tmp_path):
    short.save(tmp_path / "out")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == sorted(COMPARE_FILES)
    doc = json.loads((tmp_path / "out" / "compare.json").read_text())
    assert doc == json.loads(json.dumps(short.to_dict(), allow_nan=False))
