"""The rate limits between two controller ticks, and the largest steps a run's references and
commands made: what a mode switch must never break.

Limits, per controller tick (2 ms), and where they come from:

  * MAX_BODY_STEP (1 mm, 0.5 m/s): the trunk reference. Every trunk motion a phase plans is a
    quintic well below it (standing up 15 cm in 2 s peaks at 0.14 m/s, 0.3 mm a tick);
  * MAX_FOOT_STEP_SAME_MODE (1 mm, 0.5 m/s): a lifted foot's reference within one leg mode (a
    joint reference through the leg's forward kinematics at the body reference). The teleoperated
    foot's speed bound (max_speed, 0.1 m/s) is 0.2 mm a tick; the lifts, reaches and placings of
    the operator missions (leg_duration 1.5 s; 0.6 s for the teleop block's shorter lift) peak
    below 1 mm. A phase planned faster exceeds it without any step: a semi-autonomous reach of
    25 cm in 1 s peaks at 0.63 m/s;
  * MAX_FOOT_STEP_AT_MODE_CHANGE (1 cm): where a leg's reference changes mode (joint angles <->
    foot position) the new one starts where the old one is, converted at the trunk's estimate
    (a joint reference starts at a foot reference's joint angles; a foot reference at the
    measured foot, within the controller's tracking error), while this check converts at the trunk's
    reference: the step is the trunk's and the foot's tracking error, under 1 cm;
  * the joint position targets, of go1.command (q_des) and of a leg's joint reference: at most the
    Go1 driver's rate limit (Go1SafetyConfig.max_target_rate, 8 rad/s) times the control period,
    16 mrad. On hardware the driver clips a faster target; in simulation nothing does, so a step
    beyond it there is the controller's or the mission's own.

Steps are measured from the mission manager's first update (before it, the references are the
ones made at initialisation) and, for go1.command, from the controller's first command.
"""

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RigidTransform, RotationMatrix

from pedi_drake import robot
from pedi_drake.control.references import LEG_BLOCK, LEG_MODE_JOINTS, LEG_MODE_NONE
from pedi_drake.leg_kinematics import foot_position_B

MAX_BODY_STEP = 0.001  # [m]
MAX_FOOT_STEP_SAME_MODE = 0.001  # [m]
MAX_FOOT_STEP_AT_MODE_CHANGE = 0.01  # [m]
# Steps this far over a limit are rounding, not steps [-].
ROUNDING = 1e-9


def _first_sample_after(times: np.ndarray, t: float) -> int:
    return int(np.searchsorted(times, t + 1e-9, side="right"))


def reference_steps(times: np.ndarray, body: np.ndarray, legs: np.ndarray, first_update: float) -> dict:
    """Largest tick-to-tick steps of the mission's references from the sample after
    `first_update` [s] on: `body` [m] (trunk position), `same` and `change` [m] (every lifted
    foot's reference in the world within one leg mode and where the mode changes) and `joints`
    [rad] (a joint reference within the joint mode). `body` (19, N) and `legs` (48, N) are the
    logged body_reference and leg_reference at `times` (N,) [s]."""
    first = _first_sample_after(times, first_update)
    body, legs = body[:, first:], legs[:, first:]
    steps = {"body": 0.0, "same": 0.0, "change": 0.0, "joints": 0.0}
    if body.shape[1] < 2:
        return steps
    steps["body"] = float(np.max(np.linalg.norm(np.diff(body[0:3], axis=1), axis=0)))
    for k, leg in enumerate(robot.LEG_NAMES):
        block = legs[k * LEG_BLOCK : (k + 1) * LEG_BLOCK]
        modes = np.round(block[0]).astype(int)
        feet = np.full((3, block.shape[1]), np.nan)
        for i in np.flatnonzero(modes != LEG_MODE_NONE):
            if modes[i] == LEG_MODE_JOINTS:
                quaternion = body[3:7, i] / np.linalg.norm(body[3:7, i])
                X_WB = RigidTransform(RotationMatrix(Quaternion(quaternion)), body[0:3, i])
                feet[:, i] = X_WB @ foot_position_B(leg, block[1:4, i])
            else:
                feet[:, i] = block[1:4, i]
        both = (modes[1:] != LEG_MODE_NONE) & (modes[:-1] != LEG_MODE_NONE)
        jumps = np.linalg.norm(np.diff(feet, axis=1), axis=0)
        same = both & (modes[1:] == modes[:-1])
        if np.any(same):
            steps["same"] = max(steps["same"], float(np.max(jumps[same])))
        if np.any(both & ~same):
            steps["change"] = max(steps["change"], float(np.max(jumps[both & ~same])))
        joints = same & (modes[1:] == LEG_MODE_JOINTS)
        if np.any(joints):
            angle_steps = np.max(np.abs(np.diff(block[1:4], axis=1)), axis=0)
            steps["joints"] = max(steps["joints"], float(np.max(angle_steps[joints])))
    return steps


def command_step(times: np.ndarray, command: np.ndarray, first_command: float) -> float:
    """Largest tick-to-tick change of any joint's position target q_des in go1.command (60, N)
    from the sample after `first_command` [s] on [rad] (inf when a value is not finite)."""
    q_des = command[0:12, _first_sample_after(times, first_command) :]
    if q_des.shape[1] < 2:
        return 0.0
    if not np.isfinite(q_des).all():
        return float("inf")
    return float(np.max(np.abs(np.diff(q_des, axis=1))))


def rate_limit_table(steps: dict, command: float, max_target_step: float) -> dict:
    """{name: {step, limit, within}} of the steps (`reference_steps`, `command_step`) against the
    limits (module docstring; `max_target_step` [rad] the driver's rate limit times the period)."""
    limits = {
        "body": (steps["body"], MAX_BODY_STEP),
        "foot_same_mode": (steps["same"], MAX_FOOT_STEP_SAME_MODE),
        "foot_mode_change": (steps["change"], MAX_FOOT_STEP_AT_MODE_CHANGE),
        "joint_reference": (steps["joints"], max_target_step),
        "command_q_des": (command, max_target_step),
    }
    return {
        name: {"step": step, "limit": limit, "within": bool(step <= limit * (1.0 + ROUNDING))}
        for name, (step, limit) in limits.items()
    }
