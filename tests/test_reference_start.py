"""A leg's new reference starts where its current reference is, not where the leg is."""

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix

from pedi_drake import robot
from pedi_drake.estimation.base_state import BaseState
from pedi_drake.ik.analytic import leg_ik_solutions
from pedi_drake.leg_kinematics import foot_position_B, leg_geometry
from pedi_drake.mission.progress import (
    LEG_MODE_FOOT,
    LEG_MODE_JOINTS,
    LegTrajectory,
    MissionProgress,
    References,
)
from pedi_drake.mission.reference_start import foot_reference_start, joint_reference_start
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.trajectory import PiecewiseQuintic, QuinticSegment

# A tilted, shifted trunk, so that the world-to-trunk conversion is exercised.
X_WB = RigidTransform(RollPitchYaw(0.05, -0.08, 0.3), [0.1, -0.05, 0.27])


def _lifted_q() -> np.ndarray:
    geometry = leg_geometry("FR")
    q = robot.STANDING_Q.copy()
    q[0:3] = leg_ik_solutions("FR", geometry.p_BH + geometry.p_HT - np.array([0.0, 0.0, 0.17]))[0]
    return q


def _view(t: float, q: np.ndarray) -> RobotView:
    quaternion = X_WB.rotation().ToQuaternion()
    wxyz = np.array([quaternion.w(), quaternion.x(), quaternion.y(), quaternion.z()])
    base = BaseState(wxyz, X_WB.translation(), np.zeros(3), np.zeros(3))
    return RobotView(t, base, q, np.zeros(12), np.zeros(12), np.zeros(4))


def _progress() -> MissionProgress:
    progress = MissionProgress(phase_start=0.0)
    progress.references = References.holding(X_WB.translation(), RotationMatrix(), 0.0, 0)
    return progress


def test_a_support_leg_starts_from_its_measured_angles():
    q = _lifted_q()
    np.testing.assert_array_equal(joint_reference_start(_progress(), _view(1.0, q), "FR"), q[0:3])


def test_a_joint_reference_is_continued_from_its_value_now():
    q = _lifted_q()
    progress = _progress()
    q_goal = q[0:3] + [0.1, -0.2, 0.3]
    progress.references.legs["FR"] = LegTrajectory(
        LEG_MODE_JOINTS, PiecewiseQuintic.through(np.array([q[0:3], q_goal]), 0.0, [2.0])
    )
    # Measured 30 mrad off the reference on every joint: the start ignores the tracking error.
    view = _view(1.0, q + 0.03)
    expected = progress.references.legs["FR"].trajectory.sample(1.0).position
    np.testing.assert_allclose(joint_reference_start(progress, view, "FR"), expected, atol=1e-12)


def test_a_foot_reference_pressed_two_centimetres_behind_a_surface_becomes_its_joint_angles():
    q = _lifted_q()
    p_foot_B = foot_position_B("FR", q[0:3])
    # The foot stopped on a wall while its reference went on 2 cm into it (trunk frame forward).
    p_reference_W = X_WB @ (p_foot_B + [0.02, 0.0, 0.0])
    progress = _progress()
    progress.references.legs["FR"] = LegTrajectory(
        LEG_MODE_FOOT, QuinticSegment(p_reference_W, p_reference_W, 0.0, 1e-3)
    )
    q_start = joint_reference_start(progress, _view(1.0, q), "FR")
    np.testing.assert_allclose(X_WB @ foot_position_B("FR", q_start), p_reference_W, atol=1e-6)
    # The measured foot is 2 cm away: starting there would have stepped the reference by that.
    assert np.linalg.norm(X_WB @ p_foot_B - p_reference_W) > 0.019


def test_a_foot_reference_after_a_joint_reference_starts_at_its_foot_not_the_measured_one():
    q = _lifted_q()
    progress = _progress()
    q_reference = q[0:3] + [0.0, 0.05, -0.05]
    progress.references.legs["FR"] = LegTrajectory(
        LEG_MODE_JOINTS, PiecewiseQuintic.through(np.array([q_reference, q_reference]), 0.0, [1.0])
    )
    view = _view(2.0, q)
    np.testing.assert_allclose(
        foot_reference_start(progress, view, "FR"), X_WB @ foot_position_B("FR", q_reference), atol=1e-12
    )
    np.testing.assert_allclose(foot_reference_start(_progress(), view, "FR"), view.foot_W("FR"), atol=1e-12)
