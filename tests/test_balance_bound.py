"""The balance bound's maths: the limit is a margin of the live SUF along the push, and the foot
slows, stops and retreats as its force approaches and passes it."""

import math

import numpy as np
import pytest

from pedi_drake.mission.balance_bound import (
    APPROACH,
    FORCE_NOISE,
    RETREAT_GAIN,
    balance_limit,
    bound_balance,
    disturbance_direction,
)
from pedi_drake.suf.live import LiveSufReading
from pedi_drake.suf.warm_projection import EXACT, INCOMPLETE, NUMERICAL

BACK = np.array([-1.0, 0.0, 0.0])  # a wall ahead pushes the foot back


def _reading(status=EXACT, leg=0, value=25.0, reach=46.0, request=BACK) -> LiveSufReading:
    return LiveSufReading(status, leg, value, np.array([0.0, 0.0, 1.0]), reach, np.asarray(request, float), 0, 10, 1, 0)


def test_the_direction_is_the_forces_then_against_the_motion_then_the_last():
    np.testing.assert_allclose(disturbance_direction([-20.0, 0, 0], [0.1, 0, 0], None), BACK)
    small = [FORCE_NOISE / 2, 0.0, 0.0]
    np.testing.assert_allclose(disturbance_direction(small, [0.1, 0, 0], None), BACK)
    np.testing.assert_allclose(disturbance_direction(small, np.zeros(3), BACK), BACK)
    assert disturbance_direction(small, np.zeros(3), None) is None


def test_the_limit_is_the_margin_of_the_reach_along_the_asked_direction():
    assert balance_limit(_reading(), 0, BACK, 0.5) == pytest.approx(23.0)
    # Asked about another direction: the SUF, the smallest extent over all directions.
    assert balance_limit(_reading(request=[0, 1.0, 0]), 0, BACK, 0.5) == pytest.approx(12.5)
    # The fallback's single-direction values serve as well.
    assert balance_limit(_reading(status=INCOMPLETE), 0, BACK, 0.5) == pytest.approx(23.0)


def test_no_live_suf_of_this_leg_waits_and_a_failed_one_forbids_pushing():
    assert balance_limit(None, 0, BACK, 0.5) is None
    assert balance_limit(_reading(leg=1), 0, BACK, 0.5) is None
    assert balance_limit(_reading(status=NUMERICAL), 0, BACK, 0.5) == 0.0


def test_the_foot_slows_near_the_limit_stops_at_it_and_retreats_beyond():
    # The wall's force on the foot points back (BACK), as the mission's force estimate does.
    forward = np.array([0.1, 0.02, 0.0])  # into the wall, and a little sideways
    limit = 20.0
    far = bound_balance(forward, 5.0 * BACK, BACK, limit, 0.1)
    assert not far[1] and np.array_equal(far[0], forward)
    midway = limit * (1 - APPROACH / 2)  # halfway through the approach band
    velocity, acted = bound_balance(forward, midway * BACK, BACK, limit, 0.1)
    assert acted and velocity[0] == pytest.approx(0.05) and velocity[1] == pytest.approx(0.02)
    velocity, acted = bound_balance(forward, limit * BACK, BACK, limit, 0.1)
    assert acted and velocity[0] == pytest.approx(0.0) and velocity[1] == pytest.approx(0.02)
    velocity, _ = bound_balance(forward, (limit + 5.0) * BACK, BACK, limit, 0.1)
    assert velocity[0] == pytest.approx(-5.0 * RETREAT_GAIN)
    # Away from the wall nothing changes below the limit.
    away = np.array([-0.1, 0.0, 0.0])
    assert np.array_equal(bound_balance(away, (limit - 1.0) * BACK, BACK, limit, 0.1)[0], away)
    assert math.isfinite(bound_balance(forward, (limit + 1e6) * BACK, BACK, limit, 0.1)[0][0])
