"""Initial robot states: lying on the floor or standing, feet resting on the ground.

A Go1 with prongs cannot lie as low as one without: its trunk rests on the prong tips. Lying with
prongs is therefore a crouch at the prongs' ground-contact height, the feet on the ground where the
folded legs of the plain lying pose put them (in x and y), so that nothing starts in penetration.
"""

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

from pedi_drake import robot
from pedi_drake.ik.analytic import solve_leg_ik_analytic
from pedi_drake.leg_kinematics import foot_position_B
from pedi_drake.scenario import RobotConfig

GROUND_CLEARANCE = 0.0005  # [m] feet start this far above the ground, so nothing starts in penetration.


def _height_on_feet(q: np.ndarray, foot_radius: float = robot.FOOT_RADIUS) -> float:
    """Trunk height [m] at which the lowest foot (of `foot_radius` [m]) of the (level) pose `q`
    rests on the ground."""
    lowest = min(foot_position_B(leg, q[robot.leg_slice(leg)])[2] for leg in robot.LEG_NAMES)
    return -lowest + foot_radius + GROUND_CLEARANCE


def _prong_rest_height(config: RobotConfig) -> float | None:
    """Trunk height [m] at which the prong tips rest on the ground, if the robot has prongs."""
    return None if config.prongs is None else config.prongs.ground_contact_height() + GROUND_CLEARANCE


def initial_joint_positions(config: RobotConfig) -> np.ndarray:
    """Unitree-ordered joint angles of the initial pose [rad]."""
    if config.initial_pose != "lying":
        return robot.STANDING_Q.copy()
    q = robot.LYING_Q.copy()
    rest = _prong_rest_height(config)
    if rest is None or rest <= _height_on_feet(q):
        return q
    # Resting on the prongs: the legs reach down to the ground from the raised trunk.
    foot_z_B = -(rest - robot.FOOT_RADIUS - GROUND_CLEARANCE)
    for leg in robot.LEG_NAMES:
        s = robot.leg_slice(leg)
        p_B = foot_position_B(leg, q[s])
        p_B[2] = foot_z_B
        q[s] = solve_leg_ik_analytic(leg, p_B, q_near=q[s])
    return q


def initial_trunk_pose(config: RobotConfig, foot_radius: float = robot.FOOT_RADIUS) -> RigidTransform:
    """X_WB with the trunk level, at `initial_xy` and `initial_yaw`, resting on its lowest support.

    That is the lowest foot or, for a robot with prongs, the prong tips (whichever is lower).
    `foot_radius` [m]: the plant's feet (a scenario's model error may make them differ from the
    controllers' robot.FOOT_RADIUS); the joint angles are the same for every radius.
    """
    height = _height_on_feet(initial_joint_positions(config), foot_radius)
    rest = _prong_rest_height(config)
    if rest is not None:
        height = max(height, rest)
    x, y = config.initial_xy
    return RigidTransform(RollPitchYaw(0.0, 0.0, config.initial_yaw), [x, y, height])


def set_default_go1_state(
    plant, plant_map: robot.Go1PlantMap, config: RobotConfig, foot_radius: float = robot.FOOT_RADIUS
) -> None:
    """Sets the plant's default (initial) Go1 pose, feet of `foot_radius` [m]; call after Finalize,
    before creating contexts."""
    plant.SetDefaultFloatingBaseBodyPose(
        plant.GetBodyByName(robot.TRUNK_BODY_NAME, plant_map.model), initial_trunk_pose(config, foot_radius)
    )
    q = initial_joint_positions(config)
    for name, angle in zip(robot.JOINT_NAMES, q, strict=True):
        plant.GetJointByName(name, plant_map.model).set_default_angle(float(angle))
