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
        limits and friction pyramid (about the normal of the terrain under each contact), torque
        limits, joint limits (hard), capture point in the safety polygon (soft);
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
from pedi_drake.friction import pyramid_slope, write_contact_force_rows
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


# ------------------------------------------------------------------------------------------------
# Tasks: each writes its rows from a given row of the table's arrays and returns the next row.
# Equalities go to (A, b), hard inequalities G x <= h to (G, h), soft ones to (G, h, w).


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
def floating_base_dynamics_rows(p, s, A, b, row: int) -> int:
    """The floating base's rows of the equations of motion, M_u vdot - J_c,u^T f = -h_u (6 rows):
    the trunk moves only by the contact forces and gravity."""
    nv, nc = p.nv, p.nc
    for k in range(6):
        u = p.unactuated[k]
        A[row, :nv] = s.M[u]
        for j in range(3 * nc):
            A[row, nv + j] = -s.J_contacts[j, u]
        b[row] = -s.h[u]
        row += 1
    return row


@kernel
def _contact_velocity_row(p, s, c: int, A, b, row: int) -> int:
    """Row c of the contacts' Jacobian held still: J_c vdot = -Jdot_c v - kd J_c v (the damping kd
    bleeds the estimate's drift off); returns the next row."""
    velocity = 0.0
    for j in range(p.nv):
        velocity += s.J_contacts[c, j] * s.v[j]
    A[row, :] = 0.0
    A[row, : p.nv] = s.J_contacts[c]
    b[row] = -s.Jdot_v_contacts[c] - p.contact_damping * velocity
    return row + 1


@kernel
def contact_no_motion_rows(p, s, no_motion, sliding, A, b, row: int) -> int:
    """The held contacts (no_motion) stay still along the world's three axes; a sliding one only
    along the vertical (3 rows a held contact, 1 a sliding one)."""
    for i in range(p.nc):
        if no_motion[i]:
            for axis in range(2 if sliding[i] else 0, 3):
                row = _contact_velocity_row(p, s, 3 * i + axis, A, b, row)
    return row


@kernel
def sliding_contact_rows(p, s, sliding, A, b, row: int) -> int:
    """The sliding contacts' horizontal no-motion (2 rows each): the fallback's level of its own."""
    for i in range(p.nc):
        if sliding[i]:
            for axis in range(2):
                row = _contact_velocity_row(p, s, 3 * i + axis, A, b, row)
    return row


@kernel
def contact_force_limit_rows(p, ramp, friction: float, normals, G, h, hard: int) -> int:
    """Per contact (6 rows): the force along the ground's normal (normals (nc, 3), unit, world)
    between f_min and f_max, both scaled by the contact's ramp (so a contact coming or going has
    its force bounded to zero), and the four faces of the friction pyramid about that normal
    (inscribed in the cone of `friction` when p.inscribed)."""
    slope = pyramid_slope(friction, p.inscribed)
    for i in range(p.nc):
        for r in range(6):
            G[hard + r, :] = 0.0
        write_contact_force_rows(G, h, hard, p.nv + 3 * i, slope, normals[i], p.f_min * ramp[i], p.f_max * ramp[i])
        hard += 6
    return hard


@kernel
def torque_limit_rows(p, T, t0, G, h, hard: int) -> int:
    """|tau| <= the QP's effort limit per joint (24 rows), tau = T x + t0."""
    for r in range(12):
        G[hard + r] = T[r]
        G[hard + 12 + r] = -T[r]
        h[hard + r] = p.effort_limit[r] - t0[r]
        h[hard + 12 + r] = p.effort_limit[r] + t0[r]
    return hard + 24


@kernel
def joint_limit_rows(p, s, G, h, hard: int) -> int:
    """Joint accelerations that keep each joint within its position limits (less the margin) over
    the horizon and within its velocity limit (24 rows); a joint already beyond both gets the
    midpoint of the two bounds, so the rows stay feasible."""
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
        G[hard + r, :] = 0.0
        G[hard + 12 + r, :] = 0.0
        G[hard + r, p.v_joints[r]] = 1.0
        G[hard + 12 + r, p.v_joints[r]] = -1.0
        h[hard + r] = upper
        h[hard + 12 + r] = minus_lower
    return hard + 24


@kernel
def capture_point_rows(p, s, ground_height: float, polygon_N, polygon_d, G, h, w, soft: int) -> int:
    """The capture point predicted over the balance horizon inside the safety polygon's half-planes
    N xi <= d (one soft row each, weight 1)."""
    nv = p.nv
    xi = np.empty(2)
    omega = capture_point(s, ground_height, xi)
    horizon = p.balance_horizon
    for k in range(polygon_d.shape[0]):
        n0, n1 = polygon_N[k, 0], polygon_N[k, 1]
        G[soft, :] = 0.0
        for j in range(nv):
            G[soft, j] = (horizon / omega) * (n0 * s.J_com[0, j] + n1 * s.J_com[1, j])
        predicted0 = xi[0] + horizon * s.v_com[0] + (horizon / omega) * s.Jdot_v_com[0]
        predicted1 = xi[1] + horizon * s.v_com[1] + (horizon / omega) * s.Jdot_v_com[1]
        h[soft] = polygon_d[k] - (n0 * predicted0 + n1 * predicted1)
        w[soft] = 1.0
        soft += 1
    return soft


@kernel
def trunk_orientation_rows(p, s, body, A, b, row: int) -> int:
    """The trunk's attitude to the body reference's, Eq. 1 (3 rows)."""
    error = np.empty(3)
    orientation_error_kernel(rotation_matrix_kernel(body[3:7]), s.R_WB, error)
    kp, kd = p.trunk_orientation_gains[0], p.trunk_orientation_gains[1]
    return pd_rows(s.J_trunk[:3], s.v, error, body[13:16], body[16:19], kp, kd, s.Jdot_v_trunk[:3], A, b, row)


@kernel
def trunk_position_rows(p, s, body, A, b, row: int) -> int:
    """The trunk origin to the body reference's position, Eq. 1 (3 rows)."""
    error = np.empty(3)
    for i in range(3):
        error[i] = body[i] - s.p_WB[i]
    kp, kd = p.trunk_position_gains[0], p.trunk_position_gains[1]
    return pd_rows(s.J_trunk[3:], s.v, error, body[7:10], body[10:13], kp, kd, s.Jdot_v_trunk[3:], A, b, row)


@kernel
def foot_rows(p, s, leg: int, block, A, b, row: int) -> int:
    """A pedipulating foot to its world reference, Eq. 1 (3 rows), with the leg reference's own
    gains when it carries them (kp > 0) and its acceleration feed-forward in the position mode."""
    kp, kd = p.foot_gains[0], p.foot_gains[1]
    if block[10] > 0.0 and block[11] >= 0.0:
        kp, kd = block[10], block[11]
    error = np.empty(3)
    for k in range(3):
        error[k] = block[1 + k] - s.p_contacts[leg, k]
    a_ref = block[7:10] if round(block[0]) == _FOOT else np.zeros(3)
    J, bias = s.J_contacts[3 * leg : 3 * leg + 3], s.Jdot_v_contacts[3 * leg : 3 * leg + 3]
    return pd_rows(J, s.v, error, block[4:7], a_ref, kp, kd, bias, A, b, row)


@kernel
def calf_rows(p, s, leg: int, block, axes: int, A, b, row: int) -> int:
    """The calf's attitude to the reference's (an axis-angle in block[7:10]): its roll and pitch
    (axes 2, the 5-D foot pose) or all three axes (3, the 6-D shank pose), Eq. 1."""
    error = np.empty(3)
    orientation_error_kernel(axis_angle_kernel(block[7:10]), s.R_WC[leg], error)
    kp, kd = p.calf_gains[0], p.calf_gains[1]
    for k in range(axes):
        rate = 0.0
        for j in range(p.nv):
            rate += s.J_w_calf[leg, k, j] * s.v[j]
        A[row, :] = 0.0
        A[row, : p.nv] = s.J_w_calf[leg, k]
        b[row] = kp * error[k] - kd * rate - s.Jdot_w_calf[leg, k]
        row += 1
    return row


@kernel
def leg_joint_rows(p, s, leg: int, block, A, b, row: int) -> int:
    """A lifted leg's joints to the reference's (joint mode) or to the nominal posture (a swing leg
    without a reference), Eq. 1 on each joint (3 rows)."""
    kp, kd = p.leg_joint_gains[0], p.leg_joint_gains[1]
    joints_mode = round(block[0]) == _JOINTS
    for k in range(3):
        joint = 3 * leg + k
        if joints_mode:
            q_ref, qd_ref, qdd_ref = block[1 + k], block[4 + k], block[7 + k]
        else:
            q_ref, qd_ref, qdd_ref = p.nominal_q[joint], 0.0, 0.0
        A[row, :] = 0.0
        A[row, p.v_joints[joint]] = 1.0
        b[row] = qdd_ref + kp * (q_ref - s.q_joints[joint]) + kd * (qd_ref - s.v_joints[joint])
        row += 1
    return row


@kernel
def leg_rows(p, s, legs, no_motion, A, b, row: int) -> int:
    """Every leg's task by its reference's mode: a pedipulating foot (position, the 5-D pose or the
    6-D shank pose), joint references, or the nominal posture for a swing leg without a reference."""
    for i in range(4):
        block = legs[12 * i : 12 * i + 12]
        mode = round(block[0])
        if mode == _FOOT or mode == _FOOT_POSE or mode == _SHANK_POSE:
            row = foot_rows(p, s, i, block, A, b, row)
            if mode == _FOOT_POSE or mode == _SHANK_POSE:
                row = calf_rows(p, s, i, block, 3 if mode == _SHANK_POSE else 2, A, b, row)
        elif mode == _JOINTS or not no_motion[i]:
            row = leg_joint_rows(p, s, i, block, A, b, row)
    return row


@kernel
def posture_rows(p, s, A, b, row: int) -> int:
    """The joints towards the nominal posture, Eq. 1, weighted by p.posture_weight (12 rows)."""
    scale = math.sqrt(p.posture_weight)
    kp, kd = p.posture_gains[0], p.posture_gains[1]
    for joint in range(12):
        A[row, :] = 0.0
        A[row, p.v_joints[joint]] = scale
        target = kp * (p.nominal_q[joint] - s.q_joints[joint]) + kd * (0.0 - s.v_joints[joint])
        b[row] = target * scale
        row += 1
    return row


@kernel
def contact_force_share_rows(p, ramp, A, b, row: int) -> int:
    """The contact forces towards an even share of the weight by ramp, vertical, weighted by
    p.force_regularization_weight (3 rows a contact)."""
    scale = math.sqrt(p.force_regularization_weight)
    total_ramp = 0.0
    for i in range(p.nc):
        total_ramp += ramp[i]
    share = p.total_weight / max(total_ramp, 1e-6)
    for j in range(3 * p.nc):
        A[row, :] = 0.0
        A[row, p.nv + j] = scale
        b[row] = (ramp[j // 3] * share if j % 3 == 2 else 0.0) * scale
        row += 1
    return row


@kernel
def torque_rows(p, T, t0, A, b, row: int) -> int:
    """The torques towards zero, weighted by p.torque_weight (12 rows), tau = T x + t0."""
    scale = math.sqrt(p.torque_weight)
    for r in range(12):
        for j in range(T.shape[1]):
            A[row, j] = T[r, j] * scale
        b[row] = -t0[r] * scale
        row += 1
    return row


@kernel
def _close_level(table, level: int, row: int, hard: int, soft: int) -> int:
    """Ends level `level` at the given row counts; returns the next level's index."""
    table.eq_start[level + 1] = row
    table.hard_start[level + 1] = hard
    table.soft_start[level + 1] = soft
    return level + 1


@kernel
def sliding_contacts(p, s, no_motion, sliding) -> bool:
    """Marks in `sliding` the held contacts whose horizontal speed exceeds SLIDING_SPEED; whether any."""
    any_sliding = False
    for i in range(p.nc):
        sliding[i] = False
        if no_motion[i]:
            vx, vy = 0.0, 0.0
            for j in range(p.nv):
                vx += s.J_contacts[3 * i, j] * s.v[j]
                vy += s.J_contacts[3 * i + 1, j] * s.v[j]
            if math.hypot(vx, vy) > SLIDING_SPEED:
                sliding[i] = True
                any_sliding = True
    return any_sliding


# ------------------------------------------------------------------------------------------------
# The stacks.


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
    normals: np.ndarray,
    ground_height: float,
    relax_contacts: bool,
    T: np.ndarray,
    t0: np.ndarray,
    table,
) -> int:
    """Writes the stack's levels into `table`; returns the number of levels, 0 when
    `relax_contacts` finds no sliding contact (the fallback does not apply).

    body (19): the body reference vector; legs (48): the leg reference vector; ramp, no_motion
    (nc,); polygon_N (k, 2), polygon_d (k,): the safety polygon's half-planes; normals (nc, 3):
    the unit normal (world) of the ground under each contact; T, t0: torque_map.
    With `relax_contacts`, the tangential no-motion rows of the sliding contacts leave the physics
    level for a level of their own just below the limits, so that friction can brake them.
    """
    A, b = table.eq_A, table.eq_b
    G, h = table.hard_G, table.hard_h
    Gs, hs, ws = table.soft_G, table.soft_h, table.soft_w
    sliding = np.zeros(p.nc, dtype=np.bool_)
    if relax_contacts and not sliding_contacts(p, s, no_motion, sliding):
        return 0
    table.eq_start[0] = table.hard_start[0] = table.soft_start[0] = 0
    level, row, hard, soft = 0, 0, 0, 0

    # Physics: the floating base's dynamics, the held contacts' no-motion (a sliding one's normal only).
    row = floating_base_dynamics_rows(p, s, A, b, row)
    row = contact_no_motion_rows(p, s, no_motion, sliding, A, b, row)
    level = _close_level(table, level, row, hard, soft)

    # Feasibility: force limits and friction, torque and joint limits (hard); capture point (soft).
    hard = contact_force_limit_rows(p, ramp, friction, normals, G, h, hard)
    hard = torque_limit_rows(p, T, t0, G, h, hard)
    hard = joint_limit_rows(p, s, G, h, hard)
    if p.balance:
        soft = capture_point_rows(p, s, ground_height, polygon_N, polygon_d, Gs, hs, ws, soft)
    level = _close_level(table, level, row, hard, soft)
    if relax_contacts:
        row = sliding_contact_rows(p, s, sliding, A, b, row)
        level = _close_level(table, level, row, hard, soft)

    # Pose (paper003: the trunk's attitude, then its position, each a level; paper000: one level).
    row = trunk_orientation_rows(p, s, body, A, b, row)
    if p.stack == STACK_PAPER003:
        level = _close_level(table, level, row, hard, soft)
    row = trunk_position_rows(p, s, body, A, b, row)
    if p.stack == STACK_PAPER003:
        level = _close_level(table, level, row, hard, soft)
    row = leg_rows(p, s, legs, no_motion, A, b, row)
    level = _close_level(table, level, row, hard, soft)

    # Regularisation: posture, contact forces towards an even share of the weight, torques.
    row = posture_rows(p, s, A, b, row)
    row = contact_force_share_rows(p, ramp, A, b, row)
    row = torque_rows(p, T, t0, A, b, row)
    return _close_level(table, level, row, hard, soft)
