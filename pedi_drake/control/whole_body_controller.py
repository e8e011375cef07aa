"""WholeBodyController: the task-priority QP controller as a Drake LeafSystem.

Every `period` [s] a discrete update reads the state estimate, the measured joints and the task
references, builds the configured stack (`stacks.py`) on the controller's own plant
(`robot_model.py`), solves it with the hierarchical QP (`hqp.py`) and stores the next
`go1.command` in the Context; the `command` output is that state (a zero-order hold).

Inputs (all numeric vectors; reference layouts in `pedi_drake.control.references`):
    base_state (13)         floating-base estimate [quat wxyz, p_WB, w_WB, v_WB], world frame
    position_measured (12)  joint angles [rad], Unitree order
    velocity_measured (12)  joint rates [rad/s], Unitree order
    body_reference (19)     trunk pose trajectory sample; unconnected: hold the first-tick pose
    leg_reference (48)      per-leg foot / joint references; unconnected: no leg task
    contact_set (4 + prongs) loaded contacts 0/1; unconnected: the four feet
    safety_polygon (20)     capture-point polygon (vertices in its frame); unconnected or n = 0:
                            the support polygon of the loaded contacts shrunk by `safety_margin`
    friction (1)            ground friction coefficient; unconnected: `config.friction`
Outputs:
    command (60)            go1.command: q_des, qd_des, kp, kd, tau_ff (Unitree order)
    diagnostics             see DIAGNOSTICS_LAYOUT

Discrete state (nothing that changes lives in Python members): the command, the integrated
joint reference (q, qd), the contact ramps, the held trunk pose, the diagnostics.

Commands: tau_ff is the QP's torque (tau = M_a vdot + h_a - J_a^T f); q_des, qd_des integrate the
QP's joint accelerations (kept near the measurement) under low PD gains, so the motor PD only
corrects what the feed-forward misses. A failed QP or a non-finite input never emits NaN: the
last good command is held with zero velocity target and `failure_kd` damping, and reported.
"""

import time

import numpy as np
from pydrake.systems.framework import Context, DiscreteValues

from pedi_drake import robot
from pedi_drake.control import compiled_stack, references, tasks, whole_body_tick
from pedi_drake.control.config import HQP_MODES, QP_BACKENDS, STACKS, WholeBodyControllerConfig
from pedi_drake.control.go1_dynamics import add_trunk_external_wrench
from pedi_drake.control.hqp import HqpSettings, solve_hqp, solve_weighted
from pedi_drake.control.robot_model import ControllerModel
from pedi_drake.control.stacks import ResolvedInputs, StackBuilder
from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.exceptions import ConfigError, PediError, QpInfeasible
from pedi_drake.go1_command import held_command, initial_command
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.polygon import polygon_halfplanes
from pedi_drake.prongs import ProngDesign
from pedi_drake.runtime.jit import new_record
from pedi_drake.vector3 import orientation_error_W

STATUS_OK, STATUS_QP_FAILED, STATUS_BAD_INPUT = 0.0, 1.0, 2.0
# Solved with sliding contacts' tangential no-motion below the force limits (see StackBuilder.levels).
STATUS_CONTACTS_RELAXED = 3.0
MAX_LEVELS = 5


def diagnostics_layout(num_contacts: int) -> dict[str, slice]:
    """Named slices of the diagnostics vector."""
    sizes = [
        ("status", 1),  # 0 ok, 1 QP failed (last command held), 2 non-finite input, 3 contacts relaxed
        ("solve_time", 1),  # wall time of the HQP solve [s]
        ("tick_time", 1),  # wall time of the whole update [s]
        ("consecutive_failures", 1),
        ("total_failures", 1),
        ("capture_point", 2),  # [m], world xy
        ("trunk_position_error", 3),  # p_ref - p [m]
        ("trunk_orientation_error", 3),  # rotation vector of R_ref R^T [rad]
        ("foot_errors", 4),  # |p_ref - p_foot| of legs in foot mode, else 0 [m]
        ("level_residuals", MAX_LEVELS),  # equality residual per level (padded)
        ("contact_forces", 3 * num_contacts),  # [N], world frame
        ("tau_ff", 12),  # [N m]
        ("contact_ramp", num_contacts),  # [-]
    ]
    layout, start = {}, 0
    for name, size in sizes:
        layout[name] = slice(start, start + size)
        start += size
    return layout


def _all_finite(*arrays: np.ndarray) -> bool:
    """Whether every entry of every array is finite (one isfinite over them all: the cheapest test
    at these sizes, and it runs twice a tick)."""
    return bool(np.isfinite(np.concatenate(arrays)).all())


def _clip(x: np.ndarray, lower, upper) -> np.ndarray:
    """np.clip without its dispatch overhead (several microseconds on 12-vectors)."""
    return np.minimum(np.maximum(x, lower), upper)


class WholeBodyController(LeafSystemWithoutWitnesses):
    """Hierarchical whole-body QP controller for the Go1 (and its prongs)."""

    def __init__(self, config: WholeBodyControllerConfig, prongs: ProngDesign | None = None) -> None:
        super().__init__()
        if config.stack not in STACKS:
            raise ConfigError(f"whole_body.stack: must be one of {STACKS}, got {config.stack!r}")
        if config.hqp_mode not in HQP_MODES:
            raise ConfigError(f"whole_body.hqp_mode: must be one of {HQP_MODES}, got {config.hqp_mode!r}")
        if config.qp_backend not in QP_BACKENDS:
            raise ConfigError(f"whole_body.qp_backend: must be one of {QP_BACKENDS}, got {config.qp_backend!r}")
        if not config.period > 0.0:
            raise ConfigError(f"whole_body.period: must be > 0 s, got {config.period!r}")
        self.config = config
        # Constant after construction: the model (its scratch context is rewritten every tick).
        self.model = ControllerModel(prongs, com_bias=config.balance_com_bias)
        nc = self.model.num_contacts
        self.num_contacts = nc
        self.layout = tasks.VariableLayout(self.model.nv, nc, self.model.plant_map.v_index)
        self.builder = StackBuilder(config, self.layout, self.model.total_mass)
        self.hqp_settings = HqpSettings(backend=config.qp_backend)
        if config.level_weights and len(config.level_weights) != self.builder.num_levels:
            raise ConfigError(
                f"whole_body.level_weights: the {config.stack} stack has {self.builder.num_levels} levels, "
                f"got {len(config.level_weights)} weights"
            )
        self.diag = diagnostics_layout(nc)
        self.command_gains = np.concatenate([np.full(12, config.joint_kp), np.full(12, config.joint_kd)])
        self.default_contact_set = references.contact_set_vector(num_prongs=nc - 4)
        self.compiled = config.qp_backend == "compiled"
        if self.compiled:
            self._compiled_records()
        # What an unconnected optional input reads as in the compiled tick, which only reads them
        # (writable all the same: a read-only array is another argument type, another compilation).
        self._no_body = np.zeros(references.BODY_REFERENCE_SIZE)
        self._no_leg_reference = np.zeros(references.LEG_REFERENCE_SIZE)
        self._no_safety_polygon = np.zeros(references.SAFETY_POLYGON_SIZE)
        self._default_friction = np.array([config.friction])
        self._no_trunk_wrench = np.zeros(6)

        self.base_state_port = self.DeclareVectorInputPort("base_state", BASE_STATE_SIZE)
        self.position_port = self.DeclareVectorInputPort("position_measured", 12)
        self.velocity_port = self.DeclareVectorInputPort("velocity_measured", 12)
        self.body_reference_port = self.DeclareVectorInputPort("body_reference", references.BODY_REFERENCE_SIZE)
        self.leg_reference_port = self.DeclareVectorInputPort("leg_reference", references.LEG_REFERENCE_SIZE)
        self.contact_set_port = self.DeclareVectorInputPort("contact_set", nc)
        self.safety_polygon_port = self.DeclareVectorInputPort("safety_polygon", references.SAFETY_POLYGON_SIZE)
        self.friction_port = self.DeclareVectorInputPort("friction", 1)
        # An external wrench on the trunk the model lacks, [torque; force] at the trunk origin,
        # world [N m, N] (a carried load: pedi_drake.control.trunk_load_compensation); zero unconnected.
        self.trunk_wrench_port = self.DeclareVectorInputPort("trunk_external_wrench", 6)

        self.command_state = self.DeclareDiscreteState(initial_command(config.failure_kd))
        self.reference_state = self.DeclareDiscreteState(24)  # q_ref (12), qd_ref (12)
        self.ramp_state = self.DeclareDiscreteState(nc)
        self.hold_state = self.DeclareDiscreteState(8)  # initialised flag, p_WB (3), quat (4)
        self.diagnostics_state = self.DeclareDiscreteState(self.diag["contact_ramp"].stop)
        # The discrete states in the compiled tick's argument order.
        self._state_indices = (
            self.command_state,
            self.reference_state,
            self.ramp_state,
            self.hold_state,
            self.diagnostics_state,
        )
        self.DeclarePeriodicDiscreteUpdateEvent(config.period, 0.0, self._update)
        # The same tick on demand (CalcForcedDiscreteVariableUpdate): tests and the benchmark.
        self.DeclareForcedDiscreteUpdateEvent(self._update)
        self.command_port = self.DeclareStateOutputPort("command", self.command_state)
        self.diagnostics_port = self.DeclareStateOutputPort("diagnostics", self.diagnostics_state)
        if self.compiled:
            self._warm_up()

    def _warm_up(self) -> None:
        """Compiles (or loads from numba's cache) the compiled tick for the argument types of a
        real tick, by running one on a scratch context: never inside a control tick."""
        context = self.CreateDefaultContext()
        standing = np.array(
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, robot.trunk_height_for(robot.STANDING_Q[1], robot.STANDING_Q[2])] + [0.0] * 6
        )
        self.base_state_port.FixValue(context, standing)
        self.position_port.FixValue(context, robot.STANDING_Q)
        self.velocity_port.FixValue(context, np.zeros(12))
        self._update_compiled(context, self.AllocateDiscreteVariables())

    def _compiled_records(self) -> None:
        """The compiled tick's constant records and its workspaces (a snapshot, a row table)."""
        nv, nc = self.model.nv, self.num_contacts
        self._stack_params = compiled_stack.stack_params(
            self.config, self.layout.v_joints, nv, nc, self.model.total_mass
        )
        self._tick_params = whole_body_tick.tick_params(self.config, self.hqp_settings, self.diag, MAX_LEVELS)
        self._snapshot = self.model.dynamics.new_output()
        self._table = new_record(compiled_stack.table_dtype(nv, nc))

    def _update_compiled(self, context: Context, discrete_state: DiscreteValues) -> None:
        start = time.perf_counter()
        # A vector port's Eval is already a contiguous float64 array (no np.asarray a tick).
        base = self.base_state_port.Eval(context)
        q = self.position_port.Eval(context)
        qd = self.velocity_port.Eval(context)
        has_body = self.body_reference_port.HasValue(context)
        body = self.body_reference_port.Eval(context) if has_body else self._no_body
        contact_set = self._evaluated(self.contact_set_port, context, self.default_contact_set)
        leg_x = self._evaluated(self.leg_reference_port, context, self._no_leg_reference)
        polygon_x = self._evaluated(self.safety_polygon_port, context, self._no_safety_polygon)
        mu_x = self._evaluated(self.friction_port, context, self._default_friction)
        trunk_wrench = self._evaluated(self.trunk_wrench_port, context, self._no_trunk_wrench)
        # The framework hands the update the current state: the tick updates it in place.
        get = discrete_state.get_mutable_value
        state = [get(index) for index in self._state_indices]
        solve_start = time.perf_counter()
        whole_body_tick.whole_body_tick(
            self._tick_params,
            self._stack_params,
            self.model.dynamics.model_record,
            self._snapshot,
            base,
            q,
            qd,
            contact_set,
            body,
            has_body,
            leg_x,
            polygon_x,
            mu_x,
            trunk_wrench,
            self._table,
            *state,
        )
        diag = state[-1]
        now = time.perf_counter()
        diag[self.diag["solve_time"]] = now - solve_start
        diag[self.diag["tick_time"]] = now - start

    # ---------------------------------------------------------------------------------------------
    def _optional(self, port, context: Context, default: np.ndarray) -> np.ndarray:
        return np.asarray(port.Eval(context), float) if port.HasValue(context) else default

    @staticmethod
    def _evaluated(port, context: Context, default: np.ndarray) -> np.ndarray:
        """The port's value, or `default`."""
        return port.Eval(context) if port.HasValue(context) else default

    def _update(self, context: Context, discrete_state: DiscreteValues) -> None:
        if self.compiled:
            self._update_compiled(context, discrete_state)
            return
        start = time.perf_counter()
        c = self.config
        base = np.asarray(self.base_state_port.Eval(context), float)
        q = np.asarray(self.position_port.Eval(context), float)
        qd = np.asarray(self.velocity_port.Eval(context), float)
        hold = context.get_discrete_state(self.hold_state).value().copy()
        ramp = context.get_discrete_state(self.ramp_state).value().copy()
        q_ref = context.get_discrete_state(self.reference_state).value()[:12].copy()
        qd_ref = context.get_discrete_state(self.reference_state).value()[12:].copy()
        last_command = context.get_discrete_state(self.command_state).value().copy()
        diag = context.get_discrete_state(self.diagnostics_state).value().copy()

        contact_set = _clip(self._optional(self.contact_set_port, context, self.default_contact_set), 0.0, 1.0)
        if not _all_finite(base, q, qd, contact_set):
            self._fail(discrete_state, last_command, q, diag, STATUS_BAD_INPUT, start)
            return
        if hold[0] == 0.0:
            # First tick: hold the current trunk pose, start the reference at the measurement and
            # the contact ramps at the commanded contact set (the robot starts on its feet).
            hold = np.concatenate([[1.0], base[4:7], base[0:4]])
            q_ref, qd_ref = q.copy(), qd.copy()
            ramp = contact_set.copy()
        step = c.period / max(c.contact_ramp_time, 1e-9)
        ramp = _clip(ramp + _clip(contact_set - ramp, -step, step), 0.0, 1.0)

        default_body = np.concatenate([hold[1:4], hold[4:8], np.zeros(12)])
        body_x = self._optional(self.body_reference_port, context, default_body)
        leg_x = self._optional(self.leg_reference_port, context, np.zeros(references.LEG_REFERENCE_SIZE))
        polygon_x = self._optional(self.safety_polygon_port, context, np.zeros(references.SAFETY_POLYGON_SIZE))
        mu_x = self._optional(self.friction_port, context, np.array([c.friction]))
        trunk_wrench = self._optional(self.trunk_wrench_port, context, np.zeros(6))
        if not _all_finite(body_x, leg_x, polygon_x, mu_x, trunk_wrench) or mu_x[0] <= 0.0:
            self._fail(discrete_state, last_command, q, diag, STATUS_BAD_INPUT, start)
            return
        try:
            polygon_W = references.safety_polygon_vertices_W(polygon_x)
        except PediError:  # a vertex count the layout does not allow
            self._fail(discrete_state, last_command, q, diag, STATUS_BAD_INPUT, start)
            return

        snapshot = self.model.update(base, q, qd)
        add_trunk_external_wrench(snapshot.h, snapshot.J_trunk, trunk_wrench)
        legs = references.parse_leg_reference(leg_x)
        for i, leg in enumerate(legs):
            if leg.mode in references.CALF_ORIENTATION_ROWS:
                snapshot.calf_orientations[i] = self.model.calf_orientation(i)
        no_motion = (contact_set > 0.5) | (ramp > 0.0)
        loaded = contact_set > 0.5
        num_loaded = int(np.count_nonzero(loaded))
        if num_loaded:
            ground = float(snapshot.p_contacts[loaded, 2].sum()) / num_loaded - robot.FOOT_RADIUS
        else:
            ground = 0.0
        if polygon_W is not None:
            N, d = polygon_halfplanes(polygon_W, 0.0)
        elif num_loaded >= 3:
            N, d = polygon_halfplanes(snapshot.p_contacts[loaded, :2], c.safety_margin)
        else:
            N, d = np.zeros((0, 2)), np.zeros(0)
        inputs = ResolvedInputs(
            body=references.parse_body_reference(body_x),
            legs=legs,
            ramp=ramp,
            no_motion=no_motion,
            polygon_N=N,
            polygon_d=d,
            friction=float(mu_x[0]),
            ground_height=ground,
        )
        status = STATUS_OK
        try:
            solution = self._solve(snapshot, inputs, relax_contacts=False)
        except (QpInfeasible, np.linalg.LinAlgError):
            try:
                if not len(self.builder.sliding_contacts(snapshot, inputs)):
                    raise QpInfeasible("infeasible with every contact at rest")
                # Sliding contacts that friction cannot stop at once: let them brake.
                solution = self._solve(snapshot, inputs, relax_contacts=True)
                status = STATUS_CONTACTS_RELAXED
            except (QpInfeasible, np.linalg.LinAlgError):
                self._fail(discrete_state, last_command, q, diag, STATUS_QP_FAILED, start, ramp=ramp, hold=hold)
                return
        x = solution.x

        vdot, forces = self.layout.split(x)
        T, t0 = tasks.torque_map(snapshot, self.layout)
        tau = T @ x + t0
        qdd = vdot[self.layout.v_joints]
        # Integrate the QP's accelerations into the joint reference, kept near the measurement so
        # a long stall (e.g. contact with an obstacle) cannot wind up the PD.
        qd_ref = _clip(
            qd_ref + qdd * c.period, qd - c.max_reference_rate_deviation, qd + c.max_reference_rate_deviation
        )
        q_ref = _clip(q_ref + qd_ref * c.period, q - c.max_reference_deviation, q + c.max_reference_deviation)
        command = np.concatenate([q_ref, qd_ref, self.command_gains, tau])

        diag[self.diag["status"]] = status
        diag[self.diag["solve_time"]] = solution.solve_time
        diag[self.diag["consecutive_failures"]] = 0.0
        xi, _ = self.builder.balance.capture_point(snapshot, ground)
        diag[self.diag["capture_point"]] = xi
        diag[self.diag["trunk_position_error"]] = inputs.body.p - snapshot.p_WB
        diag[self.diag["trunk_orientation_error"]] = orientation_error_W(inputs.body.R, snapshot.R_WB)
        foot_errors = np.zeros(4)
        for i, leg in enumerate(inputs.legs):
            if leg.mode == references.LEG_MODE_FOOT:
                foot_errors[i] = np.linalg.norm(leg.position - snapshot.p_contacts[i])
        diag[self.diag["foot_errors"]] = foot_errors
        residuals = np.zeros(MAX_LEVELS)
        residuals[: min(MAX_LEVELS, len(solution.equality_residuals))] = solution.equality_residuals[:MAX_LEVELS]
        diag[self.diag["level_residuals"]] = residuals
        diag[self.diag["contact_forces"]] = forces.ravel()
        diag[self.diag["tau_ff"]] = tau
        diag[self.diag["contact_ramp"]] = ramp
        diag[self.diag["tick_time"]] = time.perf_counter() - start

        discrete_state.get_mutable_vector(self.command_state).SetFromVector(command)
        discrete_state.get_mutable_vector(self.reference_state).SetFromVector(np.concatenate([q_ref, qd_ref]))
        discrete_state.get_mutable_vector(self.ramp_state).SetFromVector(ramp)
        discrete_state.get_mutable_vector(self.hold_state).SetFromVector(hold)
        discrete_state.get_mutable_vector(self.diagnostics_state).SetFromVector(diag)

    def _solve(self, snapshot, inputs: ResolvedInputs, relax_contacts: bool):
        """The configured stack at this instant, solved (strict or weighted); raises QpInfeasible."""
        c = self.config
        levels = self.builder.levels(snapshot, inputs, relax_contacts=relax_contacts)
        if c.hqp_mode == "weighted":
            weights = list(c.level_weights)
            if weights and relax_contacts:
                weights.insert(2, weights[1])  # the demoted contacts weigh as the limits' level
            weights = weights or [100.0 ** (len(levels) - 1 - k) for k in range(len(levels))]
            solution = solve_weighted(levels, self.layout.size, weights, self.hqp_settings)
        else:
            solution = solve_hqp(levels, self.layout.size, self.hqp_settings)
        if not _all_finite(solution.x):
            raise QpInfeasible("non-finite QP solution")
        return solution

    def _fail(
        self,
        discrete_state: DiscreteValues,
        last_command: np.ndarray,
        q: np.ndarray,
        diag: np.ndarray,
        status: float,
        start: float,
        ramp: np.ndarray | None = None,
        hold: np.ndarray | None = None,
    ) -> None:
        """Holds the last good command with zero velocity target and damping; records the failure."""
        command = held_command(last_command, q, self.config.failure_kd)
        diag[self.diag["status"]] = status
        diag[self.diag["consecutive_failures"]] += 1.0
        diag[self.diag["total_failures"]] += 1.0
        diag[self.diag["tick_time"]] = time.perf_counter() - start
        discrete_state.get_mutable_vector(self.command_state).SetFromVector(command)
        discrete_state.get_mutable_vector(self.diagnostics_state).SetFromVector(diag)
        if ramp is not None:
            discrete_state.get_mutable_vector(self.ramp_state).SetFromVector(ramp)
        if hold is not None:
            discrete_state.get_mutable_vector(self.hold_state).SetFromVector(hold)
