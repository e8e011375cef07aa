"""Mission files: an ordered list of phases, each of one kind with its own fields.

A mission file is YAML:

    description: Touch the cardboard cat standing in front of the robot with FR.
    scene:                       # scene objects (pedi_drake.scenario.SceneObject)
      - {kind: target_panel, position: [0.46, -0.13, 0.0], yaw: 3.14159}
    robot: {prongs: null}        # optional: the robot variant the mission needs
    stack: paper003              # optional: the whole-body controller's task stack it needs
    pushes:                      # optional: disturbances (pedi_drake.scenario.Push), simulation only
      - {force: 30.0, direction: [0.0, -1.0, 0.0], start: 6.0, ramp: 0.5, duration: 5.0}
    phases:
      - {kind: stand_up}
      - {kind: leg_to_pedipulation, leg: FR}
      - {kind: reach, leg: FR, target: [0.40, -0.13, 0.20], tolerance: 0.005}
      - {kind: leg_to_support, leg: FR}

Every phase has `name` (defaults to "<index>_<kind>") and `timeout` [s]. Loading validates every
field and raises MissionFileError naming the file, the phase index and the field.
"""

import copy
import dataclasses
import functools
import math
from pathlib import Path

from pydrake.common.yaml import yaml_load

from pedi_drake.config_validation import check_against_schema
from pedi_drake.control.config import FORCE_ESTIMATES, STACKS
from pedi_drake.exceptions import MissionFileError
from pedi_drake.friction import FRICTION_RANGE
from pedi_drake.locomotion.footholds import NOMINAL_FEET_B
from pedi_drake.locomotion.gait import GAITS
from pedi_drake.locomotion.static_walk import FOOTHOLD_REACH
from pedi_drake.locomotion.trot import TrotTiming
from pedi_drake.mission.posture_planner import PLAN_LATENCY, POSTURE_DURATION
from pedi_drake.operator.command import CONTROLLER_NAMES
from pedi_drake.resources import missions_dir
from pedi_drake.robot import FOOT_RADIUS, LEG_NAMES
from pedi_drake.scenario import Push, RobotConfig, SceneObject, resolve_model_path, scene_problems

FRAMES = ("world", "trunk")
# The contact ramp a mission may ask of the controllers [s], and the longest a walking mission may.
MIN_RAMP_TIME, MAX_RAMP_TIME, WALK_RAMP_LIMIT = 0.02, 1.0, 0.1
# ... and a trotting one: a longer unloading eats into the 0.23 s swing.
TROT_RAMP_LIMIT = 0.03
# How leg_to_pedipulation places the trunk before lifting: "fixed" shifts the centre of mass over
# the centroid of the other supports at the current height and attitude; "optimal" takes the
# posture of largest SUF at the foot's targets (pedi_drake.suf.posture).
POSTURES = ("fixed", "optimal")
STOPS = ("suf", "fixed")  # how a walk_to chooses its stop
# Phase fields the loader derives from the phases that follow, refused in a mission file.
LOADER_FIELDS = {"leg_to_pedipulation": ("goal",), "walk_to": ("goal", "working_depth")}
# What the trunk-frame targets of the reaches after a lift with posture: optimal stay fixed to:
# "world": the world point each names with the trunk in the fixed posture (a thing in the scene,
# such as a hand: the optimal posture then takes the foot to the same point); "trunk": the trunk
# (a point on the robot itself, such as its back: it moves with the posture).
TRUNK_TARGETS = ("world", "trunk")


@dataclasses.dataclass
class PhaseBase:
    """Fields every phase has."""

    # Phase name in logs and results; defaults to "<index>_<kind>".
    name: str = ""
    # The phase fails if it has not succeeded after this long [s].
    timeout: float = 10.0


@dataclasses.dataclass
class StandUp(PhaseBase):
    """From lying (or any pose) to standing on four feet at `height`."""

    # Trunk height above the ground [m].
    height: float = 0.28
    # Duration of the quintic reference [s].
    duration: float = 2.0


@dataclasses.dataclass
class LieDown(PhaseBase):
    """From standing to lying on the floor."""

    duration: float = 2.0


@dataclasses.dataclass
class BodyMove(PhaseBase):
    """Moves the trunk by `offset` (world frame, from the phase's start pose) [m]; with `height`,
    to that trunk height above the ground instead of by the offset's z."""

    offset: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Trunk height above the ground at the end of the move [m]; unset: start height + offset z.
    height: float | None = None
    duration: float = 1.0
    # Success when the trunk is within this distance of its target [m].
    tolerance: float = 0.01


@dataclasses.dataclass
class BodyRotate(PhaseBase):
    """Rotates the trunk to roll, pitch, yaw [rad] relative to its heading at the phase start,
    about its own origin or, with `pivot`, about the tip of a loaded prong (the trunk origin then
    moves on the sphere about the tip)."""

    rpy: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])
    duration: float = 1.0
    # Success when the orientation error is below this angle [rad].
    tolerance: float = 0.02
    # A loaded prong ("prong_0", ...) to turn about; empty: the trunk origin.
    pivot: str = ""


@dataclasses.dataclass
class BodyPath(PhaseBase):
    """Moves the trunk along a closed path at its current orientation and back to its start pose:
    a circle of `radius` in the world x-y plane at constant height (`laps` times), or, with
    `radius` 0, through the world-frame offsets `via_points` from the start (then back to it).
    The circle starts at rest and ends at rest (one quintic time law over `duration`); the via
    points get one rest-to-rest quintic each, `duration` split evenly over the segments."""

    # Circle radius [m]; 0 follows `via_points` instead.
    radius: float = 0.0
    # Number of times round the circle [-].
    laps: int = 1
    # Angle of the start point seen from the circle's centre [rad] (0: the centre lies behind, -x).
    phase: float = 0.0
    # Offsets of the via poses from the start position, world frame [m].
    via_points: list[list[float]] = dataclasses.field(default_factory=list)
    # Time for the whole path [s].
    duration: float = 10.0
    # Success when, at the end, the trunk is within this distance of its start [m].
    tolerance: float = 0.01


@dataclasses.dataclass
class HoldFootPose(PhaseBase):
    """Holds the lifted foot of `leg` at its current world position and, with `orientation`, its
    calf's roll and pitch (the 5-D foot task; yaw free), with `shank` the calf's whole
    orientation (paper 002's 6-D task of the shank), for whatever comes next."""

    leg: str = "FL"
    # Also hold the calf's roll and pitch (5-D), not just the foot position (3-D).
    orientation: bool = True
    # Hold the calf's yaw too (6-D: the shank's pose); needs `orientation`.
    shank: bool = False
    # Time the phase lasts before the next starts [s].
    duration: float = 0.5


@dataclasses.dataclass
class PostureGoal:
    """What an optimal posture is chosen for: the foot targets the lifted leg will visit before
    it is put back. Made by the mission loader from the phases that follow, or by the
    semi-autonomous mode from the operator's target; not a mission file field."""

    leg: str = "FR"
    # "world", or "trunk" (the trunk at the chosen posture).
    frame: str = "world"
    # Targets at which the SUF counts [m], in `frame`.
    targets: list[list[float]] = dataclasses.field(default_factory=list)
    # Points the foot must also reach with the same posture (approach, via points, press ends) [m].
    reach_only: list[list[float]] = dataclasses.field(default_factory=list)
    # Roll, pitch and yaw (yaw relative to the heading) [rad] a body_rotate sets before the
    # targets: the posture keeps them. None: the attitude is optimised too.
    attitude: list[float] | None = None
    # With no feasible posture: True, lift in the fixed posture (a mission's lift: the mission
    # runs with it without the optimiser); False, fail before anything moves (an operator's
    # target, which the semi-autonomous mode then refuses).
    fallback_to_fixed: bool = True


@dataclasses.dataclass
class LegToPedipulation(PhaseBase):
    """Shifts the support polygon away from `leg`, removes its contact and lifts the foot to the
    working position `working_depth` below the shoulder (paper 000: 15 cm).

    `posture` says where the trunk goes first (POSTURES): with "optimal" the phase asks for the
    posture of largest SUF at the targets the leg reaches next (`goal`) and waits for it (up to
    pedi_drake.mission.posture_planner.PLAN_LATENCY and the optimiser's time) before moving; where
    no posture is feasible, it takes the fixed one (see PostureGoal.fallback_to_fixed)."""

    leg: str = "FR"
    # Foot depth below the hip joint in the working position [m].
    working_depth: float = 0.15
    duration: float = 1.5
    posture: str = "fixed"
    # With posture: optimal, what the following reaches' trunk-frame targets stay fixed to
    # (TRUNK_TARGETS); no effect with the fixed posture, where both mean the same point.
    trunk_targets: str = "world"
    # Set by the loader for posture: optimal (see PostureGoal); not a file field.
    goal: PostureGoal | None = None


@dataclasses.dataclass
class LegToSupport(PhaseBase):
    """Places the foot of `leg` on the ground, under its hip or at `foothold`, and restores its
    contact."""

    leg: str = "FR"
    duration: float = 1.5
    # Where the foot goes down, [x, y] in `frame` [m]: in "trunk", the trunk's frame of the robot
    # standing square on its other three feet (x forward, y left; wherever the trunk has shifted
    # above them), at most FOOTHOLD_REACH from the point under the hip; in "world", a point on the
    # ground. Empty: under the hip of the trunk as it is.
    foothold: list[float] = dataclasses.field(default_factory=list)
    frame: str = "trunk"


@dataclasses.dataclass
class WalkVelocity(PhaseBase):
    """Walks at a constant twist for `duration`, then stops with the feet back under the hips and
    the trunk over them (pedi_drake.mission.walk)."""

    # Forward and sideways speed [m/s] and yaw rate [rad/s], in the walking frame (the trunk's
    # heading); within the gait's limits (pedi_drake.locomotion.gait.GAIT_LIMITS).
    twist: list[float] = dataclasses.field(default_factory=lambda: [0.1, 0.0, 0.0])
    duration: float = 5.0  # [s] of walking at the twist (the stop comes after)
    gait: str = "static_walk"  # a gait of pedi_drake.locomotion.gait.GAITS
    timeout: float = 120.0


@dataclasses.dataclass
class Walk(PhaseBase):
    """Walks to a pose in the world and stops there, the feet back under the hips: succeeds when
    the estimated trunk is within `tolerance` and `yaw_tolerance` of it."""

    # The goal's x, y [m] in the world (the trunk's origin).
    position: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0])
    yaw: float = 0.0  # [rad] the goal's heading
    speed: float = 0.1  # [m/s] the largest walking speed; within the gait's forward limit
    # [rad/s] the largest yaw rate; 0: the gait's limit
    yaw_rate: float = 0.0
    gait: str = "static_walk"
    tolerance: float = 0.03  # [m]
    yaw_tolerance: float = 0.05  # [rad]
    timeout: float = 120.0


@dataclasses.dataclass
class WalkTo(Walk):
    """A walk that chooses where to stop for the work of `leg` that follows: its `position` and
    `yaw` are the fixed stop (where a `walk` would end), and it stops instead at the stance whose
    SUF at the targets of the leg's reaches (up to its leg_to_support) is largest, within `search`
    of the fixed stop (pedi_drake.suf.stop), chosen as the phase starts. The lift of `leg` must
    follow before any other walk. `stop: fixed` walks to the fixed stop (for comparison). Succeeds
    when the estimated trunk is within `tolerance` and `yaw_tolerance` of the stop taken."""

    leg: str = "FR"
    stop: str = "suf"  # "suf" or "fixed"
    # The box about the fixed stop: the largest move along the world's x and y [m], and turn [rad].
    search: list[float] = dataclasses.field(default_factory=lambda: [0.1, 0.3])
    # Set by the loader from the phases that follow (not mission file fields): the lift's goal
    # and its working depth [m].
    goal: PostureGoal | None = None
    working_depth: float = 0.15


@dataclasses.dataclass
class WalkTeleop(PhaseBase):
    """Walks at the operator's twist (a KIND_TWIST command: the remote's sticks with `sticks:
    walk`, or a foot_command_lcmt of that kind) for `duration`, then stops with the feet back under
    the hips. With no fresh twist (none yet, or older than OPERATOR_TWIST_STALE) it steps in place."""

    duration: float = 30.0  # [s] of walking at the operator's twist (the stop comes after)
    gait: str = "static_walk"
    timeout: float = 120.0


@dataclasses.dataclass
class CompanionReach:
    """A further leg that a reach phase moves at the same time as its main leg."""

    # Leg name; it must be in pedipulation mode and differ from the phase's other legs.
    leg: str = ""
    # Foot target [m], in the phase's `frame`.
    target: list[float] = dataclasses.field(default_factory=list)
    # Intermediate targets of this leg (same frame) [m]; the phase's `approach_offset` applies too.
    via_points: list[list[float]] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class GuardedTouch:
    """How a reach whose purpose is to touch confirms the touch by sensed contact.

    The joint-space motion ends at the approach point (`Reach.approach_offset` from the target);
    from there the foot moves in a straight line along the approach direction, through the target,
    until it stops with the foot force estimate against that direction, less the force the leg
    needed to move freely along it, at `force` (contact felt: the phase holds there and succeeds),
    or it has gone `over_travel` beyond the target (nothing felt: the phase fails); see
    pedi_drake.mission.phases._guard. A target in the world frame is only as good as the robot's
    idea of where the ground is; contact is what says the foot met the object.
    """

    # The estimated force against the approach direction that counts as contact [N].
    force: float = 3.0
    # How far beyond the target the foot may go before the touch fails [m].
    over_travel: float = 0.02
    # Foot speed along the approach direction [m/s].
    speed: float = 0.04


@dataclasses.dataclass
class Reach(PhaseBase):
    """Moves the foot of `leg` to `target` through the IK, optionally via `approach_offset` first.

    `together` lists further legs that move at the same time, with the same frame, segment
    duration, tolerance and hold; the phase succeeds when every foot is within the tolerance.
    """

    leg: str = "FR"
    # Foot target [m], in `frame` ("world", or "trunk": the trunk where the controller holds it at
    # the phase start, its reference; see LegToPedipulation.trunk_targets after an optimal posture).
    target: list[float] = dataclasses.field(default_factory=lambda: [0.4, -0.13, 0.2])
    frame: str = "world"
    # If set, first reach target + approach_offset (same frame) [m], then the target.
    approach_offset: list[float] = dataclasses.field(default_factory=list)
    # Intermediate targets reached in order before `target` (same frame) [m].
    via_points: list[list[float]] = dataclasses.field(default_factory=list)
    # Success when the foot is within this distance of the target [m].
    tolerance: float = 0.005
    # Duration of each joint-space quintic segment [s].
    duration: float = 1.0
    # Time to stay at the target once reached [s].
    hold: float = 0.3
    # Legs moving at the same time, e.g. [{leg: FL, target: [x, y, z]}].
    together: list[CompanionReach] = dataclasses.field(default_factory=list)
    # A touch confirmed by sensed contact (needs `approach_offset`: it gives the direction); null:
    # the phase ends when the estimated foot is within `tolerance` of the target.
    touch: GuardedTouch | None = None


@dataclasses.dataclass
class Press(PhaseBase):
    """Moves the foot of `leg` along `direction` until the foot force or displacement is reached."""

    leg: str = "FR"
    # Unit push direction in the world [-].
    direction: list[float] = dataclasses.field(default_factory=lambda: [1.0, 0.0, 0.0])
    # Stop when the estimated foot force along `direction` reaches this [N].
    force: float = 10.0
    # ... or when the foot moved this far [m].
    max_displacement: float = 0.06
    # Foot speed along `direction` [m/s].
    speed: float = 0.05
    # ... or when the force along `direction` reaches this fraction of the live SUF in that
    # direction (pedi_drake.mission.balance_bound) [-]; 0: no balance bound.
    balance_margin: float = 0.0


@dataclasses.dataclass
class FootGains:
    """A foot task's own gains (Eq. 1 of the whole-body controller), both > 0. Low gains make the
    foot compliant: held against an object, it pushes with about its leg's task-space inertia
    times `kp` times how far its reference lies inside the object."""

    kp: float = 0.0  # stiffness [1/s^2]
    kd: float = 0.0  # damping [1/s]


@dataclasses.dataclass
class FootOffset:
    """One lifted foot a move_feet phase moves, and by how much."""

    # Leg name; it must be in pedipulation mode and appear once in the phase.
    leg: str = ""
    # Displacement of the foot's reference, world frame [m].
    offset: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])


@dataclasses.dataclass
class MoveFeet(PhaseBase):
    """Moves lifted feet in task space: each foot's world-frame position reference by its
    `offset`, from where its reference is at the phase start (the measured foot if the leg had a
    joint reference), on one quintic over `duration`, then held there for whatever comes next.

    With `foot_gains`, the moved feet run at those gains from now on (until a phase gives the leg
    a joint reference again); without, each keeps the gains it had. The phase ends after
    `duration`: a foot pressed on an object stays short of its reference by design, so the
    foot errors are recorded, not required.
    """

    feet: list[FootOffset] = dataclasses.field(default_factory=list)
    duration: float = 1.0
    foot_gains: FootGains | None = None


@dataclasses.dataclass
class LeanOnProngs(PhaseBase):
    """Lowers the trunk (at its current attitude) until the prongs touch and carry load, then adds
    them as contacts. `prongs` names the prongs to lean on ("prong_0", ...); empty: every prong.
    A prong that is not named must stay clear of the ground at that height (tilt the trunk first)."""

    duration: float = 2.0
    # The prongs to load, by name; empty: all of them.
    prongs: list[str] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class LeaveProngs(PhaseBase):
    """Raises the trunk off the prongs back to standing height."""

    height: float = 0.28
    duration: float = 2.0


@dataclasses.dataclass
class TeleopFoot(PhaseBase):
    """The lifted foot of `leg` follows the operator's velocity or position command (scenario
    `operator:`), bounded; each bound counts its activations in the phase's metrics.

    Bounds: the leg's workspace (the foot target always has a closed-form IK solution at least
    `joint_margin` inside every joint limit, stays `min_height` above the ground and out of the
    trunk; a command leaving it slides along its boundary), the foot speed `max_speed`, and the
    estimated foot contact force `max_force` (beyond it the foot does not move further into what
    it pushes), and the balance bound: the estimated force never exceeds `balance_margin` times
    the live SUF in its direction (pedi_drake.mission.balance_bound; 0 turns it off). Operator
    silence: after `hold_after` the foot holds; after `return_after` the phase fails and the leg
    returns to support. Ends (succeeds) when the operator asks for the autonomous mode, or after
    `duration`."""

    leg: str = "FR"
    # Largest foot speed [m/s].
    max_speed: float = 0.1
    # Workspace: the target's IK solution stays this far inside every joint limit [rad].
    joint_margin: float = 0.05
    # Workspace: lowest foot centre height above the ground (z = 0) [m].
    min_height: float = 0.04
    # Largest estimated contact force on the foot [N] (the mission's force estimate, bias removed).
    max_force: float = 15.0
    # Balance bound: the estimated force stays below this fraction of the live SUF in its
    # direction [-]; 0: off.
    balance_margin: float = 0.5
    # Operator silent this long: the foot holds [s].
    hold_after: float = 0.2
    # Operator silent this long: the phase fails and the leg returns to support [s].
    return_after: float = 2.0
    # The phase succeeds after this long unless the operator switched to autonomous first [s].
    duration: float = 30.0
    timeout: float = 60.0


@dataclasses.dataclass
class TeleopMode(TeleopFoot):
    """The mission file's `teleop:` block: how the operator may take a foot during the mission.

    When the operator asks for the teleoperated mode, the mission manager inserts, at the next
    safe point, a teleop_foot phase on `leg` with these bounds (the fields of teleop_foot), lifted
    first to `working_depth` below its hip if it stands on the ground (leg_to_pedipulation) and
    put back afterwards (leg_to_support); then the interrupted phase restarts
    (pedi_drake.mission.mode_switch)."""

    name: str = "teleop"
    # Foot depth below the hip joint when the inserted lift is done [m].
    working_depth: float = 0.15
    # Duration of the inserted lift's and placing's joint motions [s].
    leg_duration: float = 1.5

    def foot_phase(self, name: str) -> TeleopFoot:
        """The teleop_foot phase these settings make, named `name`."""
        fields = {f.name: getattr(self, f.name) for f in dataclasses.fields(TeleopFoot)}
        return TeleopFoot(**{**fields, "name": name})


@dataclasses.dataclass
class SemiAutonomousMode:
    """The mission file's `semi_autonomous:` block: the operator may give the `leg` foot a target.

    A target (a foot_command_lcmt with the semi-autonomous mode request and a position) inside the
    workspace below is taken at the next safe point: the mission manager inserts leg_to_pedipulation
    with the optimal posture for it, a reach that holds the foot there for `hold`, and
    leg_to_support; then the interrupted phase restarts. A target outside the workspace, or sent
    while another is being served, is refused and counted (never followed)
    (pedi_drake.mission.semi_autonomous)."""

    name: str = "semi"
    leg: str = "FR"
    # Workspace: the target in the trunk frame at the request (trunk origin at the posture it
    # has then) lies in this box [m] ...
    box_min: list[float] = dataclasses.field(default_factory=lambda: [0.15, -0.35, -0.25])
    box_max: list[float] = dataclasses.field(default_factory=lambda: [0.50, 0.05, 0.05])
    # ... and its foot centre at least this high above the ground [m].
    min_height: float = 0.04
    # Foot depth below the hip joint after the lift [m].
    working_depth: float = 0.15
    # Duration of the lift's, the reach's and the placing's joint motions [s].
    leg_duration: float = 1.5
    # Success when the foot is within this distance of the target [m] ...
    tolerance: float = 0.005
    # ... held for this long [s].
    hold: float = 1.0


@dataclasses.dataclass
class Wait(PhaseBase):
    """Holds the current references for `duration` [s]."""

    duration: float = 1.0


# The controllers a switch_controller phase can ask for.
SWITCHABLE_CONTROLLERS = tuple(CONTROLLER_NAMES.values())


@dataclasses.dataclass
class SwitchController(PhaseBase):
    """Asks for the whole-body controller `to` ("whole_body" or "projected_impedance") and holds
    the current references for `duration` [s] while the hand-over blends (a scenario with
    controller_switch runs both controllers, pedi_drake.control.controller_switch; in any other
    the request changes nothing)."""

    to: str = "whole_body"
    duration: float = 0.3


@dataclasses.dataclass
class SetFriction(PhaseBase):
    """Gives the controllers the friction coefficient `mu` [-] (in FRICTION_RANGE) from now on,
    as an operator does before stepping onto ground of another friction (paper 002, IV-C: no
    algorithm estimates it online), and holds the current references for `duration` [s]."""

    mu: float = 0.8
    duration: float = 0.1


PHASE_KINDS: dict[str, type[PhaseBase]] = {
    "stand_up": StandUp,
    "lie_down": LieDown,
    "body_move": BodyMove,
    "body_rotate": BodyRotate,
    "body_path": BodyPath,
    "hold_foot_pose": HoldFootPose,
    "leg_to_pedipulation": LegToPedipulation,
    "leg_to_support": LegToSupport,
    "reach": Reach,
    "press": Press,
    "move_feet": MoveFeet,
    "lean_on_prongs": LeanOnProngs,
    "leave_prongs": LeaveProngs,
    "teleop_foot": TeleopFoot,
    "wait": Wait,
    "switch_controller": SwitchController,
    "set_friction": SetFriction,
    "walk_velocity": WalkVelocity,
    "walk": Walk,
    "walk_to": WalkTo,
    "walk_teleop": WalkTeleop,
}


@dataclasses.dataclass
class BoxLift:
    """The outcome a box-lifting mission must reach, judged by physics (the logged plant state).

    The box's lowest corner must be at least `height` above the ground, each foot of `feet`
    touching it with at least `contact_force`, for at least `hold` without a break; and the box
    must not be back on the ground before the phase `until_phase` starts.
    """

    # Scene object (model instance) name of the box.
    box: str = "box"
    # The legs whose feet hold it.
    feet: list[str] = dataclasses.field(default_factory=lambda: ["FL", "RL"])
    # Lowest corner above the ground [m].
    height: float = 0.05
    # Time held at that height [s].
    hold: float = 3.0
    # Smallest contact force of each holding foot that counts as holding [N].
    contact_force: float = 1.0
    # Name of the phase that puts the box down (the box may not be dropped before it starts).
    until_phase: str = ""


@dataclasses.dataclass
class ObjectPush:
    """A push the judge requires, by physics (the logged plant state): from the start of the phase
    `phase` to the end of the phase `until` (that phase itself when empty), the scene object
    `object` moved at least `distance` on the floor, while over `phase` every foot on the ground
    stayed within `stance_slide` of where it was at the phase start. A later `until` lets a struck
    object finish sliding before it is measured."""

    # Scene object (model instance) name of the pushed object.
    object: str = ""
    # Name of the phase that pushes it.
    phase: str = ""
    # Horizontal distance its root body must move over the phase [m].
    distance: float = 0.10
    # Largest horizontal motion of a stance foot over the phase [m].
    stance_slide: float = 0.01
    # Name of the phase at whose end the object's motion is measured; empty: `phase`.
    until: str = ""


@dataclasses.dataclass
class Touch:
    """A touch the judge requires: during the phase `phase`, the foot of `leg` pressed on the scene
    object `object` with a normal contact force of at least `force` (the logged true contact
    forces, pedi_drake.evaluation.touches); coming close is not touching."""

    # Scene object (model instance) name.
    object: str = ""
    # The leg whose foot touches it.
    leg: str = "FR"
    # Name of the phase during which it touches.
    phase: str = ""
    # Smallest peak normal contact force that counts as a touch [N].
    force: float = 1.0


@dataclasses.dataclass
class ButtonPress:
    """An E-stop button press the judge requires (pedi_drake.evaluation.button_press): during the
    teleop_foot phase `phase`, the foot of `leg` pushed the plunger of the scene's estop_button
    `button` past its trip travel, and the true contact force between them never exceeded that
    phase's `max_force` (the force bound of the teleoperated foot)."""

    # Scene object (model instance) name of the button; its kind must be estop_button.
    button: str = "estop_button"
    # The leg whose foot presses it.
    leg: str = "FR"
    # Name of the teleop_foot phase during which it is pressed.
    phase: str = ""


@dataclasses.dataclass
class MissionSpec:
    """A loaded, validated mission."""

    name: str
    description: str
    phases: list[PhaseBase]
    scene: list[SceneObject]
    robot: RobotConfig | None
    source: str  # the file it came from
    force_estimate: str = ""  # "joint_torque" or "impedance"; empty: the scenario's
    # The whole-body controller's task stack ("paper000" or "paper003"); empty: the scenario's.
    stack: str = ""
    # Both controllers' contact ramp time [s]; 0: the scenario's.
    contact_ramp_time: float = 0.0
    # Disturbances of the simulated world during the mission (added to the scenario's).
    pushes: list[Push] = dataclasses.field(default_factory=list)
    # The box lift the judge requires (None: the mission lifts nothing).
    box_lift: BoxLift | None = None
    # The touches the judge requires.
    touches: list[Touch] = dataclasses.field(default_factory=list)
    # Scene object that must be off the trunk at the end (pedi_drake.evaluation.off_trunk); empty: none.
    leaves_trunk: str = ""
    # How the operator may take a foot mid-mission (None: the mission is autonomous only).
    teleop: TeleopMode | None = None
    # How the operator may give a foot a target mid-mission (None: no semi-autonomous mode).
    semi_autonomous: SemiAutonomousMode | None = None
    # The E-stop button press the judge requires (None: none).
    button_press: ButtonPress | None = None
    # The object push the judge requires (None: none).
    object_push: ObjectPush | None = None

    def takes_an_operator(self) -> bool:
        """Whether an operator has a part in the mission: a teleop_foot or walk_teleop phase, or a
        `teleop:` or `semi_autonomous:` block."""
        teleop_phase = any(isinstance(phase, (TeleopFoot, WalkTeleop)) for phase in self.phases)
        return teleop_phase or self.teleop is not None or self.semi_autonomous is not None

    def planned_duration(self) -> float:
        """Simulated time [s] the mission takes when every phase runs for its planned `duration`
        (a phase without one, such as a press, counts nothing): a rough measure of its cost."""
        return sum(getattr(phase, "duration", 0.0) for phase in self.phases)

    def longest_duration(self) -> float:
        """Simulated time [s] the mission can take at most: every phase running to its timeout,
        then a failure's recovery putting both front legs back down."""
        return sum(phase.timeout for phase in self.phases) + 2 * LegToSupport().timeout


@dataclasses.dataclass
class _MissionFile:
    """Top-level fields of a mission file (phases are checked per kind)."""

    description: str = ""
    scene: list[SceneObject] = dataclasses.field(default_factory=list)
    robot: RobotConfig | None = None
    # The foot force estimate press phases use: "joint_torque" or "impedance"; empty: the scenario's.
    force_estimate: str = ""
    # The task stack the whole-body controller runs the mission on (pedi_drake.control.compiled_stack):
    # "paper000" or "paper003"; empty: the scenario's. Ignored by the other controllers.
    stack: str = ""
    # The controllers' contact_ramp_time for this mission [s]; 0: the scenario's. A mission that
    # walks needs at most WALK_RAMP_LIMIT: a gait loads and unloads a foot every step.
    contact_ramp_time: float = 0.0
    pushes: list[Push] = dataclasses.field(default_factory=list)
    # The box lift the judge requires of the run (pedi_drake.evaluation.box_lift).
    box_lift: BoxLift | None = None
    # Touches the judge requires of the run: a foot's contact force on a scene object in a phase.
    touches: list[Touch] = dataclasses.field(default_factory=list)
    # Scene object the run must have taken off the trunk by its end (empty: none).
    leaves_trunk: str = ""
    # The operator's teleoperated foot, inserted on request (pedi_drake.mission.mode_switch).
    teleop: TeleopMode | None = None
    # The operator's foot targets, served on request (pedi_drake.mission.semi_autonomous).
    semi_autonomous: SemiAutonomousMode | None = None
    # The E-stop button press the judge requires of the run (pedi_drake.evaluation.button_press).
    button_press: ButtonPress | None = None
    # The object push the judge requires of the run (pedi_drake.evaluation.object_push).
    object_push: ObjectPush | None = None
    phases: list[dict] = dataclasses.field(default_factory=list)


# The controller demonstrations (pedi_drake.benchmarks.demos) live in this subfolder of the
# missions: they start standing and run on the scenarios of scenarios/wbc_demos.yaml, so they are
# not part of the library that runs on the default scenario.
DEMOS_FOLDER = "demos"


def shipped_missions() -> list[str]:
    """Names of the missions in the shipped library."""
    return sorted(path.stem for path in missions_dir().glob("*.yaml"))


# Longest mission name [characters]: it names the out dir, and file names stop at 255 bytes.
MAX_MISSION_NAME = 100


def shipped_demos() -> list[str]:
    """Names ("demos/<name>") of the shipped controller demonstrations, as load_mission takes them."""
    return sorted(f"{DEMOS_FOLDER}/{path.stem}" for path in (missions_dir() / DEMOS_FOLDER).glob("*.yaml"))


def resolve_mission(name_or_path: str) -> Path:
    """A shipped mission's file from its name, or the given YAML path."""
    path = Path(name_or_path)
    shown = name_or_path if len(name_or_path) <= 80 else name_or_path[:77] + "..."
    if len(path.stem) > MAX_MISSION_NAME:
        raise MissionFileError(
            f"mission {shown!r}: name is {len(path.stem)} characters long; at most {MAX_MISSION_NAME} "
            "(it names the output folder)"
        )
    try:
        if path.suffix in (".yaml", ".yml"):
            if not path.is_file():
                raise MissionFileError(f"{path}: mission file not found")
            return path
        candidate = missions_dir() / f"{name_or_path}.yaml"
        found = candidate.is_file()
    except OSError as error:  # a path the file system cannot look up (too long, bad characters)
        raise MissionFileError(f"mission {shown!r}: cannot be looked up ({error.strerror})") from None
    if not found:
        raise MissionFileError(
            f"unknown mission {shown!r}; shipped missions: {', '.join(shipped_missions())}, or give a .yaml path"
        )
    return candidate


def _object(raw, schema, path: str, where: str):
    """Builds a dataclass from checked YAML data (numbers in float fields become floats)."""
    check_against_schema(raw, schema, path, where, MissionFileError)
    return _build(raw, schema)


def _build(raw, schema):
    import typing

    if dataclasses.is_dataclass(schema):
        hints = typing.get_type_hints(schema)
        return schema(**{key: _build(value, hints[key]) for key, value in raw.items()})
    origin = typing.get_origin(schema)
    if origin is list:
        (item,) = typing.get_args(schema)
        return [_build(v, item) for v in raw]
    if origin in (typing.Union, __import__("types").UnionType):
        if raw is None:
            return None
        (option,) = [a for a in typing.get_args(schema) if a is not type(None)]
        return _build(raw, option)
    if schema is float:
        return float(raw)
    return raw


def load_mission(name_or_path: str) -> MissionSpec:
    """Loads and validates a mission by shipped name or YAML path; raises MissionFileError."""
    path = resolve_mission(name_or_path)
    stat = path.stat()
    return copy.deepcopy(_load_mission_file(path, path.resolve(), stat.st_mtime_ns, stat.st_size))


# A study loads each task's mission: parsed once per version of the file (Drake's YAML reader is
# pure Python), keyed by its modification time and size.
@functools.lru_cache(maxsize=64)
def _load_mission_file(path: Path, resolved: Path, mtime_ns: int, size: int) -> MissionSpec:
    """The mission in `path` (named so in errors; `resolved`, its modification time and size key
    the cache), validated; shared, not to be changed: `load_mission` hands out copies."""
    where = str(path)
    try:
        raw = yaml_load(filename=str(path))
    except Exception as error:
        raise MissionFileError(f"{where}: not valid YAML: {error}") from None
    if not isinstance(raw, dict):
        raise MissionFileError(f"{where}: expected a mapping with 'phases'")
    top = {key: value for key, value in raw.items() if key != "phases"}
    header = _object(top, _MissionFile, "", where)
    if header.force_estimate not in ("", *FORCE_ESTIMATES):
        raise MissionFileError(
            f"{where}: force_estimate: must be one of {FORCE_ESTIMATES} (or absent), got {header.force_estimate!r}"
        )
    if header.stack not in ("", *STACKS):
        raise MissionFileError(f"{where}: stack: must be one of {STACKS} (or absent), got {header.stack!r}")
    if not (header.contact_ramp_time == 0.0 or MIN_RAMP_TIME <= header.contact_ramp_time <= MAX_RAMP_TIME):
        raise MissionFileError(
            f"{where}: contact_ramp_time: must be 0 (the scenario's) or within [{MIN_RAMP_TIME}, {MAX_RAMP_TIME}] s, "
            f"got {header.contact_ramp_time!r}"
        )
    for problem in scene_problems(header.scene, path.parent):
        raise MissionFileError(f"{where}: {problem}")
    for obj in header.scene:
        # A mission's own model files sit beside it: resolved now, not against the current folder.
        if obj.model and not obj.model.startswith("package://"):
            obj.model = str(resolve_model_path(obj.model, path.parent).resolve())
    for i, push in enumerate(header.pushes):
        for field, problem in push.problems():
            raise MissionFileError(f"{where}: pushes[{i}].{field}: {problem}")
    raw_phases = raw.get("phases")
    if not isinstance(raw_phases, list) or not raw_phases:
        raise MissionFileError(f"{where}: phases: expected a non-empty list of phases")
    phases = []
    for i, raw_phase in enumerate(raw_phases):
        field = f"phases[{i}]"
        if not isinstance(raw_phase, dict) or "kind" not in raw_phase:
            raise MissionFileError(f"{where}: {field}: expected a mapping with a 'kind'")
        kind = raw_phase["kind"]
        if kind not in PHASE_KINDS:
            raise MissionFileError(
                f"{where}: {field}.kind: unknown phase kind {kind!r}; kinds: {', '.join(PHASE_KINDS)}"
            )
        body = {key: value for key, value in raw_phase.items() if key != "kind"}
        for derived in LOADER_FIELDS.get(kind, ()):
            if derived in body:
                raise MissionFileError(
                    f"{where}: {field}.{derived}: set by the loader from the phases that follow, not a field"
                )
        phase = _object(body, PHASE_KINDS[kind], field, where)
        phase.name = phase.name or f"{i}_{kind}"
        _check_phase_values(phase, f"{where}: {field}")
        phases.append(phase)
    names = [phase.name for phase in phases]
    duplicates = sorted({name for name in names if names.count(name) > 1})
    if duplicates:
        raise MissionFileError(f"{where}: phases: duplicate phase names {duplicates}")
    _attach_posture_goals(phases, where)
    walks = [phase.name for phase in phases if isinstance(phase, (Walk, WalkVelocity, WalkTeleop))]
    if walks and not 0.0 < header.contact_ramp_time <= WALK_RAMP_LIMIT:
        raise MissionFileError(
            f"{where}: contact_ramp_time: the walking phases {walks} need it set, at most {WALK_RAMP_LIMIT} s "
            f"(a foot is unloaded and loaded every step), got {header.contact_ramp_time!r}"
        )
    trots = [phase.name for phase in phases if getattr(phase, "gait", "") == "trot"]
    if trots and header.contact_ramp_time > TROT_RAMP_LIMIT:
        raise MissionFileError(
            f"{where}: contact_ramp_time: the trotting phases {trots} need at most {TROT_RAMP_LIMIT} s "
            f"(a pair of feet lands and the other lifts every {TrotTiming().half} s), got {header.contact_ramp_time!r}"
        )
    if header.teleop is not None:
        _check_phase_values(header.teleop, f"{where}: teleop")
    if header.semi_autonomous is not None:
        _check_semi_autonomous(header.semi_autonomous, f"{where}: semi_autonomous")
    if header.box_lift is not None:
        _check_box_lift(header.box_lift, header.scene, names, f"{where}: box_lift")
    for i, touch in enumerate(header.touches):
        _check_touch(touch, header.scene, names, f"{where}: touches[{i}]")
    if header.button_press is not None:
        _check_button_press(header.button_press, header.scene, phases, f"{where}: button_press")
    if header.object_push is not None:
        _check_object_push(header.object_push, header.scene, names, f"{where}: object_push")
    objects = [obj.instance_name for obj in header.scene]
    if header.leaves_trunk and header.leaves_trunk not in objects:
        raise MissionFileError(
            f"{where}: leaves_trunk: must name a scene object ({objects}), got {header.leaves_trunk!r}"
        )
    return MissionSpec(
        name=path.stem,
        description=header.description,
        phases=phases,
        scene=header.scene,
        robot=header.robot,
        source=where,
        force_estimate=header.force_estimate,
        stack=header.stack,
        contact_ramp_time=header.contact_ramp_time,
        pushes=header.pushes,
        box_lift=header.box_lift,
        touches=header.touches,
        leaves_trunk=header.leaves_trunk,
        teleop=header.teleop,
        semi_autonomous=header.semi_autonomous,
        button_press=header.button_press,
        object_push=header.object_push,
    )


def _check_box_lift(check: BoxLift, scene: list[SceneObject], phase_names: list[str], where: str) -> None:
    def need(condition: bool, field: str, problem: str) -> None:
        if not condition:
            raise MissionFileError(f"{where}.{field}: {problem}")

    objects = [obj.instance_name for obj in scene]
    need(check.box in objects, "box", f"must name a scene object ({objects}), got {check.box!r}")
    need(len(check.feet) > 0, "feet", "expected at least one leg")
    for k, leg in enumerate(check.feet):
        need(leg in LEG_NAMES, f"feet[{k}]", f"must be one of {LEG_NAMES}, got {leg!r}")
    for field in ("height", "hold", "contact_force"):
        value = getattr(check, field)
        need(math.isfinite(value) and value > 0, field, f"must be > 0, got {value}")
    need(
        check.until_phase in phase_names, "until_phase", f"must name a phase of the mission, got {check.until_phase!r}"
    )


def _check_object_push(check: ObjectPush, scene: list[SceneObject], phase_names: list[str], where: str) -> None:
    objects = [obj.instance_name for obj in scene]
    problems = {
        "object": (check.object in objects, f"must name a scene object ({objects}), got {check.object!r}"),
        "phase": (check.phase in phase_names, f"must name a phase of the mission, got {check.phase!r}"),
        "until": (
            not check.until
            or (
                check.until in phase_names
                and check.phase in phase_names
                and phase_names.index(check.until) >= phase_names.index(check.phase)
            ),
            f"must name `phase` or a phase after it, got {check.until!r}",
        ),
        "distance": (math.isfinite(check.distance) and check.distance > 0, f"must be > 0 [m], got {check.distance}"),
        "stance_slide": (
            math.isfinite(check.stance_slide) and check.stance_slide > 0,
            f"must be > 0 [m], got {check.stance_slide}",
        ),
    }
    for field, (ok, problem) in problems.items():
        if not ok:
            raise MissionFileError(f"{where}.{field}: {problem}")


def _check_touch(touch: Touch, scene: list[SceneObject], phase_names: list[str], where: str) -> None:
    objects = [obj.instance_name for obj in scene]
    problems = {
        "object": (touch.object in objects, f"must name a scene object ({objects}), got {touch.object!r}"),
        "leg": (touch.leg in LEG_NAMES, f"must be one of {LEG_NAMES}, got {touch.leg!r}"),
        "phase": (touch.phase in phase_names, f"must name a phase of the mission, got {touch.phase!r}"),
        "force": (math.isfinite(touch.force) and touch.force > 0, f"must be > 0 [N], got {touch.force}"),
    }
    for field, (ok, problem) in problems.items():
        if not ok:
            raise MissionFileError(f"{where}.{field}: {problem}")


def _check_button_press(check: ButtonPress, scene: list[SceneObject], phases: list[PhaseBase], where: str) -> None:
    buttons = [obj.instance_name for obj in scene if obj.kind == "estop_button"]
    teleop = [phase.name for phase in phases if isinstance(phase, TeleopFoot)]
    problems = {
        "button": (
            check.button in buttons,
            f"must name an estop_button of the scene {buttons}, got {check.button!r}",
        ),
        "leg": (check.leg in LEG_NAMES, f"must be one of {LEG_NAMES}, got {check.leg!r}"),
        "phase": (
            check.phase in teleop,
            f"must name a teleop_foot phase {teleop}, got {check.phase!r}",
        ),
    }
    for field, (ok, problem) in problems.items():
        if not ok:
            raise MissionFileError(f"{where}.{field}: {problem}")


def _check_phase_values(phase: PhaseBase, where: str) -> None:
    def need(condition: bool, field: str, problem: str) -> None:
        if not condition:
            raise MissionFileError(f"{where}.{field}: {problem}")

    need(phase.timeout > 0, "timeout", f"must be > 0 s, got {phase.timeout}")
    for field in ("duration", "tolerance", "hold", "force", "max_displacement", "speed", "working_depth", "height"):
        value = getattr(phase, field, None)
        if value is not None:
            need(math.isfinite(value) and value >= 0, field, f"must be a finite number >= 0, got {value}")
    for field in ("duration", "speed", "height", "leg_duration", "working_depth"):
        value = getattr(phase, field, None)
        if value is not None:
            need(value > 0, field, f"must be > 0, got {value}")
    leg = getattr(phase, "leg", None)
    if leg is not None:
        need(leg in LEG_NAMES, "leg", f"must be one of {LEG_NAMES}, got {leg!r}")
    if isinstance(phase, (Walk, WalkVelocity, WalkTeleop)):
        need(phase.gait in GAITS, "gait", f"unknown gait {phase.gait!r}; gaits: {', '.join(GAITS)}")
        limits = GAITS[phase.gait]
    if isinstance(phase, WalkVelocity):
        need(len(phase.twist) == 3, "twist", f"expected [forward m/s, sideways m/s, yaw rate rad/s], got {phase.twist}")
        problem = limits.problem(phase.twist)
        need(problem is None, "twist", f"{problem} ({phase.gait})")
    if isinstance(phase, Walk):
        need(len(phase.position) == 2, "position", f"expected [x, y] in metres, got {phase.position}")
        need(all(math.isfinite(v) for v in [*phase.position, phase.yaw]), "position", "must be finite")
        need(
            phase.speed <= limits.forward,
            "speed",
            f"{phase.speed} m/s is beyond the gait's limit {limits.forward} m/s ({phase.gait})",
        )
        need(phase.yaw_tolerance > 0, "yaw_tolerance", f"must be > 0 rad, got {phase.yaw_tolerance}")
        need(
            0.0 <= phase.yaw_rate <= limits.yaw_rate,
            "yaw_rate",
            f"{phase.yaw_rate} rad/s: must be in [0, {limits.yaw_rate}] rad/s, the gait's limit ({phase.gait})",
        )
        need(phase.tolerance > 0, "tolerance", f"must be > 0 m, got {phase.tolerance}")
    if isinstance(phase, WalkTo):
        need(phase.stop in STOPS, "stop", f"must be one of {STOPS}, got {phase.stop!r}")
        need(
            len(phase.search) == 2 and all(math.isfinite(v) and v >= 0.0 for v in phase.search),
            "search",
            f"expected [largest move m, largest turn rad], each finite and >= 0, got {phase.search}",
        )
    if isinstance(phase, LegToSupport):
        need(phase.frame in FRAMES, "frame", f"must be one of {FRAMES}, got {phase.frame!r}")
        need(len(phase.foothold) in (0, 2), "foothold", f"expected [] or [x, y] in metres, got {phase.foothold}")
        need(all(math.isfinite(v) for v in phase.foothold), "foothold", "must be finite")
        if phase.foothold and phase.frame == "trunk" and phase.leg in LEG_NAMES:
            offset = math.dist(phase.foothold, NOMINAL_FEET_B[LEG_NAMES.index(phase.leg)])
            need(
                offset <= FOOTHOLD_REACH,
                "foothold",
                f"{phase.foothold} is {offset:.3f} m from the point under {phase.leg}'s hip, beyond the leg's "
                f"reach for a foothold ({FOOTHOLD_REACH} m)",
            )
    if isinstance(phase, Reach):
        need(phase.frame in FRAMES, "frame", f"must be one of {FRAMES}, got {phase.frame!r}")
        need(len(phase.target) == 3, "target", f"expected [x, y, z] in metres, got {phase.target}")
        need(len(phase.approach_offset) in (0, 3), "approach_offset", "expected [] or [x, y, z] in metres")
        for k, point in enumerate(phase.via_points):
            need(len(point) == 3, f"via_points[{k}]", f"expected [x, y, z] in metres, got {point}")
        need(phase.timeout >= phase.duration, "timeout", "must be at least the phase duration")
        if phase.touch is not None:
            touch = phase.touch
            for field in ("force", "over_travel", "speed"):
                value = getattr(touch, field)
                need(math.isfinite(value) and value > 0, f"touch.{field}", f"must be a finite number > 0, got {value}")
            need(
                len(phase.approach_offset) == 3 and math.hypot(*phase.approach_offset) > 1e-3,
                "touch",
                "a guarded touch moves along the approach direction: give approach_offset (at least 1 mm)",
            )
            need(not phase.together, "touch", "a guarded touch moves one foot: drop `together`")
        if phase.frame == "world":
            # The ground is z = 0: a foot centre below its radius would be in the floor.
            points = {"target": phase.target, **{f"via_points[{k}]": p for k, p in enumerate(phase.via_points)}}
            if phase.approach_offset:
                points["approach_offset"] = [a + b for a, b in zip(phase.target, phase.approach_offset, strict=True)]
            for k, companion in enumerate(phase.together):
                if len(companion.target) == 3:
                    points[f"together[{k}].target"] = companion.target
            for field, point in points.items():
                need(
                    len(point) != 3 or point[2] >= FOOT_RADIUS,
                    field,
                    f"target below the floor: z = {point[2]} m puts the foot centre less than its radius "
                    f"({FOOT_RADIUS} m) above the ground (z = 0)",
                )
        legs = [phase.leg]
        for k, companion in enumerate(phase.together):
            field = f"together[{k}]"
            need(companion.leg in LEG_NAMES, f"{field}.leg", f"must be one of {LEG_NAMES}, got {companion.leg!r}")
            need(
                companion.leg not in legs,
                f"{field}.leg",
                f"{companion.leg} already moves in this phase (legs {legs}); each leg may appear once",
            )
            legs.append(companion.leg)
            need(
                len(companion.target) == 3,
                f"{field}.target",
                f"expected [x, y, z] in metres, got {companion.target or 'nothing'}",
            )
            for j, point in enumerate(companion.via_points):
                need(len(point) == 3, f"{field}.via_points[{j}]", f"expected [x, y, z] in metres, got {point}")
    if isinstance(phase, MoveFeet):
        need(len(phase.feet) > 0, "feet", "expected at least one {leg, offset}")
        legs = [foot.leg for foot in phase.feet]
        for k, foot in enumerate(phase.feet):
            need(foot.leg in LEG_NAMES, f"feet[{k}].leg", f"must be one of {LEG_NAMES}, got {foot.leg!r}")
            need(legs.count(foot.leg) == 1, f"feet[{k}].leg", f"{foot.leg} appears more than once")
            need(
                len(foot.offset) == 3 and all(math.isfinite(v) for v in foot.offset),
                f"feet[{k}].offset",
                f"expected finite [x, y, z] in metres, got {foot.offset}",
            )
        need(phase.timeout >= phase.duration, "timeout", "must be at least the phase duration")
        if phase.foot_gains is not None:
            for field in ("kp", "kd"):
                value = getattr(phase.foot_gains, field)
                need(math.isfinite(value) and value > 0, f"foot_gains.{field}", f"must be > 0, got {value}")
    for k, name in enumerate(getattr(phase, "prongs", None) or []):
        need(_is_prong_name(name), f"prongs[{k}]", f"expected a prong name like 'prong_0', got {name!r}")
    pivot = getattr(phase, "pivot", "")
    if pivot:
        need(_is_prong_name(pivot), "pivot", f"expected a prong name like 'prong_0' (or empty), got {pivot!r}")
    if isinstance(phase, BodyPath):
        need(math.isfinite(phase.radius) and phase.radius >= 0, "radius", f"must be >= 0 m, got {phase.radius}")
        need(phase.laps >= 1, "laps", f"must be at least 1, got {phase.laps}")
        need(phase.radius > 0 or phase.via_points, "via_points", "give a circle radius > 0 or at least one via point")
        for k, point in enumerate(phase.via_points):
            need(len(point) == 3, f"via_points[{k}]", f"expected [x, y, z] offsets in metres, got {point}")
        need(phase.timeout >= phase.duration, "timeout", "must be at least the phase duration")
    if isinstance(phase, HoldFootPose):
        need(phase.orientation or not phase.shank, "shank", "the 6-D shank pose needs orientation: true")
    if isinstance(phase, SwitchController):
        need(phase.to in SWITCHABLE_CONTROLLERS, "to", f"must be one of {SWITCHABLE_CONTROLLERS}, got {phase.to!r}")
        need(math.isfinite(phase.duration) and phase.duration >= 0, "duration", f"must be >= 0 s, got {phase.duration}")
        need(phase.timeout >= phase.duration, "timeout", "must be at least the phase duration")
    if isinstance(phase, SetFriction):
        low, high = FRICTION_RANGE
        need(math.isfinite(phase.mu) and low <= phase.mu <= high, "mu", f"must be in [{low}, {high}], got {phase.mu}")
        need(phase.timeout >= phase.duration, "timeout", "must be at least the phase duration")
    if isinstance(phase, TeleopFoot):
        for field in ("max_speed", "max_force", "hold_after", "return_after", "joint_margin", "min_height"):
            value = getattr(phase, field)
            need(math.isfinite(value) and value > 0, field, f"must be a finite number > 0, got {value}")
        need(phase.return_after > phase.hold_after, "return_after", "must be longer than hold_after")
        need(phase.timeout >= phase.duration, "timeout", "must be at least the phase duration")
    if isinstance(phase, LegToPedipulation):
        need(phase.posture in POSTURES, "posture", f"must be one of {POSTURES}, got {phase.posture!r}")
        need(
            phase.trunk_targets in TRUNK_TARGETS,
            "trunk_targets",
            f"must be one of {TRUNK_TARGETS}, got {phase.trunk_targets!r}",
        )
        if phase.posture == "optimal":
            least = PLAN_LATENCY + POSTURE_DURATION + phase.duration
            need(
                phase.timeout > least,
                "timeout",
                f"posture: optimal plans for {PLAN_LATENCY} s and moves the trunk for {POSTURE_DURATION} s before "
                f"the {phase.duration} s lift: must exceed {least} s, got {phase.timeout}",
            )
    if isinstance(phase, TeleopFoot | Press):
        margin = phase.balance_margin
        need(math.isfinite(margin) and 0.0 <= margin <= 1.0, "balance_margin", f"must be in [0, 1], got {margin}")
    if isinstance(phase, Press):
        norm = math.sqrt(sum(v * v for v in phase.direction)) if len(phase.direction) == 3 else 0.0
        need(norm > 0.5, "direction", f"expected a unit [x, y, z] vector, got {phase.direction}")
    for field in ("offset", "rpy"):
        value = getattr(phase, field, None)
        if value is not None:
            need(len(value) == 3, field, f"expected 3 numbers, got {value}")


def _attach_posture_goals(phases: list[PhaseBase], where: str) -> None:
    """Gives every leg_to_pedipulation with posture: optimal its PostureGoal (`reach_goal`), and
    every walk_to the goal of the lift of its leg that follows it. Raises MissionFileError for
    what the optimiser cannot serve: no reach, two legs moving, the trunk on its prongs, frames
    mixed; a walk_to with no lift of its leg after it, or with targets on the trunk."""
    on_prongs = False
    for i, phase in enumerate(phases):
        if isinstance(phase, LeanOnProngs):
            on_prongs = True
        elif isinstance(phase, LeaveProngs):
            on_prongs = False
        if isinstance(phase, WalkTo):
            _attach_stop_goal(phases, i, where)
        if not (isinstance(phase, LegToPedipulation) and phase.posture == "optimal"):
            continue
        field = f"{where}: phases[{i}].posture"
        if on_prongs:
            raise MissionFileError(f"{field}: optimal: the trunk rests on its prongs here, which pin it")
        phase.goal = reach_goal(phases, i, f"{field}: optimal")


def _attach_stop_goal(phases: list[PhaseBase], i: int, where: str) -> None:
    """The walk_to phases[i]'s goal: that of the next leg_to_pedipulation of its leg, which must
    follow before any other walk, its targets in the world (targets on the trunk move with it:
    no stop serves them better); and that lift's working depth."""
    phase = phases[i]
    field = f"{where}: phases[{i}].leg"
    for j in range(i + 1, len(phases)):
        later = phases[j]
        if isinstance(later, LegToPedipulation) and later.leg == phase.leg:
            goal = reach_goal(phases, j, f"{field}: walk_to")
            if goal.frame != "world":
                raise MissionFileError(
                    f"{field}: walk_to: the reaches of {phase.leg} after it name trunk-frame targets, which move "
                    "with the trunk wherever it stops; give them in the world frame"
                )
            phase.goal, phase.working_depth = goal, later.working_depth
            return
        if isinstance(later, Walk | WalkVelocity | WalkTeleop):
            break
    raise MissionFileError(f"{field}: walk_to: no leg_to_pedipulation of {phase.leg} follows before the next walk")


def reach_goal(phases: list[PhaseBase], i: int, field: str) -> PostureGoal:
    """The PostureGoal of the leg lifted by phases[i]: the targets of the leg's reach phases up to
    its leg_to_support (and the points it must pass on the way), with the attitude of a
    body_rotate among them. `field` names the phase's field in the errors."""
    phase = phases[i]
    goal = PostureGoal(leg=phase.leg)
    frames, last_target = set(), None
    for later in phases[i + 1 :]:
        if isinstance(later, LegToSupport) and later.leg == phase.leg:
            break
        if isinstance(later, Reach) and later.leg == phase.leg:
            if later.together:
                raise MissionFileError(f"{field}: {later.name} moves further legs (together)")
            frames.add(later.frame)
            goal.targets.append(list(later.target))
            goal.reach_only.extend(list(p) for p in later.via_points)
            if later.approach_offset:
                goal.reach_only.append([a + b for a, b in zip(later.target, later.approach_offset, strict=True)])
            last_target = later.target
        elif isinstance(later, Press) and later.leg == phase.leg and last_target is not None:
            norm = math.sqrt(sum(v * v for v in later.direction))
            goal.reach_only.append(
                [t + later.max_displacement * d / norm for t, d in zip(last_target, later.direction, strict=True)]
            )
        elif isinstance(later, BodyRotate) and not later.pivot and goal.attitude is None:
            goal.attitude = list(later.rpy)
        elif isinstance(later, LegToPedipulation | MoveFeet | BodyMove | BodyPath | LeanOnProngs):
            raise MissionFileError(
                f"{field}: {later.name} ({type(later).__name__}) changes the stance or trunk "
                "before the leg is back on the ground; the optimiser chooses one posture for one lifted leg"
            )
    if not goal.targets:
        raise MissionFileError(f"{field}: no reach of {phase.leg} follows before its leg_to_support")
    if len(frames) > 1:
        raise MissionFileError(f"{field}: the reaches of {phase.leg} mix frames {sorted(frames)}")
    goal.frame = frames.pop()
    return goal


def _check_semi_autonomous(block: SemiAutonomousMode, where: str) -> None:
    def need(condition: bool, field: str, problem: str) -> None:
        if not condition:
            raise MissionFileError(f"{where}.{field}: {problem}")

    need(block.leg in LEG_NAMES, "leg", f"must be one of {LEG_NAMES}, got {block.leg!r}")
    for field in ("box_min", "box_max"):
        value = getattr(block, field)
        need(
            len(value) == 3 and all(math.isfinite(v) for v in value),
            field,
            f"expected finite [x, y, z] [m], got {value}",
        )
    need(all(a < b for a, b in zip(block.box_min, block.box_max, strict=True)), "box_max", "must exceed box_min")
    for field in ("min_height", "working_depth", "leg_duration", "tolerance", "hold"):
        value = getattr(block, field)
        need(math.isfinite(value) and value > 0, field, f"must be a finite number > 0, got {value}")
    need(block.min_height >= FOOT_RADIUS, "min_height", f"must be at least the foot radius ({FOOT_RADIUS} m)")


def _is_prong_name(name) -> bool:
    """Whether `name` has the form of a prong body's name, "prong_<index>"."""
    return isinstance(name, str) and name.startswith("prong_") and name[len("prong_") :].isdigit()


def prong_index(name: str) -> int:
    """The index of prong `name` ("prong_3" -> 3) in the contact set, after the four feet."""
    return int(name[len("prong_") :])
