"""The fall rule gives one answer whichever form it is asked in."""

import itertools

import numpy as np
import pytest

from pedi_drake.fall import trunk_has_fallen


@pytest.mark.parametrize(("has_stood", "on_prongs"), list(itertools.product([False, True], [False, True])))
def test_one_sample_agrees_with_the_array_form(has_stood, on_prongs):
    # The mission manager asks about one sample at a time (a float path); the judge about arrays.
    rng = np.random.default_rng(0)
    quaternions = rng.normal(size=(4, 2000))
    quaternions[:, :5] = 0.0  # no rotation information at all
    quaternions[:, 5] = [1.0, 0.0, 0.0, 0.0]
    quaternions[:, 6] = [np.cos(0.45), np.sin(0.45), 0.0, 0.0]  # tilted near the threshold
    heights = rng.uniform(0.0, 0.2, 2000)
    flags = np.full(2000, has_stood), np.full(2000, on_prongs)
    together = trunk_has_fallen(quaternions, heights, has_stood=flags[0], resting_on_prongs=flags[1])
    one_by_one = [
        trunk_has_fallen(quaternions[:, k], heights[k], has_stood=has_stood, resting_on_prongs=on_prongs)
        for k in range(2000)
    ]
    assert np.array_equal(together, one_by_one)
