"""One tick of paper 002's projected-impedance controller as one compiled call.

`ProjectedImpedanceController` (projected_impedance_controller.py) documents what a tick does.
`projected_impedance_tick` takes the tick's inputs and the controller's discrete state as arrays,
writes the next state and returns the tick's status, with the dynamics terms from
`go1_dynamics`, the control law from `compiled_projected_dynamics`, the leg kinematics of a
joint reference from `leg_odometry` and the steps it shares with the HQP's tick from
`tick_steps`. No Python object is touched
between the first input and the last output, and the interpreter's lock is released throughout.

Discrete state, as ProjectedImpedanceController declares it: command (60), reference (24: q_ref,
qd_ref in Unitree order), ramp (nc), hold (8: initialised flag, p_WB, quaternion), estimate (28:
per leg the last foot error rate, the filtered error acceleration and whether the leg had a foot
impedance), diagnostics (`projected_impedance_controller.projected_diagnostics_layout`).

Nothing raises: a non-finite input ends the tick as STATUS_BAD_INPUT, a failed decomposition or
an infeasible contact QP as STATUS_QP_FAILED, both holding the last good command with damping
(`tick_steps.fail`).
"""

import math

import numpy as np

from pedi_drake import robot
from pedi_drake.control import compiled_projected_dynamics as cpd
from pedi_drake.control import references, tick_steps
from pedi_drake.dynamics.go1_dynamics import add_trunk_external_wrench, go1_dynamics
from pedi_drake.estimation.leg_odometry import foot_kinematics_kernel, leg_offsets
from pedi_drake.friction import pyramid_slope
from pedi_drake.runtime.jit import kernel, new_record
from pedi_drake.terrain import terrain_normal
from pedi_drake.vector3 import axis_angle_kernel, orientation_error_kernel, rotation_matrix_kernel

# Slices of the diagnostics vector the tick writes, in this order (projected_diagnostics_layout):
# those both ticks write, then this one's own.
DIAGNOSTICS_FIELDS = (*tick_steps.DIAGNOSTICS_FIELDS, "force_estimate", "constraint_rank")
_ESTIMATE, _RANK = len(tick_steps.DIAGNOSTICS_FIELDS), len(tick_steps.DIAGNOSTICS_FIELDS) + 1
_FOOT, _JOINTS, _FOOT_POSE = references.LEG_MODE_FOOT, references.LEG_MODE_JOINTS, references.LEG_MODE_FOOT_POSE
_SHANK_POSE = references.LEG_MODE_SHANK_POSE
_ESTIMATE_ENTRIES = 7  # per leg: error rate (3), filtered error acceleration (3), active flag

# Constants of a configured ProjectedImpedanceController (`tick_params`).
TICK_PARAMS_DTYPE = np.dtype(
    [
        ("nv", "i8"),
        ("nc", "i8"),
        ("v_joints", "i8", 12),  # plant velocity index of each joint, Unitree order
        ("unactuated", "i8", 6),  # the floating base's velocity indices
        ("period", "f8"),  # [s]
        ("contact_ramp_time", "f8"),  # [s]
        ("contact_damping", "f8"),  # [1/s]
        ("rank_tolerance", "f8"),  # [-]
        ("foot_stiffness", "f8", 3),  # [N/m]
        ("foot_damping", "f8", 3),  # [N s/m]
        ("foot_orientation_stiffness", "f8"),  # [N m/rad]
        ("foot_orientation_damping", "f8"),  # [N m s/rad]
        ("idle_leg_stiffness", "f8"),  # [N m/rad]
        ("idle_leg_damping", "f8"),  # [N m s/rad]
        ("trunk_position_gains", "f8", 2),  # kp [1/s^2], kd [1/s]
        ("trunk_orientation_gains", "f8", 2),
        ("posture_gains", "f8", 2),
        ("torso_position_first", "?"),
        ("nominal_q", "f8", 12),  # [rad]
        ("inscribed", "?"),  # friction pyramid inscribed in the cone
        ("f_min", "f8"),  # [N]
        ("f_max", "f8"),  # [N]
        ("torque_limit", "f8", 12),  # the contact QP's (scale x effort limit) [N m]
        ("torque_weight", "f8"),  # [1/(N m)^2]
        ("force_weight", "f8"),  # [1/N^2]
        ("total_weight", "f8"),  # m g [N]
        ("qp_proximal_weight", "f8"),  # DAQP's eps_prox [units of the QP's Hessian]
        ("force_estimate_filter_time", "f8"),  # [s]
        ("joint_kp", "f8"),  # [N m/rad]
        ("joint_kd", "f8"),  # [N m s/rad]
        ("max_reference_deviation", "f8"),  # [rad]
        ("max_reference_rate_deviation", "f8"),  # [rad/s]
        ("failure_kd", "f8"),  # [N m s/rad]
        ("leg_offsets", "f8", (4, 4, 3)),  # leg_odometry's: p_BH, p_HT, p_TC, p_CF per leg [m]
        ("diagnostics", "i8", len(DIAGNOSTICS_FIELDS)),  # start of each DIAGNOSTICS_FIELDS slice
        ("max_residuals", "i8"),  # entries of the level_residuals slice
    ]
)

# The contact QP's eps_prox: DAQP's default, as projected_dynamics solves it (negative: proximal
# iterations only if the Hessian turns out singular; the force weight makes it definite).
CONTACT_QP_PROXIMAL_WEIGHT = -1e-6


def tick_params(
    config, v_joints: np.ndarray, nv: int, nc: int, total_mass: float, diagnostics_layout: dict
) -> np.ndarray:
    """The TICK_PARAMS_DTYPE record of a ProjectedImpedanceConfig `config` for a plant with `nv`
    velocities (joints at `v_joints`), `nc` contacts and `total_mass` [kg]."""
    mask = np.ones(nv, dtype=bool)
    mask[v_joints] = False
    record = new_record(TICK_PARAMS_DTYPE)
    r = record[0]
    r["nv"], r["nc"] = nv, nc
    r["v_joints"] = v_joints
    r["unactuated"] = np.flatnonzero(mask)
    for name in (
        "period",
        "contact_ramp_time",
        "contact_damping",
        "rank_tolerance",
        "foot_orientation_stiffness",
        "foot_orientation_damping",
        "idle_leg_stiffness",
        "idle_leg_damping",
        "torque_weight",
        "force_estimate_filter_time",
        "joint_kp",
        "joint_kd",
        "max_reference_deviation",
        "max_reference_rate_deviation",
        "failure_kd",
    ):
        r[name] = getattr(config, name)
    r["foot_stiffness"] = config.foot_stiffness
    r["foot_damping"] = config.foot_damping
    for field, gains in (
        ("trunk_position_gains", config.trunk_position),
        ("trunk_orientation_gains", config.trunk_orientation),
        ("posture_gains", config.posture),
    ):
        r[field] = gains.kp, gains.kd
    r["torso_position_first"] = bool(config.torso_position_first)
    r["nominal_q"] = np.tile(np.asarray(config.nominal_leg_posture, float), 4)
    r["inscribed"] = bool(config.friction_pyramid_inscribed)
    r["f_min"], r["f_max"] = config.min_normal_force, config.max_normal_force
    r["torque_limit"] = config.torque_limit_scale * np.asarray(robot.EFFORT_LIMIT, float)
    r["force_weight"] = config.force_regularization_weight
    r["total_weight"] = total_mass * robot.GRAVITY
    r["qp_proximal_weight"] = CONTACT_QP_PROXIMAL_WEIGHT
    r["leg_offsets"] = leg_offsets()
    r["diagnostics"] = [diagnostics_layout[name].start for name in DIAGNOSTICS_FIELDS]
    levels = diagnostics_layout["level_residuals"]
    r["max_residuals"] = levels.stop - levels.start
    return record


@kernel
def _impedance_rows(leg_x, held, rows_of_leg, foot_row) -> int:
    """The impedance level's size and where each lifted leg's rows start (rows_of_leg[i]: its
    number of rows; foot_row[i]: the first row of its foot impedance, -1 without one)."""
    m = 0
    for i in range(4):
        rows_of_leg[i] = 0
        foot_row[i] = -1
        if held[i]:
            continue
        mode = round(leg_x[12 * i])
        if mode == _FOOT or mode == _JOINTS or mode == _FOOT_POSE or mode == _SHANK_POSE:
            foot_row[i] = m
            rows_of_leg[i] = 5 if mode == _FOOT_POSE else (6 if mode == _SHANK_POSE else 3)
        else:
            rows_of_leg[i] = 3
        m += rows_of_leg[i]
    return m


@kernel
def _impedance_tasks(tp, s, leg_x, held, foot_row, J, Jdot_v, error, error_rate, acceleration_ref, stiffness, damping):
    """The first-priority tasks, stacked (ProjectedImpedanceController._impedance_tasks): a foot
    impedance for every lifted leg with a reference (and its calf's roll and pitch in the 5-D
    task), a joint impedance to the nominal posture for a lifted leg without one."""
    nv = tp.nv
    J[:, :] = 0.0
    Jdot_v[:] = 0.0
    acceleration_ref[:] = 0.0
    joints_ref = np.zeros(12)
    any_joints = False
    for i in range(4):
        if not held[i] and round(leg_x[12 * i]) == _JOINTS:
            any_joints = True
            for k in range(3):
                joints_ref[3 * i + k] = leg_x[12 * i + 1 + k]
    if any_joints:
        p_B, J_B = foot_kinematics_kernel(joints_ref, tp.leg_offsets)
    else:
        p_B, J_B = np.zeros((4, 3)), np.zeros((4, 3, 3))
    row = 0
    p_ref = np.empty(3)
    v_ref = np.empty(3)
    a_ref = np.empty(3)
    rotation_error = np.empty(3)
    r_W = np.empty(3)
    rate_B = np.empty(3)
    acceleration_B = np.empty(3)
    for i in range(4):
        if held[i]:
            continue
        block = leg_x[12 * i : 12 * i + 12]
        if foot_row[i] >= 0:
            mode = round(block[0])
            if mode == _JOINTS:
                # The foot the joint reference means on the trunk as estimated now
                # (projected_impedance_controller.joint_reference_in_world).
                # p = p_WB + R p_BF(q), v = v_WB + w x R p_BF + R J(q) qd, a = R J(q) qdd.
                for k in range(3):
                    rate_B[k] = 0.0
                    acceleration_B[k] = 0.0
                    r_W[k] = 0.0
                    for j in range(3):
                        rate_B[k] += J_B[i, k, j] * block[4 + j]
                        acceleration_B[k] += J_B[i, k, j] * block[7 + j]
                        r_W[k] += s.R_WB[k, j] * p_B[i, j]
                w0, w1, w2 = s.V_trunk[0], s.V_trunk[1], s.V_trunk[2]
                v_ref[0] = s.V_trunk[3] + (w1 * r_W[2] - w2 * r_W[1])
                v_ref[1] = s.V_trunk[4] + (w2 * r_W[0] - w0 * r_W[2])
                v_ref[2] = s.V_trunk[5] + (w0 * r_W[1] - w1 * r_W[0])
                for k in range(3):
                    p_ref[k] = s.p_WB[k] + r_W[k]
                    a_ref[k] = 0.0
                    rotated_rate = 0.0
                    for j in range(3):
                        rotated_rate += s.R_WB[k, j] * rate_B[j]
                        a_ref[k] += s.R_WB[k, j] * acceleration_B[j]
                    v_ref[k] += rotated_rate
            else:
                for k in range(3):
                    p_ref[k] = block[1 + k]
                    v_ref[k] = block[4 + k]
                    a_ref[k] = block[7 + k] if mode == _FOOT else 0.0
            for k in range(3):
                c = 3 * i + k
                velocity = 0.0
                for j in range(nv):
                    J[row + k, j] = s.J_contacts[c, j]
                    velocity += s.J_contacts[c, j] * s.v[j]
                Jdot_v[row + k] = s.Jdot_v_contacts[c]
                error[row + k] = s.p_contacts[i, k] - p_ref[k]
                error_rate[row + k] = velocity - v_ref[k]
                acceleration_ref[row + k] = a_ref[k]
                stiffness[row + k] = tp.foot_stiffness[k]
                damping[row + k] = tp.foot_damping[k]
            row += 3
            if mode == _FOOT_POSE or mode == _SHANK_POSE:
                # The calf's roll and pitch (rotation about world x and y; the 5-D task), or its
                # whole orientation (the 6-D shank task), towards the reference.
                orientation_error_kernel(axis_angle_kernel(block[7:10]), s.R_WC[i], rotation_error)
                axes = 3 if mode == _SHANK_POSE else 2
                for k in range(axes):
                    rate = 0.0
                    for j in range(nv):
                        J[row + k, j] = s.J_w_calf[i, k, j]
                        rate += s.J_w_calf[i, k, j] * s.v[j]
                    Jdot_v[row + k] = s.Jdot_w_calf[i, k]
                    error[row + k] = -rotation_error[k]
                    error_rate[row + k] = rate
                    stiffness[row + k] = tp.foot_orientation_stiffness
                    damping[row + k] = tp.foot_orientation_damping
                row += axes
        else:
            # A lifted leg without a reference: a joint impedance to the nominal posture.
            for k in range(3):
                joint = 3 * i + k
                J[row + k, tp.v_joints[joint]] = 1.0
                error[row + k] = s.q_joints[joint] - tp.nominal_q[joint]
                error_rate[row + k] = s.v_joints[joint]
                stiffness[row + k] = tp.idle_leg_stiffness
                damping[row + k] = tp.idle_leg_damping
            row += 3


@kernel
def _lower_tasks(tp, s, body, attitude_first, J, Jdot_v, desired, start) -> int:
    """The trunk's levels and the posture (ProjectedImpedanceController._lower_tasks) into the
    stacked rows; returns the number of levels (start[:levels + 1] their rows)."""
    nv = tp.nv
    orientation = np.empty(3)
    orientation_error_kernel(rotation_matrix_kernel(body[3:7]), s.R_WB, orientation)
    kp_r, kd_r = tp.trunk_orientation_gains[0], tp.trunk_orientation_gains[1]
    kp_p, kd_p = tp.trunk_position_gains[0], tp.trunk_position_gains[1]
    angular = np.empty(3)
    linear = np.empty(3)
    for k in range(3):
        angular[k] = body[16 + k] + kp_r * orientation[k] + kd_r * (body[13 + k] - s.V_trunk[k])
        linear[k] = body[10 + k] + kp_p * (body[k] - s.p_WB[k]) + kd_p * (body[7 + k] - s.V_trunk[3 + k])
    J[:, :] = 0.0
    # Trunk rows in order: (first trunk row, desired) per level; the position first unless the
    # attitude must come first (see ProjectedImpedanceController._lower_tasks) or the six rows are
    # one level.
    position_first = tp.torso_position_first and not attitude_first
    split = attitude_first or tp.torso_position_first
    row = 0
    levels = 0
    start[0] = 0
    for part in range(2):
        angular_part = (part == 1) if position_first else (part == 0)
        first = 0 if angular_part else 3
        for k in range(3):
            for j in range(nv):
                J[row + k, j] = s.J_trunk[first + k, j]
            Jdot_v[row + k] = s.Jdot_v_trunk[first + k]
            desired[row + k] = angular[k] if angular_part else linear[k]
        row += 3
        if split or part == 1:
            levels += 1
            start[levels] = row
    for joint in range(12):
        J[row, tp.v_joints[joint]] = 1.0
        Jdot_v[row] = 0.0
        desired[row] = (
            tp.posture_gains[0] * (tp.nominal_q[joint] - s.q_joints[joint]) - tp.posture_gains[1] * (s.v_joints[joint])
        )
        row += 1
    levels += 1
    start[levels] = row
    return levels


@kernel
def projected_impedance_tick(
    tick_params: np.ndarray,
    dynamics_model: np.ndarray,
    snapshot: np.ndarray,
    inputs: tuple,
    terrain: np.ndarray,
    last_command: np.ndarray,
    last_reference: np.ndarray,
    last_ramp: np.ndarray,
    last_hold: np.ndarray,
    last_estimate: np.ndarray,
    last_diag: np.ndarray,
    command: np.ndarray,
    reference: np.ndarray,
    ramp: np.ndarray,
    hold: np.ndarray,
    estimate: np.ndarray,
    diag: np.ndarray,
) -> float:
    """One controller tick (ProjectedImpedanceController's update) at the estimate `base`
    and the measured joints `q`, `qd`: writes the next command, reference, ramp, hold, estimate
    and diagnostics (all but the two timing entries) and returns the tick's status. The records
    are one-element arrays: TICK_PARAMS_DTYPE, go1_dynamics.model_record and the workspace
    `snapshot` (go1_dynamics.output_dtype: the dynamics terms this tick used). `polygon_x` is
    only checked: paper 002's law has no balance task. `terrain` is the map of the ground
    (`pedi_drake.terrain.terrain_table`; no rows: flat): each held contact's friction pyramid
    stands on the normal of the terrain under it."""
    tp, s = tick_params[0], snapshot[0]
    base, q, qd, contact_set_in, body_in, has_body, leg_x, polygon_x, mu_x, trunk_wrench = inputs
    nv, nc = tp.nv, tp.nc
    d = tp.diagnostics
    reference[:] = last_reference
    ramp[:] = last_ramp
    hold[:] = last_hold
    estimate[:] = last_estimate
    contact_set, new_ramp, new_hold = np.empty(nc), np.empty(nc), np.empty(8)
    q_ref, qd_ref, body = np.empty(12), np.empty(12), np.empty(19)
    good = tick_steps.read_inputs(
        tp, inputs, last_reference, last_ramp, last_hold, contact_set, new_ramp, new_hold, q_ref, qd_ref, body
    )
    if not good:
        return tick_steps.fail(tp, tick_steps.STATUS_BAD_INPUT, last_command, q, last_diag, ramp, False, command, diag)

    # From here a failure keeps the advanced ramps and the held pose.
    ramp[:] = new_ramp
    hold[:] = new_hold
    go1_dynamics(dynamics_model, base, q, qd, snapshot)
    add_trunk_external_wrench(s.h, s.J_trunk, trunk_wrench)
    s.Jdot_v_com[:] = 0.0  # the controller's model is ControllerModel(com_bias=False)
    if not (
        tick_steps.all_finite(s.M.ravel())
        and tick_steps.all_finite(s.h)
        and tick_steps.all_finite(s.J_contacts.ravel())
    ):
        return tick_steps.fail(tp, tick_steps.STATUS_QP_FAILED, last_command, q, last_diag, ramp, True, command, diag)
    held = np.empty(nc, dtype=np.bool_)
    num_held = 0
    on_prongs = False
    for i in range(nc):
        held[i] = contact_set[i] > 0.5 or new_ramp[i] > 0.0
        if held[i]:
            num_held += 1
            if i >= 4:
                on_prongs = True
    held_idx = np.empty(num_held, dtype=np.int64)
    normals = np.empty((num_held, 3))
    k = 0
    for i in range(nc):
        if held[i]:
            held_idx[k] = i
            terrain_normal(terrain, s.p_contacts[i, 0], s.p_contacts[i, 1], normals[k])
            k += 1
    Jc = np.empty((3 * num_held, nv))
    Jcdot_v = np.empty(3 * num_held)
    for a in range(num_held):
        for axis in range(3):
            c = 3 * held_idx[a] + axis
            for j in range(nv):
                Jc[3 * a + axis, j] = s.J_contacts[c, j]
            Jcdot_v[3 * a + axis] = s.Jdot_v_contacts[c]

    # Eqs. 2 to 5.
    P = np.empty((nv, nv))
    A = np.empty((nv, nv))
    vdot_0 = np.empty(nv)
    rank = cpd.constrained_dynamics(s.M, s.h, Jc, Jcdot_v, s.v, tp.contact_damping, tp.rank_tolerance, P, A, vdot_0)
    if rank < 0:
        return tick_steps.fail(tp, tick_steps.STATUS_QP_FAILED, last_command, q, last_diag, ramp, True, command, diag)

    # Eqs. 9 and 10: the lifted legs' impedance, then the trunk and the posture.
    rows_of_leg = np.empty(4, dtype=np.int64)
    foot_row = np.empty(4, dtype=np.int64)
    m = _impedance_rows(leg_x, held, rows_of_leg, foot_row)
    J = np.empty((m, nv))
    Jdot_v = np.empty(m)
    error = np.empty(m)
    error_rate = np.empty(m)
    acceleration_ref = np.empty(m)
    stiffness = np.empty(m)
    damping = np.empty(m)
    _impedance_tasks(tp, s, leg_x, held, foot_row, J, Jdot_v, error, error_rate, acceleration_ref, stiffness, damping)
    lower_J = np.empty((18, nv))
    lower_Jdot_v = np.empty(18)
    lower_desired = np.empty(18)
    lower_start = np.empty(4, dtype=np.int64)
    # A lifted shank held in 6-D leaves the trunk three free directions: its attitude first.
    shank_held = False
    for i in range(4):
        if not held[i] and round(leg_x[12 * i]) == _SHANK_POSE:
            shank_held = True
    num_lower = _lower_tasks(tp, s, body, on_prongs or shank_held, lower_J, lower_Jdot_v, lower_desired, lower_start)
    u = np.empty(nv)
    impedance_force = np.empty(m)
    impedance_inertia = np.empty((m, m))
    residuals = np.zeros(5)
    num_residuals = cpd.prioritized_force(
        A,
        vdot_0,
        P,
        nv - rank,
        J,
        Jdot_v,
        error,
        error_rate,
        acceleration_ref,
        stiffness,
        damping,
        lower_J,
        lower_Jdot_v,
        lower_desired,
        lower_start[: num_lower + 1],
        tp.rank_tolerance,
        u,
        impedance_force,
        impedance_inertia,
        residuals,
    )
    if num_residuals < 0:
        return tick_steps.fail(tp, tick_steps.STATUS_QP_FAILED, last_command, q, last_diag, ramp, True, command, diag)
    tau_m = np.empty(12)
    vdot = np.empty(nv)
    if not cpd.constraint_free_torque(A, vdot_0, P, u, tp.v_joints, tp.rank_tolerance, tau_m, vdot):
        return tick_steps.fail(tp, tick_steps.STATUS_QP_FAILED, last_command, q, last_diag, ramp, True, command, diag)

    # Eqs. 6 to 8: the contact forces of the planned acceleration.
    held_ramp = np.empty(num_held)
    total_ramp = 0.0
    for a in range(num_held):
        held_ramp[a] = new_ramp[held_idx[a]]
        total_ramp += held_ramp[a]
    share = tp.total_weight / max(total_ramp, 1e-6)
    force_share = np.zeros(3 * num_held)
    for a in range(num_held):
        force_share[3 * a + 2] = held_ramp[a] * share
    friction = pyramid_slope(mu_x[0], tp.inscribed)
    r = np.empty(nv)
    for i in range(nv):
        value = s.h[i]
        for j in range(nv):
            value += s.M[i, j] * vdot[j]
        r[i] = value
    if not (tick_steps.all_finite(vdot) and tick_steps.all_finite(r)):
        # The QP solver is not given non-finite terms.
        return tick_steps.fail(tp, tick_steps.STATUS_QP_FAILED, last_command, q, last_diag, ramp, True, command, diag)
    lam = np.empty(3 * num_held)
    tau = np.empty(12)
    equality_residual = np.zeros(1)
    solved = cpd.contact_forces(
        Jc,
        r,
        tp.unactuated,
        tp.v_joints,
        held_ramp,
        friction,
        normals,
        tp.f_min,
        tp.f_max,
        tp.torque_limit,
        force_share,
        tp.torque_weight,
        tp.force_weight,
        tp.rank_tolerance,
        tp.qp_proximal_weight,
        lam,
        tau,
        equality_residual,
    )
    if solved == cpd.CONTACT_FORCES_INFEASIBLE or not tick_steps.all_finite(tau):
        return tick_steps.fail(tp, tick_steps.STATUS_QP_FAILED, last_command, q, last_diag, ramp, True, command, diag)
    status = tick_steps.STATUS_CONTACTS_RELAXED if solved == cpd.CONTACT_FORCES_RELAXED else tick_steps.STATUS_OK

    qdd = np.empty(12)
    for k in range(12):
        qdd[k] = vdot[tp.v_joints[k]]
    tick_steps.write_command(tp, qdd, q, qd, tau, q_ref, qd_ref, command)

    # Eq. 11 per foot impedance: Lambda eddot + D edot + K e, eddot a filtered difference.
    alpha = tp.period / (tp.period + tp.force_estimate_filter_time)
    eddot = np.zeros(m)
    for i in range(4):
        row = foot_row[i]
        e = 7 * i
        if row < 0:
            continue
        for k in range(3):
            rate = error_rate[row + k]
            if last_estimate[e + 6] > 0.5:
                raw = (rate - estimate[e + k]) / tp.period
                estimate[e + 3 + k] += alpha * (raw - estimate[e + 3 + k])
            else:
                estimate[e + 3 + k] = 0.0
            estimate[e + k] = rate
            eddot[row + k] = estimate[e + 3 + k]
    forces_estimated = np.zeros(12)
    for i in range(4):
        row = foot_row[i]
        if row < 0:
            for k in range(_ESTIMATE_ENTRIES):
                estimate[7 * i + k] = 0.0
            continue
        cpd.impedance_force_estimate(
            impedance_inertia[row : row + 3],
            stiffness[row : row + 3],
            damping[row : row + 3],
            error[row : row + 3],
            error_rate[row : row + 3],
            eddot,
            forces_estimated[3 * i : 3 * i + 3],
        )
        estimate[7 * i + 6] = 1.0

    ground = 0.0
    if num_held:
        for a in range(num_held):
            ground += s.p_contacts[held_idx[a], 2]
        ground = ground / num_held - robot.FOOT_RADIUS
    tick_steps.write_diagnostics(tp, s, status, ground, body, tau, new_ramp, last_diag, diag)
    for i in range(4):
        row = foot_row[i]
        diag[d[tick_steps.FOOT_ERRORS] + i] = _norm3(error, row) if row >= 0 else 0.0
    for k in range(tp.max_residuals):
        diag[d[tick_steps.RESIDUALS] + k] = 0.0
    for k in range(min(num_residuals, tp.max_residuals)):
        diag[d[tick_steps.RESIDUALS] + k] = residuals[k]
    if num_residuals < tp.max_residuals:
        diag[d[tick_steps.RESIDUALS] + num_residuals] = equality_residual[0]
    for j in range(3 * nc):
        diag[d[tick_steps.FORCES] + j] = 0.0
    for a in range(num_held):
        for axis in range(3):
            diag[d[tick_steps.FORCES] + 3 * held_idx[a] + axis] = lam[3 * a + axis]
    for j in range(12):
        diag[d[_ESTIMATE] + j] = forces_estimated[j]
    diag[d[_RANK]] = rank
    reference[:12] = q_ref
    reference[12:] = qd_ref
    return status


@kernel
def _norm3(x: np.ndarray, start: int) -> float:
    return math.sqrt(x[start] ** 2 + x[start + 1] ** 2 + x[start + 2] ** 2)
