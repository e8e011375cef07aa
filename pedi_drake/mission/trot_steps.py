"""The walking phases' trot (`gait: trot`): the half-period steps of pedi_drake.locomotion.trot
run through the whole-body controller's references.

Every half period: the pair that swung lands (its contact loaded, its foot task dropped), the twist
for the next half period is taken (the phase's, rate-limited), the trunk's reference starts at the
estimate's position and moves on at it (its position at constant velocity, its heading rest to
rest), and the other pair unloads and
swings to its Raibert foothold. A foot whose sensor feels the ground after the apex lands at once
(early); one that has not by the half period's end lands then (late). When the walking is over
the twist ramps down and two half periods at rest put the feet under the hips.
"""

import dataclasses

import numpy as np
from pydrake.math import RollPitchYaw, RotationMatrix

from pedi_drake import robot
from pedi_drake.exceptions import UnreachableTarget
from pedi_drake.locomotion.footholds import PlanarPose
from pedi_drake.locomotion.trot import TrotTiming, next_twist, pair_of, trot_foothold_W
from pedi_drake.mission.progress import LEG_MODE_FOOT, RUNNING, LegTrajectory, MissionProgress
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.mission.touchdown import swing_foot_down
from pedi_drake.trajectory import PiecewiseQuintic, QuinticOrientationSegment, QuinticSegment, RampSegment

# [m] below the ground that a trot's swing ends: on it. A trot lands on its schedule, so its foot
# need not search, and a foot aimed into the ground reaches it still moving down and stamps.
TROT_PLACE_DEPTH = 0.0
STILL_STEPS = 2  # half periods at rest that end a stopping trot, every foot placed once


@dataclasses.dataclass(frozen=True)
class TrotState:
    """Where a trotting phase is (a value, shared by the progress's copies). The walking line is
    the trunk reference's planar pose: a `walk` goal is the trunk origin's (no CoM offset)."""

    step: int  # half periods begun
    t_next: float  # [s] when the running half period ends
    t_apex: float  # [s] when its swing feet are at their apex: touchdowns count after it
    twist: tuple  # the twist in force (rate-limited)
    line: PlanarPose  # the trunk reference's planar pose at the running half period's end
    height: float  # [m] the trunk's height
    stopping: bool = False
    still_steps: int = 0
    com_offset_L: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(2))
    steps: int = 0
    early_touchdowns: int = 0
    late_touchdowns: int = 0
    slowed_cycles: int = 0
    slowed_slots: int = 0
    distance: float = 0.0  # [m] the walking line's path length
    done_at: float = -1.0  # [s] when the last landing's loads are in (>= 0: finishing)

    def __deepcopy__(self, memo) -> "TrotState":
        return self


def _timing(env) -> TrotTiming:
    return TrotTiming(ramp=env.contact_ramp_time)


def start(runner, phase, progress: MissionProgress, view: RobotView, env) -> None:
    """Starts a trot (the phase's first half period)."""
    refs = progress.references
    if refs.legs or np.any(refs.contacts[:4] < 0.5) or np.any(refs.contacts[4:] > 0.5):
        raise UnreachableTarget(
            f"{phase.name}: trotting needs the robot on its four feet, no leg lifted, no prong loaded"
        )
    t = view.time
    p_ref = refs.body_position.sample(t).position
    yaw = float(RollPitchYaw(refs.body_orientation.sample(t).rotation).yaw_angle())
    line = PlanarPose(float(p_ref[0]), float(p_ref[1]), yaw)
    state = TrotState(step=0, t_next=t, t_apex=t, twist=(0.0, 0.0, 0.0), line=line, height=float(p_ref[2]))
    progress.memo["walk"] = state
    progress.memo["walk"] = _half_period(runner, phase, progress, view, env, state)


def _land(progress: MissionProgress, view: RobotView, leg: str) -> None:
    refs = progress.references
    refs.legs.pop(leg, None)
    refs.contacts[robot.LEG_NAMES.index(leg)] = 1.0


def step(runner, phase, progress: MissionProgress, view: RobotView, env) -> str:
    """Advances a trot; returns the phase's status."""
    state: TrotState = progress.memo["walk"]
    t, refs = view.time, progress.references
    early = 0
    for leg in list(refs.legs):
        if t >= state.t_apex and swing_foot_down(view, leg, env.ground_height(view.foot_W(leg)[:2])):
            _land(progress, view, leg)
            early += 1
    if early:
        state = dataclasses.replace(state, early_touchdowns=state.early_touchdowns + early)
        progress.memo["walk"] = state
    if state.done_at >= 0.0:
        if t < state.done_at:
            return RUNNING
        runner._record(progress, state, view)
        return runner.finished(phase, progress, view, state)
    if t < state.t_next:
        return RUNNING
    late = len(refs.legs)
    for leg in list(refs.legs):
        _land(progress, view, leg)
    state = dataclasses.replace(state, late_touchdowns=state.late_touchdowns + late)
    progress.memo["walk"] = _half_period(runner, phase, progress, view, env, state)
    runner._record(progress, progress.memo["walk"], view)
    return RUNNING


def _half_period(runner, phase, progress: MissionProgress, view: RobotView, env, state: TrotState) -> TrotState:
    """Starts the next half period: the twist, the trunk's reference, the swinging pair."""
    timing, t, refs = _timing(env), view.time, progress.references
    wanted = None if state.stopping else runner.twist(phase, state, state.line, t, progress, view)
    stopping = wanted is None
    if stopping and not state.stopping:
        progress.records[-1].metrics["walked_until_s"] = t
    twist = next_twist(np.asarray(state.twist, float), np.zeros(3) if stopping else wanted, timing.half, timing)
    at_rest = stopping and not np.any(twist)
    still = state.still_steps + 1 if at_rest else 0
    p_now = refs.body_position.sample(t).position
    R_now = refs.body_orientation.sample(t).rotation
    if still > STILL_STEPS:
        # Every foot has been placed at rest: the trot ends on four feet where the trunk is.
        refs.body_position = QuinticSegment(p_now, p_now, t, 1e-3)
        return dataclasses.replace(state, stopping=True, done_at=t + timing.ramp + 0.1)
    # The half period starts where the trunk is (the estimate), not where its reference was: a
    # trunk pushed off its line is caught by where the feet land around it, not pulled back by
    # stance legs reaching for a line it has left.
    p_now = np.array([view.base.p_WB[0], view.base.p_WB[1], p_now[2]])
    line_now = PlanarPose(float(p_now[0]), float(p_now[1]), state.line.yaw)
    line_end = line_now.moved(twist, timing.half)
    velocity_W = np.array([*(line_now.rotation() @ twist[:2]), 0.0])
    # The position at the twist's mean velocity over the half period (the arc's chord), the
    # heading rest to rest: both end on the walking line.
    chord = np.array([*(line_end.xy - line_now.xy), state.height - p_now[2]]) / timing.half
    refs.body_position = RampSegment(p_now, chord, t, timing.half)
    R_end = RotationMatrix(RollPitchYaw(0.0, 0.0, line_end.yaw))
    refs.body_orientation = QuinticOrientationSegment(R_now, R_end, t, timing.half)
    error_W = view.base.v_WB - velocity_W
    for leg in pair_of(state.step):
        refs.contacts[robot.LEG_NAMES.index(leg)] = 0.0
        start = view.foot_W(leg)
        hold = trot_foothold_W(leg, line_now, twist, error_W, timing)
        ground = env.ground_height(hold)
        end = np.array([*hold, ground + robot.FOOT_RADIUS - TROT_PLACE_DEPTH])
        apex = 0.5 * (start + end)
        apex[2] = max(env.ground_height(start[:2]), ground) + robot.FOOT_RADIUS + timing.step_height
        half_swing = 0.5 * timing.swing
        path = PiecewiseQuintic.through(np.array([start, start, apex, end]), t, [timing.ramp, half_swing, half_swing])
        refs.legs[leg] = LegTrajectory(LEG_MODE_FOOT, path)
    return dataclasses.replace(
        state,
        step=state.step + 1,
        t_next=t + timing.half,
        t_apex=t + timing.ramp + 0.5 * timing.swing,
        twist=tuple(float(v) for v in twist),
        line=line_end,
        stopping=stopping,
        still_steps=still,
        steps=state.steps + 2,
        distance=state.distance + float(np.linalg.norm(line_end.xy - line_now.xy)),
    )
