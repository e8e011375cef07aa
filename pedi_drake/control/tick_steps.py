"""The steps both whole-body ticks share, as kernels: reading the inputs into the tick's references,
holding the last command on a failure, turning joint accelerations into the command, and the
diagnostics every controller reports.

`whole_body_tick` (the task-priority HQP) and `projected_impedance_tick` (paper 002's law) differ
in how they find the joint accelerations and torques of an instant; what comes before and after
that is the same and lives here. A tick's parameter record (`tp`) has, whatever else it holds, the
fields `period`, `contact_ramp_time`, `max_reference_rate_deviation`, `max_reference_deviation`,
`joint_kp`, `joint_kd`, `failure_kd` and `diagnostics` (the start of each DIAGNOSTICS_FIELDS
slice, then the tick's own).
"""

import math

import numpy as np

from pedi_drake.control.compiled_stack import capture_point
from pedi_drake.go1_command import write_held_command
from pedi_drake.runtime.jit import kernel
from pedi_drake.vector3 import orientation_error_kernel, rotation_matrix_kernel

# The status a tick returns and reports in its diagnostics.
STATUS_OK, STATUS_QP_FAILED, STATUS_BAD_INPUT, STATUS_CONTACTS_RELAXED = 0.0, 1.0, 2.0, 3.0
# The slices of the diagnostics vector both ticks write, in the order of `tp.diagnostics`.
DIAGNOSTICS_FIELDS = (
    "status",
    "consecutive_failures",
    "total_failures",
    "capture_point",
    "trunk_position_error",
    "trunk_orientation_error",
    "foot_errors",
    "level_residuals",
    "contact_forces",
    "tau_ff",
    "contact_ramp",
)
STATUS, CONSECUTIVE, TOTAL, CAPTURE_POINT, TRUNK_POSITION, TRUNK_ORIENTATION = range(6)
FOOT_ERRORS, RESIDUALS, FORCES, TAU, RAMP = range(6, 11)
# A tick's inputs, a tuple in this order: the state estimate (13), the measured joint angles and
# rates (12 each), the contact set (nc), the body reference (19) and whether it is connected (else
# the held pose), the leg references (48), the safety polygon, the friction coefficient (1) and
# the trunk's external wrench (6); the controllers pass their ports' values, or stand-ins for
# unconnected ones.
TICK_INPUTS = (
    "base_state",
    "position_measured",
    "velocity_measured",
    "contact_set",
    "body_reference",
    "has_body_reference",
    "leg_reference",
    "safety_polygon",
    "friction",
    "trunk_external_wrench",
)


@kernel
def all_finite(x: np.ndarray) -> bool:
    """Whether every entry of the vector x is finite."""
    for value in x:
        if not math.isfinite(value):
            return False
    return True


@kernel
def fail(tp, status, last_command, q, last_diag, ramp, record_ramp, command, diag) -> float:
    """The last good command held with zero velocity target and `failure_kd` damping, and the
    failure counted in the diagnostics (the ramps too, when `record_ramp`); returns `status`."""
    write_held_command(last_command, q, tp.failure_kd, command)
    d = tp.diagnostics
    diag[:] = last_diag
    diag[d[STATUS]] = status
    if record_ramp:
        for i in range(ramp.shape[0]):
            diag[d[RAMP] + i] = ramp[i]
    diag[d[CONSECUTIVE]] += 1.0
    diag[d[TOTAL]] += 1.0
    return status


@kernel
def read_inputs(
    tp,
    inputs,
    last_reference,
    last_ramp,
    last_hold,
    contact_set,
    ramp,
    hold,
    q_ref,
    qd_ref,
    body,
) -> bool:
    """The tick's inputs (a TICK_INPUTS tuple) checked and turned into its references; False for a
    non-finite input or a friction coefficient that is not positive (the outputs then meaningless).

    Writes the contact set clipped to [0, 1], the contact ramps advanced towards it by at most
    period / contact_ramp_time, the held trunk pose (8: initialised flag, p_WB, quaternion), the
    joint reference (q_ref, qd_ref) and the trunk reference `body` (19; the held pose when no body
    reference is connected). On the first tick (the held pose not yet initialised) the trunk pose
    is held where it is, the joint reference starts at the measurement and the ramps at the
    contact set: the robot starts on its feet."""
    base, q, qd, contact_set_in, body_in, has_body, leg_x, polygon_x, mu_x, trunk_wrench = inputs
    for i in range(contact_set.shape[0]):
        contact_set[i] = min(max(contact_set_in[i], 0.0), 1.0)
    if not (all_finite(base) and all_finite(q) and all_finite(qd) and all_finite(contact_set)):
        return False
    hold[:] = last_hold
    ramp[:] = last_ramp
    q_ref[:] = last_reference[:12]
    qd_ref[:] = last_reference[12:]
    if hold[0] == 0.0:
        hold[0] = 1.0
        hold[1:4] = base[4:7]
        hold[4:8] = base[0:4]
        q_ref[:] = q
        qd_ref[:] = qd
        ramp[:] = contact_set
    step = tp.period / max(tp.contact_ramp_time, 1e-9)
    for i in range(ramp.shape[0]):
        change = min(max(contact_set[i] - ramp[i], -step), step)
        ramp[i] = min(max(ramp[i] + change, 0.0), 1.0)
    body[:] = 0.0
    if has_body:
        body[:] = body_in
    else:
        body[0:3] = hold[1:4]
        body[3:7] = hold[4:8]
    inputs_finite = all_finite(body) and all_finite(leg_x) and all_finite(polygon_x) and all_finite(mu_x)
    return inputs_finite and all_finite(trunk_wrench) and mu_x[0] > 0.0


@kernel
def write_command(tp, qdd, q, qd, tau, q_ref, qd_ref, command) -> None:
    """The command from the joint accelerations qdd (12, Unitree order) [rad/s^2] and torques tau
    (12) [N m]: qdd integrated into the joint reference (q_ref, qd_ref, updated in place), kept
    near the measurement so that a long stall (an obstacle in the way) cannot wind up the PD,
    under the configured joint gains."""
    for k in range(12):
        rate = qd_ref[k] + qdd[k] * tp.period
        qd_ref[k] = min(max(rate, qd[k] - tp.max_reference_rate_deviation), qd[k] + tp.max_reference_rate_deviation)
        angle = q_ref[k] + qd_ref[k] * tp.period
        q_ref[k] = min(max(angle, q[k] - tp.max_reference_deviation), q[k] + tp.max_reference_deviation)
        command[k] = q_ref[k]
        command[12 + k] = qd_ref[k]
        command[24 + k] = tp.joint_kp
        command[36 + k] = tp.joint_kd
        command[48 + k] = tau[k]


@kernel
def write_diagnostics(tp, s, status, ground: float, body, tau, ramp, last_diag, diag) -> None:
    """The diagnostics of a solved tick both controllers report: the status (the failure count
    reset), the capture point over the ground at height `ground` [m], the trunk's position and
    attitude errors against `body`, the torques and the contact ramps. The rest of `diag` is
    `last_diag` until the tick writes its own entries."""
    d = tp.diagnostics
    diag[:] = last_diag
    diag[d[STATUS]] = status
    diag[d[CONSECUTIVE]] = 0.0
    capture_point(s, ground, diag[d[CAPTURE_POINT] : d[CAPTURE_POINT] + 2])
    for k in range(3):
        diag[d[TRUNK_POSITION] + k] = body[k] - s.p_WB[k]
    start = d[TRUNK_ORIENTATION]
    orientation_error_kernel(rotation_matrix_kernel(body[3:7]), s.R_WB, diag[start : start + 3])
    for k in range(12):
        diag[d[TAU] + k] = tau[k]
    for i in range(ramp.shape[0]):
        diag[d[RAMP] + i] = ramp[i]
