"""Phase runners: each phase kind's way to set references, watch progress and judge the outcome.

Paper 000: "each mission phase is represented as a distinct state, equipped with methods to
update task references, monitor the progress of the phase, and assess its successful completion
or potential failure". A runner is stateless: `start` and `step` read and write only the
MissionProgress they are given (held in the MissionManager's Context).
"""

import collections
import dataclasses
import math
from typing import Literal

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix

from pedi_drake import robot
from pedi_drake.estimation.kalman_estimator import STILL_RATE
from pedi_drake.exceptions import MissionFileError, UnreachableTarget
from pedi_drake.ik.leg_ik_system import RETARGET_TOLERANCE
from pedi_drake.leg_kinematics import leg_geometry, working_position_B
from pedi_drake.locomotion.footholds import stance_pose
from pedi_drake.locomotion.static_walk import FOOTHOLD_REACH
from pedi_drake.mission import spec
from pedi_drake.mission.balance_bound import balance_limit
from pedi_drake.mission.posture_planner import (
    PLAN_LATENCY,
    PLAN_WAIT_LIMIT,
    POSTURE_DURATION,
    PosturePlanner,
    PostureRequest,
)
from pedi_drake.mission.progress import (
    FAILED,
    LEG_MODE_FOOT,
    LEG_MODE_FOOT_POSE,
    LEG_MODE_JOINTS,
    LEG_MODE_SHANK_POSE,
    RUNNING,
    SUCCEEDED,
    FootPush,
    IkPlan,
    LegTrajectory,
    MissionProgress,
    set_friction,
)
from pedi_drake.mission.reference_start import foot_reference_start, joint_reference_start
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.mission.teleop_foot import TeleopFootRunner
from pedi_drake.mission.touchdown import CONTACT_FORCE_THRESHOLD, PLACE_DEPTH
from pedi_drake.mission.walk import RUNNERS as WALK_RUNNERS
from pedi_drake.mission.walk import WALKING_PHASES
from pedi_drake.mission.walk import warm_up as warm_up_walk
from pedi_drake.operator.command import CONTROLLER_NAMES
from pedi_drake.prongs import ProngDesign
from pedi_drake.suf.posture import Posture, PostureCase
from pedi_drake.terrain import terrain_height, terrain_map
from pedi_drake.trajectory import (
    CircularPath,
    PiecewiseQuintic,
    PivotedPosition,
    QuinticOrientationSegment,
    QuinticSegment,
    smooth_start_kernel,
)
from pedi_drake.vector3 import orientation_error_W

LYING_HEIGHT = 0.13  # [m] trunk height when lying down under control (legs folded, off the limits)
SHIFT_DURATION = 1.0  # [s] trunk shift before lifting a leg
CONTACT_RAMP_WAIT = 0.3  # [s] wait for the controller to ramp a contact's force away
# A stand-up that starts with the trunk lower than this [m] settles it on the ground first: ...
LYING_START = 0.12
SETTLE_DEPTH = 0.03  # [m] ... lowering it by at most this ...
SETTLE_SPEED = 0.03  # [m/s] ... at this speed, until ...
# [-] ... the feet have shed this share of their load (below the share at which the estimator
# takes the trunk for resting, pedi_drake.estimation.kalman_estimator.RESTING_LOAD_SHARES), ...
SETTLE_SHED = 0.4
SETTLE_HOLD = 0.3  # [s] ... and resting this long, for the estimator to take the ground's height.
# A lean's prongs carry load when the feet have shed this fraction of what they carried before [-]
# with the legs still: well above the estimate's noise.
PRONG_LOAD_FRACTION = 0.08
# A lean's prongs are taken to carry load only with their tips this close to the ground by the
# estimate [m]: more than the estimate is off by on feet that sink (under 2 cm).
PRONG_NEAR = 0.03
PRONG_SEARCH_DEPTH = 0.03  # [m] a lean goes on down this far below its plan to find the load ...
PRONG_SEARCH_SPEED = 0.01  # [m/s] ... at this speed
# A guarded touch starts along its line once the foot is this close to the approach point [m] ...
GUARD_SETTLE_DISTANCE = 0.005
GUARD_SETTLE_TIME = 1.0  # [s] ... or after this long.
# [s] A guarded touch takes its force estimate's bias while the foot moves freely along its
# line, over this window once its speed is reached: what the leg needs to move (joint friction,
# rotor inertia, dynamics the model lacks) reads as a force against the motion, and only its
# change is contact. Joint Coulomb friction of 0.15 N m reads as about 3 N at the foot.
GUARD_BIAS_WINDOW = 0.1
# [s] The foot's advance along the line is measured over this window: contact is felt only when
# the foot has slowed below GUARD_STALL_SHARE of the drive's speed. An object stops the foot; a
# joint's friction at breakaway or a change of its sign does not.
GUARD_SPEED_WINDOW = 0.06
GUARD_STALL_SHARE = 0.5
# [m] A foot that has not yet moved freely along the line may be stuck to its joints' static
# friction, which reads as a force against the drive: its stop counts as contact only once the
# drive has run this far ahead of it (an object already at the approach point is felt then).
GUARD_STUCK_LEAD = 0.03
# [s] a press reaches its speed over this, twice the foot impedance's slow time constant (30 N s/m
# over 600 N/m: 50 ms), so that its start does not read as a force; 2.5 mm of travel at 5 cm/s.
PRESS_SPEED_RAMP = 0.1


class MissionEnvironment:
    """Constant facts a phase needs: the robot variant and the controller's contact layout, and
    the posture planner's service (pedi_drake.mission.posture_planner)."""

    def __init__(
        self,
        prongs: ProngDesign | None,
        force_estimate: str = "joint_torque",
        planner: PosturePlanner | None = None,
        wait_for_plans: bool = True,
        contact_ramp_time: float = 0.3,
        friction: float = 0.8,
        terrain: np.ndarray | None = None,
    ):
        self.prongs = prongs
        self.num_prongs = 0 if prongs is None else prongs.num_prongs
        # The foot force estimate press phases stop on: "joint_torque" or "impedance".
        self.force_estimate = force_estimate
        # Solves posture: optimal requests off the control loop; None: the mission has none.
        self.planner = planner
        # Whether a phase waits for a late answer (lock-step simulation) or keeps polling (real time).
        self.wait_for_plans = wait_for_plans
        # [s] how long the controller takes to ramp a contact's load in or out.
        self.contact_ramp_time = contact_ramp_time
        # [-] the ground friction coefficient the controllers are given until the mission or the
        # operator changes it (MissionProgress.friction).
        self.friction = friction
        # The ground's terrain (pedi_drake.terrain's table; empty: flat ground).
        self.terrain = terrain_map(terrain)

    def ground_height(self, xy) -> float:
        """[m] the ground's height under the world point `xy` (x, y) [m]."""
        return terrain_height(self.terrain, float(xy[0]), float(xy[1]))

    def friction_now(self, progress: MissionProgress) -> float:
        """[-] the friction coefficient the controllers are given now."""
        return self.friction if progress.friction is None else progress.friction


def _fail(progress: MissionProgress, reason: str) -> str:
    progress.reason = reason
    return FAILED


def _body_sample(progress: MissionProgress, t: float) -> tuple[np.ndarray, RotationMatrix]:
    refs = progress.references
    return refs.body_position.sample(t).position, refs.body_orientation.sample(t).rotation


def _move_body(progress: MissionProgress, t: float, p_end=None, R_end=None, duration: float = 1.0) -> None:
    """Quintic from the current body reference to (p_end, R_end), starting at `t`."""
    p_now, R_now = _body_sample(progress, t)
    refs = progress.references
    refs.body_position = QuinticSegment(p_now, p_now if p_end is None else p_end, t, duration)
    refs.body_orientation = QuinticOrientationSegment(R_now, R_now if R_end is None else R_end, t, duration)


def _support_points_W(view: RobotView, env: MissionEnvironment, contacts: np.ndarray, exclude: str = "") -> np.ndarray:
    """Positions of the loaded contacts (feet, prong tips) in the world, except `exclude` [m]."""
    loaded = np.asarray(contacts[:4]) > 0.5
    if exclude:
        loaded[robot.LEG_NAMES.index(exclude)] = False
    points = view.feet_W_array()[loaded]
    if env.prongs is not None:
        tips = [view.X_WB @ tip_B for k, tip_B in enumerate(env.prongs.tip_positions_B()) if contacts[4 + k] > 0.5]
        if tips:
            points = np.concatenate([points, tips])
    return points


def _trunk_target_for_com(view: RobotView, p_body_ref: np.ndarray, com_xy_goal: np.ndarray) -> np.ndarray:
    """Trunk position reference that puts the CoM's ground projection at `com_xy_goal` [m]."""
    offset = view.com_W() - view.base.p_WB
    target = p_body_ref.copy()
    target[:2] = com_xy_goal - offset[:2]
    return target


@dataclasses.dataclass(frozen=True)
class IkAnswer:
    """One leg IK system's last answer (its output ports, see pedi_drake.ik.leg_ik_system)."""

    q: np.ndarray  # (3,) goal (hip, thigh, calf) [rad]
    solved: bool
    error: float  # foot-to-target distance [m]
    target_B: np.ndarray  # (3,) the trunk-frame target it answers [m]


def _ask_ik(progress: MissionProgress, view: RobotView, X_WB: RigidTransform, targets_B: dict, what: str) -> None:
    """Asks the leg IK systems for the joint angles of `targets_B` (per leg, trunk frame, in order),
    the trunk at X_WB (the pose the targets are planned in).

    The answers arrive over the manager's ports on later ticks (`receive_ik_answers`); the phase
    reads them with `_ik_solutions` and meanwhile holds its legs where their references are.
    """
    pose = np.concatenate([X_WB.rotation().ToQuaternion().wxyz(), X_WB.translation()])
    progress.ik = IkPlan.ask(what, pose, targets_B, view.q)


def _ik_solutions(progress: MissionProgress) -> dict[str, tuple[np.ndarray, ...]] | None:
    """Per leg, the joint angles of every asked target once all have arrived (closing the request)."""
    plan = progress.ik
    if plan is None or not plan.done:
        return None
    progress.ik = None
    return plan.solutions


def receive_ik_answers(plan: IkPlan, answers: dict[str, IkAnswer]) -> IkPlan:
    """`plan` with every answer that matches its leg's pending target taken in.

    An answer to an earlier target (the IK system has not seen the request yet) is left for a
    later tick. Raises UnreachableTarget for an answered target that the IK could not reach.
    """
    for leg, answer in answers.items():
        p_B = plan.pending(leg)
        if p_B is None or not np.all(np.abs(answer.target_B - p_B) <= RETARGET_TOLERANCE):
            continue
        if not answer.solved:
            raise UnreachableTarget(
                f"{plan.what}: IK for {leg} found no joint angles within the limits for the foot target "
                f"{np.round(p_B, 3).tolist()} m (trunk frame); closest miss {answer.error * 1000:.1f} mm"
            )
        plan = plan.answered(leg, answer.q, robot.leg_slice(leg))
    return plan


def target_problem(p_W: np.ndarray, X_WB) -> str | None:
    """Why no foot can be at `p_W` (a foot centre in the world, trunk at X_WB), or None.

    The ground is the plane z = 0, so a foot centre lower than its radius is in the floor; a foot
    centre within a radius of the trunk's box is inside the robot.
    """
    p_W = np.asarray(p_W, float)
    if p_W[2] < robot.FOOT_RADIUS:
        return (
            f"target below the floor: the foot centre would be at z = {p_W[2]:.3f} m in the world, "
            f"below the foot radius ({robot.FOOT_RADIUS} m) above the ground"
        )
    p_B = X_WB.inverse() @ p_W
    if np.all(np.abs(p_B) < np.asarray(robot.TRUNK_HALF_EXTENTS) + robot.FOOT_RADIUS):
        return f"target inside the robot: {np.round(p_B, 3).tolist()} m in the trunk frame is within the trunk"
    return None


def _foot_error(view: RobotView, leg: str, target_W: np.ndarray) -> float:
    return float(np.linalg.norm(view.foot_W(leg) - target_W))


class PhaseRunner:
    """Base class: a phase kind's behaviour. `start` sets references; `step` returns a status."""

    def start(self, phase, progress: MissionProgress, view: RobotView, env: MissionEnvironment) -> None:
        pass

    def step(self, phase, progress: MissionProgress, view: RobotView, env: MissionEnvironment) -> str:
        raise NotImplementedError


class StandUpRunner(PhaseRunner):
    """Raises the trunk to `height` over the centroid of the four feet.

    From lying (the trunk lower than `LYING_START`, or resting on its prongs) it first settles the
    trunk on the ground: the trunk goes down, by at most `SETTLE_DEPTH`, until the feet have shed
    `SETTLE_SHED` of their load with the legs still (the legs' force balance, joint-torque
    estimate), and rests there for `SETTLE_HOLD`. A trunk resting on the ground is the one rigid
    thing a robot with feet that sink (rubber, carpet) can measure the ground by: the estimator
    takes the trunk's resting height and the feet's kinematics under it as the feet's sink
    (pedi_drake.estimation.kalman_estimator). A trunk that
    meets no ground within the depth (its legs at their limits) stands up without it.
    """

    def start(self, phase, progress, view, env):
        t = view.time
        memo = progress.memo
        memo.update(rise_at=t, rose_at=None)
        # Lying: low on the folded legs, or resting on the prong tips.
        lying = LYING_START if env.prongs is None else max(LYING_START, env.prongs.ground_contact_height() + 0.03)
        if view.base.p_WB[2] < lying:
            if env.prongs is not None:
                # Lying on the prongs: they carry the trunk until it rises (the estimator pins
                # their tips to the ground, the controller shares the load with them).
                progress.references.contacts[4:] = 1.0
            p_now, _ = _body_sample(progress, t)
            _move_body(progress, t, p_now - [0.0, 0.0, SETTLE_DEPTH], None, SETTLE_DEPTH / SETTLE_SPEED)
            baseline = feet_vertical_load(view)
            memo.update(rise_at=None, settle_end=t + SETTLE_DEPTH / SETTLE_SPEED, baseline=baseline)
            progress.records[-1].metrics.update(settle=dict(feet_load_before_n=baseline, rested=False))

    @staticmethod
    def _rise(phase, progress, view) -> None:
        t = view.time
        progress.references.contacts[4:] = 0.0
        feet = np.array(list(view.feet_W().values()))
        p_goal = _trunk_target_for_com(view, view.base.p_WB.copy(), feet[:, :2].mean(axis=0))
        p_goal[2] = phase.height
        yaw = RollPitchYaw(view.X_WB.rotation()).yaw_angle()
        _move_body(progress, t, p_goal, RotationMatrix.MakeZRotation(yaw), phase.duration)
        progress.memo.update(goal=p_goal, rose_at=t)

    def step(self, phase, progress, view, env):
        t, memo = view.time, progress.memo
        if memo["rise_at"] is None:
            settle = progress.records[-1].metrics["settle"]
            load = feet_vertical_load(view)
            memo["baseline"] = max(memo["baseline"], load)  # as the lean's baseline
            settle["feet_load_before_n"] = memo["baseline"]
            shed = memo["baseline"] - load
            settle["feet_load_shed_n"] = shed
            if shed >= SETTLE_SHED * memo["baseline"] and legs_still(view):
                p_now, _ = _body_sample(progress, t)
                _move_body(progress, t, p_now, None, SETTLE_HOLD)
                settle.update(rested=True, rested_at_s=t)
                memo["rise_at"] = t + SETTLE_HOLD
            elif t >= memo["settle_end"]:
                memo["rise_at"] = t
        if memo["rose_at"] is None:
            if memo["rise_at"] is not None and t >= memo["rise_at"]:
                self._rise(phase, progress, view)
            return RUNNING
        done = t >= memo["rose_at"] + phase.duration
        if done and np.linalg.norm(view.base.p_WB - memo["goal"]) < 0.01:
            return SUCCEEDED
        return RUNNING


class LieDownRunner(PhaseRunner):
    """Lowers the trunk to the lying height."""

    def start(self, phase, progress, view, env):
        p_now, _ = _body_sample(progress, view.time)
        goal = p_now.copy()
        goal[2] = LYING_HEIGHT
        _move_body(progress, view.time, goal, None, phase.duration)
        progress.memo["goal"] = goal

    def step(self, phase, progress, view, env):
        done = view.time >= progress.phase_start + phase.duration
        return SUCCEEDED if done and abs(view.base.p_WB[2] - LYING_HEIGHT) < 0.015 else RUNNING


class BodyMoveRunner(PhaseRunner):
    def start(self, phase, progress, view, env):
        p_now, _ = _body_sample(progress, view.time)
        goal = p_now + np.asarray(phase.offset)
        if phase.height is not None:
            goal[2] = phase.height
        _move_body(progress, view.time, goal, None, phase.duration)
        progress.memo["goal"] = goal

    def step(self, phase, progress, view, env):
        done = view.time >= progress.phase_start + phase.duration
        ok = np.linalg.norm(view.base.p_WB - progress.memo["goal"]) < phase.tolerance
        return SUCCEEDED if done and ok else RUNNING


class BodyRotateRunner(PhaseRunner):
    def start(self, phase, progress, view, env):
        yaw0 = RollPitchYaw(progress.references.body_orientation.sample(view.time).rotation).yaw_angle()
        roll, pitch, yaw = phase.rpy
        goal = RotationMatrix(RollPitchYaw(roll, pitch, yaw0 + yaw))
        _move_body(progress, view.time, None, goal, phase.duration)
        if phase.pivot:
            k = _loaded_prong(phase.name, phase.pivot, progress, env)
            refs = progress.references
            p_now, _ = _body_sample(progress, view.time)
            tip_W = view.X_WB @ env.prongs.tip_positions_B()[k]
            refs.body_position = PivotedPosition(refs.body_orientation, tip_W, p_now)
        progress.memo["goal"] = goal

    def step(self, phase, progress, view, env):
        done = view.time >= progress.phase_start + phase.duration
        error = view.X_WB.rotation().inverse().multiply(progress.memo["goal"])
        angle = abs(error.ToAngleAxis().angle())
        return SUCCEEDED if done and angle < phase.tolerance else RUNNING


class BodyPathRunner(PhaseRunner):
    """The trunk along a circle or through via poses, back to its start; orientation held."""

    def start(self, phase, progress, view, env):
        t = view.time
        p_now, R_now = _body_sample(progress, t)
        if phase.radius > 0.0:
            path = CircularPath(p_now, phase.radius, t, phase.duration, phase.laps, phase.phase)
        else:
            points = [p_now] + [p_now + np.asarray(o, float) for o in phase.via_points] + [p_now]
            n = len(points) - 1
            path = PiecewiseQuintic.through(np.array(points), t, [phase.duration / n] * n)
        refs = progress.references
        refs.body_position = path
        refs.body_orientation = QuinticOrientationSegment(R_now, R_now, t, 1e-3)
        progress.memo.update(goal=p_now, squared_error=0.0, samples=0, max_error=0.0)

    def step(self, phase, progress, view, env):
        memo = progress.memo
        error = float(np.linalg.norm(view.base.p_WB - progress.references.body_position.sample(view.time).position))
        memo["squared_error"] += error**2
        memo["samples"] += 1
        memo["max_error"] = max(memo["max_error"], error)
        # From the state estimate (what the mission sees); ground-truth figures come from the run's logs.
        progress.records[-1].metrics.update(
            tracking_rms_m=math.sqrt(memo["squared_error"] / memo["samples"]), tracking_max_m=memo["max_error"]
        )
        done = view.time >= progress.phase_start + phase.duration
        if done and np.linalg.norm(view.base.p_WB - memo["goal"]) < phase.tolerance:
            return SUCCEEDED
        return RUNNING


class HoldFootPoseRunner(PhaseRunner):
    """The lifted foot held where its reference is now (and its calf's roll and pitch, or its whole
    orientation) from now on."""

    def start(self, phase, progress, view, env):
        if phase.leg not in progress.references.legs:
            raise UnreachableTarget(f"{phase.name}: {phase.leg} is not in pedipulation mode")
        p = foot_reference_start(progress, view, phase.leg)
        hold = QuinticSegment(p, p, view.time, 1e-3)
        if phase.orientation:
            rotation = orientation_error_W(view.calf_rotation_W(phase.leg), np.eye(3))  # its rotation vector
            mode = LEG_MODE_SHANK_POSE if phase.shank else LEG_MODE_FOOT_POSE
            leg_trajectory = LegTrajectory(mode, hold, calf_rotation=rotation)
        else:
            leg_trajectory = LegTrajectory(LEG_MODE_FOOT, hold)
        progress.references.legs[phase.leg] = leg_trajectory
        progress.records[-1].metrics.update(leg=phase.leg, p_WF=p.tolist())

    def step(self, phase, progress, view, env):
        return SUCCEEDED if view.time >= progress.phase_start + phase.duration else RUNNING


def _on_prongs(refs) -> bool:
    """True while the prongs are in the contact set (the trunk rests on them)."""
    return bool(np.any(np.asarray(refs.contacts[4:]) > 0.5))


def posture_request(
    phase, view: RobotView, env: MissionEnvironment, contacts: np.ndarray, p_fixed_W: np.ndarray, R_WB: RotationMatrix
) -> PostureRequest:
    """The optimal-posture request of a leg_to_pedipulation phase (its `goal`), made from the
    loaded feet measured now (`contacts`: the contact set); the optimiser starts from the fixed
    posture (p_fixed_W [m], R_WB), with the attitude of the goal's body_rotate if it has one.
    Trunk-frame targets that stay fixed in the world (`target_anchor`) go to the optimiser as the
    world points they name at that fixed posture."""
    goal = phase.goal
    rpy = RollPitchYaw(R_WB).vector()
    fixed: tuple[str, ...] = ()
    if goal.attitude is not None:
        rpy = np.array([goal.attitude[0], goal.attitude[1], rpy[2] + goal.attitude[2]])
        fixed = ("roll", "pitch", "yaw")
    start = Posture(tuple(float(v) for v in p_fixed_W), tuple(float(v) for v in rpy))
    anchor = target_anchor(phase, start)
    frame = goal.frame if anchor is None else "world"

    def points(given: list) -> tuple[tuple[float, float, float], ...]:
        as_given = [np.asarray(p, float) for p in given]
        return tuple(tuple(float(v) for v in (p if anchor is None else anchor @ p)) for p in as_given)

    stance = [leg for k, leg in enumerate(robot.LEG_NAMES) if leg != phase.leg and contacts[k] > 0.5]
    case = PostureCase(
        stance_W=tuple((leg, tuple(float(v) for v in view.foot_W(leg))) for leg in stance),
        leg=phase.leg,
        targets=points(goal.targets),
        frame=frame,
        reach_only=points(goal.reach_only),
        lift_B=tuple(float(v) for v in working_position_B(phase.leg, phase.working_depth)),
        prongs_key=robot.design_key(env.prongs),
    )
    return PostureRequest(case, start, fixed=fixed)


def target_anchor(phase, start: Posture) -> RigidTransform | None:
    """The pose X_WB in which the trunk-frame targets after the lift `phase` name their world
    points: the trunk at the fixed posture `start` when they stay fixed in the world
    (`trunk_targets: world`: the foot then goes where it would have gone without the optimiser,
    whatever posture the trunk takes); None for world targets and for targets on the trunk."""
    if phase.goal.frame != "trunk" or phase.trunk_targets != "world":
        return None
    return start.pose()


def _reach_frame(progress: MissionProgress, X_WB: RigidTransform, leg: str, frame: str) -> RigidTransform:
    """X_WF of the frame a reach's points for `leg` are given in: the world; the trunk at X_WB,
    the pose the reach plans in; or, after an optimal posture, the trunk at the fixed posture in
    which they name world points (`progress.target_anchors`)."""
    if frame == "world":
        return RigidTransform()
    return progress.target_anchors.get(leg, X_WB)


def _planning_pose(progress: MissionProgress, view: RobotView) -> RigidTransform:
    """The trunk pose X_WB a reach plans its joint goals in: on its feet, the body reference
    now, where the controller holds the trunk and brings it back after a disturbance (the
    reaction of a press that has just ended, the swing of the leg itself), so that the goals put
    the foot on its target once the trunk is back there; the estimate of a moment could be
    millimetres and milliradians off, which the foot, 0.4 m out, would keep. On its prongs, the
    estimate: there the prong contact holds the trunk, above its reference (which is set into the
    ground to keep the prongs loaded)."""
    if _on_prongs(progress.references):
        return view.X_WB
    p_WB, R_WB = _body_sample(progress, view.time)
    return RigidTransform(R_WB, p_WB)


def _posture_metrics(request: PostureRequest, result) -> dict:
    """The lift record's `posture` metrics: the case (stance, targets), the fixed and the optimal
    posture and their SUFs."""

    def row(evaluation) -> dict:
        return {
            "p_WB": list(evaluation.posture.p_WB),
            "rpy": list(evaluation.posture.rpy),
            "suf_n": evaluation.suf,
            "suf_per_target_n": list(evaluation.suf_per_target),
            "feasible": evaluation.feasible,
            "reason": evaluation.reason,
        }

    case = request.case
    return {
        "stance_W": {leg: list(p) for leg, p in case.stance_W},
        "frame": case.frame,
        "targets": [list(p) for p in case.targets],
        "reach_only": [list(p) for p in case.reach_only],
        "lift_B": list(case.lift_B),
        "fixed_coordinates": list(request.fixed),
        "fixed": row(result.start_reference),
        "optimal": row(result.best),
        "method": result.method,
        "evaluations": result.evaluations,
    }


@dataclasses.dataclass(frozen=True)
class PedipulationLift:
    """Where a leg_to_pedipulation phase is: waiting for the posture planner ("plan"), the trunk
    shifting over the other supports ("shift"), the foot's load ramping out ("release"), the leg
    lifting to its working position ("lift"). Each stage waits until `until` [s] at least."""

    stage: Literal["plan", "shift", "release", "lift"]
    until: float  # [s] when the stage's wait ends (the plan is due, the trunk or the ramp is done)
    request: PostureRequest | None = None  # "plan": the question asked of the planner
    p_work_B: np.ndarray | None = None  # "release", "lift": the foot's working position, trunk frame [m]

    def __deepcopy__(self, memo) -> "PedipulationLift":
        return self  # a value, shared by the progress's copies (see pedi_drake.mission.progress)


@dataclasses.dataclass(frozen=True)
class FootPlacing:
    """Where a leg_to_support phase is: the IK of its path being solved ("plan"), the foot coming
    down on its footprint ("place", done on touch or at `until`), its load ramping in ("load"),
    the trunk re-centring over the four feet ("centre")."""

    stage: Literal["plan", "place", "load", "centre"]
    footprint_W: np.ndarray  # where the foot is placed, world frame [m]
    until: float = 0.0  # [s] when the stage's wait ends
    t_above: float = 0.0  # [s] when the foot is above its footprint: touches count after it

    def __deepcopy__(self, memo) -> "FootPlacing":
        return self  # a value, shared by the progress's copies (see pedi_drake.mission.progress)


class LegToPedipulationRunner(PhaseRunner):
    """Place the trunk (the fixed shift of the CoM over the other supports, or the optimal
    posture), release the contact, lift the foot to work height."""

    def start(self, phase, progress, view, env):
        refs = progress.references
        supports = _support_points_W(view, env, refs.contacts, exclude=phase.leg)
        if len(supports) < 3:
            raise UnreachableTarget(f"{phase.name}: lifting {phase.leg} would leave fewer than three supports")
        p_now, R_now = _body_sample(progress, view.time)
        if _on_prongs(refs):
            # The loaded prong tips pin the trunk: it cannot shift, and the prongs widen the support
            # enough to lift a leg where it stands (the balance task still bounds the CoM).
            goal = p_now
        else:
            goal = _trunk_target_for_com(view, p_now, supports[:, :2].mean(axis=0))
        if phase.posture == "optimal":
            if env.planner is None:
                raise UnreachableTarget(f"{phase.name}: posture: optimal needs the posture planner")
            request = posture_request(phase, view, env, refs.contacts, goal, R_now)
            env.planner.ask(request)
            progress.memo["lift"] = PedipulationLift("plan", view.time + PLAN_LATENCY, request=request)
            return
        _move_body(progress, view.time, goal, None, SHIFT_DURATION)
        progress.memo["lift"] = PedipulationLift("shift", view.time + SHIFT_DURATION)

    def step(self, phase, progress, view, env):
        t, leg = view.time, phase.leg
        refs = progress.references
        k = robot.LEG_NAMES.index(leg)
        lift: PedipulationLift = progress.memo["lift"]
        if lift.stage == "plan":
            result = env.planner.answer(lift.request, wait=env.wait_for_plans) if t >= lift.until else None
            if result is None:
                if t >= lift.until:
                    # Late (a loaded machine, or the worker beside real-time loops): the robot holds
                    # still, which the phase's timeout does not count; a planner that never answers
                    # ends the phase.
                    progress.plan_wait = t - lift.until
                    if progress.plan_wait > PLAN_WAIT_LIMIT:
                        late = f"no posture plan {PLAN_WAIT_LIMIT:.0f} s after it was due"
                        return _fail(progress, f"{phase.name}: {late}")
                return RUNNING
            if progress.plan_wait > 0.0:
                progress.plan_wait = t - lift.until  # held still until this update too
            metrics = _posture_metrics(lift.request, result)
            metrics["plan_wait_s"] = progress.plan_wait
            progress.records[-1].metrics.update(leg=leg, posture=metrics)
            if not result.best.feasible:
                why = f"no posture within the limits reaches the targets of {leg} ({result.best.reason})"
                if not phase.goal.fallback_to_fixed:
                    metrics.update(taken="none", fallback="")
                    raise UnreachableTarget(f"{phase.name}: {why}")
                # The mission's own posture, which it runs without the optimiser: the trunk shifts
                # as a fixed lift's does (position only: a later body_rotate turns it).
                metrics.update(taken="fixed", fallback=f"{why}: the fixed posture is taken")
                _move_body(progress, t, np.asarray(lift.request.start.p_WB), None, SHIFT_DURATION)
                progress.memo["lift"] = PedipulationLift("shift", t + SHIFT_DURATION)
                return RUNNING
            metrics.update(taken="optimal", fallback="")
            posture = result.best.posture
            progress.pre_posture[leg] = _body_sample(progress, t)
            anchor = target_anchor(phase, lift.request.start)
            if anchor is not None:
                progress.target_anchors[leg] = anchor
            # A body_rotate among the targets turns the trunk later (about its origin): only the
            # position is taken now.
            R_goal = None if phase.goal.attitude is not None else RotationMatrix(RollPitchYaw(*posture.rpy))
            _move_body(progress, t, np.asarray(posture.p_WB), R_goal, POSTURE_DURATION)
            progress.memo["lift"] = PedipulationLift("shift", t + POSTURE_DURATION)
        elif t < lift.until:
            return RUNNING
        elif lift.stage == "shift":
            refs.contacts[k] = 0.0
            # The working pose's joint angles are asked now, to be there when the force has ramped away.
            p_work_B = working_position_B(leg, phase.working_depth)
            _ask_ik(progress, view, view.X_WB, {leg: [p_work_B]}, phase.name)
            progress.memo["lift"] = PedipulationLift("release", t + CONTACT_RAMP_WAIT, p_work_B=p_work_B)
        elif lift.stage == "release":
            solutions = _ik_solutions(progress)
            if solutions is None:
                return RUNNING
            trajectory = PiecewiseQuintic.through(
                np.array([joint_reference_start(progress, view, leg), solutions[leg][0]]), t, [phase.duration]
            )
            refs.legs[leg] = LegTrajectory(LEG_MODE_JOINTS, trajectory)
            progress.memo["lift"] = dataclasses.replace(lift, stage="lift", until=t + phase.duration)
        elif lift.stage == "lift":
            error = float(np.linalg.norm(view.foot_B(leg) - lift.p_work_B))
            if error < 0.01:
                progress.records[-1].metrics["working_position_error_m"] = error
                return SUCCEEDED
        return RUNNING


def _reach_legs(phase) -> list[tuple[str, list, list]]:
    """(leg, target, via_points) of every leg a reach phase moves, the main leg first."""
    legs = [(phase.leg, phase.target, phase.via_points)]
    return legs + [(c.leg, c.target, c.via_points) for c in phase.together]


class ReachRunner(PhaseRunner):
    """IK to the target (and the approach and via points), then joint-space quintics through them.

    The joint goals are planned in the trunk pose of `_planning_pose`, the targets given in the
    trunk frame are in that pose too (or, after an optimal posture, in `progress.target_anchors`).

    With `together`, every listed leg gets its own quintics over the same time span, so the feet
    move and arrive together; the phase succeeds when every foot is within the tolerance.

    With `touch` (spec.GuardedTouch) the quintics end at the approach point and a guarded move
    follows (`_guard`): the phase succeeds when contact is felt, wherever the estimate puts the
    foot, and fails when nothing is felt within the over-travel.
    """

    def start(self, phase, progress, view, env):
        legs = _reach_legs(phase)
        for leg, _, _ in legs:
            if leg not in progress.references.legs:
                raise UnreachableTarget(
                    f"{phase.name}: {leg} is not in pedipulation mode (add leg_to_pedipulation first)"
                )
        if phase.touch is not None and env.force_estimate not in view.foot_force_estimates_W(phase.leg):
            raise UnreachableTarget(
                f"{phase.name}: the {env.force_estimate} force estimate a touch feels with is not available "
                "from this controller"
            )
        targets_B, targets_W = {}, {}
        X_WB = _planning_pose(progress, view)
        X_BW = X_WB.inverse()
        approach_W = None
        for leg, target, via_points in legs:
            points = [np.asarray(p, float) for p in via_points]
            if phase.approach_offset:
                points.append(np.asarray(target) + np.asarray(phase.approach_offset))
            if phase.touch is None:
                points.append(np.asarray(target, float))
            X_WF = _reach_frame(progress, X_WB, leg, phase.frame)
            points_W = [X_WF @ point for point in points]
            for p_W in points_W + [X_WF @ np.asarray(target, float)]:
                problem = target_problem(p_W, X_WB)
                if problem is not None:
                    raise UnreachableTarget(f"{phase.name}: {leg}: {problem}")
            targets_B[leg] = [X_BW @ p_W for p_W in points_W]
            targets_W[leg] = X_WF @ np.asarray(target, float)
            if phase.touch is not None:
                offset = X_WF.rotation() @ np.asarray(phase.approach_offset, float)
                approach_W = GuardedApproach(direction_W=-offset / np.linalg.norm(offset), start_W=points_W[-1])
        _ask_ik(progress, view, X_WB, targets_B, phase.name)
        # The motion starts once the IK has answered (`t_arrive` is set then).
        progress.memo.update(
            t_arrive=math.inf, target_W=targets_W[phase.leg], targets_W=targets_W, t_ok=None, approach=approach_W
        )

    @staticmethod
    def _plan(phase, progress, view) -> None:
        """Joint-space quintics through the answered waypoints, every leg over the same span."""
        solutions = _ik_solutions(progress)
        if solutions is None:
            return
        plans = [
            (leg, np.array([joint_reference_start(progress, view, leg), *solutions[leg]]))
            for leg in progress.memo["targets_W"]
        ]
        # Every leg spans the time of the leg with the most segments (`duration` per segment).
        t = view.time
        span = phase.duration * max(len(waypoints) - 1 for _, waypoints in plans)
        for leg, waypoints in plans:
            n = len(waypoints) - 1
            trajectory = PiecewiseQuintic.through(waypoints, t, [span / n] * n)
            progress.references.legs[leg] = LegTrajectory(LEG_MODE_JOINTS, trajectory)
        progress.memo["t_arrive"] = t + span

    def step(self, phase, progress, view, env):
        memo = progress.memo
        if memo["t_arrive"] == math.inf:
            self._plan(phase, progress, view)
        errors = {leg: _foot_error(view, leg, target_W) for leg, target_W in memo["targets_W"].items()}
        record = progress.records[-1]
        # The main leg's figures at the top level, every leg's in `legs`.
        record.metrics.update(leg=phase.leg, error_m=errors[phase.leg], target_W=memo["target_W"].tolist())
        if phase.together:
            record.metrics["legs"] = [
                {"leg": leg, "target_W": target_W.tolist(), "error_m": errors[leg]}
                for leg, target_W in memo["targets_W"].items()
            ]
        if view.time < memo["t_arrive"]:
            return RUNNING
        if phase.touch is not None:
            return _guard(phase, progress, view, env)
        if max(errors.values()) < phase.tolerance:
            memo["t_ok"] = memo["t_ok"] if memo["t_ok"] is not None else view.time
            if view.time - memo["t_ok"] >= phase.hold:
                return SUCCEEDED
        else:
            memo["t_ok"] = None
        return RUNNING

    @staticmethod
    def timeout_reason(phase, progress) -> str:
        metrics = progress.records[-1].metrics
        if phase.touch is not None:
            touch = metrics.get("touch")
            if touch is None:
                return "the foot did not reach its approach point"
            return (
                f"no contact felt: the foot moved {1000 * touch['travel_m']:.1f} mm along the approach "
                f"(the largest force against it {touch['largest_force_n']:.2f} N, {phase.touch.force:.1f} N needed)"
            )
        rows = metrics.get("legs") or [{"leg": phase.leg, "error_m": metrics.get("error_m", float("nan"))}]
        late = [row for row in rows if not row["error_m"] < phase.tolerance] or rows
        errors = ", ".join(f"{row['leg']} {row['error_m'] * 1000:.1f} mm" for row in late)
        return f"foot error {errors} still above the {phase.tolerance * 1000:.1f} mm tolerance"


@dataclasses.dataclass(frozen=True)
class GuardedApproach:
    """The straight line of a guarded touch: its world direction [-] and the approach point it
    starts from [m]."""

    direction_W: np.ndarray
    start_W: np.ndarray


def _force_against(view: RobotView, leg: str, direction_W: np.ndarray) -> dict[str, float]:
    """Every available estimate of the force pushing the foot of `leg` back against `direction_W` [N]."""
    return {source: float(-force @ direction_W) for source, force in view.foot_force_estimates_W(leg).items()}


def _guard(phase, progress: MissionProgress, view: RobotView, env: MissionEnvironment) -> str:
    """The guarded move of a touching reach, one mission update: RUNNING, SUCCEEDED or FAILED.

    The joint motion to the approach point may end with the foot behind it (a leg with more
    friction and rotor inertia than the model has): the foot is held there until it is within
    GUARD_SETTLE_DISTANCE of it, for GUARD_SETTLE_TIME at most. Then it is driven along the
    approach direction (the press reference) from the approach point.

    Contact is felt when the foot has stopped advancing (below GUARD_STALL_SHARE of the drive's
    speed over GUARD_SPEED_WINDOW, once the drive is at speed) after it had moved freely (or,
    never having moved, with the drive GUARD_STUCK_LEAD ahead of it: static friction holds a foot
    as an object would) and the mission's force estimate, less its bias, reaches the touch's
    force. The bias is first the estimate at the approach point, at rest; once the foot has moved
    freely at speed for GUARD_BIAS_WINDOW it is the median over that window, which holds the force
    the leg needs to move (joint friction, a load the model lacks). Pressed against an object the
    leg's friction opposes its push as it opposed its motion, so the moving bias is also the bias
    against the object. The foot's reference is then held where the drive had brought it, a
    little past the foot (the tracking lag keeps a
    light preload), for `hold`.
    """
    memo, refs, touch, leg = progress.memo, progress.references, phase.touch, phase.leg
    approach: GuardedApproach = memo["approach"]
    t = view.time
    metrics = progress.records[-1].metrics
    if "guard" not in memo:
        start = approach.start_W
        if "settle_until" not in memo:
            refs.legs[leg] = LegTrajectory(LEG_MODE_FOOT, QuinticSegment(start, start, t, 1e-3))
            memo["settle_until"] = t + GUARD_SETTLE_TIME
        if np.linalg.norm(view.foot_W(leg) - start) > GUARD_SETTLE_DISTANCE and t < memo["settle_until"]:
            return RUNNING
        refs.press = dict(
            leg=leg,
            start=start,
            direction=approach.direction_W,
            speed=touch.speed,
            ramp=PRESS_SPEED_RAMP,
            t0=t,
            frozen_at=None,
        )
        to_target = float((memo["target_W"] - start) @ approach.direction_W)
        memo["guard"] = dict(
            start=start,
            to_target=to_target,
            bias=_force_against(view, leg, approach.direction_W),
            bias_in_motion=False,
            window=[],
            track=collections.deque(),
            at_speed=t + PRESS_SPEED_RAMP,
            moved=False,
            felt_at=None,
        )
        metrics["touch"] = dict(confirmed=False, travel_m=0.0, largest_force_n=0.0, force_estimate=env.force_estimate)
        return RUNNING
    guard = memo["guard"]
    if guard["felt_at"] is not None:
        return SUCCEEDED if t - guard["felt_at"] >= phase.hold else RUNNING
    raw = _force_against(view, leg, approach.direction_W)
    forces = {source: value - guard["bias"][source] for source, value in raw.items() if source in guard["bias"]}
    force = forces[env.force_estimate]
    travel = float((view.foot_W(leg) - guard["start"]) @ approach.direction_W)
    track = guard["track"]
    track.append((t, travel))
    while len(track) > 1 and track[1][0] <= t - GUARD_SPEED_WINDOW:
        track.popleft()
    stalled = False
    if t >= guard["at_speed"] and t - track[0][0] >= 0.5 * GUARD_SPEED_WINDOW:
        advance_speed = (travel - track[0][1]) / (t - track[0][0])
        stalled = advance_speed < GUARD_STALL_SHARE * touch.speed
        guard["moved"] = guard["moved"] or not stalled
    press = refs.press
    driven, _, _ = smooth_start_kernel(t, press["t0"], press["ramp"])
    reference_travel = touch.speed * driven
    record = metrics["touch"]
    record.update(travel_m=travel, largest_force_n=max(record["largest_force_n"], force), forces_n=forces)
    stopped = stalled and (guard["moved"] or reference_travel - travel >= GUARD_STUCK_LEAD)
    if force >= touch.force and stopped:
        held = guard["start"] + reference_travel * approach.direction_W
        refs.press = None
        refs.legs[leg] = LegTrajectory(LEG_MODE_FOOT, QuinticSegment(held, held, t, 1e-3))
        guard["felt_at"] = t
        # Where contact came along the line, from the target (< 0: before it, > 0: beyond it).
        record.update(
            confirmed=True,
            force_n=force,
            felt_from_target_m=travel - guard["to_target"],
            t=t,
        )
        return SUCCEEDED if phase.hold <= 0.0 else RUNNING
    if not guard["bias_in_motion"] and t >= guard["at_speed"] and not stalled:
        guard["window"].append(raw)
        if t - guard["at_speed"] >= GUARD_BIAS_WINDOW:
            window = guard["window"]
            guard["bias"] = {source: float(np.median([sample[source] for sample in window])) for source in raw}
            guard["bias_in_motion"] = True
            record["bias_n"] = guard["bias"][env.force_estimate]
    limit = guard["to_target"] + touch.over_travel
    # The reference may run ahead of a foot that is held back by something it does not feel.
    if travel >= limit or reference_travel >= limit + touch.over_travel:
        refs.press = None
        hold = PiecewiseQuintic.through(np.array([view.leg_q(leg)] * 2), t, [1e-3])
        refs.legs[leg] = LegTrajectory(LEG_MODE_JOINTS, hold)
        return _fail(
            progress,
            f"{phase.name}: no contact felt: the {leg} foot went {1000 * (travel - guard['to_target']):.1f} mm "
            f"beyond the target along the approach (the largest force against it {record['largest_force_n']:.2f} N "
            f"by the {env.force_estimate} estimate, {touch.force:.1f} N needed)",
        )
    return RUNNING


class PressRunner(PhaseRunner):
    """Drives the foot along `direction` until the estimated force or the displacement is reached.

    The force is the mission's estimate (`MissionEnvironment.force_estimate`); every available
    estimate is recorded beside it, each with its own bias and stiffness. With `balance_margin`,
    the press also stops when the force reaches that fraction of the live SUF against its
    direction (pedi_drake.mission.balance_bound)."""

    def start(self, phase, progress, view, env):
        if phase.leg not in progress.references.legs:
            raise UnreachableTarget(f"{phase.name}: {phase.leg} is not in pedipulation mode")
        estimates = view.foot_force_estimates_W(phase.leg)
        if env.force_estimate not in estimates:
            raise UnreachableTarget(
                f"{phase.name}: the {env.force_estimate} force estimate is not available from this controller"
            )
        direction = np.asarray(phase.direction, float)
        direction /= np.linalg.norm(direction)
        start = view.foot_W(phase.leg)
        trajectory = QuinticSegment(start, start, view.time, 1e-3)
        progress.references.legs[phase.leg] = LegTrajectory(LEG_MODE_FOOT, trajectory)
        progress.references.press = dict(
            leg=phase.leg,
            start=start,
            direction=direction,
            speed=phase.speed,
            ramp=PRESS_SPEED_RAMP,
            t0=view.time,
            frozen_at=None,
        )
        # Each estimate has a bias from model errors; measure it before touching anything.
        biases = {source: float(-force @ direction) for source, force in estimates.items()}
        # The force-displacement curve of the press, a row [displacement, force by each estimate]
        # a tick: what tells a fixed obstacle from one that gives way
        # (pedi_drake.evaluation.obstacle_response). An array, as the memo is copied every tick.
        progress.memo.update(start=start, force_bias=biases, curve=np.empty((0, 1 + len(biases))))

    def step(self, phase, progress, view, env):
        memo, press = progress.memo, progress.references.press
        direction = press["direction"]
        estimates = view.foot_force_estimates_W(phase.leg)
        forces = {
            source: float(-force @ direction) - memo["force_bias"][source]
            for source, force in estimates.items()
            if source in memo["force_bias"]
        }
        force = forces[env.force_estimate]
        displacement = float((view.foot_W(phase.leg) - memo["start"]) @ direction)
        sample = [displacement] + [forces[source] for source in memo["force_bias"]]
        memo["curve"] = np.vstack([memo["curve"], sample])
        metrics = progress.records[-1].metrics
        metrics.update(
            leg=phase.leg,
            force_n=force,
            displacement_m=displacement,
            force_estimate=env.force_estimate,
            forces_n=forces,
        )
        # The environment pushes the foot back against the press direction.
        limit = None
        if phase.balance_margin > 0.0:
            limit = balance_limit(view.suf, robot.LEG_NAMES.index(phase.leg), -direction, phase.balance_margin)
            metrics["balance_limit_n"] = limit
        balanced = limit is not None and force >= limit
        shown = math.nan if limit is None else limit
        progress.push = FootPush(phase.leg, -force * direction, -direction, shown, balanced)
        if force >= phase.force or displacement >= phase.max_displacement or balanced:
            press["frozen_at"] = view.time
            metrics["stopped_by"] = "force" if force >= phase.force else "balance" if balanced else "displacement"
            curve = memo["curve"]
            metrics["curve"] = {
                "displacement_m": curve[:, 0],
                "force_n": {source: curve[:, 1 + k] for k, source in enumerate(memo["force_bias"])},
            }
            # Hold the foot where it is, in joint space, for whatever comes next.
            hold = PiecewiseQuintic.through(np.array([view.leg_q(phase.leg)] * 2), view.time, [1e-3])
            progress.references.legs[phase.leg] = LegTrajectory(LEG_MODE_JOINTS, hold)
            progress.references.press = None
            return SUCCEEDED
        return RUNNING


class MoveFeetRunner(PhaseRunner):
    """Lifted feet moved in task space by world offsets (one quintic each), at the phase's gains."""

    def start(self, phase, progress, view, env):
        refs, t = progress.references, view.time
        targets_W = {}
        for foot in phase.feet:
            current = refs.legs.get(foot.leg)
            if current is None:
                raise UnreachableTarget(f"{phase.name}: {foot.leg} is not in pedipulation mode")
            if current.mode in (LEG_MODE_FOOT, LEG_MODE_FOOT_POSE, LEG_MODE_SHANK_POSE):
                # From the reference, not the foot: a foot held short of its reference by an
                # object keeps pressing by the same amount as the reference moves on.
                start = current.trajectory.sample(t).position
                gains = current.foot_gains
            else:
                start, gains = view.foot_W(foot.leg), None
            end = start + np.asarray(foot.offset, float)
            if phase.foot_gains is not None:
                gains = (phase.foot_gains.kp, phase.foot_gains.kd)
            refs.legs[foot.leg] = LegTrajectory(
                LEG_MODE_FOOT, QuinticSegment(start, end, t, phase.duration), foot_gains=gains
            )
            targets_W[foot.leg] = end
        progress.memo["targets_W"] = targets_W

    def step(self, phase, progress, view, env):
        targets_W = progress.memo["targets_W"]
        # The estimate's view; the true foot forces and positions come from the run's logs.
        progress.records[-1].metrics["legs"] = [
            {"leg": leg, "target_W": target.tolist(), "error_m": _foot_error(view, leg, target)}
            for leg, target in targets_W.items()
        ]
        return SUCCEEDED if view.time >= progress.phase_start + phase.duration else RUNNING


def footprint_xy_W(phase: spec.LegToSupport, view: RobotView) -> np.ndarray:
    """Where a leg_to_support phase puts its foot down, world x, y [m]: its `foothold` in the world,
    or in the stance frame of the other feet (`stance_pose`: the trunk's frame of the robot standing
    square on them), or under the hip of the trunk as it is."""
    if phase.foothold and phase.frame == "world":
        return np.asarray(phase.foothold, dtype=float)
    k = robot.LEG_NAMES.index(phase.leg)
    if phase.foothold:
        others = [i for i in range(4) if i != k]
        return stance_pose(view.feet_W_array()[others, :2], others).to_world(phase.foothold)
    geometry = leg_geometry(phase.leg)
    return (view.X_WB @ (geometry.p_BH + geometry.p_HT))[:2]


class LegToSupportRunner(PhaseRunner):
    """Places the foot on the ground (under its hip or at the phase's foothold), restores the
    contact, re-centres the trunk over the four feet."""

    def start(self, phase, progress, view, env):
        leg = phase.leg
        xy = footprint_xy_W(phase, view)
        geometry = leg_geometry(leg)
        under_hip = (view.X_WB @ (geometry.p_BH + geometry.p_HT))[:2]
        if np.linalg.norm(xy - under_hip) > FOOTHOLD_REACH:
            raise UnreachableTarget(
                f"{phase.name}: the foothold {np.round(xy, 3).tolist()} is "
                f"{np.linalg.norm(xy - under_hip):.3f} m from the point under {leg}'s hip, beyond the leg's "
                f"reach for a foothold ({FOOTHOLD_REACH} m)"
            )
        # Aim 1.5 cm into the floor: the estimate's height may be off by millimetres, and the
        # phase switches the foot to a contact as soon as its sensor feels the floor.
        ground = np.array([xy[0], xy[1], robot.FOOT_RADIUS - PLACE_DEPTH])
        above = ground + [0.0, 0.0, 0.05]
        X_BW = view.X_WB.inverse()
        _ask_ik(progress, view, view.X_WB, {leg: [X_BW @ above, X_BW @ ground]}, phase.name)
        progress.memo["placing"] = FootPlacing("plan", footprint_W=ground)

    def step(self, phase, progress, view, env):
        t, leg, refs = view.time, phase.leg, progress.references
        k = robot.LEG_NAMES.index(leg)
        placing: FootPlacing = progress.memo["placing"]
        if placing.stage == "plan":
            solutions = _ik_solutions(progress)
            if solutions is None:
                return RUNNING
            q_above, q_ground = solutions[leg]
            trajectory = PiecewiseQuintic.through(
                np.array([joint_reference_start(progress, view, leg), q_above, q_ground]),
                t,
                [phase.duration, 0.6 * phase.duration],
            )
            refs.legs[leg] = LegTrajectory(LEG_MODE_JOINTS, trajectory)
            progress.memo["placing"] = dataclasses.replace(
                placing, stage="place", t_above=t + phase.duration, until=t + 1.6 * phase.duration + 0.3
            )
            return RUNNING
        if placing.stage == "place":
            # A touch counts only on the way down from above the footprint: before that, the foot
            # sensor may still feel whatever the foot was pushing (an obstacle, a box).
            touched = t >= placing.t_above and view.foot_force[k] > CONTACT_FORCE_THRESHOLD
            if not (touched or t >= placing.until):
                return RUNNING
            placed = view.foot_W(leg)
            progress.records[-1].metrics.update(
                leg=leg,
                placed_W=placed.tolist(),
                placement_error_m=float(np.linalg.norm(placed[:2] - placing.footprint_W[:2])),
            )
            refs.legs.pop(leg, None)
            refs.contacts[k] = 1.0
            progress.memo["placing"] = dataclasses.replace(placing, stage="load", until=t + CONTACT_RAMP_WAIT)
        elif t < placing.until:
            return RUNNING
        elif placing.stage == "load":
            supports = _support_points_W(view, env, refs.contacts)
            p_now, _ = _body_sample(progress, t)
            goal = p_now if _on_prongs(refs) else _trunk_target_for_com(view, p_now, supports[:, :2].mean(axis=0))
            # After an optimal posture: back to the height and attitude the trunk had before it.
            p_before, R_before = progress.pre_posture.pop(leg, (None, None))
            progress.target_anchors.pop(leg, None)
            duration = SHIFT_DURATION if p_before is None else POSTURE_DURATION
            if p_before is not None:
                goal[2] = p_before[2]
            _move_body(progress, t, goal, R_before, duration)
            progress.memo["placing"] = dataclasses.replace(placing, stage="centre", until=t + duration)
        elif placing.stage == "centre":
            return SUCCEEDED if view.foot_force[k] > CONTACT_FORCE_THRESHOLD else RUNNING
        return RUNNING


def _loaded_prong(what: str, name: str, progress: MissionProgress, env: MissionEnvironment) -> int:
    """The index of prong `name`, which must exist and be loaded."""
    if env.prongs is None or spec.prong_index(name) >= env.num_prongs:
        raise UnreachableTarget(f"{what}: the robot has no {name} ({env.num_prongs} prongs)")
    k = spec.prong_index(name)
    if progress.references.contacts[4 + k] < 0.5:
        raise UnreachableTarget(f"{what}: {name} is not loaded (lean on it first)")
    return k


def _lean_prongs(phase, env: MissionEnvironment) -> list[int]:
    """Indices of the prongs a lean_on_prongs phase loads."""
    names = phase.prongs or list(robot.prong_body_names(env.prongs))
    for name in names:
        if spec.prong_index(name) >= env.num_prongs:
            raise UnreachableTarget(f"{phase.name}: the robot has no {name} ({env.num_prongs} prongs)")
    return [spec.prong_index(name) for name in names]


def feet_vertical_load(view: RobotView) -> float:
    """The summed vertical force of the ground on the four feet, by the joint-torque estimate [N]."""
    return float(sum(view.foot_external_force_W(leg)[2] for leg in robot.LEG_NAMES))


def legs_still(view: RobotView) -> bool:
    """Whether every joint turns slower than the estimator's STILL_RATE: only then do the joint
    torques give the feet's loads alone (in a motion they carry the legs' dynamics and the joints'
    friction, which on a real Go1 reads as tens of newtons)."""
    return bool(np.all(np.abs(view.qd) < STILL_RATE))


class LeanOnProngsRunner(PhaseRunner):
    """Lowers the trunk at its attitude until the named prong tips carry load, then loads them.

    The descent aims 5 mm below the height at which the estimate puts the tips on the ground. The
    tips carry load when the feet carry less: the legs' force balance (joint-torque estimate),
    against what they carried at the phase start, must drop by `PRONG_LOAD_FRACTION` of it, the
    legs still (the prongs have stopped the trunk) and the tips within PRONG_NEAR of the ground by
    the estimate. A
    robot whose estimated height is off (soft feet, carpet) reaches that load above or below the
    planned height; if the descent ends without it, the trunk goes on down slowly, by at most
    `PRONG_SEARCH_DEPTH`, and the phase fails if no load is felt by then.
    """

    def start(self, phase, progress, view, env):
        if env.prongs is None:
            raise UnreachableTarget(f"{phase.name}: the robot has no prongs (set robot.prongs)")
        lean = _lean_prongs(phase, env)
        p_now, R_now = _body_sample(progress, view.time)
        # Trunk height at which each tip's sphere touches flat ground at the reference attitude.
        drop = (R_now.matrix() @ env.prongs.tip_positions_B().T)[2]
        touch = env.prongs.tip_radius - drop
        goal = p_now.copy()
        # 5 mm below the touch of the highest named tip, so that every named tip carries load.
        goal[2] = float(np.min(touch[lean])) - 0.005
        others = [k for k in range(env.num_prongs) if k not in lean]
        if others and float(np.max(touch[others])) > goal[2] - 0.005:
            raise UnreachableTarget(
                f"{phase.name}: prongs {[f'prong_{k}' for k in others]} would touch the ground too "
                "(tilt the trunk first, or lean on them as well)"
            )
        _move_body(progress, view.time, goal, None, phase.duration)
        baseline = feet_vertical_load(view)
        progress.memo.update(goal=goal, loaded=False, lean=lean, baseline=baseline, searching=False)
        progress.records[-1].metrics.update(feet_load_before_n=baseline)

    def step(self, phase, progress, view, env):
        t, memo = view.time, progress.memo
        if memo["loaded"]:
            return SUCCEEDED if t >= memo["t_loaded"] else RUNNING
        # What the feet carried before the prongs took any: the most they have carried in the
        # phase (at its first tick the motors may not have taken the weight yet).
        load = feet_vertical_load(view)
        memo["baseline"] = max(memo["baseline"], load)
        prong_load = memo["baseline"] - load
        metrics = progress.records[-1].metrics
        metrics["feet_load_before_n"] = memo["baseline"]
        metrics.update(prong_load_n=prong_load)
        # The descent moves the legs until the prongs stop the trunk: only then is the load theirs,
        # and only with the tips near the ground by the estimate (the legs' loads swing by more than
        # the fraction as the descent starts).
        tips_z = (view.X_WB.rotation().matrix() @ env.prongs.tip_positions_B().T)[2] + view.base.p_WB[2]
        near = bool(np.all(tips_z[memo["lean"]] < env.prongs.tip_radius + PRONG_NEAR))
        if prong_load >= PRONG_LOAD_FRACTION * memo["baseline"] and legs_still(view) and near:
            for k in memo["lean"]:
                progress.references.contacts[4 + k] = 1.0
            # Once loaded, the estimator puts the tips on the ground: the planned goal, 5 mm
            # below their touch, is then a height in the same terms.
            p_now, _ = _body_sample(progress, t)
            goal = memo["goal"].copy()
            goal[2] = min(goal[2], p_now[2])
            _move_body(progress, t, goal, None, CONTACT_RAMP_WAIT)
            metrics.update(load_felt_at_s=t, trunk_reference_height_m=float(p_now[2]))
            memo.update(loaded=True, t_loaded=t + CONTACT_RAMP_WAIT)
            return RUNNING
        descent_end = progress.phase_start + phase.duration
        if t >= descent_end and not memo["searching"]:
            deeper = memo["goal"] - [0.0, 0.0, PRONG_SEARCH_DEPTH]
            _move_body(progress, t, deeper, None, PRONG_SEARCH_DEPTH / PRONG_SEARCH_SPEED)
            memo.update(searching=True, t_search_end=t + PRONG_SEARCH_DEPTH / PRONG_SEARCH_SPEED)
        if memo["searching"] and t >= memo["t_search_end"]:
            return _fail(
                progress,
                f"{phase.name}: no load felt on the prongs {1000 * PRONG_SEARCH_DEPTH:.0f} mm below their planned "
                f"touch (the feet shed {prong_load:.1f} N of {memo['baseline']:.1f} N, "
                f"{100 * PRONG_LOAD_FRACTION:.0f} % needed)",
            )
        return RUNNING


class LeaveProngsRunner(PhaseRunner):
    def start(self, phase, progress, view, env):
        progress.references.contacts[4:] = 0.0
        p_now, _ = _body_sample(progress, view.time)
        goal = p_now.copy()
        goal[2] = phase.height
        t = view.time + CONTACT_RAMP_WAIT
        refs = progress.references
        refs.body_position = QuinticSegment(p_now, goal, t, phase.duration)
        progress.memo.update(goal=goal, t_done=t + phase.duration)

    def step(self, phase, progress, view, env):
        if view.time >= progress.memo["t_done"] and abs(view.base.p_WB[2] - phase.height) < 0.01:
            return SUCCEEDED
        return RUNNING


class WaitRunner(PhaseRunner):
    def step(self, phase, progress, view, env):
        return SUCCEEDED if view.time >= progress.phase_start + phase.duration else RUNNING


class SwitchControllerRunner(PhaseRunner):
    """Asks for the phase's controller (MissionProgress.controller_request), then holds."""

    def start(self, phase, progress, view, env):
        codes = {name: code for code, name in CONTROLLER_NAMES.items()}
        progress.controller_request = codes[phase.to]

    def step(self, phase, progress, view, env):
        return SUCCEEDED if view.time >= progress.phase_start + phase.duration else RUNNING


class SetFrictionRunner(PhaseRunner):
    """Sets the controllers' friction coefficient (MissionProgress.friction), then holds."""

    def start(self, phase, progress, view, env):
        set_friction(progress, phase.mu, view.time, "mission")

    def step(self, phase, progress, view, env):
        return SUCCEEDED if view.time >= progress.phase_start + phase.duration else RUNNING


RUNNERS: dict[type, PhaseRunner] = {
    spec.StandUp: StandUpRunner(),
    spec.LieDown: LieDownRunner(),
    spec.BodyMove: BodyMoveRunner(),
    spec.BodyRotate: BodyRotateRunner(),
    spec.BodyPath: BodyPathRunner(),
    spec.HoldFootPose: HoldFootPoseRunner(),
    spec.LegToPedipulation: LegToPedipulationRunner(),
    spec.LegToSupport: LegToSupportRunner(),
    spec.Reach: ReachRunner(),
    spec.Press: PressRunner(),
    spec.MoveFeet: MoveFeetRunner(),
    spec.LeanOnProngs: LeanOnProngsRunner(),
    spec.LeaveProngs: LeaveProngsRunner(),
    spec.TeleopFoot: TeleopFootRunner(),
    spec.Wait: WaitRunner(),
    spec.SwitchController: SwitchControllerRunner(),
    spec.SetFriction: SetFrictionRunner(),
    **WALK_RUNNERS,
}
assert set(RUNNERS) == set(spec.PHASE_KINDS.values()), "every phase kind needs a runner"


def warm_up(mission: spec.MissionSpec, env: MissionEnvironment) -> None:
    """Loads (or compiles) the kernels the phases of `mission` call from Python, outside any control
    tick (the MissionManager's constructor): each is otherwise loaded in the tick that first calls
    it, and on a hardware run that tick is late by the load. A guarded touch's drive, a held
    calf's rotation and a walk's planner (pedi_drake.mission.walk.warm_up)."""
    smooth_start_kernel(0.0, 0.0, 1.0)
    orientation_error_W(np.eye(3), np.eye(3))
    if any(isinstance(phase, WALKING_PHASES) for phase in mission.phases):
        warm_up_walk(env)


def kind_name(phase) -> str:
    """The mission-file kind of `phase` (its own class's: a walk_to is a walk too)."""
    return next(name for name, cls in spec.PHASE_KINDS.items() if type(phase) is cls)


def register_phase_kind(name: str, spec_class: type[spec.PhaseBase], runner: PhaseRunner) -> None:
    """Adds a phase kind: mission files may then use `kind: name`, loaded into `spec_class` and
    run by `runner` (docs/extending.md walks through one).

    `spec_class` is a dataclass deriving from `spec.PhaseBase`, whose fields (each with a default,
    a comment and a unit) are the phase's mission file fields; the loader checks them against the
    field types and applies the common value checks (durations > 0, a `leg` among the leg names).
    `runner` is a stateless `PhaseRunner`. A name or a class already registered raises
    MissionFileError, so a kind is never silently replaced.
    """
    if not name.isidentifier():
        raise MissionFileError(f"phase kind {name!r}: must be an identifier (it is a mission file's `kind:`)")
    if name in spec.PHASE_KINDS or spec_class in RUNNERS:
        raise MissionFileError(f"phase kind {name!r} ({spec_class.__name__}) is already registered")
    if not (dataclasses.is_dataclass(spec_class) and issubclass(spec_class, spec.PhaseBase)):
        raise MissionFileError(f"phase kind {name!r}: {spec_class!r} must be a dataclass deriving from PhaseBase")
    if not isinstance(runner, PhaseRunner):
        raise MissionFileError(f"phase kind {name!r}: the runner must be a PhaseRunner, got {type(runner).__name__}")
    spec.PHASE_KINDS[name] = spec_class
    RUNNERS[spec_class] = runner
