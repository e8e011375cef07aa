"""The task stacks of the two papers: the rows one control instant gives every HQP level.

Decision variables x = [vdot (nv = 18); f (3 nc)]: generalised accelerations (trunk angular and
linear acceleration in world, then joint accelerations in the plant's order) and one world-frame
force per contact point (the four feet, then the prongs). Joint torques are eliminated with the
actuated rows of the dynamics, tau = M_a vdot + h_a - J_c,a^T f, so every torque task (limits,
minimisation) is linear in x: the QP shrinks from 18 + 12 + 3 nc to 18 + 3 nc variables, and
dense active-set solvers scale with the cube of the size (paper 003 uses the same trick, its ref.
[34]). Contacts out of contact keep their force variables, bounded to zero: the QP keeps a fixed
size and adding or removing a contact is a continuous change of bounds (the ramp). Acceleration
tasks follow Eq. 1 of paper 000: J vdot = a_ref + Kp (x_ref - x) + Kd (v_ref - v) - Jdot v.

The paper's level 0 is solved as two sub-levels: "physics" (floating-base dynamics and contact
no-motion, equalities that some x always meets exactly, so solving them first by null-space
projection loses nothing and halves the size of every QP below) then "feasibility".

paper000 (Sec. III-B, two TSID levels, here strict):
    level 0 "physics" + "feasibility": floating-base dynamics, contact no-motion; contact force
        limits and friction pyramid, torque limits, joint limits (hard), capture point in the
        safety polygon (soft);
    level 1 "pose": trunk position and attitude, pedipulation foot / leg joint reference (or the
        optional 5-D foot pose: foot position and the calf's roll and pitch), idle legs;
    level 2 "regularisation" (added so the optimum is unique): posture, contact forces, torques.
paper003 (Sec. VI, five levels):
    0 dynamic feasibility (as above; the capture point optionally, `paper003_balance`),
    1 torso angular acceleration, 2 torso translational acceleration, 3 swing foot acceleration
    (and leg joint references, idle legs), 4 torque minimisation (with light posture and force terms).
Prong contacts sit in the same augmented contact Jacobian as the feet (paper 003).

`build_levels` writes the rows straight into preallocated arrays (`compiled_hqp.RowTable` layout)
inside one compiled call. tests/reference_stacks.py and tests/reference_tasks.py are the same
stacks in numpy, one class per task: the oracle of tests/test_compiled_controller.py, which
checks that both give the same rows and the same solution on random and recorded states.

Inputs are records (one-element structured arrays, indexed [0] in compiled code): the stack
parameters (constants of the configured controller, built once by `stack_params`), a snapshot
(the dynamics terms of `robot_model.RobotSnapshot`, `go1_dynamics.output_dtype`) and the resolved
references of the instant, as arrays; the rows go into a table record (`table_dtype`).
"""

import math

import numpy as np

from pedi_drake import robot
from pedi_drake.control import references
from pedi_drake.control.config import WholeBodyControllerConfig
from pedi_drake.friction import pyramid_slope, write_pyramid_faces
from pedi_drake.runtime.jit import kernel, new_record
from pedi_drake.vector3 import axis_angle_kernel, orientation_error_kernel, rotation_matrix_kernel

STACK_PAPER000, STACK_PAPER003 = 0, 1
# Leg reference modes (references.py).
_FOOT, _JOINTS, _FOOT_POSE = references.LEG_MODE_FOOT, references.LEG_MODE_JOINTS, references.LEG_MODE_FOOT_POSE
_SHANK_POSE = references.LEG_MODE_SHANK_POSE


# The constants of a configured whole-body controller (`stack_params`).
STACK_PARAMS_DTYPE = np.dtype(
    [
        ("stack", "i8"),  # STACK_PAPER000 or STACK_PAPER003
        ("balance", "?"),  # capture point in the feasibility level
        ("nv", "i8"),
        ("nc", "i8"),
        ("v_joints", "i8", 12),  # plant velocity index of each joint, Unitree order
        ("unactuated", "i8", 6),  # the floating base's velocity indices
        ("contact_damping", "f8"),  # [1/s]
        ("f_min", "f8"),  # [N]
        ("f_max", "f8"),  # [N]
        ("inscribed", "?"),
        ("effort_limit", "f8", 12),  # the QP's torque limit (scale x effort limit) [N m]
        ("q_lower", "f8", 12),  # [rad]
        ("q_upper", "f8", 12),  # [rad]
        ("v_max", "f8", 12),  # [rad/s]
        ("joint_limit_horizon", "f8"),  # [s]
        ("joint_limit_margin", "f8"),  # [rad]
        ("balance_horizon", "f8"),  # [s]
        ("com_bias", "?"),  # Jdot_com v in the capture point's prediction (else taken as zero)
        ("trunk_orientation_gains", "f8", 2),  # kp [1/s^2], kd [1/s]
        ("trunk_position_gains", "f8", 2),
        ("foot_gains", "f8", 2),
        ("calf_gains", "f8", 2),
        ("leg_joint_gains", "f8", 2),
        ("posture_gains", "f8", 2),
        ("nominal_q", "f8", 12),  # [rad]
        ("posture_weight", "f8"),
        ("force_regularization_weight", "f8"),
        ("torque_weight", "f8"),
        ("total_weight", "f8"),  # m g [N]
    ]
)


def stack_params(
    config: WholeBodyControllerConfig, v_joints: np.ndarray, nv: int, nc: int, total_mass: float
) -> np.ndarray:
    """The stack parameters (a STACK_PARAMS_DTYPE record) of `config` for a plant with `nv`
    velocities (joints at `v_joints`) and `nc` contacts."""
    mask = np.ones(nv, dtype=bool)
    mask[v_joints] = False
    record = new_record(STACK_PARAMS_DTYPE)
    r = record[0]
    r["stack"] = STACK_PAPER003 if config.stack == "paper003" else STACK_PAPER000
    r["balance"] = bool(config.paper003_balance) if config.stack == "paper003" else True
    r["nv"], r["nc"] = nv, nc
    r["v_joints"] = v_joints
    r["unactuated"] = np.flatnonzero(mask)
    r["contact_damping"] = config.contact_damping
    r["f_min"], r["f_max"] = config.min_normal_force, config.max_normal_force
    r["inscribed"] = bool(config.friction_pyramid_inscribed)
    r["effort_limit"] = config.torque_limit_scale * np.asarray(robot.EFFORT_LIMIT, float)
    r["q_lower"], r["q_upper"], r["v_max"] = robot.Q_LOWER, robot.Q_UPPER, robot.VELOCITY_LIMIT
    r["joint_limit_horizon"], r["joint_limit_margin"] = config.joint_limit_horizon, config.joint_limit_margin
    r["balance_horizon"] = config.balance_horizon
    r["com_bias"] = bool(config.balance_com_bias)
    for field, gains in (
        ("trunk_orientation_gains", config.trunk_orientation),
        ("trunk_position_gains", config.trunk_position),
        ("foot_gains", config.foot_position),
        ("calf_gains", config.foot_orientation),
        ("leg_joint_gains", config.leg_joints),
        ("posture_gains", config.posture),
    ):
        r[field] = gains.kp, gains.kd
    r["nominal_q"] = np.tile(np.asarray(config.nominal_leg_posture, float), 4)
    r["posture_weight"] = config.posture_weight
    r["force_regularization_weight"] = config.force_regularization_weight
    r["torque_weight"] = config.torque_weight
    r["total_weight"] = total_mass * robot.GRAVITY
    return record


MAX_LEVELS = 7  # paper003's six, and the sliding contacts' level
# A held contact moving faster than this along the ground is sliding [m/s] (well above the
# estimator's velocity noise of a few mm/s).
SLIDING_SPEED = 0.02


def num_levels(stack: str) -> int:
    """How many HQP levels the stack `stack` has (without the sliding contacts' level)."""
    return 6 if stack == "paper003" else 4


def table_dtype(nv: int, nc: int) -> np.dtype:
    """A RowTable (compiled_hqp) at its largest sizes for any stack on `nc` contacts; `*_start`
    give each level's rows."""
    n = nv + 3 * nc
    # physics 6 + 3 nc; pose up to 6 + 4 x 6 (a 6-D shank task per leg); regularisation 24 + 3 nc
    max_eq = (6 + 3 * nc) + 30 + (24 + 3 * nc)
    max_hard = 6 * nc + 48
    max_soft = references.SAFETY_POLYGON_MAX_VERTICES + nc
    return np.dtype(
        [
            ("eq_A", "f8", (max_eq, n)),
            ("eq_b", "f8", max_eq),
            ("eq_start", "i8", MAX_LEVELS + 1),
            ("hard_G", "f8", (max_hard, n)),
            ("hard_h", "f8", max_hard),
            ("hard_start", "i8", MAX_LEVELS + 1),
            ("soft_G", "f8", (max_soft, n)),
            ("soft_h", "f8", max_soft),
            ("soft_w", "f8", max_soft),
            ("soft_start", "i8", MAX_LEVELS + 1),
        ]
    )


# ------------------------------------------------------------------------------------------------
# Small geometry.


@kernel
def capture_point(s, ground_height: float, xi: np.ndarray) -> float:
    """The capture point xi (2,) [m] into `xi`; returns omega [1/s]."""
    z = max(s.p_com[2] - ground_height, 0.05)
    omega = np.sqrt(robot.GRAVITY / z)
    xi[0] = s.p_com[0] + s.v_com[0] / omega
    xi[1] = s.p_com[1] + s.v_com[1] / omega
    return omega


# ------------------------------------------------------------------------------------------------
# Rows.


@kernel
def torque_map(p, s, T: np.ndarray, t0: np.ndarray) -> None:
    """tau = T x + t0 (Unitree order) from the actuated dynamics rows."""
    nv = p.nv
    for r in range(12):
        row = p.v_joints[r]
        for j in range(nv):
            T[r, j] = s.M[row, j]
        for j in range(3 * p.nc):
            T[r, nv + j] = -s.J_contacts[j, row]
        t0[r] = s.h[row]


@kernel
def pd_rows(J, v, p_error, v_ref, a_ref, kp, kd, bias, A, b, row) -> int:
    """Writes the rows [J 0] x = a_ref + kp p_error + kd (v_ref - J v) - bias; returns the next row."""
    nv = J.shape[1]
    for i in range(J.shape[0]):
        velocity = 0.0
        for j in range(nv):
            velocity += J[i, j] * v[j]
        A[row + i, :] = 0.0
        A[row + i, :nv] = J[i]
        b[row + i] = a_ref[i] + kp * p_error[i] + kd * (v_ref[i] - velocity) - bias[i]
    return row + J.shape[0]


@kernel
def _close_level(table, level: int, row: int, hard: int, soft: int) -> int:
    """Ends level `level` at the given row counts; returns the next level's index."""
    table.eq_start[level + 1] = row
    table.hard_start[level + 1] = hard
    table.soft_start[level + 1] = soft
    return level + 1


@kernel
def build_levels(
    p,
    s,
    body: np.ndarray,
    legs: np.ndarray,
    ramp: np.ndarray,
    no_motion: np.ndarray,
    polygon_N: np.ndarray,
    polygon_d: np.ndarray,
    friction: float,
    ground_height: float,
    relax_contacts: bool,
    T: np.ndarray,
    t0: np.ndarray,
    table,
) -> int:
    """Writes the stack's levels into `table` (StackBuilder.levels); returns the number of levels,
    0 when `relax_contacts` finds no sliding contact (the fallback does not apply).

    body (19): the body reference vector; legs (48): the leg reference vector; ramp, no_motion
    (nc,); polygon_N (k, 2), polygon_d (k,): the safety polygon's half-planes; T, t0: torque_map.
    """
    nv, nc = p.nv, p.nc
    eq_A, eq_b, eq_start = table.eq_A, table.eq_b, table.eq_start
    hard_G, hard_h, hard_start = table.hard_G, table.hard_h, table.hard_start
    soft_G, soft_h, soft_w, soft_start = table.soft_G, table.soft_h, table.soft_w, table.soft_start

    # Sliding contacts of the relaxed fallback (StackBuilder.sliding_contacts).
    sliding = np.zeros(nc, dtype=np.bool_)
    if relax_contacts:
        any_sliding = False
        for i in range(nc):
            if no_motion[i]:
                vx, vy = 0.0, 0.0
                for j in range(nv):
                    vx += s.J_contacts[3 * i, j] * s.v[j]
                    vy += s.J_contacts[3 * i + 1, j] * s.v[j]
                if math.hypot(vx, vy) > SLIDING_SPEED:
                    sliding[i] = True
                    any_sliding = True
        if not any_sliding:
            return 0

    level = 0
    row = 0
    # Physics: the floating base's dynamics rows, then the held contacts' no-motion rows.
    for k in range(6):
        u = p.unactuated[k]
        eq_A[row, :nv] = s.M[u]
        for j in range(3 * nc):
            eq_A[row, nv + j] = -s.J_contacts[j, u]
        eq_b[row] = -s.h[u]
        row += 1
    zero3 = np.zeros(3)
    for i in range(nc):
        if not no_motion[i]:
            continue
        for axis in range(3):
            if sliding[i] and axis < 2:
                continue
            c = 3 * i + axis
            velocity = 0.0
            for j in range(nv):
                velocity += s.J_contacts[c, j] * s.v[j]
            eq_A[row, :] = 0.0
            eq_A[row, :nv] = s.J_contacts[c]
            eq_b[row] = -s.Jdot_v_contacts[c] - p.contact_damping * velocity
            row += 1
    hard = 0
    soft = 0
    eq_start[0] = hard_start[0] = soft_start[0] = 0
    level = _close_level(table, level, row, hard, soft)

    # Feasibility: force limits and friction, torque limits, joint limits (hard); capture point (soft).
    slope = pyramid_slope(friction, p.inscribed)
    for i in range(nc):
        for r in range(6):
            hard_G[hard + r, :] = 0.0
        f = nv + 3 * i
        hard_G[hard, f + 2] = -1.0
        hard_G[hard + 1, f + 2] = 1.0
        write_pyramid_faces(hard_G, hard + 2, f, slope)
        hard_h[hard] = -p.f_min * ramp[i]
        hard_h[hard + 1] = p.f_max * ramp[i]
        for r in range(2, 6):
            hard_h[hard + r] = 0.0
        hard += 6
    for r in range(12):
        hard_G[hard + r] = T[r]
        hard_G[hard + 12 + r] = -T[r]
        hard_h[hard + r] = p.effort_limit[r] - t0[r]
        hard_h[hard + 12 + r] = p.effort_limit[r] + t0[r]
    hard += 24
    horizon = p.joint_limit_horizon
    for r in range(12):
        q, qd = s.q_joints[r], s.v_joints[r]
        reach = q + qd * horizon
        upper = min((2.0 / horizon**2) * (p.q_upper[r] - p.joint_limit_margin - reach), (p.v_max[r] - qd) / horizon)
        minus_lower = min(
            (2.0 / horizon**2) * (reach - p.q_lower[r] - p.joint_limit_margin), (p.v_max[r] + qd) / horizon
        )
        if upper + minus_lower < 0.0:
            mid = 0.5 * (upper - minus_lower)
            upper, minus_lower = mid, -mid
        hard_G[hard + r, :] = 0.0
        hard_G[hard + 12 + r, :] = 0.0
        hard_G[hard + r, p.v_joints[r]] = 1.0
        hard_G[hard + 12 + r, p.v_joints[r]] = -1.0
        hard_h[hard + r] = upper
        hard_h[hard + 12 + r] = minus_lower
    hard += 24
    if p.balance:
        xi = np.empty(2)
        omega = capture_point(s, ground_height, xi)
        horizon = p.balance_horizon
        for k in range(polygon_d.shape[0]):
            n0, n1 = polygon_N[k, 0], polygon_N[k, 1]
            soft_G[soft, :] = 0.0
            for j in range(nv):
                soft_G[soft, j] = (horizon / omega) * (n0 * s.J_com[0, j] + n1 * s.J_com[1, j])
            predicted0 = xi[0] + horizon * s.v_com[0] + (horizon / omega) * s.Jdot_v_com[0]
            predicted1 = xi[1] + horizon * s.v_com[1] + (horizon / omega) * s.Jdot_v_com[1]
            soft_h[soft] = polygon_d[k] - (n0 * predicted0 + n1 * predicted1)
            soft_w[soft] = 1.0
            soft += 1
    level = _close_level(table, level, row, hard, soft)

    if relax_contacts:
        # The sliding contacts' tangential rows, just below the limits.
        for i in range(nc):
            if not sliding[i]:
                continue
            for axis in range(2):
                c = 3 * i + axis
                velocity = 0.0
                for j in range(nv):
                    velocity += s.J_contacts[c, j] * s.v[j]
                eq_A[row, :] = 0.0
                eq_A[row, :nv] = s.J_contacts[c]
                eq_b[row] = -s.Jdot_v_contacts[c] - p.contact_damping * velocity
                row += 1
        level = _close_level(table, level, row, hard, soft)

    # Trunk orientation and position (paper003: a level each; paper000: with the legs in "pose").
    error = np.empty(3)
    R_ref = rotation_matrix_kernel(body[3:7])
    orientation_error_kernel(R_ref, s.R_WB, error)
    kp, kd = p.trunk_orientation_gains[0], p.trunk_orientation_gains[1]
    row = pd_rows(s.J_trunk[:3], s.v, error, body[13:16], body[16:19], kp, kd, s.Jdot_v_trunk[:3], eq_A, eq_b, row)
    if p.stack == STACK_PAPER003:
        level = _close_level(table, level, row, hard, soft)
    for i in range(3):
        error[i] = body[i] - s.p_WB[i]
    kp, kd = p.trunk_position_gains[0], p.trunk_position_gains[1]
    row = pd_rows(s.J_trunk[3:], s.v, error, body[7:10], body[10:13], kp, kd, s.Jdot_v_trunk[3:], eq_A, eq_b, row)
    if p.stack == STACK_PAPER003:
        level = _close_level(table, level, row, hard, soft)

    # Legs: pedipulation feet (position, the 5-D pose or the 6-D shank pose), joint references, idle
    # swing legs.
    for i in range(4):
        block = legs[12 * i : 12 * i + 12]
        mode = round(block[0])
        ref_kp, ref_kd = block[10], block[11]
        if mode == _FOOT or mode == _FOOT_POSE or mode == _SHANK_POSE:
            kp, kd = p.foot_gains[0], p.foot_gains[1]
            if ref_kp > 0.0 and ref_kd >= 0.0:
                kp, kd = ref_kp, ref_kd
            for k in range(3):
                error[k] = block[1 + k] - s.p_contacts[i, k]
            a_ref = block[7:10] if mode == _FOOT else zero3
            J = s.J_contacts[3 * i : 3 * i + 3]
            row = pd_rows(
                J, s.v, error, block[4:7], a_ref, kp, kd, s.Jdot_v_contacts[3 * i : 3 * i + 3], eq_A, eq_b, row
            )
            if mode == _FOOT_POSE or mode == _SHANK_POSE:
                calf_error = np.empty(3)
                orientation_error_kernel(axis_angle_kernel(block[7:10]), s.R_WC[i], calf_error)
                kp, kd = p.calf_gains[0], p.calf_gains[1]
                # Roll and pitch (the 5-D task), or all three axes (the 6-D shank task).
                axes = 3 if mode == _SHANK_POSE else 2
                for k in range(axes):
                    rate = 0.0
                    for j in range(nv):
                        rate += s.J_w_calf[i, k, j] * s.v[j]
                    eq_A[row, :] = 0.0
                    eq_A[row, :nv] = s.J_w_calf[i, k]
                    eq_b[row] = kp * calf_error[k] - kd * rate - s.Jdot_w_calf[i, k]
                    row += 1
        elif mode == _JOINTS or not no_motion[i]:
            kp, kd = p.leg_joint_gains[0], p.leg_joint_gains[1]
            for k in range(3):
                joint = 3 * i + k
                if mode == _JOINTS:
                    q_ref, qd_ref, qdd_ref = block[1 + k], block[4 + k], block[7 + k]
                else:
                    q_ref, qd_ref, qdd_ref = p.nominal_q[joint], 0.0, 0.0
                eq_A[row, :] = 0.0
                eq_A[row, p.v_joints[joint]] = 1.0
                eq_b[row] = qdd_ref + kp * (q_ref - s.q_joints[joint]) + kd * (qd_ref - s.v_joints[joint])
                row += 1
    level = _close_level(table, level, row, hard, soft)

    # Regularisation: posture, contact forces towards an even share of the weight, torques.
    scale = math.sqrt(p.posture_weight)
    kp, kd = p.posture_gains[0], p.posture_gains[1]
    for joint in range(12):
        eq_A[row, :] = 0.0
        eq_A[row, p.v_joints[joint]] = scale
        target = 0.0 + kp * (p.nominal_q[joint] - s.q_joints[joint]) + kd * (0.0 - s.v_joints[joint])
        eq_b[row] = target * scale
        row += 1
    scale = math.sqrt(p.force_regularization_weight)
    total_ramp = 0.0
    for i in range(nc):
        total_ramp += ramp[i]
    share = p.total_weight / max(total_ramp, 1e-6)
    for j in range(3 * nc):
        eq_A[row, :] = 0.0
        eq_A[row, nv + j] = scale
        eq_b[row] = (ramp[j // 3] * share if j % 3 == 2 else 0.0) * scale
        row += 1
    scale = math.sqrt(p.torque_weight)
    for r in range(12):
        for j in range(T.shape[1]):
            eq_A[row, j] = T[r, j] * scale
        eq_b[row] = -t0[r] * scale
        row += 1
    return _close_level(table, level, row, hard, soft)
