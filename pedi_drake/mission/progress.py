"""The mission's changing state, held by the MissionManager as one abstract state value.

It is plain data: the phase index and timing, the reference trajectories the controller is
following, the contact set, and the record of finished phases. Once stored in a Context it is
treated as immutable (`MissionProgress.copy()` gives the copy to change). Its parts are either
values, shared by every copy (trajectories, LegTrajectory, IkPlan, ModeSwitch: frozen, and
their `__deepcopy__` returns them), or containers that the runners change in place, which a
copy duplicates: the memo, the references' leg table, contact set and press, the running
phase's record and the lists.
"""

import copy
import dataclasses

import numpy as np
from pydrake.math import RotationMatrix

# The leg reference's modes, which the mission writes (pedi_drake.control.references has their layout).
from pedi_drake.control.references import LEG_MODE_FOOT as LEG_MODE_FOOT
from pedi_drake.control.references import LEG_MODE_FOOT_POSE as LEG_MODE_FOOT_POSE
from pedi_drake.control.references import LEG_MODE_JOINTS as LEG_MODE_JOINTS
from pedi_drake.control.references import LEG_MODE_NONE as LEG_MODE_NONE
from pedi_drake.control.references import LEG_MODE_SHANK_POSE as LEG_MODE_SHANK_POSE
from pedi_drake.trajectory import (
    CircularPath,
    PiecewiseQuintic,
    PivotedPosition,
    QuinticOrientationSegment,
    QuinticSegment,
    RampSegment,
)

RUNNING, SUCCEEDED, FAILED, RECOVERING = "running", "succeeded", "failed", "recovering"
STATUS_CODES = {RUNNING: 0, SUCCEEDED: 1, FAILED: 2, RECOVERING: 3}


@dataclasses.dataclass(frozen=True)
class LegTrajectory:
    """Reference of one pedipulation leg: joint angles (mode 2), foot position in W (mode 1), or
    a held foot pose in W (mode 3: the trajectory's position and the calf's roll and pitch; mode
    4: the shank's pose, the calf's whole orientation).

    A value (a new reference replaces it): shared by the copies of a progress."""

    mode: int
    trajectory: PiecewiseQuintic | QuinticSegment | RampSegment
    # Mode 3: rotation vector of the calf's reference orientation R_WC_ref [rad].
    calf_rotation: np.ndarray | None = None
    # Modes 1 and 3: the foot task's own (kp [1/s^2], kd [1/s]); None: the controller's gains.
    foot_gains: tuple[float, float] | None = None

    def __deepcopy__(self, memo) -> "LegTrajectory":
        return self


@dataclasses.dataclass
class References:
    """What the controller is asked to do, as trajectories sampled at output time."""

    body_position: QuinticSegment | PiecewiseQuintic | CircularPath | PivotedPosition  # p_WB [m]
    body_orientation: QuinticOrientationSegment  # R_WB
    legs: dict[str, LegTrajectory]  # pedipulation legs only
    contacts: np.ndarray  # (4 + number of prongs,) 1 = loaded contact
    # A press phase drives the foot along d at its speed, reached smoothly over `ramp` [s] from t0
    # (trajectory.smooth_start_time_law), until frozen.
    press: dict | None = None

    def copy(self) -> "References":
        """A copy whose leg table, contact set and press can be changed (the trajectories are values)."""
        press = None if self.press is None else dict(self.press)
        return References(self.body_position, self.body_orientation, dict(self.legs), self.contacts.copy(), press)

    def same_trajectories(self, other: "References") -> bool:
        """Whether `other` holds the same trajectory values and press (not the contact set)."""
        if self.body_position is not other.body_position or self.body_orientation is not other.body_orientation:
            return False
        if self.legs.keys() != other.legs.keys() or any(self.legs[leg] is not other.legs[leg] for leg in self.legs):
            return False
        if self.press is None or other.press is None:
            return self.press is other.press
        return self.press.keys() == other.press.keys() and all(self.press[k] is other.press[k] for k in self.press)

    @staticmethod
    def holding(p_WB: np.ndarray, R_WB: RotationMatrix, t: float, num_prongs: int) -> "References":
        return References(
            body_position=QuinticSegment(p_WB, p_WB, t, 1e-3),
            body_orientation=QuinticOrientationSegment(R_WB, R_WB, t, 1e-3),
            legs={},
            contacts=np.concatenate([np.ones(4), np.zeros(num_prongs)]),
        )


@dataclasses.dataclass(frozen=True)
class IkPlan:
    """Foot targets a phase waits on the leg IK systems to turn into joint angles.

    Each leg's targets are asked one at a time, in order: the next is asked once the answer to
    the previous has arrived (one manager tick later) and starts from that answer, so a path of
    waypoints gets continuous joint solutions. Legs are asked in parallel.
    """

    what: str  # the asking phase's name, for the failure message
    X_WB: np.ndarray  # (7,) trunk pose [quaternion wxyz, p_WB [m]] the targets are expressed in
    targets_B: dict[str, tuple[np.ndarray, ...]]  # per leg, foot-centre targets in the trunk frame [m]
    q_seed: np.ndarray  # (12,) start of every leg's next solve, Unitree order [rad]
    solutions: dict[str, tuple[np.ndarray, ...]]  # per leg, the joint angles answered so far [rad]

    @staticmethod
    def ask(what: str, X_WB: np.ndarray, targets_B: dict[str, list], q: np.ndarray) -> "IkPlan":
        targets = {leg: tuple(np.asarray(p, float) for p in points) for leg, points in targets_B.items()}
        return IkPlan(what, np.asarray(X_WB, float), targets, np.asarray(q, float).copy(), {leg: () for leg in targets})

    def pending(self, leg: str) -> np.ndarray | None:
        """The trunk-frame target `leg` is waiting on, or None."""
        done = len(self.solutions.get(leg, ()))
        targets = self.targets_B.get(leg, ())
        return targets[done] if done < len(targets) else None

    def answered(self, leg: str, q_leg: np.ndarray, leg_slice: slice) -> "IkPlan":
        """The plan with `q_leg` [rad] as the answer to `leg`'s pending target (and its next seed)."""
        q_seed = self.q_seed.copy()
        q_seed[leg_slice] = q_leg
        solutions = dict(self.solutions)
        solutions[leg] = solutions[leg] + (np.asarray(q_leg, float).copy(),)
        return dataclasses.replace(self, q_seed=q_seed, solutions=solutions)

    @property
    def done(self) -> bool:
        return all(self.pending(leg) is None for leg in self.targets_B)

    def __deepcopy__(self, memo) -> "IkPlan":
        return self  # a value: `answered` makes a new plan


@dataclasses.dataclass
class PhaseRecord:
    """A finished (or running) phase, as reported in result.json."""

    name: str
    kind: str
    status: str
    t_start: float
    t_end: float | None = None
    reason: str = ""
    # Phase-specific measurements (foot error, press force and displacement, ...).
    metrics: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass(frozen=True)
class ModeSwitch:
    """One switch of the operation mode, as reported in result.json (`mode_switches`)."""

    time: float  # [s] diagram time
    from_mode: str  # "autonomous" or "teleop"
    to_mode: str
    reason: str
    # The mission phase the switch interrupted, or the one the mission resumes with.
    phase: str

    def __deepcopy__(self, memo) -> "ModeSwitch":
        return self  # a value


@dataclasses.dataclass(frozen=True)
class FootPush:
    """What the phase driving a lifted foot (teleop_foot, press) reports at each update: the
    direction the live SUF is asked about, and the operator's haptic feedback.

    A value (a new one replaces it): shared by the copies of a progress."""

    leg: str
    force_W: np.ndarray  # (3,) estimated force of the environment on the foot, bias removed, world [N]
    direction_W: np.ndarray | None  # (3,) unit direction of that force for the balance bound, world
    # The limit the force is held under [N]: teleop_foot's tighter of its force bound and its balance
    # bound along direction_W; press's balance limit; nan when there is none.
    limit: float
    bound_active: bool  # the balance bound changed the foot's motion at this update

    def __deepcopy__(self, memo) -> "FootPush":
        return self


def _shallow(obj):
    """A new object of obj's class with the same attributes (copy.copy without its protocol's cost)."""
    clone = object.__new__(type(obj))
    clone.__dict__.update(obj.__dict__)
    return clone


def _duplicate(value):
    """A deep copy of plain data (dicts, lists, tuples, arrays, scalars, values), at a fraction of
    copy.deepcopy's cost on the small memos and metrics copied at every mission update."""
    if isinstance(value, dict):
        return {key: _duplicate(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_duplicate(item) for item in value]
    if isinstance(value, np.ndarray):
        return value.copy()
    if isinstance(value, (float, int, str, bool, type(None), np.floating, np.integer, np.bool_)):
        return value
    return copy.deepcopy(value)


@dataclasses.dataclass
class MissionProgress:
    """Everything about the mission that changes during a run."""

    index: int = 0  # phase being run
    status: str = RUNNING
    reason: str = ""
    started: bool = False  # the current phase's start() has run
    phase_start: float = 0.0
    # [s] how long the running phase has held still waiting for a late posture plan (beyond
    # PLAN_LATENCY): time its timeout does not count.
    plan_wait: float = 0.0
    memo: dict = dataclasses.field(default_factory=dict)  # the current phase's private data
    references: References | None = None
    records: list[PhaseRecord] = dataclasses.field(default_factory=list)
    # Recovery after a failure: the phases still to run to reach a safe posture.
    recovery: list = dataclasses.field(default_factory=list)
    # Foot targets waiting for joint angles from the leg IK systems (None: nothing asked).
    ik: IkPlan | None = None
    # The operator's teleop sequence inserted into the mission (pedi_drake.mission.mode_switch):
    # its phases, run at `index` while the mission waits at `resume_index`. Empty: autonomous.
    interlude: list = dataclasses.field(default_factory=list)
    resume_index: int = 0
    # The operator's mode request last seen (pedi_drake.operator.command MODE_*), and whether a
    # request for the teleoperated mode waits for a safe point.
    operator_mode: int = 0
    teleop_pending: bool = False
    # The whole-body controller the mission last asked for (pedi_drake.operator.command
    # CONTROLLER_*; 0: none asked), the `controller_request` output.
    controller_request: int = 0
    # The friction coefficient the controllers are given [-] (the `friction` output; None: the
    # scenario's), every change of it as (time [s], coefficient, "mission" or "operator"), and
    # the operator's last friction request seen (0: none).
    friction: float | None = None
    friction_changes: list = dataclasses.field(default_factory=list)
    operator_friction: float = 0.0
    switches: list[ModeSwitch] = dataclasses.field(default_factory=list)
    # The semi-autonomous mode (pedi_drake.mission.semi_autonomous): every target the operator
    # sent (SemiAutonomous TargetRequest values), the last value seen [m], the accepted target
    # waiting for a safe point (world [m], or None), and what the inserted interlude serves
    # ("semi_autonomous", or "" for the teleop sequence).
    target_requests: list = dataclasses.field(default_factory=list)
    last_target: tuple | None = None
    target_pending: tuple | None = None
    interlude_mode: str = ""
    # Per lifted leg, the trunk reference (p_WB [m], R_WB) before an optimal posture moved it:
    # leg_to_support puts the trunk back there (re-centred over the feet as always).
    pre_posture: dict = dataclasses.field(default_factory=dict)
    # Per lifted leg, after an optimal posture: the trunk pose X_WB (RigidTransform) of the fixed
    # posture, in which its reaches' trunk-frame targets name the world points they stay at.
    target_anchors: dict = dataclasses.field(default_factory=dict)
    # The running phase's lifted-foot push (None when no phase drives a foot against anything).
    push: FootPush | None = None

    def phase_time(self, t: float) -> float:
        """[s] how long the running phase has run at time `t` [s], less its wait for a late posture
        plan: what its timeout judges."""
        return t - self.phase_start - self.plan_wait

    def copy(self) -> "MissionProgress":
        """A copy that is safe to change (a progress in a Context is never changed): its containers
        are duplicated, its values shared (see the module docstring)."""
        clone = _shallow(self)
        clone.memo = _duplicate(self.memo)
        clone.references = None if self.references is None else self.references.copy()
        # Only the current phase's record (the last) is ever changed: the finished phases'
        # records are shared, so a tick's copy does not grow with the mission.
        clone.records = self.records[:-1]
        if self.records:
            last = self.records[-1]
            record = _shallow(last)
            record.metrics = _duplicate(last.metrics)
            clone.records.append(record)
        # Lists of phases (never changed during a run) and of ModeSwitch values.
        clone.recovery, clone.interlude, clone.switches = list(self.recovery), list(self.interlude), list(self.switches)
        # Of (array, RotationMatrix), RigidTransform and TargetRequest values, never changed.
        clone.pre_posture = dict(self.pre_posture)
        clone.target_anchors = dict(self.target_anchors)
        clone.target_requests = list(self.target_requests)
        clone.friction_changes = list(self.friction_changes)  # of tuples, never changed
        return clone

    def __deepcopy__(self, memo) -> "MissionProgress":
        # Shared, not copied: a progress stored in a Context is never changed in place (the
        # MissionManager changes a `copy()` and stores that), and Drake copies the whole state
        # for every unrestricted update, among them the plant's at each step (its sampled
        # output ports): a deep copy would be paid twice a control tick.
        return self


def set_friction(progress: MissionProgress, mu: float, time: float, source: str) -> None:
    """Gives the controllers friction coefficient `mu` [-] from time `time` [s] on, recording the
    change and who made it (`source`: "mission" or "operator")."""
    progress.friction = float(mu)
    progress.friction_changes.append((float(time), float(mu), source))
