"""Every function that takes a damper's name takes the damper itself (a model of
railride.secondary.dampers, a user's own Bouc-Wen damper), resolved once by
`railride.secondary.suspension.damper_model`."""

from __future__ import annotations

import json

import numpy as np
import tomllib

import pytest

import railride as rr
from railride.secondary import dampers
from railride.secondary.suspension import damper_model

SC = dict(duration=0.5)
#: a damper of the user's own: the railway damper with 10 % more Bouc-Wen force
MINE = dampers.RAILWAY.replace(alpha_a=dampers.RAILWAY.alpha_a * 1.1)


def test_a_preset_given_as_a_model_runs_as_its_name():
    by_name = rr.compare(rr.scenario("paper-sine", **SC), controllers=["pid"], damper="railway")
    by_model = rr.compare(rr.scenario("paper-sine", **SC), controllers=["pid"], damper=dampers.RAILWAY)
    assert np.array_equal(by_name.metrics.values, by_model.metrics.values)


def test_a_model_of_ones_own_runs_and_is_recorded_in_every_study(tmp_path):
    sc = rr.scenario("paper-sine", **SC)
    compared = rr.compare(sc, controllers=["pid"], damper=MINE)
    preset = rr.compare(sc, controllers=["pid"], damper="railway")
    assert not np.array_equal(compared.metrics.values, preset.metrics.values)  # it is used, not the preset
    assert compared.to_dict()["settings"]["damper"] == MINE.to_dict()
    swept = rr.run_sweep(rr.sweep.grid(["passive", "pid"], speed=[40.0], damper=MINE, **SC))
    assert json.loads(json.dumps(swept.to_dict()))  # a plain JSON document
    assert len(swept.to_pandas()) == 2
    studied = rr.study(["pid"], scenario="paper-sine", speeds=[40.0], damper=MINE, **SC)
    assert studied.to_dict()["settings"]["damper"] == MINE.to_dict()
    swept.save(tmp_path / "sweep")
    compared.save(tmp_path / "compare")


@pytest.mark.slow
def test_tune_and_pareto_take_a_model():
    tuned = rr.tune(controllers=["pid"], damper=MINE, budget=15, scenario_options=SC)
    assert tuned.to_dict()["settings"]["damper"] == MINE.to_dict()
    # its gains file is TOML (a damper object has no preset: JSON's null has no TOML form)
    assert tomllib.loads(tuned.gains_toml())["provenance"]["damper"]["alpha_a"] == MINE.alpha_a
    front = rr.pareto("pid", damper=MINE, n_samples=8, scenario_options=SC)
    assert front.to_dict()["settings"]["damper"] == MINE.to_dict()


def test_damper_model_resolves_names_and_models_alike():
    assert damper_model("railway") is dampers.RAILWAY
    assert damper_model(MINE) is MINE
    assert damper_model(MINE, 2.0) == MINE.scaled(2.0)
    with pytest.raises(rr.errors.InputError, match="damper = 3: must be a name"):
        damper_model(3)
    with pytest.raises(rr.errors.InputError, match="no force capacity to scale"):
        damper_model(dampers.IDEAL, 2.0)
