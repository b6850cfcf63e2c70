"""The shared input checks: what they accept, and that every refusal names field, value and rule."""

import math

import numpy as np
import pytest

from railride import validation
from railride.model.track import SineTrack


@pytest.mark.parametrize("value", [3, 3.0, np.float32(3.0), np.float64(3.0), np.int64(3), np.int8(3)])
def test_numpy_and_python_numbers_are_numbers(value):
    assert validation.number("speed", value, "positive", "m/s") == 3.0
    assert type(validation.number("speed", value)) is float


@pytest.mark.parametrize("value", [True, np.bool_(True), "3", None, [3.0], math.nan, math.inf, -math.inf])
def test_non_numbers_and_non_finite_values_are_refused(value):
    with pytest.raises(ValueError, match=r"^speed = .*: must be a finite number > 0 \(m/s\)$"):
        validation.number("speed", value, "positive", "m/s")


@pytest.mark.parametrize(
    "rule, bad, good", [("positive", 0.0, 1e-300), ("nonnegative", -1e-300, 0.0), ("finite", math.nan, -1e300)]
)
def test_each_rule_draws_its_line(rule, bad, good):
    assert validation.number("x", good, rule) == good
    with pytest.raises(ValueError, match=validation.RULES[rule][0]):
        validation.number("x", bad, rule)


def test_numpy_values_are_shown_as_plain_numbers():
    with pytest.raises(ValueError, match=r"^dt = -0.5: "):
        validation.number("dt", np.float64(-0.5))


def test_integer_bounds_and_types():
    assert validation.integer("n", np.int64(4), 2, 10) == 4
    for bad in (1, 11, 4.0, True, "4"):
        with pytest.raises(ValueError, match=r"n = .*: must be a whole number >= 2 and <= 10"):
            validation.integer("n", bad, 2, 10)


def test_choice_lists_what_is_allowed():
    assert validation.choice("rails", "left", ("both", "left")) == "left"
    with pytest.raises(ValueError, match=r"rails = 'up': allowed both, left"):
        validation.choice("rails", "up", ("both", "left"))


def test_a_frozen_value_accepts_numpy_numbers_through_the_shared_checks():
    track = SineTrack(amplitude=np.float32(0.05), wavelength=np.int64(60))
    assert track.wavelength == 60.0 and type(track.amplitude) is float
