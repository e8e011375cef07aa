"""Go1 stances for SUF analysis: trunk height, symmetric feet, prongs, and the end-effector foot.

The design parameters of paper 003 (Eq. 7): feet at (+-x_f, +-y_f) on flat ground, the trunk
level at height b_z above them, prongs (if any) long enough to touch the ground at that height.
Joint angles come from the closed-form leg IK; the end-effector leg holds its foot at a given
point in the trunk frame (by default 15 cm below its shoulder, the pedipulation working position).
"""

import dataclasses

import numpy as np

from pedi_drake import robot
from pedi_drake.exceptions import SufError, UnreachableTarget
from pedi_drake.ik.analytic import solve_leg_ik_analytic
from pedi_drake.leg_kinematics import leg_geometry
from pedi_drake.prongs import PRONG_HALF_SPACING, ProngDesign
from pedi_drake.suf.problem import PRONG_PREFIX, ContactPoint, RejectableForceProblem, build_problem


@dataclasses.dataclass
class Go1Stance:
    """A static Go1 configuration for SUF analysis."""

    trunk_height: float  # b_z: trunk origin above the ground [m]
    feet_x: float = 0.19  # x_f: |x| of the feet in the trunk frame [m]
    feet_y: float = 0.13  # y_f: |y| of the feet [m]
    # Contacts carrying the robot: leg names and/or "prong0", "prong1", ...
    contacts: tuple[str, ...] = ("FL", "RR", "RL")
    # The leg whose foot is the end-effector (not in `contacts`), ...
    end_effector: str = "FR"
    # ... and where that foot is, trunk frame [m]; None: 15 cm below its shoulder.
    end_effector_B: tuple[float, float, float] | None = None
    # Prongs on the trunk, or None. `with_prongs_at_height` sizes them for the trunk height.
    prongs: ProngDesign | None = None
    # Trunk origin x, y in the world, the feet being placed around the world origin [m]: on three
    # legs the trunk leans over the support triangle, as the controller's balance task makes it.
    trunk_xy: tuple[float, float] = (0.0, 0.0)

    def end_effector_position_B(self) -> np.ndarray:
        if self.end_effector_B is not None:
            return np.asarray(self.end_effector_B, dtype=float)
        g = leg_geometry(self.end_effector)
        return g.p_BH + g.p_HT - np.array([0.0, 0.0, 0.15])

    def joint_angles(self) -> np.ndarray:
        """The 12 joint angles (Unitree order) [rad]; raises SufError if a foot is out of reach."""
        q = robot.STANDING_Q.copy()
        for leg in robot.LEG_NAMES:
            sx = 1.0 if leg.startswith("F") else -1.0
            sy = -1.0 if leg.endswith("R") else 1.0
            if leg == self.end_effector:
                target = self.end_effector_position_B()
            else:
                foot_W = np.array([sx * self.feet_x, sy * self.feet_y, robot.FOOT_RADIUS])
                target = foot_W - np.array([self.trunk_xy[0], self.trunk_xy[1], self.trunk_height])
            sl = robot.leg_slice(leg)
            try:
                q[sl] = solve_leg_ik_analytic(leg, target, robot.STANDING_Q[sl])
            except UnreachableTarget as error:
                raise SufError(f"stance out of reach: {error}") from None
        return q


def with_prongs_at_height(stance: Go1Stance, x_positions=(PRONG_HALF_SPACING, -PRONG_HALF_SPACING)) -> Go1Stance:
    """The stance with centre-line prongs whose tips touch the ground at its trunk height."""
    return dataclasses.replace(stance, prongs=ProngDesign.for_trunk_height(stance.trunk_height, x_positions))


def stance_problem(stance: Go1Stance, *, mu: float = 0.6, qdd_desired=None) -> RejectableForceProblem:
    """The RejectableForceProblem of a stance (see build_problem)."""
    if stance.end_effector in stance.contacts:
        raise SufError(f"end_effector: {stance.end_effector} is also a contact")
    prongs = stance.prongs
    plant, plant_map = robot.make_go1_plant(robot.design_key(prongs))
    q = plant_map.full_positions(
        np.array([1.0, 0.0, 0.0, 0.0]),
        np.array([0.0, 0.0, stance.trunk_height]),
        stance.joint_angles(),
        plant.num_positions(),
    )
    prong_names = robot.prong_body_names(prongs)
    contacts = []
    for name in stance.contacts:
        if name in robot.LEG_NAMES:
            contacts.append(ContactPoint(name, f"{name}_foot", np.zeros(3)))
        elif name.startswith(PRONG_PREFIX) and name[len(PRONG_PREFIX) :].isdigit():
            k = int(name[len(PRONG_PREFIX) :])
            if k >= len(prong_names):
                raise SufError(f"contacts: {name!r} but the robot has {len(prong_names)} prongs")
            contacts.append(ContactPoint(name, prong_names[k], np.array([0.0, 0.0, -prongs.length])))
        else:
            raise SufError(f"contacts: unknown contact {name!r} (a leg name or prong0, prong1, ...)")
    if stance.end_effector not in robot.LEG_NAMES:
        raise SufError(f"end_effector: must be a leg name, got {stance.end_effector!r}")
    effector = ContactPoint(stance.end_effector, f"{stance.end_effector}_foot", np.zeros(3))
    return build_problem(plant, q, contacts, effector, mu=mu, qdd_desired=qdd_desired)


def teleoperation_stance(trunk_height: float = 0.27, feet_x: float = 0.19, feet_y: float = 0.13) -> Go1Stance:
    """Paper 003's teleoperation scenario on the Go1: FL, RR, RL stance, the FR foot is the end-effector.

    The trunk sits over the centroid of the three stance feet, (-x_f / 3, y_f / 3).
    """
    return Go1Stance(trunk_height, feet_x, feet_y, ("FL", "RR", "RL"), "FR", trunk_xy=(-feet_x / 3, feet_y / 3))


def prong_manipulation_stance(trunk_height: float = 0.17, feet_x: float = 0.19, feet_y: float = 0.13) -> Go1Stance:
    """Paper 003's manipulation scenario: both prongs and both rear feet down, the FR foot is the end-effector."""
    stance = Go1Stance(trunk_height, feet_x, feet_y, ("RR", "RL", "prong0", "prong1"), "FR")
    return with_prongs_at_height(stance)
