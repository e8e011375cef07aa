"""The prongs' spacing from the legs' clearance (paper 003: as far apart as the legs allow)."""

import pytest

from pedi_drake import robot
from pedi_drake.prongs import (
    PRONG_HALF_SPACING,
    PRONG_HIP_INWARD_LIMIT,
    TRUNK_HALF_HEIGHT,
    WIDEST_PRONG_HALF_SPACING,
    ProngDesign,
)
from pedi_drake.suf.prong_clearance import hip_inward_reach, leg_prong_clearance, widest_prong_spacing


def test_the_widest_spacing_is_the_trunks_end_and_the_shipped_one_within_it():
    shipped = ProngDesign()
    assert shipped.attachment_points[0][0] == PRONG_HALF_SPACING <= WIDEST_PRONG_HALF_SPACING
    widest = widest_prong_spacing(shipped.length, shipped.tip_radius, PRONG_HIP_INWARD_LIMIT)
    assert widest == pytest.approx(WIDEST_PRONG_HALF_SPACING, abs=1e-3)
    # The Go1's legs do not bound it: the trunk's end does.
    assert widest == pytest.approx(robot.TRUNK_HALF_EXTENTS[0] - robot.PRONG_ROD_RADIUS, abs=1e-9)


def test_the_legs_clear_the_shipped_prongs_within_the_hip_bound_and_hit_them_beyond_it():
    shipped = ProngDesign()
    assert leg_prong_clearance(shipped, PRONG_HIP_INWARD_LIMIT) >= 0.01
    # A hip turned inwards to its joint limit takes the leg under the trunk, into the prongs.
    assert leg_prong_clearance(shipped) < 0.0


def test_a_leg_reaches_centre_line_prongs_at_the_same_hip_angle_whatever_their_spacing():
    def pair(x):
        return ProngDesign(attachment_points=[[x, 0.0, -TRUNK_HALF_HEIGHT], [-x, 0.0, -TRUNK_HALF_HEIGHT]])

    reaches = [hip_inward_reach(pair(x)) for x in (0.05, WIDEST_PRONG_HALF_SPACING)]
    assert PRONG_HIP_INWARD_LIMIT < reaches[0] < robot.HARDWARE_Q_UPPER[0]
    assert reaches[1] == reaches[0]


def test_a_prong_off_the_centre_line_under_a_leg_is_hit_within_the_hip_bound():
    # A prong right under the FR hip's leg plane (y = -0.13 m): the leg sweeps through it.
    design = ProngDesign(attachment_points=[[0.1, -0.13, -TRUNK_HALF_HEIGHT]])
    assert leg_prong_clearance(design, PRONG_HIP_INWARD_LIMIT) < 0.0
