"""The press classifier on force-displacement curves of known obstacles (paper 000, Fig. 5)."""

import numpy as np
import pytest

from pedi_drake.evaluation.obstacle_response import CONTACT_FORCE, classify_press

SPEED_STEP = 1e-4  # [m] a press's displacement per control tick (5 cm/s at 500 Hz)
NOISE = 0.3  # [N] standard deviation of the force estimate's noise


def curve(free: float, stiffness: float, plateau: float, limit_force: float, limit_travel: float, seed: int):
    """(displacement, force, stopped_by) of a press: `free` metres of free travel, then a force
    rising at `stiffness` [N/m] up to `plateau` [N] (inf: fixed), stopped at `limit_force` or
    `limit_travel`; noisy."""
    rng = np.random.default_rng(seed)
    d = np.arange(0.0, limit_travel, SPEED_STEP)
    force = np.minimum(stiffness * np.maximum(d - free, 0.0), plateau) + NOISE * rng.standard_normal(len(d))
    reached = np.flatnonzero(force >= limit_force)
    if reached.size:
        end = reached[0] + 1
        return d[:end], force[:end], "force"
    return d, force, "displacement"


CASES = {
    # A block welded to the floor: loaded over a few millimetres of the leg's compliance.
    ("rigid", "fixed"): dict(free=0.002, stiffness=5000.0, plateau=np.inf),
    # A sprung plate: 400 N/m, fixed.
    ("soft", "fixed"): dict(free=0.01, stiffness=400.0, plateau=np.inf),
    # A light block sliding at 6 N once touched.
    ("rigid", "mobile"): dict(free=0.0, stiffness=20000.0, plateau=6.0),
    # The sprung plate on a sled that slides at 5 N.
    ("soft", "mobile"): dict(free=0.005, stiffness=400.0, plateau=5.0),
}


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("expected", sorted(CASES))
def test_each_obstacle_is_classified_right(expected, seed):
    d, force, stopped_by = curve(**CASES[expected], limit_force=12.0, limit_travel=0.05, seed=seed)
    response = classify_press(d, force, stopped_by)
    assert (response.stiffness_class, response.mobility) == expected


def test_a_soft_fixed_obstacle_pressed_to_the_displacement_limit_is_not_taken_for_mobile():
    # Softer than the press's force limit over its travel: the press ends by displacement with the
    # force still rising, as a fixed soft obstacle does.
    d, force, stopped_by = curve(free=0.0, stiffness=150.0, plateau=np.inf, limit_force=12.0, limit_travel=0.06, seed=0)
    assert stopped_by == "displacement"
    response = classify_press(d, force, stopped_by)
    assert (response.stiffness_class, response.mobility) == ("soft", "fixed")


def test_a_press_that_touched_nothing_says_so():
    d, force, stopped_by = curve(free=1.0, stiffness=400.0, plateau=np.inf, limit_force=12.0, limit_travel=0.05, seed=0)
    response = classify_press(d, force, stopped_by)
    assert response.peak_force_n < CONTACT_FORCE
    assert (response.stiffness_class, response.mobility) == ("nothing", "nothing")


def test_mismatched_curves_are_refused():
    with pytest.raises(ValueError, match="matching samples"):
        classify_press(np.zeros(3), np.zeros(2), "force")
