"""The oracle of the compiled whole-body tick (pedi_drake.control.whole_body_tick): the same tick
in numpy, composed of the reference stacks, tasks and hierarchical QP of this folder and of the
controller model's Drake dynamics (`ControllerModel.update`).

`ReferenceTick(controller).update(context, discrete_state)` computes what
`WholeBodyController`'s periodic update computes, from the same context, into the same discrete
state layout; tests/test_compiled_controller.py runs both at every tick of simulated missions.
"""

import time

import numpy as np
import reference_tasks as tasks
from pydrake.systems.framework import Context, DiscreteValues
from reference_hqp import solve_hqp, solve_weighted
from reference_stacks import ResolvedInputs, StackBuilder

from pedi_drake import robot
from pedi_drake.control import references
from pedi_drake.control.tick_steps import STATUS_BAD_INPUT, STATUS_CONTACTS_RELAXED, STATUS_OK, STATUS_QP_FAILED
from pedi_drake.control.whole_body_controller import MAX_LEVELS, WholeBodyController
from pedi_drake.dynamics.go1_dynamics import add_trunk_external_wrench
from pedi_drake.exceptions import PediError, QpInfeasible
from pedi_drake.go1_command import held_command
from pedi_drake.polygon import polygon_halfplanes
from pedi_drake.vector3 import orientation_error_W


def _all_finite(*arrays: np.ndarray) -> bool:
    return bool(np.isfinite(np.concatenate(arrays)).all())


def _clip(x: np.ndarray, lower, upper) -> np.ndarray:
    return np.minimum(np.maximum(x, lower), upper)


class ReferenceTick:
    """The whole-body tick of `controller` in numpy (its ports, state indices and model)."""

    def __init__(self, controller: WholeBodyController) -> None:
        self.controller = controller
        self.config = controller.config
        self.model = controller.model
        self.diag = controller.diag
        nc = controller.num_contacts
        self.layout = tasks.VariableLayout(self.model.nv, nc, self.model.plant_map.v_index)
        self.builder = StackBuilder(self.config, self.layout, self.model.total_mass)
        self.hqp_settings = controller.hqp_settings
        self.command_gains = np.concatenate([np.full(12, self.config.joint_kp), np.full(12, self.config.joint_kd)])
        self.default_contact_set = controller.default_contact_set
        for name in (
            "base_state_port",
            "position_port",
            "velocity_port",
            "body_reference_port",
            "leg_reference_port",
            "contact_set_port",
            "safety_polygon_port",
            "friction_port",
            "trunk_wrench_port",
            "command_state",
            "reference_state",
            "ramp_state",
            "hold_state",
            "diagnostics_state",
        ):
            setattr(self, name, getattr(controller, name))

    def _optional(self, port, context: Context, default: np.ndarray) -> np.ndarray:
        return np.asarray(port.Eval(context), float) if port.HasValue(context) else default

    def update(self, context: Context, discrete_state: DiscreteValues) -> None:
        """The tick: the controller's next discrete state into `discrete_state`."""
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
