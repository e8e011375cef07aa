"""The oracle of paper 002's compiled tick (pedi_drake.control.projected_impedance_tick): the same
tick in numpy on the reference control law (reference_projected_dynamics) and the controller
model's Drake dynamics (`ControllerModel.update`).

`ReferenceTick(controller).update(context, discrete_state)` computes what
`ProjectedImpedanceController`'s periodic update computes, from the same context, into the same
discrete state layout; tests/test_projected_impedance_tick.py runs both side by side.
"""

import time

import numpy as np
import reference_projected_dynamics as pd
import reference_tasks as tasks
from pydrake.systems.framework import Context, DiscreteValues

from pedi_drake import robot
from pedi_drake.control import references
from pedi_drake.control.projected_impedance_controller import ProjectedImpedanceController
from pedi_drake.control.robot_model import RobotSnapshot
from pedi_drake.control.tick_steps import STATUS_BAD_INPUT, STATUS_CONTACTS_RELAXED, STATUS_OK, STATUS_QP_FAILED
from pedi_drake.dynamics.go1_dynamics import add_trunk_external_wrench
from pedi_drake.exceptions import QpInfeasible
from pedi_drake.friction import pyramid_slope
from pedi_drake.go1_command import held_command
from pedi_drake.leg_kinematics import foot_jacobian_B, foot_position_B
from pedi_drake.vector3 import axis_angle_matrix, cross3, orientation_error_W


def _all_finite(*arrays: np.ndarray) -> bool:
    return bool(np.isfinite(np.concatenate(arrays)).all())


def _clip(x: np.ndarray, lower, upper) -> np.ndarray:
    return np.minimum(np.maximum(x, lower), upper)


def _skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def joint_reference_in_world(
    leg: str, s: RobotSnapshot, leg_ref: references.LegReference
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(p, v, a) of the foot a joint reference means on the trunk as it is [m, m/s, m/s^2].

    p = p_WB + R p_BF(q), v = v_WB + w x R p_BF + R J(q) qd, a = a_WB + R J(q) qdd with the
    estimated trunk pose and velocity (the terms quadratic in the rates, and the trunk's
    acceleration, are left out: they only feed forward). A joint reference is the mission's IK
    answer in the trunk frame, so it moves with the trunk: the foot error is the leg's own.
    """
    p_B = foot_position_B(leg, leg_ref.position)
    J_B = foot_jacobian_B(leg, leg_ref.position)
    r_W = s.R_WB @ p_B
    w, v = s.V_trunk[:3], s.V_trunk[3:]
    p = s.p_WB + r_W
    velocity = v + cross3(w, r_W) + s.R_WB @ (J_B @ leg_ref.velocity)
    a = s.R_WB @ (J_B @ leg_ref.acceleration)
    return p, velocity, a


class ReferenceTick:
    """Paper 002's tick of `controller` in numpy (its ports, state indices and model)."""

    def __init__(self, controller: ProjectedImpedanceController) -> None:
        config = controller.config
        self.config = config
        self.model = controller.model
        self.diag = controller.diag
        self.num_contacts = controller.num_contacts
        self.default_contact_set = controller.default_contact_set
        nv = self.model.nv
        self.v_index = np.asarray(self.model.plant_map.v_index)
        mask = np.ones(nv, dtype=bool)
        mask[self.v_index] = False
        self.unactuated = np.flatnonzero(mask)
        self.S = np.zeros((12, nv))  # tau -> generalised force: S^T tau
        self.S[np.arange(12), self.v_index] = 1.0
        self.total_weight = self.model.total_mass * robot.GRAVITY
        self.nominal_q = np.tile(np.asarray(config.nominal_leg_posture, float), 4)
        self.foot_stiffness = np.asarray(config.foot_stiffness, float)
        self.foot_damping = np.asarray(config.foot_damping, float)
        self.balance = tasks.CapturePointBalance()
        self.command_gains = np.concatenate([np.full(12, config.joint_kp), np.full(12, config.joint_kd)])
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
            "estimate_state",
            "diagnostics_state",
        ):
            setattr(self, name, getattr(controller, name))

    def _optional(self, port, context: Context, default: np.ndarray) -> np.ndarray:
        return np.asarray(port.Eval(context), float) if port.HasValue(context) else default

    def _impedance_tasks(
        self, s: RobotSnapshot, legs: list[references.LegReference], held: np.ndarray
    ) -> tuple[list[pd.ImpedanceTask], dict[int, slice]]:
        """The first-priority tasks and, per leg with a foot impedance, its rows in the stack."""
        c = self.config
        impedance, foot_rows, row = [], {}, 0
        for i, (leg, ref) in enumerate(zip(robot.LEG_NAMES, legs, strict=True)):
            if held[i]:
                continue
            if ref.mode in (references.LEG_MODE_FOOT, references.LEG_MODE_JOINTS, *references.CALF_ORIENTATION_ROWS):
                if ref.mode == references.LEG_MODE_JOINTS:
                    p_ref, v_ref, a_ref = joint_reference_in_world(leg, s, ref)
                elif ref.mode == references.LEG_MODE_FOOT:
                    p_ref, v_ref, a_ref = ref.position, ref.velocity, ref.acceleration
                else:
                    p_ref, v_ref, a_ref = ref.position, ref.velocity, np.zeros(3)
                rows = slice(3 * i, 3 * i + 3)
                J = s.J_contacts[rows]
                task = pd.ImpedanceTask(
                    f"foot_{leg}",
                    J,
                    s.Jdot_v_contacts[rows],
                    s.p_contacts[i] - p_ref,
                    J @ s.v - v_ref,
                    a_ref,
                    self.foot_stiffness,
                    self.foot_damping,
                )
                if ref.mode in references.CALF_ORIENTATION_ROWS:
                    axes = references.CALF_ORIENTATION_ROWS[ref.mode]
                    task = pd.stack_impedance_tasks([task, self._calf_task(s, i, leg, ref, axes)], self.model.nv)
                impedance.append(task)
                foot_rows[i] = slice(row, row + 3)
                row += task.J.shape[0]
                continue
            # A lifted leg without a reference: a joint impedance to the nominal posture.
            joints = np.arange(3 * i, 3 * i + 3)
            J = self.S[joints]
            impedance.append(
                pd.ImpedanceTask(
                    f"idle_{leg}",
                    J,
                    np.zeros(3),
                    s.q_joints[joints] - self.nominal_q[joints],
                    s.v_joints[joints],
                    np.zeros(3),
                    np.full(3, c.idle_leg_stiffness),
                    np.full(3, c.idle_leg_damping),
                )
            )
            row += 3
        return impedance, foot_rows

    def _calf_task(
        self, s: RobotSnapshot, i: int, leg: str, ref: references.LegReference, axes: int
    ) -> pd.ImpedanceTask:
        """The orientation rows of the foot-pose tasks: the calf's rotation towards the reference
        about world x and y (roll and pitch; the 5-D task, `axes` 2, the yaw left free) or about
        all three axes (the 6-D shank task, `axes` 3)."""
        c = self.config
        R_WC, J_w, bias_w = self.model.calf_orientation(i)
        R_ref = axis_angle_matrix(ref.acceleration)
        error = -orientation_error_W(R_ref, R_WC)  # e = x - x_ref, as a rotation vector
        return pd.ImpedanceTask(
            f"calf_{leg}",
            J_w[:axes],
            bias_w[:axes],
            error[:axes],
            (J_w @ s.v)[:axes],
            np.zeros(axes),
            np.full(axes, c.foot_orientation_stiffness),
            np.full(axes, c.foot_orientation_damping),
        )

    def _lower_tasks(
        self, s: RobotSnapshot, body: references.BodyReference, attitude_first: bool
    ) -> list[pd.AccelerationTask]:
        """The trunk's tasks and the posture, in the feet's null space. The attitude comes first
        (`attitude_first`) on loaded prongs, whose tips pin the trunk's position, and while a lifted
        shank is held in 6-D, whose six rows leave the trunk three free directions that its
        position would otherwise take, its attitude left uncontrolled."""
        c = self.config
        w, v = s.V_trunk[:3], s.V_trunk[3:]
        angular = (
            body.alpha
            + c.trunk_orientation.kp * orientation_error_W(body.R, s.R_WB)
            + c.trunk_orientation.kd * (body.w - w)
        )
        linear = body.a + c.trunk_position.kp * (body.p - s.p_WB) + c.trunk_position.kd * (body.v - v)
        if c.torso_position_first and not attitude_first:
            torso = [
                pd.AccelerationTask("torso_position", s.J_trunk[3:], s.Jdot_v_trunk[3:], linear),
                pd.AccelerationTask("torso_orientation", s.J_trunk[:3], s.Jdot_v_trunk[:3], angular),
            ]
        else:
            torso = [pd.AccelerationTask("torso", s.J_trunk, s.Jdot_v_trunk, np.concatenate([angular, linear]))]
        if attitude_first:
            # A loaded prong pins the trunk (or a held shank leaves it three directions): its
            # attitude comes first; its position takes what remains.
            torso = [
                pd.AccelerationTask("torso_orientation", s.J_trunk[:3], s.Jdot_v_trunk[:3], angular),
                pd.AccelerationTask("torso_position", s.J_trunk[3:], s.Jdot_v_trunk[3:], linear),
            ]
        posture = pd.AccelerationTask(
            "posture",
            self.S,
            np.zeros(12),
            c.posture.kp * (self.nominal_q - s.q_joints) - c.posture.kd * s.v_joints,
        )
        return [*torso, posture]

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
        estimate = context.get_discrete_state(self.estimate_state).value().copy().reshape(4, 7)
        last_command = context.get_discrete_state(self.command_state).value().copy()
        diag = context.get_discrete_state(self.diagnostics_state).value().copy()

        contact_set = _clip(self._optional(self.contact_set_port, context, self.default_contact_set), 0.0, 1.0)
        if not _all_finite(base, q, qd, contact_set):
            self._fail(discrete_state, last_command, q, diag, STATUS_BAD_INPUT, start)
            return
        if hold[0] == 0.0:
            hold = np.concatenate([[1.0], base[4:7], base[0:4]])
            q_ref, qd_ref = q.copy(), qd.copy()
            ramp = contact_set.copy()
        step = c.period / c.contact_ramp_time
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
        body = references.parse_body_reference(body_x)
        legs = references.parse_leg_reference(leg_x)

        s = self.model.update(base, q, qd)
        add_trunk_external_wrench(s.h, s.J_trunk, trunk_wrench)
        held = (contact_set > 0.5) | (ramp > 0.0)
        held_idx = np.flatnonzero(held)
        rows = tasks.contact_rows(held)
        Jc = s.J_contacts[rows]
        try:
            dynamics = pd.constrained_dynamics(
                s.M, s.h, Jc, s.Jdot_v_contacts[rows], s.v, c.contact_damping, c.rank_tolerance
            )
            impedance, foot_rows = self._impedance_tasks(s, legs, held)
            stacked = pd.stack_impedance_tasks(impedance, self.model.nv)
            shank_held = any(ref.mode == references.LEG_MODE_SHANK_POSE and not held[i] for i, ref in enumerate(legs))
            lower = self._lower_tasks(s, body, bool(held[4:].any()) or shank_held)
            law = pd.prioritized_force(dynamics, s.v, stacked, lower, c.rank_tolerance)
            free = pd.constraint_free_torque(dynamics, law.u, self.S, c.rank_tolerance)
            share = self.total_weight / max(float(ramp[held_idx].sum()), 1e-6)
            force_share = np.zeros(3 * len(held_idx))
            force_share[2::3] = ramp[held_idx] * share
            mu = pyramid_slope(float(mu_x[0]), c.friction_pyramid_inscribed)
            problem = pd.ContactForceProblem(
                Jc=Jc,
                r=s.M @ free.vdot + s.h,
                unactuated=self.unactuated,
                actuated=self.v_index,
                ramp=ramp[held_idx],
                friction=mu,
                f_min=c.min_normal_force,
                f_max=c.max_normal_force,
                torque_limit=c.torque_limit_scale * robot.EFFORT_LIMIT,
                force_share=force_share,
                torque_weight=c.torque_weight,
                force_weight=c.force_regularization_weight,
                rank_tolerance=c.rank_tolerance,
            )
            solution = pd.solve_contact_forces(problem)
            if not _all_finite(solution.tau, free.vdot):
                raise QpInfeasible("non-finite torque")
        except (QpInfeasible, np.linalg.LinAlgError):
            self._fail(discrete_state, last_command, q, diag, STATUS_QP_FAILED, start, ramp=ramp, hold=hold)
            return
        tau = solution.tau

        qdd = free.vdot[self.v_index]
        qd_ref = _clip(
            qd_ref + qdd * c.period, qd - c.max_reference_rate_deviation, qd + c.max_reference_rate_deviation
        )
        q_ref = _clip(q_ref + qd_ref * c.period, q - c.max_reference_deviation, q + c.max_reference_deviation)
        command = np.concatenate([q_ref, qd_ref, self.command_gains, tau])

        # Eq. 11 per foot impedance: Lambda eddot + D edot + K e, eddot a filtered difference.
        forces_estimated = np.zeros((4, 3))
        alpha = c.period / (c.period + c.force_estimate_filter_time)
        eddot_stack = np.zeros(stacked.J.shape[0])
        active = np.zeros(4, dtype=bool)
        for i, r in foot_rows.items():
            active[i] = True
            rate = stacked.error_rate[r]
            if estimate[i, 6] > 0.5:
                raw = (rate - estimate[i, 0:3]) / c.period
                estimate[i, 3:6] += alpha * (raw - estimate[i, 3:6])
            else:
                estimate[i, 3:6] = 0.0
            estimate[i, 0:3] = rate
            eddot_stack[r] = estimate[i, 3:6]
        for i, r in foot_rows.items():
            forces_estimated[i] = pd.impedance_force_estimate(
                law.impedance_inertia[r],
                stacked.stiffness[r],
                stacked.damping[r],
                stacked.error[r],
                stacked.error_rate[r],
                eddot_stack,
            )
        estimate[~active] = 0.0
        estimate[active, 6] = 1.0

        ground = float(s.p_contacts[held_idx, 2].mean()) - robot.FOOT_RADIUS if len(held_idx) else 0.0
        forces = np.zeros((self.num_contacts, 3))
        forces[held_idx] = solution.lam.reshape(-1, 3)
        diag[self.diag["status"]] = STATUS_CONTACTS_RELAXED if solution.relaxed else STATUS_OK
        diag[self.diag["solve_time"]] = solution.solve_time
        diag[self.diag["consecutive_failures"]] = 0.0
        diag[self.diag["capture_point"]] = self.balance.capture_point(s, ground)[0]
        diag[self.diag["trunk_position_error"]] = body.p - s.p_WB
        diag[self.diag["trunk_orientation_error"]] = orientation_error_W(body.R, s.R_WB)
        foot_errors = np.zeros(4)
        for i, r in foot_rows.items():
            foot_errors[i] = np.linalg.norm(stacked.error[r])
        diag[self.diag["foot_errors"]] = foot_errors
        residuals = np.zeros(self.diag["level_residuals"].stop - self.diag["level_residuals"].start)
        figures = [*law.residuals, solution.equality_residual][: len(residuals)]
        residuals[: len(figures)] = figures
        diag[self.diag["level_residuals"]] = residuals
        diag[self.diag["contact_forces"]] = forces.ravel()
        diag[self.diag["tau_ff"]] = tau
        diag[self.diag["contact_ramp"]] = ramp
        diag[self.diag["force_estimate"]] = forces_estimated.ravel()
        diag[self.diag["constraint_rank"]] = dynamics.projection.rank
        diag[self.diag["tick_time"]] = time.perf_counter() - start

        discrete_state.get_mutable_vector(self.command_state).SetFromVector(command)
        discrete_state.get_mutable_vector(self.reference_state).SetFromVector(np.concatenate([q_ref, qd_ref]))
        discrete_state.get_mutable_vector(self.ramp_state).SetFromVector(ramp)
        discrete_state.get_mutable_vector(self.hold_state).SetFromVector(hold)
        discrete_state.get_mutable_vector(self.estimate_state).SetFromVector(estimate.ravel())
        discrete_state.get_mutable_vector(self.diagnostics_state).SetFromVector(diag)

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
        if ramp is not None:
            diag[self.diag["contact_ramp"]] = ramp  # the ramps advance through failures too
        diag[self.diag["consecutive_failures"]] += 1.0
        diag[self.diag["total_failures"]] += 1.0
        diag[self.diag["tick_time"]] = time.perf_counter() - start
        discrete_state.get_mutable_vector(self.command_state).SetFromVector(command)
        discrete_state.get_mutable_vector(self.diagnostics_state).SetFromVector(diag)
        if ramp is not None:
            discrete_state.get_mutable_vector(self.ramp_state).SetFromVector(ramp)
        if hold is not None:
            discrete_state.get_mutable_vector(self.hold_state).SetFromVector(hold)
