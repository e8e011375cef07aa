"""MissionManager: runs a mission phase by phase and drives the whole-body controller.

Inputs are the state estimate and `go1.*` measurements; outputs are the controller's reference
ports (layouts in pedi_drake/control/references.py) and a status vector. The mission's progress
is one abstract state value (MissionProgress), updated at `period`; references are quintic
trajectories sampled at output time, so the controller sees smooth references at its own rate.

What a tick costs: at each update the references are packed into a ReferenceTable (abstract
state), which `references` (body_reference then leg_reference, 19 + 48) samples with one
compiled kernel: the diagram splits it for the controller and the logs (a Demultiplexer), so one
Python call a tick serves both; `body_reference` and `leg_reference` give the same vectors
separately (tests, scripts). Every other output changes only at the updates, so it is discrete
state written there and its port is a state output port (no Python runs when the controller,
the estimator or a log reads it).

Joint angles for foot targets come from one LegIkSystem per leg the mission moves (`ik_legs`),
through ports: the manager asks on `ik_foot_target_W.<leg>` (NaN when it asks nothing), with
the trunk pose the target was planned in on `ik_X_WB` and the solve's start angles on
`ik_q_seed`; the IK system answers on its discrete state, read back on `ik_q_goal.<leg>`,
`ik_solved.<leg>`, `ik_error.<leg>` and `ik_target_B.<leg>`. The answer arrives on a later
manager tick (the IK updates between the manager's ticks): a phase asks, holds its legs, and
plans its motion when the answers are in (a path of waypoints takes one tick a waypoint).

`safety_polygon` is the capture-point polygon of the current stance (see
`stance_polygon.stance_safety_polygon`), recomputed at every update from the estimated support points.

The live SUF (pedi_drake.suf.live_suf_system) is asked about on `suf_request` (the lifted foot:
the one a teleop_foot or press phase drives, else the first lifted leg; and the direction of
that phase's push) and read back on `suf`, for the balance bound of those phases; the haptic
feedback of the driven foot leaves on `operator_feedback` (pedi_drake.operator.feedback). The
whole-body controller a switch_controller phase asked for leaves on `controller_request`
(pedi_drake.control.controller_switch). The controllers' ground friction coefficient leaves on
`friction`: the constructor's, until a set_friction phase or the operator (a friction request on
`operator_command`) changes it (`MissionProgress.friction_changes`).

A failed phase (IK unreachable, timeout, fall) fails the mission with a reason; the manager then
places any lifted leg back on the ground ("recovering") and holds the robot standing.

With a `teleop:` block in the mission, the operator's request for the teleoperated mode inserts
a teleop sequence at the next safe point and the mission resumes afterwards
(pedi_drake.mission.mode_switch); every switch is in `MissionProgress.switches`.
"""

import dataclasses

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.math import RotationMatrix
from pydrake.systems.framework import BasicVector

from pedi_drake import robot
from pedi_drake.control import references as controller_refs
from pedi_drake.estimation.base_state import BASE_STATE_SIZE, BaseState
from pedi_drake.estimation.leg_odometry import foot_kinematics_B
from pedi_drake.exceptions import ConfigError, PediError
from pedi_drake.fall import trunk_has_fallen
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.mission import mode_switch, semi_autonomous, spec
from pedi_drake.mission.phases import (
    RUNNERS,
    IkAnswer,
    MissionEnvironment,
    ReachRunner,
    kind_name,
    receive_ik_answers,
)
from pedi_drake.mission.phases import warm_up as warm_up_phases
from pedi_drake.mission.posture_planner import shared_planner
from pedi_drake.mission.progress import (
    FAILED,
    RECOVERING,
    RUNNING,
    STATUS_CODES,
    SUCCEEDED,
    MissionProgress,
    ModeSwitch,
    PhaseRecord,
    References,
    set_friction,
)
from pedi_drake.mission.reference_table import (
    REFERENCES_SIZE,
    body_reference_into,
    leg_reference_into,
    reference_table,
    references_into,
    warm_up,
)
from pedi_drake.mission.robot_view import RobotView
from pedi_drake.mission.stance_polygon import prong_tips_B, stance_safety_polygon
from pedi_drake.operator.command import (
    MODE_AUTONOMOUS,
    MODE_SEMI_AUTONOMOUS,
    MODE_TELEOP,
    OPERATOR_COMMAND_SIZE,
    OperatorCommand,
)
from pedi_drake.operator.feedback import feedback_vector
from pedi_drake.prongs import ProngDesign
from pedi_drake.suf.live import SUF_SIZE, LiveSufReading
from pedi_drake.suf.live_suf_system import suf_request_vector

MISSION_STATUS_SIZE = 4  # [phase index, status code, pedipulation active, number of phases]
MISSION_PERIOD = 0.01  # [s] the manager's update period, unless given
_IDENTITY_POSE = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])


def needs_posture_planner(mission: spec.MissionSpec) -> bool:
    """Whether the mission can ask for an optimal posture (a phase's or the semi-autonomous mode's)
    or a stop chosen by the SUF (a walk_to's)."""
    optimal = any(isinstance(p, spec.LegToPedipulation) and p.posture == "optimal" for p in mission.phases)
    chosen_stop = any(isinstance(p, spec.WalkTo) and p.stop == "suf" for p in mission.phases)
    return optimal or chosen_stop or mission.semi_autonomous is not None


def ik_legs_of(mission: spec.MissionSpec) -> tuple[str, ...]:
    """The legs whose joint angles the mission's phases (and their recovery) ask the IK for."""
    legs = set()
    for phase in mission.phases:
        if isinstance(phase, spec.LegToPedipulation | spec.LegToSupport | spec.TeleopFoot):
            legs.add(phase.leg)
        elif isinstance(phase, spec.Reach):
            legs.update([phase.leg, *(companion.leg for companion in phase.together)])
    if mission.teleop is not None:
        legs.add(mission.teleop.leg)
    if mission.semi_autonomous is not None:
        legs.add(mission.semi_autonomous.leg)
    return tuple(leg for leg in robot.LEG_NAMES if leg in legs)


class MissionManager(LeafSystemWithoutWitnesses):
    """Mission phases -> controller references. Ports: see the module docstring."""

    def __init__(
        self,
        mission: spec.MissionSpec,
        *,
        prongs: ProngDesign | None = None,
        friction: float = 0.8,
        terrain: np.ndarray | None = None,
        safety_margin: float = 0.03,
        period: float = MISSION_PERIOD,
        force_estimate: str = "joint_torque",
        contact_ramp_time: float = 0.3,
        wait_for_plans: bool = True,
    ):
        """
        Args:
            mission: the phases to run.
            prongs: the robot's prongs (their tips count as supports when loaded), or None.
            friction: ground friction coefficient sent to the controller [-].
            terrain: the ground's terrain (pedi_drake.terrain's table; None: flat ground), where
                walks put their feet down and how high they carry the trunk.
            safety_margin: the stance's support polygon is shrunk by this for the capture point [m].
            period: update period [s].
            contact_ramp_time: how long the controller takes to ramp a contact's load in or out [s].
            wait_for_plans: a posture answer later than its due time is waited for (lock-step
                simulation: runs do not depend on the machine's speed) or polled for (real time).
        """
        super().__init__()
        self._mission = mission
        # The posture planner's worker starts here, not in an update (pedi_drake.mission.posture_planner).
        planner = shared_planner() if needs_posture_planner(mission) else None
        self._env = MissionEnvironment(
            prongs, force_estimate, planner, wait_for_plans, contact_ramp_time, friction, terrain
        )
        self._prong_tips_B = prong_tips_B(prongs)
        self._friction = friction
        self._safety_margin = float(safety_margin)
        num_contacts = 4 + self._env.num_prongs
        if num_contacts > controller_refs.SAFETY_POLYGON_MAX_VERTICES:
            raise ConfigError(
                f"robot.prongs: {self._env.num_prongs} prongs; the safety polygon holds at most "
                f"{controller_refs.SAFETY_POLYGON_MAX_VERTICES} supports (four feet and "
                f"{controller_refs.SAFETY_POLYGON_MAX_VERTICES - 4} prong tips)"
            )
        self.ik_legs = ik_legs_of(mission)
        self._period = period
        self._base_state = self.DeclareVectorInputPort("base_state", BASE_STATE_SIZE)
        self._position = self.DeclareVectorInputPort("position_measured", 12)
        self._velocity = self.DeclareVectorInputPort("velocity_measured", 12)
        self._torque = self.DeclareVectorInputPort("torque_estimated", 12)
        self._foot_contact = self.DeclareVectorInputPort("foot_contact", 4)
        # Eq. 11 of paper 002 per foot, world [N] (the projected-impedance controller's
        # `force_estimate` diagnostic); unconnected: only the joint-torque estimate exists.
        self._impedance_force = self.DeclareVectorInputPort("foot_force_estimate", 12)
        # The operator's command (pedi_drake.operator.command); unconnected: no operator.
        self._operator = self.DeclareVectorInputPort("operator_command", OPERATOR_COMMAND_SIZE)
        # The live SUF (pedi_drake.suf.live); unconnected: the balance bound has nothing to act on.
        self._suf = self.DeclareVectorInputPort("suf", SUF_SIZE)
        self._ik_answer_ports = {
            leg: (
                self.DeclareVectorInputPort(f"ik_q_goal.{leg}", 3),
                self.DeclareVectorInputPort(f"ik_solved.{leg}", 1),
                self.DeclareVectorInputPort(f"ik_error.{leg}", 1),
                self.DeclareVectorInputPort(f"ik_target_B.{leg}", 3),
            )
            for leg in self.ik_legs
        }
        self._progress = self.DeclareAbstractState(AbstractValue.Make(MissionProgress()))
        # What the outputs read, written with every progress stored (`_store`); until the first
        # one, the values of a mission that has not started (references: holding the origin).
        holding = References.holding(np.zeros(3), RotationMatrix(), 0.0, self._env.num_prongs)
        self._references = self.DeclareAbstractState(AbstractValue.Make(reference_table(holding)))
        self._polygon = self.DeclareDiscreteState(controller_refs.SAFETY_POLYGON_SIZE)
        self._contacts = self.DeclareDiscreteState(np.concatenate([np.ones(4), np.zeros(self._env.num_prongs)]))
        self._status = self.DeclareDiscreteState(self._status_vector(MissionProgress()))
        self._ik_pose = self.DeclareDiscreteState(_IDENTITY_POSE)
        self._ik_seed = self.DeclareDiscreteState(robot.STANDING_Q)
        self._ik_targets = {leg: self.DeclareDiscreteState(np.full(3, np.nan)) for leg in self.ik_legs}
        self._suf_request = self.DeclareDiscreteState(suf_request_vector(-1, None))
        self._feedback = self.DeclareDiscreteState(feedback_vector(-1, None, np.nan, np.nan, 0, False))
        self._controller_request = self.DeclareDiscreteState(1)
        # The controllers' friction coefficient: the constructor's until a set_friction phase or
        # the operator changes it (MissionProgress.friction).
        self._friction_state = self.DeclareDiscreteState([self._friction])
        self.DeclareInitializationUnrestrictedUpdateEvent(self._initialize)
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._update)
        # Trajectory samples change with time: computed when evaluated, from the packed references.
        samples = {self.time_ticket(), self.abstract_state_ticket(self._references)}
        self.DeclareVectorOutputPort(
            "body_reference", controller_refs.BODY_REFERENCE_SIZE, self._calc_body, prerequisites_of_calc=samples
        )
        self.DeclareVectorOutputPort(
            "leg_reference", controller_refs.LEG_REFERENCE_SIZE, self._calc_legs, prerequisites_of_calc=samples
        )
        self.DeclareVectorOutputPort(
            "references", REFERENCES_SIZE, self._calc_references, prerequisites_of_calc=samples
        )
        self.DeclareStateOutputPort("contact_set", self._contacts)
        self.DeclareStateOutputPort("safety_polygon", self._polygon)
        for leg in self.ik_legs:
            self.DeclareStateOutputPort(f"ik_foot_target_W.{leg}", self._ik_targets[leg])
        self.DeclareStateOutputPort("ik_X_WB", self._ik_pose)
        self.DeclareStateOutputPort("ik_q_seed", self._ik_seed)
        self.DeclareStateOutputPort("friction", self._friction_state)
        self.DeclareStateOutputPort("mission_status", self._status)
        self.DeclareStateOutputPort("suf_request", self._suf_request)
        self.DeclareStateOutputPort("operator_feedback", self._feedback)
        # The whole-body controller the mission asks for (a switch_controller phase; 0: none).
        self.DeclareStateOutputPort("controller_request", self._controller_request)
        warm_up(holding)
        # The stance's safety polygon is made at every update: its kernel is compiled here, not
        # in the first update (on hardware, a first tick late by the compile latches the driver).
        stance_safety_polygon(
            np.array([1.0, 0.0, 0.0, 0.0]),
            np.zeros(3),
            np.array(robot.STANDING_Q),
            np.ones(4 + self._env.num_prongs),
            self._prong_tips_B,
            self._safety_margin,
        )
        # So are the feet's kinematics every RobotView computes, and what the phases call.
        foot_kinematics_B(robot.STANDING_Q)
        warm_up_phases(self._mission, self._env)

    @property
    def mission(self) -> spec.MissionSpec:
        return self._mission

    @property
    def period(self) -> float:
        """Update period [s]."""
        return self._period

    def progress(self, context) -> MissionProgress:
        """The mission's progress in `context` (this system's context)."""
        return context.get_abstract_state(self._progress).get_value()

    # Updates ---------------------------------------------------------------------------------

    def _view(self, context) -> RobotView:
        return RobotView(
            time=context.get_time(),
            base=BaseState.from_vector(self._base_state.Eval(context)),
            q=np.asarray(self._position.Eval(context)),
            qd=np.asarray(self._velocity.Eval(context)),
            tau=np.asarray(self._torque.Eval(context)),
            foot_force=np.asarray(self._foot_contact.Eval(context)),
            impedance_forces=(
                np.asarray(self._impedance_force.Eval(context)).reshape(4, 3)
                if self._impedance_force.HasValue(context)
                else None
            ),
            operator=(
                OperatorCommand.from_vector(self._operator.Eval(context)) if self._operator.HasValue(context) else None
            ),
            suf=LiveSufReading.from_vector(self._suf.Eval(context)) if self._suf.HasValue(context) else None,
        )

    def _initialize(self, context, state) -> None:
        view = self._view(context)
        progress = MissionProgress(phase_start=view.time)
        progress.references = References.holding(view.base.p_WB, view.X_WB.rotation(), view.time, self._env.num_prongs)
        self._store(state, progress)
        # The polygon stays the default (zeros) until the first update: the estimate seen here
        # may not be initialised yet (see `_update`).

    def _store(self, state, progress: MissionProgress, previous: MissionProgress | None = None) -> None:
        """Stores `progress` and what the outputs read of it (the parts that changed since
        `previous`, the progress stored before: the update's state starts as a copy of it)."""
        state.get_mutable_abstract_state(self._progress).set_value(progress)
        refs = progress.references
        if previous is None or not refs.same_trajectories(previous.references):
            state.get_mutable_abstract_state(self._references).set_value(reference_table(refs))
        state.get_mutable_discrete_state(self._contacts).SetFromVector(refs.contacts)
        state.get_mutable_discrete_state(self._status).SetFromVector(self._status_vector(progress))
        state.get_mutable_discrete_state(self._suf_request).SetFromVector(self._suf_request_vector(progress))
        state.get_mutable_discrete_state(self._controller_request).SetFromVector([progress.controller_request])
        friction = self._friction if progress.friction is None else progress.friction
        state.get_mutable_discrete_state(self._friction_state).SetFromVector([friction])
        plan = progress.ik
        if previous is not None and plan is previous.ik:
            return
        state.get_mutable_discrete_state(self._ik_pose).SetFromVector(_IDENTITY_POSE if plan is None else plan.X_WB)
        state.get_mutable_discrete_state(self._ik_seed).SetFromVector(robot.STANDING_Q if plan is None else plan.q_seed)
        for leg, index in self._ik_targets.items():
            state.get_mutable_discrete_state(index).SetFromVector(self._ik_target_W(plan, leg))

    def _set_polygon(self, state, view: RobotView, progress: MissionProgress) -> None:
        """The safety polygon of the stance, and the operator's feedback (both read the view)."""
        base = view.base
        polygon = stance_safety_polygon(
            base.quaternion_wxyz,
            base.p_WB,
            view.q,
            progress.references.contacts,
            self._prong_tips_B,
            self._safety_margin,
        )
        state.get_mutable_discrete_state(self._polygon).SetFromVector(polygon)
        push, suf = progress.push, view.suf
        feedback = feedback_vector(
            -1 if push is None else robot.LEG_NAMES.index(push.leg),
            None if push is None else push.force_W,
            np.nan if push is None else push.limit,
            np.nan if suf is None else suf.value,
            0 if suf is None else suf.status,
            push is not None and push.bound_active,
        )
        state.get_mutable_discrete_state(self._feedback).SetFromVector(feedback)

    @staticmethod
    def _suf_request_vector(progress: MissionProgress) -> np.ndarray:
        """What the live SUF is asked about: the driven foot and its push direction, else the first
        lifted leg (the last worst direction), else nothing."""
        if progress.push is not None:
            return suf_request_vector(robot.LEG_NAMES.index(progress.push.leg), progress.push.direction_W)
        legs = progress.references.legs if progress.references is not None else {}
        lifted = [k for k, leg in enumerate(robot.LEG_NAMES) if leg in legs]
        return suf_request_vector(lifted[0] if lifted else -1, None)

    def _ik_answers(self, context) -> dict[str, IkAnswer]:
        answers = {}
        for leg, (q_goal, solved, error, target_B) in self._ik_answer_ports.items():
            answers[leg] = IkAnswer(
                q=np.asarray(q_goal.Eval(context), float),
                solved=bool(solved.Eval(context)[0] > 0.5),
                error=float(error.Eval(context)[0]),
                target_B=np.asarray(target_B.Eval(context), float),
            )
        return answers

    def _update(self, context, state) -> None:
        previous = self.progress(context)
        progress = previous.copy()
        view = self._view(context)
        if progress.status in (SUCCEEDED, FAILED):
            self._set_polygon(state, view, progress)  # the robot still stands on whatever it stands on
            return
        if view.operator is not None and view.operator.estop:
            self._stop_for_estop(progress, view)
            self._store(state, progress, previous)
            self._set_polygon(state, view, progress)
            return
        if view.operator is not None:
            self._follow_friction_request(progress, view)
        if view.operator is not None and self._mission.teleop is not None:
            self._follow_mode_request(progress, view)
        if view.operator is not None and self._mission.semi_autonomous is not None:
            self._follow_target(progress, view)
        phases = self._phases(progress)
        phase = phases[progress.index]
        runner = RUNNERS[type(phase)]
        outcome = RUNNING
        if not progress.records:
            # The mission starts: hold the pose measured now. At initialisation the estimator's
            # output may not be initialised yet (Drake runs all initialisation events on the
            # same pre-event context), so the references made there can be far off (z = 0).
            progress.references = References.holding(
                view.base.p_WB, view.X_WB.rotation(), view.time, self._env.num_prongs
            )
        if not progress.started:
            progress.started, progress.phase_start, progress.memo = True, view.time, {}
            progress.plan_wait = 0.0
            progress.records.append(PhaseRecord(phase.name, kind_name(phase), RUNNING, view.time))
            try:
                runner.start(phase, progress, view, self._env)
            except PediError as error:
                outcome, progress.reason = FAILED, str(error)
        if outcome == RUNNING:
            try:
                if progress.ik is not None and not progress.ik.done:
                    progress.ik = receive_ik_answers(progress.ik, self._ik_answers(context))
                outcome = runner.step(phase, progress, view, self._env)
            except PediError as error:
                outcome, progress.reason = FAILED, str(error)
        if outcome == RUNNING and progress.phase_time(view.time) > phase.timeout:
            detail = ReachRunner.timeout_reason(phase, progress) if isinstance(phase, spec.Reach) else "not done"
            outcome, progress.reason = FAILED, f"{phase.name}: timed out after {phase.timeout:.1f} s ({detail})"
        if outcome == RUNNING and self._fell(view, progress):
            # The manager sees only the estimate: the judge compares this with what the robot did.
            outcome = FAILED
            progress.reason = (
                f"{phase.name}: the state estimate says the robot fell (trunk height or tilt out of range)"
            )
            progress.records[-1].metrics["estimate_fell"] = True
        if outcome != RUNNING:
            self._finish_phase(progress, phases, outcome, view)
        self._store(state, progress, previous)
        self._set_polygon(state, view, progress)

    def _stop_for_estop(self, progress: MissionProgress, view: RobotView) -> None:
        """The operator's E-stop: the motors are damped (OperatorEstopGate or the driver), so the
        mission fails here, without a recovery (nothing would carry it out)."""
        reason = "operator E-stop: the motors are in damping"
        if progress.records and progress.records[-1].t_end is None:
            record = progress.records[-1]
            record.status, record.t_end, record.reason = FAILED, view.time, reason
        if progress.status == RUNNING:
            # During a teleop sequence the mission's own phase has not (re)started yet.
            first = progress.resume_index if progress.interlude else progress.index + (1 if progress.started else 0)
            for later in self._mission.phases[first:]:
                progress.records.append(PhaseRecord(later.name, kind_name(later), "skipped", view.time))
        progress.interlude = []
        progress.status, progress.reason, progress.started, progress.ik = FAILED, reason, False, None
        progress.references.press, progress.push = None, None

    def _fell(self, view: RobotView, progress: MissionProgress) -> bool:
        standing_started = any(r.kind == "stand_up" and r.status == SUCCEEDED for r in progress.records)
        on_prongs = any(loaded > 0.5 for loaded in progress.references.contacts[4:].tolist())
        return bool(
            trunk_has_fallen(
                view.base.quaternion_wxyz,
                view.base.p_WB[2],
                has_stood=standing_started,
                resting_on_prongs=on_prongs,
            )
        )

    def _finish_phase(self, progress: MissionProgress, phases, outcome: str, view: RobotView) -> None:
        record = progress.records[-1]
        if progress.interlude and isinstance(phases[progress.index], spec.TeleopFoot):
            outcome = self._end_teleop(progress, outcome, view)
        record.status, record.t_end = outcome, view.time
        if outcome == FAILED:
            record.reason = progress.reason
        progress.started, progress.ik, progress.push = False, None, None
        if outcome == SUCCEEDED:
            progress.index += 1
            if progress.index < len(phases):
                return
            if progress.interlude:  # the teleop sequence is done: the interrupted phase restarts
                if progress.interlude_mode == semi_autonomous.SEMI_AUTONOMOUS:
                    self._record_switch(progress, view, semi_autonomous.SEMI_AUTONOMOUS, "target served")
                progress.interlude, progress.index, progress.interlude_mode = [], progress.resume_index, ""
                return
            progress.status = SUCCEEDED if progress.status == RUNNING else FAILED
            return
        if self._refuse_unplannable_target(progress, phases, view):
            return
        # A failure: mark the rest skipped and, once, put lifted legs back down.
        if progress.status == RUNNING:
            first = progress.resume_index if progress.interlude else progress.index + 1
            progress.interlude = []
            for later in self._mission.phases[first:]:
                progress.records.append(PhaseRecord(later.name, kind_name(later), "skipped", view.time))
            lifted = [leg for leg in robot.LEG_NAMES if leg in progress.references.legs]
            progress.references.press = None
            if lifted:
                progress.recovery = [spec.LegToSupport(name=f"recover_{leg}", leg=leg) for leg in lifted]
                progress.status, progress.index = RECOVERING, 0
                return
        progress.status = FAILED

    # Mode switches -----------------------------------------------------------------------------

    def _phases(self, progress: MissionProgress) -> list:
        """The phase list being run: the mission's, a teleop sequence inserted into it, or the recovery."""
        if progress.status != RUNNING:
            return progress.recovery
        return progress.interlude or self._mission.phases

    def _follow_mode_request(self, progress: MissionProgress, view: RobotView) -> None:
        """Takes a change of the operator's mode request; starts a pending teleop at a safe point."""
        block, request = self._mission.teleop, view.operator.mode_request
        if progress.status == RUNNING and request != progress.operator_mode:
            progress.operator_mode = request
            progress.teleop_pending = request == MODE_TELEOP and not progress.interlude
            if request == MODE_AUTONOMOUS and progress.interlude:
                self._drop_teleop_not_started(progress, view)
        if progress.status != RUNNING or not progress.teleop_pending:
            return
        why = mode_switch.safe_point(progress, view, block)
        if why is None:
            return
        interrupted = self._mission.phases[progress.index]
        if progress.started:  # a held foot: the phase is stopped here and restarts afterwards
            record = progress.records[-1]
            record.status, record.t_end, record.reason = "interrupted", view.time, "the operator took the foot"
            progress.started, progress.ik, progress.memo, progress.push = False, None, {}, None
        number = 1 + sum(switch.to_mode == mode_switch.TELEOP for switch in progress.switches)
        lifted = block.leg in progress.references.legs
        progress.interlude = mode_switch.teleop_sequence(block, lifted, view.foot_W(block.leg), number)
        progress.resume_index, progress.index, progress.teleop_pending = progress.index, 0, False
        progress.switches.append(
            ModeSwitch(
                view.time, mode_switch.AUTONOMOUS, mode_switch.TELEOP, f"operator request ({why})", interrupted.name
            )
        )

    def _follow_target(self, progress: MissionProgress, view: RobotView) -> None:
        """Takes a new target of the operator (checked, refused or queued) and starts the queued
        one's sequence at a phase boundary (pedi_drake.mission.semi_autonomous)."""
        block = self._mission.semi_autonomous
        if progress.status != RUNNING:
            return
        if view.operator.mode_request == MODE_SEMI_AUTONOMOUS:
            semi_autonomous.take_target(progress, block, view.operator, view.X_WB, view.time)
        if progress.target_pending is None or block.leg in progress.references.legs:
            return
        why = mode_switch.safe_point(progress, view, block)
        if why is None:
            return
        number = 1 + sum(switch.to_mode == semi_autonomous.SEMI_AUTONOMOUS for switch in progress.switches)
        progress.interlude = semi_autonomous.target_sequence(block, np.array(progress.target_pending), number)
        progress.resume_index, progress.index, progress.target_pending = progress.index, 0, None
        progress.interlude_mode = semi_autonomous.SEMI_AUTONOMOUS
        interrupted = self._mission.phases[progress.resume_index].name
        reason = f"operator target ({why})"
        progress.switches.append(
            ModeSwitch(view.time, mode_switch.AUTONOMOUS, semi_autonomous.SEMI_AUTONOMOUS, reason, interrupted)
        )

    def _record_switch(self, progress: MissionProgress, view: RobotView, from_mode: str, reason: str) -> None:
        """Records the switch back to the autonomous mission at the end of an interlude."""
        resumed = self._mission.phases[progress.resume_index].name
        progress.switches.append(ModeSwitch(view.time, from_mode, mode_switch.AUTONOMOUS, reason, resumed))

    def _refuse_unplannable_target(self, progress: MissionProgress, phases, view: RobotView) -> bool:
        """Whether a failed phase was the semi-autonomous lift still planning (nothing moved: no
        posture reaches the target): the target is then refused and the mission resumes."""
        phase = phases[progress.index]
        lift = progress.memo.get("lift")
        planning = isinstance(phase, spec.LegToPedipulation) and lift is not None and lift.stage == "plan"
        if progress.interlude_mode != semi_autonomous.SEMI_AUTONOMOUS or not planning:
            return False
        progress.records[-1].status = "refused"
        request = progress.target_requests[-1]
        progress.target_requests[-1] = dataclasses.replace(request, accepted=False, reason=progress.reason)
        progress.reason = ""
        self._record_switch(progress, view, semi_autonomous.SEMI_AUTONOMOUS, "target refused: no posture reaches it")
        progress.interlude, progress.index, progress.interlude_mode = [], progress.resume_index, ""
        return True

    def _drop_teleop_not_started(self, progress: MissionProgress, view: RobotView) -> None:
        """The operator asked for the autonomous mode before the teleop phase began: it is left
        out (the switch says so; the leg is still put back by the rest of the sequence)."""
        for k in range(progress.index + (1 if progress.started else 0), len(progress.interlude)):
            if isinstance(progress.interlude[k], spec.TeleopFoot):
                progress.interlude = progress.interlude[:k] + progress.interlude[k + 1 :]
                progress.switches.append(
                    ModeSwitch(
                        view.time,
                        mode_switch.TELEOP,
                        mode_switch.AUTONOMOUS,
                        "operator request (before the foot was taken)",
                        self._mission.phases[progress.resume_index].name,
                    )
                )
                return

    def _end_teleop(self, progress: MissionProgress, outcome: str, view: RobotView) -> str:
        """Records the switch back to autonomous at the end of an inserted teleop_foot phase; the
        outcome to record. Operator silence ends the teleoperation, not the mission: the foot has
        held and the rest of the sequence returns it."""
        metrics = progress.records[-1].metrics
        ended_by = metrics.get("ended_by", "")
        if outcome == FAILED and ended_by == "operator_silence":
            metrics["silence"] = progress.reason
            outcome, progress.reason = SUCCEEDED, ""
        if outcome == SUCCEEDED:
            reason = {"operator": "operator request", "operator_silence": "operator silence"}.get(ended_by, ended_by)
            progress.switches.append(
                ModeSwitch(
                    view.time,
                    mode_switch.TELEOP,
                    mode_switch.AUTONOMOUS,
                    reason,
                    self._mission.phases[progress.resume_index].name,
                )
            )
        return outcome

    # Outputs ---------------------------------------------------------------------------------

    def _calc_body(self, context, output: BasicVector) -> None:
        table = context.get_abstract_state(self._references).get_value()
        body_reference_into(table.body, context.get_time(), output.get_mutable_value())

    def _calc_legs(self, context, output: BasicVector) -> None:
        table = context.get_abstract_state(self._references).get_value()
        leg_reference_into(table.legs, context.get_time(), output.get_mutable_value())

    def _calc_references(self, context, output: BasicVector) -> None:
        table = context.get_abstract_state(self._references).get_value()
        references_into(table.body, table.legs, context.get_time(), output.get_mutable_value())

    @staticmethod
    def _ik_target_W(plan, leg: str) -> np.ndarray:
        """The world-frame foot target `leg` is asked for; NaN when nothing is asked."""
        p_B = plan.pending(leg) if plan is not None else None
        if p_B is None:
            return np.full(3, np.nan)
        pose = BaseState(plan.X_WB[0:4], plan.X_WB[4:7], np.zeros(3), np.zeros(3)).pose()
        return pose @ p_B

    @staticmethod
    def _follow_friction_request(progress: MissionProgress, view: RobotView) -> None:
        """A new friction coefficient from the operator (its input checked the range) is given
        to the controllers at once, in any mode: it is a fact about the ground, not a motion."""
        request = view.operator.friction_request
        if request != 0.0 and request != progress.operator_friction:
            set_friction(progress, request, view.time, "operator")
        progress.operator_friction = request

    def _status_vector(self, progress: MissionProgress) -> list[float]:
        """The `mission_status` vector of `progress`."""
        active = 1.0 if progress.references is not None and progress.references.legs else 0.0
        index = progress.resume_index if progress.interlude else progress.index
        return [index, STATUS_CODES[progress.status], active, len(self._mission.phases)]
