"""The walking phases, `walk`, `walk_to`, `walk_velocity` and `walk_teleop`: the static walk of
pedi_drake.locomotion run through the whole-body controller's references (`gait: trot` runs
pedi_drake.mission.trot_steps instead).

Each slot of the gait is planned as it starts (pedi_drake.locomotion.static_walk.plan_slot): the
trunk gets one rest-to-rest quintic to the slot's CoM target on the walking line, at the slot's
heading, and a swing slot unloads its foot (the contact set), then swings it (a foot position
task in the world, mode 1 of the leg reference: the HQP's foot task, paper 002's 3-D foot
impedance with the trunk in its null space) through an apex to its foothold and on into the
ground, and loads it again when its sensor feels the ground:

* an early touchdown ends the swing at once (the contact set loads the foot where it is);
* a late one keeps the slot open, the foot's reference going on down at SEARCH_SPEED past its
  end (PLACE_DEPTH into the planned ground), until the sensor feels the ground or LATE_TOUCHDOWN
  has passed (then the phase fails: no ground).

The twist is read at the start of every cycle (a `walk` steers its walking line to its goal), and
the cycle for it chosen then; when the walking is over a last cycle at rest puts every foot back
under its hip, and the trunk is centred over the four feet.
"""

import dataclasses
import math

import numpy as np
from pydrake.math import RollPitchYaw, RotationMatrix

from pedi_drake import robot
from pedi_drake.exceptions import PediError, UnreachableTarget
from pedi_drake.leg_kinematics import working_position_B
from pedi_drake.locomotion.footholds import NOMINAL_FEET_B, PlanarPose
from pedi_drake.locomotion.gait import (
    CYCLE_LENGTH,
    GAITS,
    SWING,
    GaitLimits,
    StaticWalkTiming,
    friction_slowdown,
)
from pedi_drake.locomotion.static_walk import SlotPlan, choose_cycle, replan_slot
from pedi_drake.mission import spec, trot_steps
from pedi_drake.mission.posture_planner import PLAN_LATENCY, PLAN_WAIT_LIMIT
from pedi_drake.mission.progress import FAILED, LEG_MODE_FOOT, RUNNING, SUCCEEDED, LegTrajectory, MissionProgress
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.mission.touchdown import PLACE_DEPTH, swing_foot_down
from pedi_drake.operator.command import KIND_TWIST, OperatorCommand
from pedi_drake.suf.stop import StopCase, StopLimits, StopRequest
from pedi_drake.trajectory import PiecewiseQuintic, QuinticOrientationSegment, QuinticSegment, RampSegment

LATE_TOUCHDOWN = 0.4  # [s] after its swing's end a foot that has felt no ground fails the phase
SEARCH_SPEED = 0.1  # [m/s] a late foot's reference goes on down at this speed
# A stopping walk is done when every foot is this close to its place under its hip [m].
SQUARED_UP = 0.02
CENTRE_DURATION = 0.6  # [s] the trunk's last move over the four feet
# [s] an operator twist older than this is taken for none (the walk steps in place): the remote
# and the LCM operator send at 10 Hz or more.
OPERATOR_TWIST_STALE = 0.5
TROT_STEER_TIME = 1.0  # [s] a trotting `walk` closes its error to the goal over this


@dataclasses.dataclass(frozen=True)
class WalkState:
    """Where a walking phase is (a value, shared by the progress's copies)."""

    cycle: tuple  # the cycle's slots (pedi_drake.locomotion.gait)
    index: int  # the running slot's index in the cycle
    plan: SlotPlan | None  # the running slot's plan; None: the walk is centring (its last move)
    feet_xy: np.ndarray  # (4, 2) the feet's planned positions, world [m]
    height: float  # [m] the trunk's height above the mean ground height under the four feet
    com_offset_L: np.ndarray  # (2,) the CoM's offset from the trunk origin in the heading's frame [m]
    stage: str = "down"  # a swing's stage: "unload", "swing", "load"; "down" for a shift
    t_apex: float = 0.0  # [s] when the swing foot is at its apex: touchdowns count after it
    t_swing_end: float = 0.0  # [s] when its reference reaches the ground
    searching: bool = False  # a late foot's reference goes on down (SEARCH_SPEED)
    twist: tuple = (0.0, 0.0, 0.0)  # the cycle's twist
    stopping: bool = False  # the walking is over: the cycle at rest squares the feet up
    steps: int = 0
    late_touchdowns: int = 0
    early_touchdowns: int = 0
    slowed_cycles: int = 0  # cycles walked at a share of the twist (static_walk.TWIST_SCALES)
    slowed_slots: int = 0  # slots of a cycle under way replanned slower from where the feet landed
    distance: float = 0.0  # [m] the walking line's path length
    until: float = 0.0  # [s] centring: when it ends
    # The cycle's friction_slowdown (gait.py): chosen at each cycle's start from the friction
    # coefficient the controllers are given then.
    slowdown: float = 1.0

    def __deepcopy__(self, memo) -> "WalkState":
        return self


def _timing(env, state: "WalkState") -> StaticWalkTiming:
    """The timing of `state`'s cycle: the controller's contact ramps, slowed for the friction."""
    return StaticWalkTiming(ramp=env.contact_ramp_time).slowed(state.slowdown)


def _line_of(view: RobotView, progress: MissionProgress) -> tuple[PlanarPose, np.ndarray]:
    """The walking line at the CoM under the trunk's reference, and the CoM's offset from the
    trunk origin in the heading's frame [m] (the legs move it by millimetres: taken as fixed)."""
    refs = progress.references
    p_ref = refs.body_position.sample(view.time).position
    yaw = float(RollPitchYaw(refs.body_orientation.sample(view.time).rotation).yaw_angle())
    heading = PlanarPose(0.0, 0.0, yaw)
    offset_L = heading.rotation().T @ (view.com_W() - view.base.p_WB)[:2]
    com_xy = p_ref[:2] + heading.rotation() @ offset_L
    return PlanarPose(float(com_xy[0]), float(com_xy[1]), yaw), offset_L


def _ground_under(env, feet_xy: np.ndarray) -> float:
    """[m] the mean height of the ground (the terrain's, env.ground_height) under the four feet: the
    trunk walks its standing height above it, up and down slopes alike."""
    return float(np.mean([env.ground_height(foot) for foot in feet_xy]))


def _attitude(env, feet_xy: np.ndarray, yaw: float) -> RotationMatrix:
    """The trunk's orientation at heading `yaw` [rad] over the feet at `feet_xy` (4, 2) [m]: pitched
    and rolled as the plane through the ground under them (least squares), so that on a slope the
    front and rear legs, or the two sides, stand at the same length (level on flat ground)."""
    heights = np.array([env.ground_height(foot) for foot in feet_xy])
    if not np.any(heights):
        return _heading(yaw)
    heading = PlanarPose(0.0, 0.0, yaw).rotation()
    feet_L = (feet_xy - feet_xy.mean(axis=0)) @ heading  # rows: each foot in the heading's frame
    (rise_x, rise_y), *_ = np.linalg.lstsq(feet_L, heights - heights.mean(), rcond=None)
    # Nose up on the way up (pitch about +y is nose down), the higher side up.
    return RotationMatrix(RollPitchYaw(math.atan(rise_y), -math.atan(rise_x), yaw))


def _trunk_xy(com_xy: np.ndarray, yaw: float, offset_L: np.ndarray) -> np.ndarray:
    """The trunk origin's x, y [m] that puts the CoM at `com_xy` with the heading `yaw`."""
    return np.asarray(com_xy, float) - PlanarPose(0.0, 0.0, yaw).rotation() @ offset_L


def _heading(yaw: float) -> RotationMatrix:
    return RotationMatrix(RollPitchYaw(0.0, 0.0, yaw))


class WalkRunnerBase:
    """The static walk, its twist given by `twist` (a subclass's)."""

    def twist(
        self, phase, state: WalkState, line: PlanarPose, t: float, progress: MissionProgress, view: RobotView
    ) -> np.ndarray | None:
        """The twist for the next cycle (read at time `t` [s] from `view`); None: the walking is over."""
        raise NotImplementedError

    def start(self, phase, progress, view, env):
        if phase.gait == "trot":
            trot_steps.start(self, phase, progress, view, env)
            return
        refs = progress.references
        if refs.legs or np.any(refs.contacts[:4] < 0.5) or np.any(refs.contacts[4:] > 0.5):
            raise UnreachableTarget(
                f"{phase.name}: walking needs the robot on its four feet, no leg lifted, no prong loaded"
            )
        line, offset = _line_of(view, progress)
        p_ref = refs.body_position.sample(view.time).position
        feet_xy = view.feet_W_array()[:, :2].copy()
        state = WalkState(
            cycle=(),
            index=CYCLE_LENGTH - 1,
            plan=None,
            feet_xy=feet_xy,
            height=float(p_ref[2]) - _ground_under(env, feet_xy),
            com_offset_L=offset,
        )
        progress.memo["line"] = line
        progress.memo["walk"] = state
        progress.memo["walk"] = self._next_slot(phase, progress, view, env, state, line, view.time)

    def _next_slot(self, phase, progress, view, env, state: WalkState, line: PlanarPose, t: float) -> WalkState:
        """Plans and starts the slot after `state`'s (a new cycle after the last)."""
        com_xy = line.to_world(np.zeros(2)) if state.plan is None else state.plan.com_end_xy
        index = (state.index + 1) % CYCLE_LENGTH
        cycle, twist, stopping = state.cycle, np.asarray(state.twist, float), state.stopping
        slowed = state.slowed_cycles
        if index == 0:
            state = dataclasses.replace(state, slowdown=friction_slowdown(env.friction_now(progress)))
        timing = _timing(env, state)
        if index == 0:
            wanted = None if stopping else self.twist(phase, state, line, t, progress, view)
            if wanted is None and not stopping:
                progress.records[-1].metrics["walked_until_s"] = t  # the stop starts
            stopping = wanted is None
            twist = np.zeros(3) if stopping else np.asarray(wanted, float) / state.slowdown
            if stopping and _squared_up(state.feet_xy, line):
                return self._centre(progress, env, state, line, t)
            chosen = choose_cycle(line, com_xy, state.feet_xy, twist, timing)
            if chosen is None:
                raise UnreachableTarget(
                    f"{phase.name}: no static walk cycle keeps the CoM inside the support at twist {list(twist)}"
                )
            cycle, scale = chosen
            twist = scale * twist
            slowed += scale < 1.0
        try:
            plan, share = replan_slot(cycle, index, t, line, com_xy, state.feet_xy, twist, timing)
        except PediError as error:
            raise UnreachableTarget(f"{phase.name}: {error}") from None
        slowed_slots = state.slowed_slots + (share < 1.0 and np.any(twist != 0.0))
        refs = progress.references
        p_now = refs.body_position.sample(t).position
        R_now = refs.body_orientation.sample(t).rotation
        feet_after = state.feet_xy.copy()
        if plan.slot.kind == SWING:
            feet_after[robot.LEG_NAMES.index(plan.slot.leg)] = plan.foothold_xy
        trunk_z = state.height + _ground_under(env, feet_after)
        goal = np.array([*_trunk_xy(plan.com_end_xy, plan.line_end.yaw, state.com_offset_L), trunk_z])
        refs.body_position = QuinticSegment(p_now, goal, t, plan.duration)
        attitude = _attitude(env, feet_after, plan.line_end.yaw)
        refs.body_orientation = QuinticOrientationSegment(R_now, attitude, t, plan.duration)
        stage = "down"
        if plan.slot.kind == SWING:
            refs.contacts[robot.LEG_NAMES.index(plan.slot.leg)] = 0.0
            stage = "unload"
        travelled = float(np.linalg.norm(plan.line_end.xy - line.xy))
        progress.memo["line"] = plan.line_end
        return dataclasses.replace(
            state,
            cycle=cycle,
            index=index,
            plan=plan,
            stage=stage,
            twist=tuple(float(v) for v in twist),
            stopping=stopping,
            slowed_cycles=slowed,
            slowed_slots=slowed_slots,
            distance=state.distance + travelled,
        )

    def _centre(self, progress, env, state: WalkState, line: PlanarPose, t: float) -> WalkState:
        """The walk's last move: the CoM over the middle of the four feet, at the line's heading."""
        refs = progress.references
        p_now = refs.body_position.sample(t).position
        R_now = refs.body_orientation.sample(t).rotation
        centre = state.feet_xy.mean(axis=0)
        trunk_z = state.height + _ground_under(env, state.feet_xy)
        goal = np.array([*_trunk_xy(centre, line.yaw, state.com_offset_L), trunk_z])
        refs.body_position = QuinticSegment(p_now, goal, t, CENTRE_DURATION)
        attitude = _attitude(env, state.feet_xy, line.yaw)
        refs.body_orientation = QuinticOrientationSegment(R_now, attitude, t, CENTRE_DURATION)
        return dataclasses.replace(state, plan=None, until=t + CENTRE_DURATION)

    def step(self, phase, progress, view, env):
        if phase.gait == "trot":
            return trot_steps.step(self, phase, progress, view, env)
        state: WalkState = progress.memo["walk"]
        t = view.time
        if state.plan is None:  # centring
            if t < state.until:
                return RUNNING
            self._record(progress, state, view)
            return self.finished(phase, progress, view, state)
        plan = state.plan
        timing = _timing(env, state)
        if plan.slot.kind == SWING:
            state = self._swing(phase, progress, view, env, state, timing)
            if state is None:
                return FAILED
            progress.memo["walk"] = state
            if state.stage != "load":
                return RUNNING
        if t < plan.t_end:
            return RUNNING
        if plan.slot.kind == SWING:
            state = dataclasses.replace(state, steps=state.steps + 1)
        progress.memo["walk"] = self._next_slot(phase, progress, view, env, state, progress.memo["line"], t)
        self._record(progress, progress.memo["walk"], view)
        return RUNNING

    def _swing(self, phase, progress, view, env, state: WalkState, timing: StaticWalkTiming) -> WalkState | None:
        """Advances the swing of the running slot; None if the foot found no ground."""
        plan, t, refs = state.plan, view.time, progress.references
        leg = plan.slot.leg
        k = robot.LEG_NAMES.index(leg)
        if state.stage == "unload":
            if t < plan.t0 + timing.ramp:
                return state
            start = view.foot_W(leg)
            ground = env.ground_height(plan.foothold_xy)
            end = np.array([*plan.foothold_xy, ground + robot.FOOT_RADIUS - PLACE_DEPTH])
            apex = 0.5 * (start + end)
            apex[2] = max(start[2], ground + robot.FOOT_RADIUS) + timing.step_height
            half = 0.5 * timing.swing
            path = PiecewiseQuintic.through(np.array([start, apex, end]), t, [half, half])
            refs.legs[leg] = LegTrajectory(LEG_MODE_FOOT, path)
            return dataclasses.replace(state, stage="swing", t_apex=t + half, t_swing_end=t + timing.swing)
        if state.stage == "swing":
            touched = t >= state.t_apex and swing_foot_down(view, leg, env.ground_height(view.foot_W(leg)[:2]))
            if not touched:
                if t > state.t_swing_end + LATE_TOUCHDOWN:
                    progress.reason = f"{phase.name}: {leg} felt no ground {LATE_TOUCHDOWN} s after its swing's end"
                    return None
                if t >= state.t_swing_end and not state.searching:
                    # Late: the ground is lower than planned (or the foot rests on it too lightly
                    # to be felt); its reference goes on down until the sensor feels the ground.
                    end = refs.legs[leg].trajectory.sample(t).position
                    search = RampSegment(end, np.array([0.0, 0.0, -SEARCH_SPEED]), t, LATE_TOUCHDOWN)
                    refs.legs[leg] = LegTrajectory(LEG_MODE_FOOT, search)
                    return dataclasses.replace(state, searching=True)
                return state
            refs.legs.pop(leg, None)
            refs.contacts[k] = 1.0
            feet = state.feet_xy.copy()
            feet[k] = view.foot_W(leg)[:2]
            early = t < state.t_swing_end - 0.05 * timing.swing
            late = t > state.t_swing_end
            metrics = progress.records[-1].metrics
            errors = metrics.setdefault("foothold_errors_m", [])
            errors.append(float(np.linalg.norm(feet[k] - plan.foothold_xy)))
            return dataclasses.replace(
                state,
                stage="load",
                searching=False,
                feet_xy=feet,
                early_touchdowns=state.early_touchdowns + early,
                late_touchdowns=state.late_touchdowns + late,
            )
        return state

    @staticmethod
    def _record(progress: MissionProgress, state: WalkState, view: RobotView) -> None:
        metrics = progress.records[-1].metrics
        metrics.update(
            steps=state.steps,
            early_touchdowns=state.early_touchdowns,
            late_touchdowns=state.late_touchdowns,
            slowed_cycles=state.slowed_cycles,
            slowed_slots=state.slowed_slots,
            planned_distance_m=state.distance,
            estimated_pose=[*view.base.p_WB[:2].tolist(), float(RollPitchYaw(view.X_WB.rotation()).yaw_angle())],
        )

    def finished(self, phase, progress, view, state: WalkState) -> str:
        return SUCCEEDED


def _squared_up(feet_xy: np.ndarray, line: PlanarPose) -> bool:
    """Whether every foot is within SQUARED_UP of its place under its hip on the walking line."""
    nominal = np.array([line.to_world(p) for p in NOMINAL_FEET_B])
    return bool(np.all(np.linalg.norm(feet_xy - nominal, axis=1) < SQUARED_UP))


class WalkVelocityRunner(WalkRunnerBase):
    """walk_velocity: the phase's twist for its duration."""

    def twist(self, phase, state, line, t, progress, view):
        return np.asarray(phase.twist, float) if t < progress.phase_start + phase.duration else None


class WalkToRunner(WalkRunnerBase):
    """walk: steers the walking line to the goal, then stops; judged by the trunk's estimate."""

    def twist(self, phase, state, line, t, progress, view):
        goal = self._goal_line(phase, state)
        error_L = line.rotation().T @ (goal.xy - line.xy)
        yaw_error = _wrap(goal.yaw - line.yaw)
        if np.linalg.norm(error_L) < 0.25 * phase.tolerance and abs(yaw_error) < 0.25 * phase.yaw_tolerance:
            return None
        limits = GAITS[phase.gait]
        # The horizon over which the error is asked of the twist: a static walk's cycle (its twist
        # holds for one), a trot's steering time (its twist changes every half period).
        cycle = TROT_STEER_TIME if phase.gait == "trot" else StaticWalkTiming().cycle
        top_yaw_rate = phase.yaw_rate or limits.yaw_rate
        yaw_rate = float(np.clip(yaw_error / cycle, -top_yaw_rate, top_yaw_rate))
        bounds = np.array([min(phase.speed, limits.forward), min(phase.speed, limits.sideways)])
        velocity = self._velocity(error_L, yaw_rate, cycle, bounds)
        # Where the sideways speed leaves the turn less (limits.turn_limit), the yaw rate gives way
        # and the speed is solved again for it: the position is closed first, the heading after.
        turn = limits.turn_limit(velocity[1])
        if abs(yaw_rate) > turn:
            yaw_rate = math.copysign(turn, yaw_rate)
            velocity = self._velocity(error_L, yaw_rate, cycle, bounds)
            yaw_rate = float(np.clip(yaw_rate, -limits.turn_limit(velocity[1]), limits.turn_limit(velocity[1])))
        return np.array([velocity[0], velocity[1], yaw_rate])

    @staticmethod
    def _velocity(error_L: np.ndarray, yaw_rate: float, cycle: float, bounds: np.ndarray) -> np.ndarray:
        """The speed (forward, sideways) [m/s] whose arc at `yaw_rate` [rad/s] ends `cycle` [s] on
        the goal `error_L` [m] ahead in the line's frame (PlanarPose.moved inverted), scaled down as
        a whole (its direction kept) to `bounds`."""
        angle = yaw_rate * cycle
        if abs(angle) < 1e-9:
            velocity = error_L / cycle
        else:
            s, c = math.sin(angle), math.cos(angle)
            arc = np.array([[s, -(1.0 - c)], [1.0 - c, s]]) / yaw_rate
            velocity = np.linalg.solve(arc, error_L)
        return velocity * min(1.0, *(bounds / np.maximum(np.abs(velocity), 1e-12)))

    @staticmethod
    def _goal_line(phase, state: WalkState) -> PlanarPose:
        """The goal as a walking line: the CoM's place with the trunk origin at the goal."""
        goal = PlanarPose(phase.position[0], phase.position[1], phase.yaw)
        x, y = goal.to_world(state.com_offset_L)
        return PlanarPose(float(x), float(y), phase.yaw)

    def finished(self, phase, progress, view, state):
        error = float(np.linalg.norm(view.base.p_WB[:2] - np.asarray(phase.position, float)))
        yaw = float(RollPitchYaw(view.X_WB.rotation()).yaw_angle())
        yaw_error = abs(_wrap(phase.yaw - yaw))
        progress.records[-1].metrics.update(goal_error_m=error, goal_yaw_error_rad=yaw_error)
        if error <= phase.tolerance and yaw_error <= phase.yaw_tolerance:
            return SUCCEEDED
        progress.reason = f"{phase.name}: stopped {error:.3f} m and {yaw_error:.3f} rad from the goal"
        return FAILED


class WalkToStopRunner(WalkToRunner):
    """walk_to: the stop of largest SUF for the work that follows (pedi_drake.suf.stop), chosen by
    the posture planner's worker as the phase starts (the robot stands meanwhile, as a lift
    waiting for its posture does), then walked to as `walk` walks to its goal; `stop: fixed` walks
    to the fixed stop at once."""

    def start(self, phase, progress, view, env):
        request = stop_request(phase, view, env)
        progress.memo["stop_request"] = request
        if phase.stop == "fixed":
            self._walk_to(phase, progress, view, env, request.fixed, None)
            return
        if env.planner is None:
            raise UnreachableTarget(f"{phase.name}: stop: suf needs the posture planner")
        env.planner.ask(request)
        progress.memo["stop_due"] = view.time + PLAN_LATENCY

    def step(self, phase, progress, view, env):
        walk = progress.memo.get("walk_phase")
        if walk is not None:
            return super().step(walk, progress, view, env)
        t, due, request = view.time, progress.memo["stop_due"], progress.memo["stop_request"]
        result = env.planner.answer(request, wait=env.wait_for_plans) if t >= due else None
        if result is None:
            if t >= due:
                # Late: the robot stands, which the phase's timeout does not count.
                progress.plan_wait = t - due
                if progress.plan_wait > PLAN_WAIT_LIMIT:
                    progress.reason = f"{phase.name}: no stop chosen {PLAN_WAIT_LIMIT:.0f} s after it was due"
                    return FAILED
            return RUNNING
        if not result.best.posture.feasible:
            progress.reason = (
                f"{phase.name}: no stop within {phase.search} of the fixed stop lets {phase.leg} reach its targets "
                f"({result.best.posture.reason})"
            )
            return FAILED
        self._walk_to(phase, progress, view, env, result.best.stop, result)
        return RUNNING

    def _walk_to(self, phase, progress, view, env, stop, result) -> None:
        """Starts the walk to `stop` (x, y [m], yaw [rad]) and records the stop's choice."""
        walk = dataclasses.replace(phase, position=[float(stop[0]), float(stop[1])], yaw=float(stop[2]))
        progress.memo["walk_phase"] = walk
        request = progress.memo["stop_request"]
        record = {"chosen_by": phase.stop, "fixed_W": list(request.fixed), "taken_W": [float(v) for v in stop]}
        if result is not None:
            record.update(
                fixed_suf_n=result.fixed.posture.suf,
                fixed_feasible=result.fixed.posture.feasible,
                taken_suf_n=result.best.posture.suf,
                evaluations=result.evaluations,
                plan_wait_s=progress.plan_wait,
            )
        progress.records[-1].metrics.update(leg=phase.leg, stop=record)
        super().start(walk, progress, view, env)


# The phase kinds that walk.
WALKING_PHASES = (spec.Walk, spec.WalkVelocity, spec.WalkTeleop)


def warm_up(env) -> None:
    """Loads (or compiles) the kernels a walk's plans call from Python, outside any control tick:
    the terrain under a foothold and the static walk's planner (a cycle chosen for a stance
    under the hips). Otherwise the tick that starts a walk's first slot loads them, and is late
    by as much on a hardware run."""
    line = PlanarPose(0.0, 0.0, 0.0)
    feet_xy = np.array([line.to_world(p) for p in NOMINAL_FEET_B])
    for foot in feet_xy:
        env.ground_height(foot)
    choose_cycle(line, np.zeros(2), feet_xy, np.zeros(3), StaticWalkTiming())


def stop_request(phase, view: RobotView, env) -> StopRequest:
    """The stop to choose for the walk_to `phase`: its lift's targets, the stance the walk leaves
    (the feet under the hips), the trunk at the height it stands at now above the ground."""
    goal = phase.goal
    fixed = (float(phase.position[0]), float(phase.position[1]), float(phase.yaw))
    ground = env.ground_height(np.array(fixed[:2]))
    feet = view.feet_W_array()
    height = float(view.base.p_WB[2]) - _ground_under(env, feet[:, :2])

    def points(given) -> tuple[tuple[float, float, float], ...]:
        return tuple(tuple(float(v) for v in p) for p in given)

    case = StopCase(
        leg=phase.leg,
        targets=points(goal.targets),
        reach_only=points(goal.reach_only),
        lift_B=tuple(float(v) for v in working_position_B(phase.leg, phase.working_depth)),
        feet_B=points(NOMINAL_FEET_B),
        height=height,
        ground=ground,
        prongs_key=robot.design_key(env.prongs),
    )
    return StopRequest(case, fixed, StopLimits(shift=float(phase.search[0]), turn=float(phase.search[1])))


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class WalkTeleopRunner(WalkRunnerBase):
    """walk_teleop: the operator's twist, held to the gait's limits, for the phase's duration."""

    def start(self, phase, progress, view, env):
        if view.operator is None:
            raise UnreachableTarget(f"{phase.name}: no operator input (set the scenario's operator.source)")
        super().start(phase, progress, view, env)

    def twist(self, phase, state, line, t, progress, view):
        if t >= progress.phase_start + phase.duration:
            return None
        return operator_twist(view.operator, GAITS[phase.gait])


def operator_twist(command: OperatorCommand | None, limits: GaitLimits) -> np.ndarray:
    """The operator's twist held to `limits` (`GaitLimits.held`: each component saturated, a stick at
    full deflection asks for the most there is, and the turn within what the sideways speed leaves);
    zero without a fresh KIND_TWIST command."""
    if command is None or command.kind != KIND_TWIST or not command.age < OPERATOR_TWIST_STALE:
        return np.zeros(3)
    value = np.asarray(command.value, float)
    if not np.all(np.isfinite(value)):
        return np.zeros(3)
    return limits.held(value)


RUNNERS = {
    spec.WalkVelocity: WalkVelocityRunner(),
    spec.Walk: WalkToRunner(),
    spec.WalkTo: WalkToStopRunner(),
    spec.WalkTeleop: WalkTeleopRunner(),
}
