"""TeleopFootRunner: the lifted foot follows the operator's command within the phase's bounds.

Every mission tick the operator's command (RobotView.operator) becomes a desired foot velocity in
the world: a velocity command as it is (rotated from the trunk frame by the estimated attitude),
a position command as the velocity that would reach it in one tick. Then, in this order:

  1. silence: with no valid message for `hold_after` the velocity is zero (the foot holds); for
     `return_after` the phase fails, and the mission's recovery puts the leg back on the ground;
  2. speed: at most `max_speed`;
  3. force: with the estimated contact force (the mission's estimate, its bias at the phase start
     removed) near `max_force`, motion further into the contact slowed,
     stopped at it, turned into a retreat beyond it. The bound acts a margin of the estimate's
     measured noise below `max_force` (pedi_drake.mission.estimate_noise), so that the true
     force, which the noise shakes as much, stays under it;
  4. balance: the estimated force along its own direction stays below `balance_margin` times the
     live SUF in that direction, less the same noise margin (pedi_drake.mission.balance_bound:
     slowed near the limit, stopped at it, retreating beyond it), so the operator cannot push the
     robot over;
  5. workspace: the step is kept in the leg's workspace, sliding along its boundary
     (pedi_drake.mission.teleop_bounds). When the trunk has moved under the foot's target so
     that the target is outside, the target first steps back in along the boundary's normal, and
     the operator's step gets what is left of the tick's length at the speed bound: the reference
     neither jumps nor outruns the speed bound (the measured foot is no place to restart from: it
     lies off the reference by the tracking error, possibly outside too).

The reference is a RampSegment from where the previous one ended, so it never jumps. Each bound
counts the ticks it acted in the phase's metrics (`bound_activations`); the balance bound also
records its limits and the largest force it saw (`balance`). Each update leaves a FootPush in the
progress: the direction the live SUF is asked about next and the operator's haptic feedback. The phase succeeds when
the operator asks for the autonomous mode (after having asked for anything else during the
phase), or after `duration`; the foot then holds where its reference ended.
"""

import math

import numpy as np

from pedi_drake import robot
from pedi_drake.exceptions import UnreachableTarget
from pedi_drake.mission.balance_bound import balance_limit, bound_balance, disturbance_direction
from pedi_drake.mission.estimate_noise import EstimateNoise
from pedi_drake.mission.progress import (
    FAILED,
    LEG_MODE_FOOT,
    RUNNING,
    SUCCEEDED,
    FootPush,
    LegTrajectory,
    MissionProgress,
)
from pedi_drake.mission.reference_start import foot_reference_start
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.mission.teleop_bounds import (
    bound_force,
    bound_speed,
    slide_in_workspace,
    step_into_workspace,
    workspace_margin,
)
from pedi_drake.operator.command import FRAME_TRUNK, KIND_POSITION, KIND_TWIST, MODE_AUTONOMOUS
from pedi_drake.trajectory import RampSegment

BOUNDS = ("workspace", "speed", "force", "balance", "silence_hold")
# Length of the first reference segment, before a tick length is known [s].
_FIRST_TICK = 0.01


def _desired_velocity_W(view: RobotView, p_ref_W: np.ndarray, dt: float) -> np.ndarray:
    """The operator's command as a world-frame foot velocity [m/s]; a command so large that it
    overflows gives an infinite one (which the speed bound turns into no motion), silently."""
    command = view.operator
    if command.kind == KIND_TWIST:  # a walking command: not for a lifted foot, which holds still
        return np.zeros(3)
    R_WB = view.X_WB.rotation().matrix()
    with np.errstate(over="ignore", invalid="ignore"):
        if command.kind == KIND_POSITION:
            goal_W = view.X_WB @ command.value if command.frame == FRAME_TRUNK else command.value
            return (goal_W - p_ref_W) / dt
        return R_WB @ command.value if command.frame == FRAME_TRUNK else command.value


class TeleopFootRunner:
    """The teleop_foot phase kind (see the module docstring)."""

    def start(self, phase, progress: MissionProgress, view: RobotView, env) -> None:
        if phase.leg not in progress.references.legs:
            raise UnreachableTarget(f"{phase.name}: {phase.leg} is not in pedipulation mode (lift it first)")
        if view.operator is None:
            raise UnreachableTarget(f"{phase.name}: no operator input (set the scenario's operator.source)")
        estimates = view.foot_force_estimates_W(phase.leg)
        if env.force_estimate not in estimates:
            raise UnreachableTarget(f"{phase.name}: the {env.force_estimate} force estimate is not available")
        p_ref = foot_reference_start(progress, view, phase.leg)
        progress.references.legs[phase.leg] = LegTrajectory(
            LEG_MODE_FOOT, RampSegment(p_ref, np.zeros(3), view.time, _FIRST_TICK)
        )
        progress.memo.update(
            p_ref_W=np.asarray(p_ref, float),
            t_prev=view.time,
            force_bias=estimates[env.force_estimate].copy(),
            noise=EstimateNoise(),
            min_force_limit_n=math.inf,
            counts=dict.fromkeys(BOUNDS, 0),
            holding=False,
            other_mode_seen=view.operator.mode_request != MODE_AUTONOMOUS,
            max_force_n=0.0,
            push_direction=None,
            balance=dict(margin=phase.balance_margin, min_limit_n=math.inf, last_limit_n=None, max_force_along_n=0.0),
        )
        progress.records[-1].metrics.update(leg=phase.leg, bound_activations=dict.fromkeys(BOUNDS, 0))

    def step(self, phase, progress: MissionProgress, view: RobotView, env) -> str:
        memo, command, t = progress.memo, view.operator, view.time
        dt = t - memo["t_prev"]
        metrics = progress.records[-1].metrics
        if dt <= 0.0:
            return RUNNING
        memo["t_prev"] = t
        counts = memo["counts"]
        p_ref = memo["p_ref_W"]
        silence = min(command.age, t - progress.phase_start)
        if command.mode_request != MODE_AUTONOMOUS:
            memo["other_mode_seen"] = True
        elif memo["other_mode_seen"]:
            metrics["ended_by"] = "operator"
            return SUCCEEDED
        if silence > phase.return_after:
            metrics["ended_by"] = "operator_silence"
            progress.reason = (
                f"{phase.name}: no operator command for {silence:.2f} s (over return_after "
                f"{phase.return_after:g} s): the foot held, then the leg returns to support"
            )
            return FAILED
        if silence > phase.hold_after:
            velocity = np.zeros(3)
            if not memo["holding"]:
                counts["silence_hold"] += 1
            memo["holding"] = True
        else:
            memo["holding"] = False
            velocity = _desired_velocity_W(view, p_ref, dt)
        velocity, clipped = bound_speed(velocity, phase.max_speed)
        counts["speed"] += clipped
        estimate = view.foot_force_estimates_W(phase.leg)[env.force_estimate]
        memo["noise"].update(estimate, dt)
        force = estimate - memo["force_bias"]
        memo["max_force_n"] = max(memo["max_force_n"], float(np.linalg.norm(force)))
        force_limit = memo["noise"].bounded_limit(phase.max_force)
        memo["min_force_limit_n"] = min(memo["min_force_limit_n"], force_limit)
        velocity, limited = bound_force(velocity, force, force_limit, phase.max_speed)
        counts["force"] += limited
        velocity, acted = self._balance(phase, progress, view, force, velocity, force_limit)
        counts["balance"] += acted

        X_WB = view.X_WB
        X_BW = X_WB.inverse()

        def margin(p_B):
            return workspace_margin(phase.leg, p_B, X_WB, phase.joint_margin, phase.min_height)

        p_from_B = X_BW @ p_ref
        if margin(p_from_B) < 0.0:
            # The trunk moved under the held target: first back inside, along the boundary's normal,
            # within this tick's length at the speed bound; the operator's step gets the rest.
            counts["workspace"] += 1
            inside = step_into_workspace(margin, p_from_B, phase.max_speed * dt)
            if inside is None:  # no way in at the speed bound (the trunk moved faster): hold
                velocity = np.zeros(3)
            else:
                rest = phase.max_speed * dt - float(np.linalg.norm(inside - p_from_B))
                p_from_B = inside
                velocity, _ = bound_speed(velocity, max(rest, 0.0) / dt)
        p_to_B, clipped = slide_in_workspace(margin, p_from_B, p_from_B + X_BW.rotation() @ (velocity * dt))
        counts["workspace"] += clipped
        p_next = X_WB @ p_to_B
        progress.references.legs[phase.leg] = LegTrajectory(
            LEG_MODE_FOOT, RampSegment(p_ref, (p_next - p_ref) / dt, t, dt)
        )
        memo["p_ref_W"] = p_next
        metrics.update(
            bound_activations=dict(counts),
            max_force_n=memo["max_force_n"],
            force_noise_n=memo["noise"].sigma,
            min_force_limit_n=memo["min_force_limit_n"],
            target_W=p_next.tolist(),
            foot_error_m=float(np.linalg.norm(view.foot_W(phase.leg) - p_ref)),
            balance=dict(memo["balance"]),
        )
        if t - progress.phase_start >= phase.duration:
            metrics["ended_by"] = "duration"
            return SUCCEEDED
        return RUNNING

    @staticmethod
    def _balance(
        phase, progress: MissionProgress, view: RobotView, force: np.ndarray, velocity: np.ndarray, force_limit: float
    ):
        """(velocity, whether the balance bound acted), and the update's FootPush, whose limit is the
        tighter of the force bound's `force_limit` [N] and the balance bound's."""
        memo = progress.memo
        direction = disturbance_direction(force, velocity, memo["push_direction"])
        memo["push_direction"] = direction
        limit, acted = None, False
        if phase.balance_margin > 0.0 and direction is not None:
            limit = balance_limit(view.suf, robot.LEG_NAMES.index(phase.leg), direction, phase.balance_margin)
            if limit is not None:
                limit = memo["noise"].bounded_limit(limit)
                velocity, acted = bound_balance(velocity, force, direction, limit, phase.max_speed)
                # The retreat adds to the command: the speed bound holds for the sum.
                velocity, _ = bound_speed(velocity, phase.max_speed)
                balance = memo["balance"]
                balance["last_limit_n"] = limit
                balance["min_limit_n"] = min(balance["min_limit_n"], limit)
                balance["max_force_along_n"] = max(balance["max_force_along_n"], float(force @ direction))
        tighter = force_limit if limit is None else min(force_limit, float(limit))
        progress.push = FootPush(phase.leg, force.copy(), direction, tighter, bool(acted))
        return velocity, acted
