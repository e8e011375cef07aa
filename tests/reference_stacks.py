"""The oracle of the compiled stacks (pedi_drake.control.compiled_stack): the task stacks of the
two papers, as presets that turn one control instant into reference_hqp levels.

The stacks' levels and tasks are described in compiled_stack's docstring.
"""

import dataclasses

import numpy as np
import reference_tasks as tasks
from reference_hqp import EqualityTask, Level

from pedi_drake import robot
from pedi_drake.control.compiled_stack import SLIDING_SPEED
from pedi_drake.control.config import WholeBodyControllerConfig
from pedi_drake.control.references import (
    CALF_ORIENTATION_ROWS,
    LEG_MODE_FOOT,
    LEG_MODE_JOINTS,
    BodyReference,
    LegReference,
)
from pedi_drake.control.robot_model import RobotSnapshot
from pedi_drake.vector3 import axis_angle_matrix


@dataclasses.dataclass
class ResolvedInputs:
    """Every reference of one control instant, defaults applied."""

    body: BodyReference
    legs: list[LegReference]  # 4, Unitree order
    ramp: np.ndarray  # (nc,) contact activation in [0, 1]
    no_motion: np.ndarray  # (nc,) bool: contacts held still
    polygon_N: np.ndarray  # (k, 2) safety polygon half-planes N xi <= d
    polygon_d: np.ndarray  # (k,) [m]
    friction: float  # [-]
    ground_height: float  # height of the contact plane [m]


class StackBuilder:
    """Builds the HQP levels of the configured stack from a snapshot and resolved inputs."""

    def __init__(self, config: WholeBodyControllerConfig, layout: tasks.VariableLayout, total_mass: float) -> None:
        self.config = config
        self.layout = layout
        self.total_weight = total_mass * tasks.GRAVITY
        c = config
        self.dynamics = tasks.FloatingBaseDynamics()
        self.no_motion = tasks.ContactNoMotion(c.contact_damping)
        self.forces = tasks.ContactForceLimits(c.min_normal_force, c.max_normal_force, c.friction_pyramid_inscribed)
        self.torque_limits = tasks.TorqueLimits(c.torque_limit_scale)
        self.joint_limits = tasks.JointLimits(c.joint_limit_horizon, c.joint_limit_margin)
        self.balance = tasks.CapturePointBalance(c.balance_horizon)
        self.trunk_orientation = tasks.TrunkOrientation(tasks.PdGains(c.trunk_orientation.kp, c.trunk_orientation.kd))
        self.trunk_position = tasks.TrunkPosition(tasks.PdGains(c.trunk_position.kp, c.trunk_position.kd))
        self.foot = tasks.FootPosition(tasks.PdGains(c.foot_position.kp, c.foot_position.kd))
        self.calf = tasks.CalfOrientation(tasks.PdGains(c.foot_orientation.kp, c.foot_orientation.kd))
        self.leg_joints = tasks.JointPosture(tasks.PdGains(c.leg_joints.kp, c.leg_joints.kd), "leg_joints")
        self.posture = tasks.JointPosture(tasks.PdGains(c.posture.kp, c.posture.kd), "posture")
        self.force_regularization = tasks.ContactForceRegularization()
        self.torque_min = tasks.TorqueMinimization()
        self.nominal_q = np.tile(np.asarray(c.nominal_leg_posture, float), 4)
        self.leg_joint_indices = [np.arange(3 * i, 3 * i + 3) for i in range(4)]  # Unitree order
        self.all_joints = np.arange(12)
        self.zero_joint_targets = np.zeros(12)
        self.nominal_leg_q = [self.nominal_q[joints] for joints in self.leg_joint_indices]

    @property
    def num_levels(self) -> int:
        """Number of HQP levels the configured stack produces."""
        return 6 if self.config.stack == "paper003" else 4

    def physics(self, s: RobotSnapshot, inputs: ResolvedInputs) -> Level:
        """Floating-base dynamics and contact no-motion: equalities that some x always meets exactly."""
        return Level(
            "physics", [self.dynamics.rows(s, self.layout), self.no_motion.rows(s, self.layout, inputs.no_motion)]
        )

    def feasibility(self, s: RobotSnapshot, inputs: ResolvedInputs, balance: bool) -> Level:
        lay = self.layout
        level = Level(
            "feasibility",
            [],
            [
                self.forces.rows(lay, inputs.ramp, inputs.friction),
                self.torque_limits.rows(s, lay, robot.EFFORT_LIMIT),
                self.joint_limits.rows(s, lay, robot.Q_LOWER, robot.Q_UPPER, robot.VELOCITY_LIMIT),
            ],
        )
        if balance:
            level.inequalities.append(
                self.balance.rows(s, lay, inputs.polygon_N, inputs.polygon_d, inputs.ground_height)
            )
        return level

    def leg_tasks(self, s: RobotSnapshot, inputs: ResolvedInputs) -> list[EqualityTask]:
        """Pedipulation legs (foot or joint reference) and idle swing legs (held at the nominal posture)."""
        rows = []
        for i, (leg, ref) in enumerate(zip(robot.LEG_NAMES, inputs.legs, strict=True)):
            joints = self.leg_joint_indices[i]
            # A mission may run a foot at its own gains (a compliant, low-gain foot on an object).
            gains = tasks.PdGains(ref.foot_kp, ref.foot_kd) if ref.foot_kp > 0.0 and ref.foot_kd >= 0.0 else None
            if ref.mode == LEG_MODE_FOOT:
                rows.append(self.foot.rows(s, self.layout, i, ref.position, ref.velocity, ref.acceleration, gains))
                rows[-1].name = f"foot_{leg}"
            elif ref.mode in CALF_ORIENTATION_ROWS:
                # The 5-D task (the foot held at a world pose, its calf's roll and pitch too) or the
                # 6-D shank task (the calf's whole orientation).
                rows.append(self.foot.rows(s, self.layout, i, ref.position, ref.velocity, np.zeros(3), gains))
                rows[-1].name = f"foot_{leg}"
                R_ref = axis_angle_matrix(ref.acceleration)
                rows.append(self.calf.rows(s, self.layout, i, R_ref, CALF_ORIENTATION_ROWS[ref.mode]))
                rows[-1].name = f"calf_{leg}"
            elif ref.mode == LEG_MODE_JOINTS:
                rows.append(self.leg_joints.rows(s, self.layout, joints, ref.position, ref.velocity, ref.acceleration))
                rows[-1].name = f"joints_{leg}"
            elif not inputs.no_motion[i]:
                zero = self.zero_joint_targets[:3]
                rows.append(self.leg_joints.rows(s, self.layout, joints, self.nominal_leg_q[i], zero, zero))
                rows[-1].name = f"idle_{leg}"
        return rows

    def regularisation(self, s: RobotSnapshot, inputs: ResolvedInputs) -> list[EqualityTask]:
        c = self.config
        zero = self.zero_joint_targets
        return [
            self.posture.rows(s, self.layout, self.all_joints, self.nominal_q, zero, zero, c.posture_weight),
            self.force_regularization.rows(self.layout, inputs.ramp, self.total_weight, c.force_regularization_weight),
            self.torque_min.rows(s, self.layout, c.torque_weight),
        ]

    def sliding_contacts(self, s: RobotSnapshot, inputs: ResolvedInputs) -> np.ndarray:
        """Indices of the held contacts whose tangential (horizontal) speed exceeds SLIDING_SPEED."""
        held = np.flatnonzero(inputs.no_motion)
        velocities = (s.J_contacts @ s.v).reshape(-1, 3)[held]
        return held[np.hypot(velocities[:, 0], velocities[:, 1]) > SLIDING_SPEED]

    def levels(self, s: RobotSnapshot, inputs: ResolvedInputs, relax_contacts: bool = False) -> list[Level]:
        """The stack's levels. `relax_contacts` is the fallback for an instant at which the
        contacts cannot be held still within the force limits (prong tips sliding under a push,
        say): the tangential no-motion rows of the sliding contacts then leave the physics level
        for a least-squares level just below the limits, so they brake as hard as friction allows
        instead of the QP failing and the controller dropping to damping."""
        lay, body = self.layout, inputs.body
        orientation = self.trunk_orientation.rows(s, lay, body.R, body.w, body.alpha)
        position = self.trunk_position.rows(s, lay, body.p, body.v, body.a)
        legs = self.leg_tasks(s, inputs)
        sliding = self.sliding_contacts(s, inputs) if relax_contacts else np.zeros(0, dtype=int)
        if len(sliding):
            # Only the tangential rows of contacts already sliding yield: a slip cannot be stopped
            # at once when friction cannot hold it. The normal rows and the contacts at rest stay
            # exact, so no force is bought by a contact accelerating into, off or along the ground.
            no_motion = self.no_motion.rows(s, self.layout, inputs.no_motion)
            held = np.ones(len(no_motion.b), dtype=bool)
            in_contact = list(np.flatnonzero(inputs.no_motion))
            for i in sliding:
                k = in_contact.index(i)
                held[3 * k : 3 * k + 2] = False  # x, y rows of contact i (world frame, flat ground)
            physics = Level(
                "physics",
                [
                    self.dynamics.rows(s, self.layout),
                    EqualityTask("contact_no_motion", no_motion.A[held], no_motion.b[held]),
                ],
            )
            contacts = [Level("contact_sliding", [EqualityTask("sliding", no_motion.A[~held], no_motion.b[~held])])]
        else:
            physics, contacts = self.physics(s, inputs), []
        if self.config.stack == "paper003":
            return [
                physics,
                self.feasibility(s, inputs, self.config.paper003_balance),
                *contacts,
                Level("torso_angular", [orientation]),
                Level("torso_linear", [position]),
                Level("swing_foot", legs),
                Level("torque_minimisation", self.regularisation(s, inputs)),
            ]
        return [
            physics,
            self.feasibility(s, inputs, True),
            *contacts,
            Level("pose", [orientation, position] + legs),
            Level("regularisation", self.regularisation(s, inputs)),
        ]
