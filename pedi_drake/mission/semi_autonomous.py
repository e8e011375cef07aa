"""The semi-autonomous mode: the operator gives a foot target, the mission serves it on its own.

The operator sends a foot_command_lcmt with the semi-autonomous mode request
(pedi_drake.operator.command.MODE_SEMI_AUTONOMOUS), kind position and the target in its `value`
(world or trunk frame). A new target (one that differs from the last one seen) is checked at
once (`target_problem`); a bad one is refused and counted, never followed:

  * it must be a position (not a velocity);
  * in the trunk frame at the request it must lie in the mission's `semi_autonomous` box, its foot
    centre `min_height` above the ground and clear of the trunk (values are finite: the operator
    input drops non-finite messages before they get here);
  * a target that arrives while another is waiting or being served is refused (busy).

An accepted target waits for a safe point (the one of the teleop switch: a phase boundary, the
robot standing, the leg on the ground with the other three feet loaded); then the manager inserts
`target_sequence`: leg_to_pedipulation with the optimal posture for the target (its planning
fails, and the target is refused, when no posture within the limits reaches it), a reach that
holds the foot at the target, and leg_to_support. The interrupted phase restarts afterwards
(pedi_drake.mission.mode_switch). The target is kept in the world frame of the request, so the
foot goes where the operator pointed whatever posture the trunk then takes.
"""

import dataclasses

import numpy as np
from pydrake.math import RigidTransform

from pedi_drake import robot
from pedi_drake.mission import spec
from pedi_drake.mission.posture_planner import PLAN_LATENCY, POSTURE_DURATION
from pedi_drake.mission.progress import MissionProgress
from pedi_drake.operator.command import FRAME_TRUNK, KIND_POSITION, OperatorCommand

SEMI_AUTONOMOUS = "semi_autonomous"
# A target within this of the last one seen is the same request (the operator repeats it) [m].
SAME_TARGET = 1e-3
# Time the inserted phases may take beyond their motions (planning aside) before they fail [s].
EXTRA_TIME = 4.0


@dataclasses.dataclass(frozen=True)
class TargetRequest:
    """One target the operator sent, and what became of it (result.json `operator_targets`)."""

    time: float  # [s] diagram time
    target_W: tuple[float, float, float]  # [m] (NaN where it could not be put in the world)
    accepted: bool
    reason: str  # why refused; empty when accepted

    def __deepcopy__(self, memo) -> "TargetRequest":
        return self  # a value


def target_problem(block: spec.SemiAutonomousMode, command: OperatorCommand, X_WB: RigidTransform) -> str | None:
    """Why the operator's target cannot be served (see the module docstring), or None."""
    if command.kind != KIND_POSITION:
        return "not a position command (kind must be position for a target)"
    value = np.asarray(command.value, float)
    if not np.all(np.isfinite(value)):
        return "non-finite target"
    p_B = value if command.frame == FRAME_TRUNK else X_WB.inverse() @ value
    p_W = X_WB @ p_B
    if np.any(p_B < np.asarray(block.box_min)) or np.any(p_B > np.asarray(block.box_max)):
        return (
            f"outside the workspace: {np.round(p_B, 3).tolist()} m in the trunk frame, box "
            f"{block.box_min} to {block.box_max} m"
        )
    if p_W[2] < block.min_height:
        return f"too low: the foot centre would be {p_W[2]:.3f} m above the ground (at least {block.min_height} m)"
    if np.all(np.abs(p_B) < np.asarray(robot.TRUNK_HALF_EXTENTS) + robot.FOOT_RADIUS):
        return "inside the trunk"
    return None


def take_target(
    progress: MissionProgress, block: spec.SemiAutonomousMode, command: OperatorCommand, X_WB: RigidTransform, t: float
) -> None:
    """Takes the operator's target if it is new (not within SAME_TARGET of the last one seen):
    recorded in `progress.target_requests`, refused (busy, or `target_problem`) or queued in
    `progress.target_pending` (world [m])."""
    value = tuple(float(v) for v in command.value)
    last = progress.last_target
    if last is not None and max(abs(a - b) for a, b in zip(value, last, strict=True)) <= SAME_TARGET:
        return
    progress.last_target = value
    busy = progress.target_pending is not None or bool(progress.interlude)
    problem = "busy: another target is being served" if busy else target_problem(block, command, X_WB)
    p_W = tuple(float(v) for v in target_W(command, X_WB))
    progress.target_requests.append(TargetRequest(t, p_W, problem is None, problem or ""))
    if problem is None:
        progress.target_pending = p_W


def target_W(command: OperatorCommand, X_WB: RigidTransform) -> np.ndarray:
    """The operator's target in the world [m] (a trunk-frame one at the trunk pose X_WB)."""
    value = np.asarray(command.value, float)
    return X_WB @ value if command.frame == FRAME_TRUNK else value.copy()


def target_sequence(block: spec.SemiAutonomousMode, p_W: np.ndarray, number: int) -> list[spec.PhaseBase]:
    """The phases that serve the `number`-th target `p_W` [m] (world): lift with the optimal
    posture for it, reach and hold, put the leg back."""
    name, leg, duration = f"{block.name}_{number}", block.leg, block.leg_duration
    target = [float(v) for v in p_W]
    goal = spec.PostureGoal(leg=leg, frame="world", targets=[target], fallback_to_fixed=False)
    lift = spec.LegToPedipulation(
        name=f"{name}_lift",
        leg=leg,
        working_depth=block.working_depth,
        duration=duration,
        posture="optimal",
        goal=goal,
        timeout=PLAN_LATENCY + POSTURE_DURATION + duration + EXTRA_TIME,
    )
    reach = spec.Reach(
        name=f"{name}_reach",
        leg=leg,
        target=target,
        frame="world",
        tolerance=block.tolerance,
        duration=duration,
        hold=block.hold,
        timeout=duration + block.hold + EXTRA_TIME,
    )
    back = spec.LegToSupport(name=f"{name}_return", leg=leg, duration=duration, timeout=1.6 * duration + EXTRA_TIME)
    return [lift, reach, back]
