"""The static walk on paper: its cycles, footholds and the CoM's place over the support
(pedi_drake.locomotion)."""

import itertools
import math

import numpy as np
import pytest

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.locomotion.footholds import NOMINAL_FEET_B, PlanarPose, foothold_W, support_margin
from pedi_drake.locomotion.gait import GAITS, SHIFT, STATIC_WALK_CYCLES, SWING, StaticWalkTiming
from pedi_drake.locomotion.static_walk import SUPPORT_MARGIN, choose_cycle, plan_cycle, support_margins

TIMING = StaticWalkTiming()
LIMITS = GAITS["static_walk"]


@pytest.mark.parametrize("cycle", STATIC_WALK_CYCLES)
def test_every_leg_swings_once_a_cycle_and_never_two_at_once(cycle):
    swings = [slot.leg for slot in cycle if slot.kind == SWING]
    assert sorted(swings) == sorted(robot.LEG_NAMES)
    # A slot lifts at most one foot: never fewer than three feet loaded.
    assert all((slot.kind == SWING) == bool(slot.leg) for slot in cycle)
    # The two legs of a side swing together, the CoM on the other side; a shift crosses over.
    for k, slot in enumerate(cycle):
        if slot.kind == SWING:
            assert slot.side == (1.0 if slot.leg.endswith("R") else -1.0)
        else:
            assert slot.kind == SHIFT and cycle[(k + 1) % len(cycle)].side == slot.side


def test_the_cycle_lasts_its_slots_and_the_stride_is_speed_times_cycle():
    assert TIMING.cycle == pytest.approx(4 * (TIMING.swing + 2 * TIMING.ramp) + 2 * TIMING.shift)
    assert TIMING.stride(0.1) == pytest.approx(0.1 * TIMING.cycle)
    assert TIMING.stance() == pytest.approx(TIMING.cycle - TIMING.swing)


def test_a_twist_held_turns_along_its_arc():
    # Half a turn at 0.1 m/s and 0.5 rad/s: a half circle of radius 0.2 m to the left.
    pose = PlanarPose(0.0, 0.0, 0.0).moved([0.1, 0.0, 0.5], math.pi / 0.5)
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((0.0, 0.4, math.pi), abs=1e-12)
    assert PlanarPose(1.0, 2.0, math.pi / 2).moved([0.2, 0.1, 0.0], 2.0).xy == pytest.approx([0.8, 2.4])


def test_the_foothold_is_the_hip_at_mid_stance_by_hand():
    # Forward at 0.1 m/s, 1.5 s to mid-stance: FR lands 15 cm ahead of its place under the hip.
    hold = foothold_W("FR", PlanarPose(1.0, 0.0, 0.0), np.array([0.1, 0.0, 0.0]), 1.5)
    assert hold == pytest.approx([1.0 + 0.1881 + 0.15, -(0.04675 + 0.08)])
    # Facing +y, the same step is along +y and the right foot is at +x.
    hold = foothold_W("FR", PlanarPose(0.0, 0.0, math.pi / 2), np.array([0.1, 0.0, 0.0]), 1.5)
    assert hold == pytest.approx([0.12675, 0.1881 + 0.15])


def test_the_support_margin_is_the_distance_inside():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert support_margin(square, [0.5, 0.2]) == pytest.approx(0.2)
    assert support_margin(square[::-1], [1.3, 0.5]) == pytest.approx(-0.3)


# The extreme twists within the limits: each component at its limit or zero, the yaw rate held to
# what the sideways speed leaves it.
CORNERS = [
    LIMITS.held(np.array(c) * [LIMITS.forward, LIMITS.sideways, LIMITS.yaw_rate])
    for c in itertools.product((-1, 0, 1), repeat=3)
]


@pytest.mark.parametrize("twist", CORNERS, ids=lambda t: f"{t[0]:+.2f},{t[1]:+.2f},{t[2]:+.2f}")
def test_every_twist_within_the_limits_keeps_the_com_inside_the_support(twist):
    margins, scales, feet = support_margins(NOMINAL_FEET_B, PlanarPose(0.0, 0.0, 0.3), twist, TIMING, cycles=4)
    assert margins.min() >= SUPPORT_MARGIN - 1e-6
    # Some combinations are walked slower for a cycle, none stops the walk.
    assert scales.min() >= 0.25
    # The feet stay spread about the hips: none ends farther from their middle than a hip's
    # place (0.23 m) and half the largest stride.
    assert np.all(np.linalg.norm(feet - feet.mean(axis=0), axis=1) < 0.23 + 0.5 * TIMING.stride(LIMITS.forward))


@pytest.mark.parametrize(
    "twist", [[0.2, 0, 0], [-0.2, 0, 0], [0, 0.1, 0], [0, -0.1, 0], [0, 0, -0.3], [0.1, 0.05, 0.1]]
)
def test_straight_sideways_and_turning_walks_run_at_the_full_twist(twist):
    _, scales, _ = support_margins(NOMINAL_FEET_B, PlanarPose(0.0, 0.0, 0.0), np.array(twist), TIMING, cycles=4)
    assert np.all(scales == 1.0)


@pytest.mark.parametrize("twist", CORNERS, ids=lambda t: f"{t[0]:+.2f},{t[1]:+.2f},{t[2]:+.3f}")
def test_every_twist_within_the_limits_lands_each_foot_on_its_own_side(twist):
    # Seen from the trunk at touchdown a swing foot lands on its own side of the centre line: a
    # sideways step and a turn at their limits together put a front foot 4 cm across it.
    line = PlanarPose(0.0, 0.0, 0.0)
    cycle, scale = choose_cycle(line, line.xy, NOMINAL_FEET_B, twist, TIMING)
    for plan in plan_cycle(cycle, 0.0, line, line.xy, NOMINAL_FEET_B, scale * twist, TIMING):
        if plan.foothold_xy is not None:
            k = robot.LEG_NAMES.index(plan.slot.leg)
            across = plan.line_end.rotation().T @ (plan.foothold_xy - plan.line_end.xy)
            assert math.copysign(1.0, NOMINAL_FEET_B[k][1]) * across[1] > 0.0, (plan.slot.leg, across)


def test_a_twist_past_the_limits_is_refused_not_clipped():
    assert LIMITS.problem([0.1, 0.0, 0.0]) is None
    assert "forward" in LIMITS.problem([0.25, 0.0, 0.0])
    assert "yaw rate" in LIMITS.problem([0.0, 0.0, -0.35])
    # Sideways and turning share one budget.
    assert LIMITS.problem([0.0, 0.055, 0.15]) is None
    assert "share one budget" in LIMITS.problem([0.0, 0.1, 0.2])


def test_walking_forward_starts_with_the_right_hind_leg_and_its_slots_chain():
    line = PlanarPose(0.0, 0.0, 0.0)
    twist = np.array([0.1, 0.0, 0.0])
    cycle, scale = choose_cycle(line, line.xy, NOMINAL_FEET_B, twist, TIMING)
    assert scale == 1.0
    assert [slot.leg for slot in cycle if slot.kind == SWING][0] in ("RR", "RL")
    plans = plan_cycle(cycle, 2.0, line, line.xy, NOMINAL_FEET_B, twist, TIMING)
    for before, after in itertools.pairwise(plans):
        assert after.t0 == pytest.approx(before.t_end)
        assert after.com_start_xy == pytest.approx(before.com_end_xy)
    assert plans[-1].line_end.x == pytest.approx(0.1 * TIMING.cycle)


def test_a_foot_that_cannot_keep_the_support_is_refused():
    # Feet bunched under the trunk leave no triangle with room for the CoM.
    feet = 0.2 * NOMINAL_FEET_B
    with pytest.raises(PediError, match="no CoM position"):
        plan_cycle(STATIC_WALK_CYCLES[0], 0.0, PlanarPose(0.0, 0.0, 0.0), np.zeros(2), feet, np.zeros(3), TIMING)
