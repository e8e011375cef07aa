"""One tick of the whole-body controller as one compiled call.

`WholeBodyController` (whole_body_controller.py) documents what a tick does. `whole_body_tick`
takes the tick's inputs and the controller's discrete state as arrays, writes the next state, and
returns the tick's status, with the dynamics terms from `go1_dynamics`, the levels from
`compiled_stack.build_levels`, the hierarchical solve from `compiled_hqp` and the steps it shares
with paper 002's tick from `tick_steps`. No Python object is touched between the first input and the last
output, so a tick costs tens of microseconds instead of a millisecond, and the interpreter's lock
is released throughout (the driver's receive thread runs meanwhile).

Discrete state, as WholeBodyController declares it: command (60), reference (24: q_ref, qd_ref
in Unitree order), ramp (nc), hold (8: initialised flag, p_WB, quaternion), diagnostics
(`whole_body_controller.diagnostics_layout`).
"""

import math

import numpy as np

from pedi_drake import robot
from pedi_drake.control import compiled_hqp
from pedi_drake.control.compiled_stack import MAX_LEVELS, build_levels, torque_map
from pedi_drake.control.references import SAFETY_POLYGON_MAX_VERTICES
from pedi_drake.control.tick_steps import (
    DIAGNOSTICS_FIELDS,
    FOOT_ERRORS,
    FORCES,
    RESIDUALS,
    STATUS_BAD_INPUT,
    STATUS_CONTACTS_RELAXED,
    STATUS_OK,
    STATUS_QP_FAILED,
    all_finite,
    fail,
    read_inputs,
    write_command,
    write_diagnostics,
)
from pedi_drake.dynamics.go1_dynamics import add_trunk_external_wrench, go1_dynamics
from pedi_drake.polygon import halfplanes_kernel
from pedi_drake.runtime.jit import kernel, new_record
from pedi_drake.terrain import terrain_normal

_FOOT_MODE = 1


# Constants of a configured WholeBodyController's tick (`tick_params`); the stack's own are
# compiled_stack.STACK_PARAMS_DTYPE.
TICK_PARAMS_DTYPE = np.dtype(
    [
        ("period", "f8"),  # [s]
        ("contact_ramp_time", "f8"),  # [s]
        ("max_reference_rate_deviation", "f8"),  # [rad/s]
        ("max_reference_deviation", "f8"),  # [rad]
        ("joint_kp", "f8"),  # [N m/rad]
        ("joint_kd", "f8"),  # [N m s/rad]
        ("failure_kd", "f8"),  # [N m s/rad]
        ("safety_margin", "f8"),  # [m]
        ("strict", "?"),  # strict priorities, else one weighted QP
        ("num_level_weights", "i8"),  # 0: weights 100^(L-1-k)
        ("level_weights", "f8", MAX_LEVELS),  # weighted mode, per level of the stack
        ("rank_tolerance", "f8"),
        ("fix_tolerance", "f8"),
        ("proximal_weight", "f8"),
        ("regularization", "f8"),
        ("diagnostics", "i8", len(DIAGNOSTICS_FIELDS)),  # start of each DIAGNOSTICS_FIELDS slice
        ("max_residuals", "i8"),  # entries of the level_residuals slice
    ]
)


def tick_params(config, settings, diagnostics_layout: dict[str, slice], max_residuals: int) -> np.ndarray:
    """The TICK_PARAMS_DTYPE record of a WholeBodyControllerConfig `config`, HqpSettings
    `settings` and the controller's diagnostics layout."""
    record = new_record(TICK_PARAMS_DTYPE)
    r = record[0]
    for name in (
        "period",
        "contact_ramp_time",
        "max_reference_rate_deviation",
        "max_reference_deviation",
        "joint_kp",
        "joint_kd",
        "failure_kd",
        "safety_margin",
    ):
        r[name] = getattr(config, name)
    r["strict"] = config.hqp_mode != "weighted"
    r["num_level_weights"] = len(config.level_weights)
    r["level_weights"][: len(config.level_weights)] = config.level_weights
    for name in ("rank_tolerance", "fix_tolerance", "proximal_weight", "regularization"):
        r[name] = getattr(settings, name)
    r["diagnostics"] = [diagnostics_layout[name].start for name in DIAGNOSTICS_FIELDS]
    r["max_residuals"] = max_residuals
    return record


@kernel
def _solve(tp, p, table, num_levels: int, relaxed: bool, x, residuals) -> int:
    """The built levels, solved strictly or weighted; a compiled_hqp status."""
    n = p.nv + 3 * p.nc
    t = table
    eq_start = t.eq_start[: num_levels + 1]
    hard_start = t.hard_start[: num_levels + 1]
    soft_start = t.soft_start[: num_levels + 1]
    eq_A, eq_b = t.eq_A[: eq_start[num_levels]], t.eq_b[: eq_start[num_levels]]
    hard_G, hard_h = t.hard_G[: hard_start[num_levels]], t.hard_h[: hard_start[num_levels]]
    ms = soft_start[num_levels]
    rows = (eq_A, eq_b, eq_start, hard_G, hard_h, hard_start, t.soft_G[:ms], t.soft_h[:ms], t.soft_w[:ms], soft_start)
    if tp.strict:
        status = compiled_hqp.solve_strict(
            n, rows, tp.rank_tolerance, tp.fix_tolerance, tp.proximal_weight, x, residuals[:num_levels]
        )
    else:
        weights = np.empty(num_levels)
        if tp.num_level_weights:
            k = 0
            for level in range(num_levels):
                # The sliding contacts' level weighs as the limits' level above it.
                if relaxed and level == 2:
                    weights[level] = tp.level_weights[1]
                else:
                    weights[level] = tp.level_weights[k]
                    k += 1
        else:
            for level in range(num_levels):
                weights[level] = 100.0 ** (num_levels - 1 - level)
        status = compiled_hqp.solve_weighted(
            n, rows, weights, tp.regularization, tp.proximal_weight, x, residuals[:num_levels]
        )
    if status == compiled_hqp.STATUS_OK and not all_finite(x):
        status = compiled_hqp.STATUS_INFEASIBLE
    return status


@kernel
def whole_body_tick(
    tick_params: np.ndarray,
    stack_params: np.ndarray,
    dynamics_model: np.ndarray,
    snapshot: np.ndarray,
    inputs: tuple,
    terrain: np.ndarray,
    table_record: np.ndarray,
    command: np.ndarray,
    reference: np.ndarray,
    ramp: np.ndarray,
    hold: np.ndarray,
    diag: np.ndarray,
) -> float:
    """One controller tick (WholeBodyController._update) at the estimate `base` and the measured
    joints `q`, `qd`: updates the discrete state in place (command, reference, ramp, hold and
    diagnostics hold the current state on entry and the next on return; the diagnostics' two
    timing entries are the caller's) and returns the tick's status. The records are one-element arrays:
    TICK_PARAMS_DTYPE, compiled_stack.STACK_PARAMS_DTYPE, go1_dynamics.model_record, and the
    workspaces `snapshot` (go1_dynamics.output_dtype: the dynamics terms this tick used) and
    `table_record` (compiled_stack.table_dtype: the levels' rows). `terrain` is the map of the
    ground (`pedi_drake.terrain.terrain_table`; no rows: flat): each contact's friction pyramid
    stands on the normal of the terrain under it."""
    tp, p, s, table = tick_params[0], stack_params[0], snapshot[0], table_record[0]
    base, q, qd, contact_set_in, body_in, has_body, leg_x, polygon_x, mu_x, trunk_wrench = inputs
    last_command, last_reference = command.copy(), reference.copy()
    last_ramp, last_hold, last_diag = ramp.copy(), hold.copy(), diag.copy()
    nv, nc = p.nv, p.nc
    d = tp.diagnostics
    contact_set, new_ramp, new_hold = np.empty(nc), np.empty(nc), np.empty(8)
    q_ref, qd_ref, body = np.empty(12), np.empty(12), np.empty(19)
    good = read_inputs(
        tp, inputs, last_reference, last_ramp, last_hold, contact_set, new_ramp, new_hold, q_ref, qd_ref, body
    )
    num_vertices = round(polygon_x[0]) if good else 0
    zero_quaternion = base[0] == 0.0 and base[1] == 0.0 and base[2] == 0.0 and base[3] == 0.0
    if not good or zero_quaternion or (num_vertices != 0 and not 3 <= num_vertices <= SAFETY_POLYGON_MAX_VERTICES):
        return fail(tp, STATUS_BAD_INPUT, last_command, q, last_diag, ramp, False, command, diag)
    go1_dynamics(dynamics_model, base, q, qd, snapshot)
    add_trunk_external_wrench(s.h, s.J_trunk, trunk_wrench)
    if not p.com_bias:
        s.Jdot_v_com[:] = 0.0

    no_motion = np.empty(nc, dtype=np.bool_)
    normals = np.empty((nc, 3))
    num_loaded = 0
    ground = 0.0
    for i in range(nc):
        terrain_normal(terrain, s.p_contacts[i, 0], s.p_contacts[i, 1], normals[i])
        no_motion[i] = contact_set[i] > 0.5 or new_ramp[i] > 0.0
        if contact_set[i] > 0.5:
            num_loaded += 1
            ground += s.p_contacts[i, 2]
    if num_loaded:
        ground = ground / num_loaded - robot.FOOT_RADIUS
    max_rows = max(SAFETY_POLYGON_MAX_VERTICES, nc)
    polygon_N = np.empty((max_rows, 2))
    polygon_d = np.empty(max_rows)
    rows = 0
    if num_vertices > 0:
        c, sn = math.cos(polygon_x[3]), math.sin(polygon_x[3])
        vertices = np.empty((num_vertices, 2))
        for k in range(num_vertices):
            vx, vy = polygon_x[4 + 2 * k], polygon_x[5 + 2 * k]
            vertices[k, 0] = polygon_x[1] + (vx * c - vy * sn)
            vertices[k, 1] = polygon_x[2] + (vx * sn + vy * c)
        rows = halfplanes_kernel(vertices, 0.0, polygon_N, polygon_d)
    elif num_loaded >= 3:
        points = np.empty((num_loaded, 2))
        k = 0
        for i in range(nc):
            if contact_set[i] > 0.5:
                points[k, 0] = s.p_contacts[i, 0]
                points[k, 1] = s.p_contacts[i, 1]
                k += 1
        rows = halfplanes_kernel(points, tp.safety_margin, polygon_N, polygon_d)

    n = nv + 3 * nc
    T = np.empty((12, n))
    t0 = np.empty(12)
    torque_map(p, s, T, t0)
    x = np.zeros(n)
    residuals = np.zeros(MAX_LEVELS)
    # The stack as it is; if that fails, again with the sliding contacts let brake (friction
    # cannot stop them at once): their no-motion rows on a level of their own below the limits.
    status = STATUS_QP_FAILED
    num_levels = 0
    for relaxed in (False, True):
        num_levels = build_levels(
            p,
            s,
            body,
            leg_x,
            new_ramp,
            no_motion,
            polygon_N[:rows],
            polygon_d[:rows],
            mu_x[0],
            normals,
            ground,
            relaxed,
            T,
            t0,
            table,
        )
        if num_levels == 0:
            break  # no sliding contact: relaxing changes nothing
        if _solve(tp, p, table, num_levels, relaxed, x, residuals) == compiled_hqp.STATUS_OK:
            status = STATUS_CONTACTS_RELAXED if relaxed else STATUS_OK
            break
    if status == STATUS_QP_FAILED:
        ramp[:] = new_ramp
        hold[:] = new_hold
        return fail(tp, STATUS_QP_FAILED, last_command, q, last_diag, ramp, False, command, diag)

    tau = T @ x + t0
    qdd = np.empty(12)
    for k in range(12):
        qdd[k] = x[p.v_joints[k]]
    write_command(tp, qdd, q, qd, tau, q_ref, qd_ref, command)

    write_diagnostics(tp, s, status, ground, body, tau, new_ramp, last_diag, diag)
    for i in range(4):
        error = 0.0
        if round(leg_x[12 * i]) == _FOOT_MODE:
            for k in range(3):
                error += (leg_x[12 * i + 1 + k] - s.p_contacts[i, k]) ** 2
        diag[d[FOOT_ERRORS] + i] = math.sqrt(error)
    for k in range(tp.max_residuals):
        diag[d[RESIDUALS] + k] = residuals[k] if k < num_levels else 0.0
    for j in range(3 * nc):
        diag[d[FORCES] + j] = x[nv + j]
    reference[:12] = q_ref
    reference[12:] = qd_ref
    ramp[:] = new_ramp
    hold[:] = new_hold
    return status
