"""Where a leg's new reference starts: where its current reference is, so that a phase that
hands the leg from one reference to another (a lift to a reach, a teleoperated foot to a
placing) never steps it.

Starting from where the leg is measured instead would step the reference by the leg's tracking
error: about a millimetre for a free foot, centimetres for a foot pressed on a surface (its
reference lies behind the surface). A reference of the other kind is converted at the trunk's
estimate: that is where the leg's joints put the foot in the world.
"""

import numpy as np

from pedi_drake.leg_kinematics import foot_jacobian_B, foot_position_B
from pedi_drake.mission.progress import LEG_MODE_JOINTS, MissionProgress
from pedi_drake.mission.robot_view import RobotView

# Damped Newton steps of the foot-to-joints conversion, and their damping [m]: a foot reference
# lies within centimetres of the measured foot, from where three steps reach micrometres.
NEWTON_STEPS = 3
DAMPING = 1e-3


def joint_reference_start(progress: MissionProgress, view: RobotView, leg: str) -> np.ndarray:
    """The joint angles [rad] (hip, thigh, calf) a new joint-space reference of `leg` starts from.

    A joint reference's value now; a foot reference (a world point) turned into joint angles by
    damped Newton steps from the measured angles; a leg without a reference (a support leg): its
    measured angles.
    """
    q = view.leg_q(leg).copy()
    current = progress.references.legs.get(leg) if progress.references is not None else None
    if current is None:
        return q
    reference = np.asarray(current.trajectory.sample(view.time).position, float)
    if current.mode == LEG_MODE_JOINTS:
        return reference.copy()
    p_B = view.X_WB.inverse() @ reference
    for _ in range(NEWTON_STEPS):
        J = foot_jacobian_B(leg, q)
        q = q + J.T @ np.linalg.solve(J @ J.T + DAMPING**2 * np.eye(3), p_B - foot_position_B(leg, q))
    return q


def foot_reference_start(progress: MissionProgress, view: RobotView, leg: str) -> np.ndarray:
    """The world point [m] a new foot reference of `leg` starts from: a foot reference's value now;
    a joint reference's foot at the trunk's estimate; a leg without a reference: its measured foot."""
    current = progress.references.legs.get(leg) if progress.references is not None else None
    if current is None:
        return view.foot_W(leg)
    reference = np.asarray(current.trajectory.sample(view.time).position, float)
    if current.mode == LEG_MODE_JOINTS:
        return view.X_WB @ foot_position_B(leg, reference)
    return reference.copy()
