"""Geometry of one Go1 leg, read from the model, and its forward kinematics in numpy.

The leg is a fixed-base chain from the trunk: hip (abduction, about x), thigh (about y),
calf (about y), then the foot centre. `LegGeometry` holds the joint offsets and axes as found
in the finalized plant, so the IK and every other user of the leg share one source of truth.
"""

import dataclasses
import functools

import numpy as np

from pedi_drake import robot
from pedi_drake.vector3 import axis_angle_matrix


@dataclasses.dataclass(frozen=True)
class LegGeometry:
    """Joint origins, axes and limits of one leg, each in its parent's frame at zero angles."""

    leg: str
    p_BH: np.ndarray  # hip joint origin in the trunk frame [m]
    p_HT: np.ndarray  # thigh joint origin in the hip frame [m]
    p_TC: np.ndarray  # calf joint origin in the thigh frame [m]
    p_CF: np.ndarray  # foot centre in the calf frame [m]
    axes: np.ndarray  # (3, 3) unit joint axes (hip, thigh, calf), each in its own joint frame
    q_lower: np.ndarray  # (3,) [rad]
    q_upper: np.ndarray  # (3,) [rad]

    def joint_offsets(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return self.p_BH, self.p_HT, self.p_TC, self.p_CF


@functools.lru_cache(maxsize=4)
def leg_geometry(leg: str) -> LegGeometry:
    """The geometry of `leg` (FR, FL, RR, RL) read from the Go1 model."""
    plant, plant_map = robot.make_go1_plant()
    context = plant.CreateDefaultContext()
    names = [f"{leg}_{kind}_joint" for kind in robot.JOINT_KINDS]
    joints = [plant.GetJointByName(name, plant_map.model) for name in names]
    offsets = []
    for joint in joints:
        X_PJ = joint.frame_on_parent().CalcPoseInBodyFrame(context)
        if not np.allclose(X_PJ.rotation().matrix(), np.eye(3)):
            raise robot.PediError(f"{joint.name()}: joint frames rotated from their parent are not supported")
        offsets.append(X_PJ.translation().copy())
    calf = plant.GetBodyByName(f"{leg}_calf", plant_map.model)
    foot = plant.GetBodyByName(f"{leg}_foot", plant_map.model)
    p_CF = plant.CalcRelativeTransform(context, calf.body_frame(), foot.body_frame()).translation().copy()
    axes = np.array([np.asarray(j.revolute_axis(), float) for j in joints])
    return LegGeometry(
        leg=leg,
        p_BH=offsets[0],
        p_HT=offsets[1],
        p_TC=offsets[2],
        p_CF=p_CF,
        axes=axes,
        q_lower=np.array([j.position_lower_limits()[0] for j in joints]),
        q_upper=np.array([j.position_upper_limits()[0] for j in joints]),
    )


def joint_frames(geometry: LegGeometry, q_leg: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """World-free forward kinematics in the trunk frame.

    Returns (positions, rotations): positions of the hip, thigh and calf joints and the foot
    centre [m] (4 entries) and the orientations R_BH, R_BT, R_BC of the three links.
    """
    R = np.eye(3)
    p = geometry.p_BH.copy()
    positions, rotations = [p.copy()], []
    for offset_next, axis, angle in zip(
        (geometry.p_HT, geometry.p_TC, geometry.p_CF), geometry.axes, q_leg, strict=True
    ):
        R = R @ axis_angle_matrix(float(angle) * np.asarray(axis))
        rotations.append(R.copy())
        p = p + R @ offset_next
        positions.append(p.copy())
    return positions, rotations


def working_position_B(leg: str, working_depth: float) -> np.ndarray:
    """Where leg_to_pedipulation lifts the foot of `leg` [m], trunk frame: `working_depth` [m]
    below the hip joint, beside it as the thigh offset puts it."""
    geometry = leg_geometry(leg)
    return geometry.p_BH + geometry.p_HT - np.array([0.0, 0.0, working_depth])


def foot_position_B(leg: str, q_leg: np.ndarray) -> np.ndarray:
    """Foot centre in the trunk frame [m] for the leg's joint angles (hip, thigh, calf) [rad]."""
    positions, _ = joint_frames(leg_geometry(leg), np.asarray(q_leg, float))
    return positions[-1]


def foot_jacobian_B(leg: str, q_leg: np.ndarray) -> np.ndarray:
    """(3, 3) Jacobian of `foot_position_B` with respect to the leg's joint angles."""
    geometry = leg_geometry(leg)
    positions, rotations = joint_frames(geometry, np.asarray(q_leg, float))
    foot = positions[-1]
    # Each joint's axis in the trunk frame: the hip's parent is the trunk itself.
    frames = [np.eye(3), rotations[0], rotations[1]]
    return np.column_stack([np.cross(frames[k] @ geometry.axes[k], foot - positions[k]) for k in range(3)])
