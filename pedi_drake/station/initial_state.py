"""Initial robot states: lying on the floor or standing, feet resting on the ground."""

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

from pedi_drake import robot
from pedi_drake.leg_kinematics import foot_position_B
from pedi_drake.station.scenario import RobotConfig

GROUND_CLEARANCE = 0.0005  # [m] feet start this far above the ground, so nothing starts in penetration.


def initial_joint_positions(config: RobotConfig) -> np.ndarray:
    """Unitree-ordered joint angles of the initial pose [rad]."""
    return (robot.LYING_Q if config.initial_pose == "lying" else robot.STANDING_Q).copy()


def initial_trunk_pose(config: RobotConfig) -> RigidTransform:
    """X_WB with the trunk level, at `initial_xy` and `initial_yaw`, the lowest foot on the ground."""
    q = initial_joint_positions(config)
    lowest = min(foot_position_B(leg, q[robot.leg_slice(leg)])[2] for leg in robot.LEG_NAMES)
    height = -lowest + robot.FOOT_RADIUS + GROUND_CLEARANCE
    x, y = config.initial_xy
    return RigidTransform(RollPitchYaw(0.0, 0.0, config.initial_yaw), [x, y, height])


def set_default_go1_state(plant, plant_map: robot.Go1PlantMap, config: RobotConfig) -> None:
    """Sets the plant's default (initial) Go1 pose; call after Finalize, before creating contexts."""
    plant.SetDefaultFloatingBaseBodyPose(
        plant.GetBodyByName(robot.TRUNK_BODY_NAME, plant_map.model), initial_trunk_pose(config)
    )
    q = initial_joint_positions(config)
    for name, angle in zip(robot.JOINT_NAMES, q, strict=True):
        plant.GetJointByName(name, plant_map.model).set_default_angle(float(angle))
