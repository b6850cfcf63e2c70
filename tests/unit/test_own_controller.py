"""An outer loop of one's own (anything with ``gains(vehicle)``, ``name`` and ``to_dict()``, as
`Suspension` says): it runs, its result is written like any other, and gains that are not a
controller's (a missing part of the interface, H of another shape, a value that is not finite)
are input errors naming the controller before any run, in the time domain and the frequency
domain alike."""

from __future__ import annotations

import numpy as np
import pytest

import railride as rr
from railride.errors import InputError
from railride.frequency.linear import linear_model


class BounceSkyhook:
    """f_i = -c z_c' at every corner: a skyhook on the carbody's bounce alone."""

    name = "my-skyhook"

    def __init__(self, c=8.0e4, H=None, G=None):
        self.c, self.H, self.G = c, H, G

    def gains(self, vehicle):
        G = np.zeros((4, 6))
        G[:, 3] = -self.c
        return (G if self.G is None else self.G), (np.zeros((4, 3)) if self.H is None else self.H)

    def to_dict(self):
        return {"c": self.c}


SHORT = rr.scenario("paper-sine", duration=0.5)


def test_an_own_controller_runs_and_its_result_is_written(tmp_path):
    result = rr.simulate(SHORT, "paper", rr.Suspension.ideal(BounceSkyhook()))
    doc = result.to_dict()
    assert "my-skyhook" in str(doc)
    result.save(tmp_path / "out")
    assert (tmp_path / "out").is_dir() and any((tmp_path / "out").iterdir())
    # the bounce skyhook damps the carbody's bounce: less than passive's on the sine
    passive = rr.simulate(SHORT, "paper").metrics().sel(response="displacement_m", statistic="rms")
    assert float(result.metrics().sel(response="displacement_m", statistic="rms")) < float(passive)


class NoDict:
    name = "no-dict"

    def gains(self, vehicle):
        return np.zeros((4, 6)), np.zeros((4, 3))


@pytest.mark.parametrize(
    "controller, fragments",
    [
        (NoDict(), ("controller = ", "has no to_dict")),
        (BounceSkyhook(H=np.zeros(3)), ("'my-skyhook'", "H of shape (3,)", "allowed (4, 3)")),
        (BounceSkyhook(c=np.nan), ("'my-skyhook'", "G[0, 3] = nan", "must be finite")),
        (BounceSkyhook(G=np.zeros((3, 6))), ("'my-skyhook'", "G of shape (3, 6)", "4 rows")),
    ],
)
def test_gains_that_are_not_a_controllers_are_refused_before_a_run(controller, fragments):
    def attempts():
        yield lambda: rr.simulate(SHORT, "paper", rr.Suspension.ideal(controller))
        yield lambda: linear_model("paper", rr.Suspension.ideal(controller))

    for attempt in attempts():
        with pytest.raises(InputError) as caught:
            attempt()
        for fragment in fragments:
            assert fragment in str(caught.value), str(caught.value)
