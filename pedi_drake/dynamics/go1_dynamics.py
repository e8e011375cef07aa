"""Compiled rigid-body dynamics of the Go1 as the whole-body controllers see it, in one call.

`go1_dynamics(model, base_state, q_joints, v_joints, out)` is a `pedi_drake.runtime.jit.kernel`: from the
state estimate and the measured joints it fills every term of a `RobotSnapshot` (mass matrix,
bias, contact and trunk Jacobians with their bias accelerations, centre of mass, calf
orientations) in the plant's own velocity order. It is nopython-callable, so a compiled
controller calls it inside its own kernel; `Go1Dynamics` is the Python owner of its arrays.

Why this exists beside Drake's MultibodyPlant, which computes the same terms (the tests hold the
two equal; `ControllerModel(compiled=False)` is the Drake path): one update by Drake's calls takes
about fifty times as long as this kernel, and longer than the whole compiled whole-body tick
that calls it (medians measured in one run by `python -m
pedi_drake.benchmarks.dynamics`), which would take the controller side's tick past its budget.

Parameters come from the plant (`robot.make_go1_plant(robot.design_key(prongs))`) once, in
`Go1Model.from_plant`, never from constants: a changed URDF or prong design flows through. The
plant is a floating trunk with revolute joints under it; bodies welded to a jointed body (rotors,
feet, the IMU, prongs) are merged into that body's rigid body (mass, centre of mass, inertia).
The joint actuators' reflected rotor inertia (rotor inertia x gear ratio^2 [kg m^2]) is added to
the mass matrix's diagonal, as Drake does; the joints' viscous damping [N m s/rad] is added to h,
as `ControllerModel` does.

Frames and notation. W world, B trunk, b any jointed body, F a joint's frame on its parent body,
M its frame on the child (X_FM = rotation about the joint axis by q). Every spatial quantity in the
kernel is expressed in W's axes and taken about O, the world-fixed point that coincides with the
trunk origin at this instant (so positions r = p_W* - p_WB stay small whatever p_WB is, and the
floating base's velocity v_base = [w_WB; v_WB] is itself the trunk's spatial velocity about O).
Spatial vectors are [angular; linear]:
    twist V_b = [w_b; v_b(O)] in [rad/s, m/s], v_b(O) the velocity of b's material point at O;
    a point P of b at r moves with v_P = v_b(O) + w_b x r;
    a revolute joint with unit axis a through r_F has the motion subspace S = [a; r_F x a];
    rigid body inertia about O, body mass m, centre of mass at c, rotational inertia Ibar about
    the centre of mass (W axes): I = [[Ibar + m [c]x [c]x^T, m [c]x], [m [c]x^T, m 1]].

Algorithms (n bodies, nv = 6 + n - 1 velocities):
1. Forward kinematics, trunk to leaves: R_Wb, r_b, S_b, V_b = V_parent + S_b qd_b.
2. Bias accelerations with vdot = 0: the spatial acceleration (time derivative of V at fixed O)
   A_B = [0; v_WB x w_WB] of the trunk (from differentiating v_B(O) = v_WB + (p_WB - O) x w_WB),
   A_b = A_parent + (V_parent x S_b) qd_b [rad/s^2, m/s^2] for the joints. The classical
   acceleration of a point P fixed in b is a_P = A_b,lin + A_b,ang x r_P + w_b x v_P: that gives
   Jdot v of every contact point, of the trunk origin (zero: the base velocities are the trunk's
   own) and of every body's centre of mass (Jdot_v_com = sum m_b a_cb / m).
3. Recursive Newton-Euler with vdot = 0 and gravity as a fictitious base acceleration -g:
   f_b = I_b (A_b + [0; -g]) + V_b x* (I_b V_b), summed leaves to trunk into f_c,b; then
   h_b = S_b^T f_c,b + damping_b qd_b for the joints and h_base = f_c,B [N m, N]. So h = C(q, v) v
   - tau_g(q) + damping v, exactly what ControllerModel computes from Drake.
4. Composite rigid bodies: I_c,b = I_b + sum over children; M_base,base = I_c,B; for a joint b,
   F = I_c,b S_b, M_bb = S_b^T F + reflected inertia, M_jb = S_j^T F for every joint j on b's path
   to the trunk and M_base,b = F [kg, kg m, kg m^2]. The trunk row block's linear part F_lin / m is
   the centre-of-mass Jacobian (the robot's linear momentum is m v_com).
5. Jacobians from the motion subspaces: a point P of b has the column S_j,lin + S_j,ang x r_P for
   each joint j on b's path, -[r_P]x for w_WB and 1 for v_WB; the calf's angular velocity has
   S_j,ang and 1 for w_WB; the trunk's spatial Jacobian is [1 0; 0 1] on the base and zero else.

The kernel allocates only its per-body workspace; the outputs are the caller's.
"""

import math
from typing import NamedTuple

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import BodyIndex, JointActuatorIndex, JointIndex

from pedi_drake import robot
from pedi_drake.dynamics.robot_snapshot import RobotSnapshot
from pedi_drake.exceptions import PediError
from pedi_drake.prongs import ProngDesign
from pedi_drake.runtime.jit import kernel, new_record


def contact_points(prongs: ProngDesign | None) -> tuple[tuple[str, np.ndarray], ...]:
    """(body name, p_BP [m] in that body's frame) of every contact in the controller's order:
    the four foot sphere centres (Unitree order), then the prong tip sphere centres."""
    feet = tuple((name, np.zeros(3)) for name in robot.FOOT_BODY_NAMES)
    tips = tuple((name, np.array([0.0, 0.0, -prongs.length])) for name in robot.prong_body_names(prongs))
    return feet + tips


CALF_BODY_NAMES = tuple(f"{leg}_calf" for leg in robot.LEG_NAMES)


class Go1Model(NamedTuple):
    """The plant's parameters for `go1_dynamics`: n jointed bodies (0 the trunk, every parent
    before its children), nv velocities, nc contact points. Rows of per-body arrays hold the
    body's joint (the trunk's row is unused where it has no joint)."""

    parent: np.ndarray  # (n,) int64 parent body row, -1 for the trunk
    joint_unitree: np.ndarray  # (n,) int64 index of the body's joint in Unitree order, -1 for the trunk
    joint_q: np.ndarray  # (n,) int64 plant position index of the body's joint, -1 for the trunk
    joint_v: np.ndarray  # (n,) int64 plant velocity index of the body's joint, -1 for the trunk
    base_start: np.ndarray  # (2,) int64 the trunk's start in q (quaternion wxyz, p_WB) and in v (w, v)
    R_PF: np.ndarray  # (n, 3, 3) orientation of the joint frame F in the parent body's frame
    p_PF: np.ndarray  # (n, 3) position of F's origin in the parent body's frame [m]
    axis_F: np.ndarray  # (n, 3) unit joint axis in F (and in M)
    R_MC: np.ndarray  # (n, 3, 3) orientation of the body frame C in the joint's child frame M
    p_MC: np.ndarray  # (n, 3) position of C's origin in M [m]
    mass: np.ndarray  # (n,) mass of the merged rigid body [kg]
    p_CScm: np.ndarray  # (n, 3) its centre of mass in the body frame [m]
    I_Scm: np.ndarray  # (n, 3, 3) its rotational inertia about that centre, body frame [kg m^2]
    reflected_inertia: np.ndarray  # (nv,) rotor inertia x gear ratio^2 on the actuated joints [kg m^2]
    damping: np.ndarray  # (nv,) viscous damping of the revolute joints [N m s/rad]
    gravity: np.ndarray  # (3,) gravity acceleration in W [m/s^2]
    contact_body: np.ndarray  # (nc,) int64 body row of each contact point
    p_CP: np.ndarray  # (nc, 3) each contact point in its body's frame [m]
    calf_body: np.ndarray  # (4,) int64 body row of each calf, Unitree leg order

    @staticmethod
    def from_plant(plant: MultibodyPlant, plant_map: robot.Go1PlantMap, prongs: ProngDesign | None) -> "Go1Model":
        """Reads the tree, inertias, actuators, damping and gravity of a finalized Go1 plant."""
        return _model_from_plant(plant, plant_map, prongs)


def output_dtype(nq: int, nv: int, nc: int) -> np.dtype:
    """What `go1_dynamics` fills, as a record (`jit.new_record`): the fields of `RobotSnapshot` (v
    in the plant's order) and the calves' angular terms."""
    return np.dtype(
        [
            ("q", "f8", nq),  # plant positions, unit quaternion
            ("v", "f8", nv),  # plant velocities
            ("M", "f8", (nv, nv)),  # mass matrix, reflected rotor inertia included
            ("h", "f8", nv),  # C(q, v) v - tau_g(q) + damping v [N m, N]
            ("J_contacts", "f8", (3 * nc, nv)),  # translational Jacobians of the contact points, W
            ("Jdot_v_contacts", "f8", 3 * nc),  # their bias accelerations, W [m/s^2]
            ("p_contacts", "f8", (nc, 3)),  # contact points in W [m]
            ("J_trunk", "f8", (6, nv)),  # trunk spatial Jacobian [angular; translational], W
            ("Jdot_v_trunk", "f8", 6),  # trunk spatial bias acceleration [rad/s^2; m/s^2]
            ("R_WB", "f8", (3, 3)),
            ("p_WB", "f8", 3),  # [m]
            ("p_com", "f8", 3),  # centre of mass in W [m]
            ("J_com", "f8", (3, nv)),
            ("Jdot_v_com", "f8", 3),  # [m/s^2]
            ("V_trunk", "f8", 6),  # [w_WB; v_WB] [rad/s, m/s]
            ("v_com", "f8", 3),  # [m/s]
            ("q_joints", "f8", 12),  # the measured joints, Unitree order [rad]
            ("v_joints", "f8", 12),  # [rad/s]
            ("R_WC", "f8", (4, 3, 3)),  # calf orientations, Unitree leg order
            ("J_w_calf", "f8", (4, 3, nv)),  # calf angular-velocity Jacobians, W
            ("Jdot_w_calf", "f8", (4, 3)),  # calf angular bias accelerations, W [rad/s^2]
        ]
    )


def model_record(model: Go1Model) -> np.ndarray:
    """`model` as a record (`jit.new_record`), the form `go1_dynamics` takes."""
    fields = model._asdict()
    dtype = np.dtype([(name, value.dtype, value.shape) for name, value in fields.items()])
    record = new_record(dtype)
    for name, value in fields.items():
        record[0][name] = value
    return record


def _model_from_plant(plant: MultibodyPlant, plant_map: robot.Go1PlantMap, prongs: ProngDesign | None) -> Go1Model:
    context = plant.CreateDefaultContext()
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME, plant_map.model)
    joints = [plant.get_joint(JointIndex(i)) for i in range(plant.num_joints())]
    joint_of_child = {j.child_body().index(): j for j in joints}
    floating = joint_of_child[trunk.index()]
    if floating.type_name() != "quaternion_floating" or floating.parent_body().index() != BodyIndex(0):
        raise PediError(f"go1_dynamics expects the trunk on a quaternion floating joint, not {floating.type_name()}")
    if np.any(floating.default_damping_vector() != 0.0):
        raise PediError("go1_dynamics expects no damping on the trunk's floating joint (ControllerModel has none)")

    # Jointed bodies in tree order (parents first); welded bodies map to the jointed body they move with.
    children: dict = {}
    for j in joints:
        children.setdefault(j.parent_body().index(), []).append(j)
    rows = [trunk.index()]
    mobilizer_of = {trunk.index(): trunk.index()}  # body -> the jointed body it is welded to
    queue = [trunk.index()]
    while queue:
        body = queue.pop(0)
        for j in children.get(body, []):
            child = j.child_body().index()
            if j.type_name() == "weld":
                mobilizer_of[child] = mobilizer_of[body]
            elif j.type_name() == "revolute":
                mobilizer_of[child] = child
                rows.append(child)
            else:
                raise PediError(f"go1_dynamics handles revolute and weld joints; {j.name()} is {j.type_name()}")
            queue.append(child)
    if len(mobilizer_of) != plant.num_bodies() - 1:
        raise PediError("go1_dynamics expects every body of the plant (but the world) under the trunk")
    row_of = {body: i for i, body in enumerate(rows)}
    n = len(rows)
    nv = plant.num_velocities()

    def X_mobilizer(body_index):
        """X_AB: pose of body `body_index` in the frame of the jointed body A it is welded to."""
        frame_A = plant.get_body(mobilizer_of[body_index]).body_frame()
        return plant.CalcRelativeTransform(context, frame_A, plant.get_body(body_index).body_frame())

    unitree_of_joint = {name: i for i, name in enumerate(robot.JOINT_NAMES)}
    parent = np.full(n, -1, dtype=np.int64)
    joint_unitree = np.full(n, -1, dtype=np.int64)
    joint_q = np.full(n, -1, dtype=np.int64)
    joint_v = np.full(n, -1, dtype=np.int64)
    R_PF, p_PF, axis_F = np.tile(np.eye(3), (n, 1, 1)), np.zeros((n, 3)), np.zeros((n, 3))
    R_MC, p_MC = np.tile(np.eye(3), (n, 1, 1)), np.zeros((n, 3))
    damping = np.zeros(nv)
    for i, body in enumerate(rows[1:], start=1):
        j = joint_of_child[body]
        if j.name() not in unitree_of_joint:
            raise PediError(f"go1_dynamics: revolute joint {j.name()} is not one of the Go1's twelve")
        parent_mobilizer = mobilizer_of[j.parent_body().index()]
        parent[i] = row_of[parent_mobilizer]
        joint_unitree[i] = unitree_of_joint[j.name()]
        joint_q[i] = j.position_start()
        joint_v[i] = j.velocity_start()
        X_PF = plant.CalcRelativeTransform(context, plant.get_body(parent_mobilizer).body_frame(), j.frame_on_parent())
        R_PF[i], p_PF[i] = X_PF.rotation().matrix(), X_PF.translation()
        axis_F[i] = j.revolute_axis()
        X_MC = j.frame_on_child().GetFixedPoseInBodyFrame().inverse()
        R_MC[i], p_MC[i] = X_MC.rotation().matrix(), X_MC.translation()
        damping[j.velocity_start()] = j.default_damping()

    # Merged rigid bodies: mass, centre of mass and central inertia of each jointed body and its welds.
    mass = np.zeros(n)
    p_CScm = np.zeros((n, 3))
    I_Scm = np.zeros((n, 3, 3))
    parts: dict = {i: [] for i in range(n)}
    for body_index, mobilizer in mobilizer_of.items():
        body = plant.get_body(body_index)
        M_BBo_B = body.CalcSpatialInertiaInBodyFrame(context)
        m, p_BBcm = M_BBo_B.get_mass(), M_BBo_B.get_com()
        # Rotational inertia about the body's own centre of mass (parallel axis theorem).
        I_BBcm = M_BBo_B.CalcRotationalInertia().CopyToFullMatrix3() - m * (
            (p_BBcm @ p_BBcm) * np.eye(3) - np.outer(p_BBcm, p_BBcm)
        )
        X_AB = X_mobilizer(body_index)
        R_AB = X_AB.rotation().matrix()
        parts[row_of[mobilizer]].append((m, X_AB @ p_BBcm, R_AB @ I_BBcm @ R_AB.T))
    for i, members in parts.items():
        mass[i] = sum(m for m, _, _ in members)
        if mass[i] > 0.0:  # a massless body keeps its centre of mass at its origin (it weighs nothing)
            p_CScm[i] = sum(m * c for m, c, _ in members) / mass[i]
        for m, c, inertia in members:
            d = c - p_CScm[i]
            I_Scm[i] += inertia + m * ((d @ d) * np.eye(3) - np.outer(d, d))

    reflected_inertia = np.zeros(nv)
    for k in range(plant.num_actuators()):
        actuator = plant.get_joint_actuator(JointActuatorIndex(k))
        reflected_inertia[actuator.joint().velocity_start()] += actuator.default_reflected_inertia()

    contact_body, p_CP = [], []
    for name, p_BP in contact_points(prongs):
        body = plant.GetBodyByName(name, plant_map.model).index()
        contact_body.append(row_of[mobilizer_of[body]])
        p_CP.append(X_mobilizer(body) @ p_BP)
    calf_body = []
    for name in CALF_BODY_NAMES:
        body = plant.GetBodyByName(name, plant_map.model).index()
        if body not in row_of:
            raise PediError(f"go1_dynamics expects {name} to have its own joint")
        calf_body.append(row_of[body])

    return Go1Model(
        parent=parent,
        joint_unitree=joint_unitree,
        joint_q=joint_q,
        joint_v=joint_v,
        base_start=np.array([floating.position_start(), floating.velocity_start()], dtype=np.int64),
        R_PF=R_PF,
        p_PF=p_PF,
        axis_F=axis_F,
        R_MC=R_MC,
        p_MC=p_MC,
        mass=mass,
        p_CScm=p_CScm,
        I_Scm=I_Scm,
        reflected_inertia=reflected_inertia,
        damping=damping,
        gravity=np.asarray(plant.gravity_field().gravity_vector(), float).copy(),
        contact_body=np.array(contact_body, dtype=np.int64),
        p_CP=np.array(p_CP, dtype=float).reshape(-1, 3),
        calf_body=np.array(calf_body, dtype=np.int64),
    )


@kernel
def _point_bias(V, A, r0, r1, r2):
    """(v_P, a_P) of a point at r (about O) of a body with twist V and bias acceleration A."""
    w0, w1, w2 = V[0], V[1], V[2]
    v0 = V[3] + w1 * r2 - w2 * r1
    v1 = V[4] + w2 * r0 - w0 * r2
    v2 = V[5] + w0 * r1 - w1 * r0
    # Grouped so that the trunk origin's (A_lin = v_WB x w_WB, r = 0) comes out exactly zero.
    a0 = A[3] + (A[1] * r2 - A[2] * r1) + (w1 * v2 - w2 * v1)
    a1 = A[4] + (A[2] * r0 - A[0] * r2) + (w2 * v0 - w0 * v2)
    a2 = A[5] + (A[0] * r1 - A[1] * r0) + (w0 * v1 - w1 * v0)
    return v0, v1, v2, a0, a1, a2


@kernel
def add_trunk_external_wrench(h, J_trunk, wrench):
    """Moves an external wrench on the trunk into the bias, in place: h -= J_trunk^T w.

    The dynamics M vdot + h = S tau + J_c^T f + J_trunk^T w (w = [torque; force] on the trunk at
    its origin, world [N m, N], as an unmodelled load) are then the snapshot's own. Only the
    floating base's rows change: J_trunk has no joint columns, so no leg's torques do.
    h (nv,) [N m, N]; J_trunk (6, nv) [angular; translational], world; wrench (6,)."""
    for j in range(h.shape[0]):
        total = 0.0
        for k in range(6):
            total += J_trunk[k, j] * wrench[k]
        h[j] -= total


@kernel
def go1_dynamics(model_record, base_state, q_joints, v_joints, out_record):
    """Fills the record `out_record` (`output_dtype`) from the estimate and the measured joints.

    model_record: the record of a Go1Model (`model_record`); base_state (13,)
    (pedi_drake.estimation.base_state layout: quaternion wxyz, p_WB [m], w_WB [rad/s] and v_WB
    [m/s] in W); q_joints, v_joints (12,) Unitree order [rad, rad/s].
    """
    model, out = model_record[0], out_record[0]
    n = model.parent.shape[0]
    nv = out.v.shape[0]
    qs, vs = model.base_start[0], model.base_start[1]

    # State vectors; the quaternion normalised as ControllerModel does.
    norm = math.sqrt(base_state[0] ** 2 + base_state[1] ** 2 + base_state[2] ** 2 + base_state[3] ** 2)
    qw, qx, qy, qz = base_state[0] / norm, base_state[1] / norm, base_state[2] / norm, base_state[3] / norm
    out.q[:] = 0.0
    out.v[:] = 0.0
    out.q[qs], out.q[qs + 1], out.q[qs + 2], out.q[qs + 3] = qw, qx, qy, qz
    for k in range(3):
        out.q[qs + 4 + k] = base_state[4 + k]
        out.p_WB[k] = base_state[4 + k]
        out.v[vs + k] = base_state[7 + k]
        out.v[vs + 3 + k] = base_state[10 + k]
    out.q_joints[:] = q_joints
    out.v_joints[:] = v_joints
    for i in range(1, n):
        out.q[model.joint_q[i]] = q_joints[model.joint_unitree[i]]
        out.v[model.joint_v[i]] = v_joints[model.joint_unitree[i]]

    # Per-body workspace, all in W axes about O: orientation, origin, motion subspace, twist,
    # bias acceleration, centre of mass, spatial inertia (then composite), force (then composite).
    R = np.empty((n, 3, 3))
    r = np.zeros((n, 3))
    S = np.zeros((n, 6))
    V = np.empty((n, 6))
    A = np.empty((n, 6))
    c = np.empty((n, 3))
    Ic = np.empty((n, 6, 6))
    f = np.empty((n, 6))
    hm = np.empty(6)  # one body's momentum I V
    F = np.empty(6)  # I_c S of one joint
    rp = np.empty(3)  # one contact point about O
    R_WF, R_FM, R_WM = np.empty((3, 3)), np.empty((3, 3)), np.empty((3, 3))  # one joint's frames

    # 1-2. Kinematics, twists and bias accelerations, trunk first.
    R[0, 0, 0] = 1.0 - 2.0 * (qy * qy + qz * qz)
    R[0, 0, 1] = 2.0 * (qx * qy - qw * qz)
    R[0, 0, 2] = 2.0 * (qx * qz + qw * qy)
    R[0, 1, 0] = 2.0 * (qx * qy + qw * qz)
    R[0, 1, 1] = 1.0 - 2.0 * (qx * qx + qz * qz)
    R[0, 1, 2] = 2.0 * (qy * qz - qw * qx)
    R[0, 2, 0] = 2.0 * (qx * qz - qw * qy)
    R[0, 2, 1] = 2.0 * (qy * qz + qw * qx)
    R[0, 2, 2] = 1.0 - 2.0 * (qx * qx + qy * qy)
    for k in range(6):
        V[0, k] = out.v[vs + k]
    w0, w1, w2, u0, u1, u2 = V[0, 0], V[0, 1], V[0, 2], V[0, 3], V[0, 4], V[0, 5]
    A[0, 0], A[0, 1], A[0, 2] = 0.0, 0.0, 0.0
    A[0, 3], A[0, 4], A[0, 5] = u1 * w2 - u2 * w1, u2 * w0 - u0 * w2, u0 * w1 - u1 * w0  # v_WB x w_WB
    for i in range(1, n):
        P = model.parent[i]
        angle = q_joints[model.joint_unitree[i]]
        rate = v_joints[model.joint_unitree[i]]
        for a in range(3):
            for b in range(3):
                R_WF[a, b] = (
                    R[P, a, 0] * model.R_PF[i, 0, b]
                    + R[P, a, 1] * model.R_PF[i, 1, b]
                    + R[P, a, 2] * model.R_PF[i, 2, b]
                )
        # X_FM: rotation by `angle` about the unit axis (Rodrigues).
        e0, e1, e2 = model.axis_F[i, 0], model.axis_F[i, 1], model.axis_F[i, 2]
        cq, sq = math.cos(angle), math.sin(angle)
        t = 1.0 - cq
        R_FM[0, 0], R_FM[0, 1], R_FM[0, 2] = cq + t * e0 * e0, t * e0 * e1 - sq * e2, t * e0 * e2 + sq * e1
        R_FM[1, 0], R_FM[1, 1], R_FM[1, 2] = t * e1 * e0 + sq * e2, cq + t * e1 * e1, t * e1 * e2 - sq * e0
        R_FM[2, 0], R_FM[2, 1], R_FM[2, 2] = t * e2 * e0 - sq * e1, t * e2 * e1 + sq * e0, cq + t * e2 * e2
        for a in range(3):
            for b in range(3):
                R_WM[a, b] = R_WF[a, 0] * R_FM[0, b] + R_WF[a, 1] * R_FM[1, b] + R_WF[a, 2] * R_FM[2, b]
        for a in range(3):
            for b in range(3):
                R[i, a, b] = (
                    R_WM[a, 0] * model.R_MC[i, 0, b]
                    + R_WM[a, 1] * model.R_MC[i, 1, b]
                    + R_WM[a, 2] * model.R_MC[i, 2, b]
                )
        rF0 = r[P, 0] + R[P, 0, 0] * model.p_PF[i, 0] + R[P, 0, 1] * model.p_PF[i, 1] + R[P, 0, 2] * model.p_PF[i, 2]
        rF1 = r[P, 1] + R[P, 1, 0] * model.p_PF[i, 0] + R[P, 1, 1] * model.p_PF[i, 1] + R[P, 1, 2] * model.p_PF[i, 2]
        rF2 = r[P, 2] + R[P, 2, 0] * model.p_PF[i, 0] + R[P, 2, 1] * model.p_PF[i, 1] + R[P, 2, 2] * model.p_PF[i, 2]
        r[i, 0] = rF0 + R_WM[0, 0] * model.p_MC[i, 0] + R_WM[0, 1] * model.p_MC[i, 1] + R_WM[0, 2] * model.p_MC[i, 2]
        r[i, 1] = rF1 + R_WM[1, 0] * model.p_MC[i, 0] + R_WM[1, 1] * model.p_MC[i, 1] + R_WM[1, 2] * model.p_MC[i, 2]
        r[i, 2] = rF2 + R_WM[2, 0] * model.p_MC[i, 0] + R_WM[2, 1] * model.p_MC[i, 1] + R_WM[2, 2] * model.p_MC[i, 2]
        s0 = R_WF[0, 0] * e0 + R_WF[0, 1] * e1 + R_WF[0, 2] * e2
        s1 = R_WF[1, 0] * e0 + R_WF[1, 1] * e1 + R_WF[1, 2] * e2
        s2 = R_WF[2, 0] * e0 + R_WF[2, 1] * e1 + R_WF[2, 2] * e2
        S[i, 0], S[i, 1], S[i, 2] = s0, s1, s2
        S[i, 3], S[i, 4], S[i, 5] = rF1 * s2 - rF2 * s1, rF2 * s0 - rF0 * s2, rF0 * s1 - rF1 * s0
        for k in range(6):
            V[i, k] = V[P, k] + S[i, k] * rate
        # (V_P x S) rate: [w x a; w x l + v x a] rate.
        pw0, pw1, pw2, pv0, pv1, pv2 = V[P, 0], V[P, 1], V[P, 2], V[P, 3], V[P, 4], V[P, 5]
        l0, l1, l2 = S[i, 3], S[i, 4], S[i, 5]
        A[i, 0] = A[P, 0] + (pw1 * s2 - pw2 * s1) * rate
        A[i, 1] = A[P, 1] + (pw2 * s0 - pw0 * s2) * rate
        A[i, 2] = A[P, 2] + (pw0 * s1 - pw1 * s0) * rate
        A[i, 3] = A[P, 3] + (pw1 * l2 - pw2 * l1 + pv1 * s2 - pv2 * s1) * rate
        A[i, 4] = A[P, 4] + (pw2 * l0 - pw0 * l2 + pv2 * s0 - pv0 * s2) * rate
        A[i, 5] = A[P, 5] + (pw0 * l1 - pw1 * l0 + pv0 * s1 - pv1 * s0) * rate

    # 3. Spatial inertias about O and the Newton-Euler forces with gravity as base acceleration -g.
    g0, g1, g2 = -model.gravity[0], -model.gravity[1], -model.gravity[2]
    total_mass = 0.0
    mc0, mc1, mc2 = 0.0, 0.0, 0.0  # sum m c [kg m]
    ma0, ma1, ma2 = 0.0, 0.0, 0.0  # sum m a_c [N]
    for i in range(n):
        m = model.mass[i]
        for a in range(3):
            c[i, a] = (
                r[i, a]
                + R[i, a, 0] * model.p_CScm[i, 0]
                + R[i, a, 1] * model.p_CScm[i, 1]
                + R[i, a, 2] * model.p_CScm[i, 2]
            )
        c0, c1, c2 = c[i, 0], c[i, 1], c[i, 2]
        # Ibar = R I_Scm R^T into the upper-left block, then the parallel-axis term m ([c]x [c]x^T).
        for a in range(3):
            for b in range(3):
                acc = 0.0
                for k in range(3):
                    acc += R[i, a, k] * (
                        model.I_Scm[i, k, 0] * R[i, b, 0]
                        + model.I_Scm[i, k, 1] * R[i, b, 1]
                        + model.I_Scm[i, k, 2] * R[i, b, 2]
                    )
                Ic[i, a, b] = acc
        cc = c0 * c0 + c1 * c1 + c2 * c2
        Ic[i, 0, 0] += m * (cc - c0 * c0)
        Ic[i, 1, 1] += m * (cc - c1 * c1)
        Ic[i, 2, 2] += m * (cc - c2 * c2)
        Ic[i, 0, 1] -= m * c0 * c1
        Ic[i, 1, 0] -= m * c1 * c0
        Ic[i, 0, 2] -= m * c0 * c2
        Ic[i, 2, 0] -= m * c2 * c0
        Ic[i, 1, 2] -= m * c1 * c2
        Ic[i, 2, 1] -= m * c2 * c1
        # m [c]x (upper right) and its transpose (lower left); m 1 (lower right).
        Ic[i, 0, 3], Ic[i, 0, 4], Ic[i, 0, 5] = 0.0, -m * c2, m * c1
        Ic[i, 1, 3], Ic[i, 1, 4], Ic[i, 1, 5] = m * c2, 0.0, -m * c0
        Ic[i, 2, 3], Ic[i, 2, 4], Ic[i, 2, 5] = -m * c1, m * c0, 0.0
        for a in range(3):
            for b in range(3):
                Ic[i, 3 + a, b] = Ic[i, b, 3 + a]
                Ic[i, 3 + a, 3 + b] = m if a == b else 0.0
        # f = I (A + [0; -g]) + V x* (I V).
        w0, w1, w2 = V[i, 0], V[i, 1], V[i, 2]
        u0, u1, u2 = V[i, 3], V[i, 4], V[i, 5]
        for a in range(6):
            acc_f = 0.0
            acc_h = 0.0
            for b in range(6):
                acc_h += Ic[i, a, b] * V[i, b]
                acc_f += Ic[i, a, b] * A[i, b]
            acc_f += Ic[i, a, 3] * g0 + Ic[i, a, 4] * g1 + Ic[i, a, 5] * g2
            hm[a] = acc_h
            f[i, a] = acc_f
        L0, L1, L2, p0, p1, p2 = hm[0], hm[1], hm[2], hm[3], hm[4], hm[5]
        f[i, 0] += w1 * L2 - w2 * L1 + u1 * p2 - u2 * p1
        f[i, 1] += w2 * L0 - w0 * L2 + u2 * p0 - u0 * p2
        f[i, 2] += w0 * L1 - w1 * L0 + u0 * p1 - u1 * p0
        f[i, 3] += w1 * p2 - w2 * p1
        f[i, 4] += w2 * p0 - w0 * p2
        f[i, 5] += w0 * p1 - w1 * p0
        # Centre of mass and its bias acceleration.
        _, _, _, ac0, ac1, ac2 = _point_bias(V[i], A[i], c0, c1, c2)
        total_mass += m
        mc0 += m * c0
        mc1 += m * c1
        mc2 += m * c2
        ma0 += m * ac0
        ma1 += m * ac1
        ma2 += m * ac2

    # Leaves to trunk: composite inertias and forces.
    for i in range(n - 1, 0, -1):
        P = model.parent[i]
        for a in range(6):
            f[P, a] += f[i, a]
            for b in range(6):
                Ic[P, a, b] += Ic[i, a, b]

    # 3-4. h and M (with the centre-of-mass Jacobian from the momentum rows).
    out.M[:, :] = 0.0
    for a in range(6):
        out.h[vs + a] = f[0, a]
        for b in range(6):
            out.M[vs + a, vs + b] = Ic[0, a, b]
    for a in range(3):
        for b in range(6):
            out.J_com[a, vs + b] = Ic[0, 3 + a, b] / total_mass
    for i in range(1, n):
        col = model.joint_v[i]
        out.h[col] = (
            S[i, 0] * f[i, 0]
            + S[i, 1] * f[i, 1]
            + S[i, 2] * f[i, 2]
            + S[i, 3] * f[i, 3]
            + S[i, 4] * f[i, 4]
            + S[i, 5] * f[i, 5]
        ) + model.damping[col] * out.v[col]
        for a in range(6):
            F[a] = (
                Ic[i, a, 0] * S[i, 0]
                + Ic[i, a, 1] * S[i, 1]
                + Ic[i, a, 2] * S[i, 2]
                + Ic[i, a, 3] * S[i, 3]
                + Ic[i, a, 4] * S[i, 4]
                + Ic[i, a, 5] * S[i, 5]
            )
        out.M[col, col] = (
            S[i, 0] * F[0] + S[i, 1] * F[1] + S[i, 2] * F[2] + S[i, 3] * F[3] + S[i, 4] * F[4] + S[i, 5] * F[5]
        ) + model.reflected_inertia[col]
        j = model.parent[i]
        while j > 0:
            row = model.joint_v[j]
            value = S[j, 0] * F[0] + S[j, 1] * F[1] + S[j, 2] * F[2] + S[j, 3] * F[3] + S[j, 4] * F[4] + S[j, 5] * F[5]
            out.M[row, col] = value
            out.M[col, row] = value
            j = model.parent[j]
        for a in range(6):
            out.M[vs + a, col] = F[a]
            out.M[col, vs + a] = F[a]
        for a in range(3):
            out.J_com[a, col] = F[3 + a] / total_mass

    # Centre of mass, trunk.
    out.p_com[0], out.p_com[1], out.p_com[2] = (
        out.p_WB[0] + mc0 / total_mass,
        out.p_WB[1] + mc1 / total_mass,
        out.p_WB[2] + mc2 / total_mass,
    )
    out.Jdot_v_com[0], out.Jdot_v_com[1], out.Jdot_v_com[2] = ma0 / total_mass, ma1 / total_mass, ma2 / total_mass
    for a in range(3):
        acc = 0.0
        for k in range(nv):
            acc += out.J_com[a, k] * out.v[k]
        out.v_com[a] = acc
        for b in range(3):
            out.R_WB[a, b] = R[0, a, b]
    out.J_trunk[:, :] = 0.0
    for a in range(6):
        out.J_trunk[a, vs + a] = 1.0
        out.V_trunk[a] = V[0, a]
    _, _, _, at0, at1, at2 = _point_bias(V[0], A[0], 0.0, 0.0, 0.0)
    out.Jdot_v_trunk[0], out.Jdot_v_trunk[1], out.Jdot_v_trunk[2] = A[0, 0], A[0, 1], A[0, 2]
    out.Jdot_v_trunk[3], out.Jdot_v_trunk[4], out.Jdot_v_trunk[5] = at0, at1, at2

    # 5. Contact points.
    out.J_contacts[:, :] = 0.0
    for k in range(model.contact_body.shape[0]):
        i = model.contact_body[k]
        for a in range(3):
            rp[a] = (
                r[i, a] + R[i, a, 0] * model.p_CP[k, 0] + R[i, a, 1] * model.p_CP[k, 1] + R[i, a, 2] * model.p_CP[k, 2]
            )
            out.p_contacts[k, a] = out.p_WB[a] + rp[a]
        r0, r1, r2 = rp[0], rp[1], rp[2]
        _, _, _, ap0, ap1, ap2 = _point_bias(V[i], A[i], r0, r1, r2)
        out.Jdot_v_contacts[3 * k], out.Jdot_v_contacts[3 * k + 1], out.Jdot_v_contacts[3 * k + 2] = ap0, ap1, ap2
        j = i
        while j > 0:
            col = model.joint_v[j]
            out.J_contacts[3 * k, col] = S[j, 3] + S[j, 1] * r2 - S[j, 2] * r1
            out.J_contacts[3 * k + 1, col] = S[j, 4] + S[j, 2] * r0 - S[j, 0] * r2
            out.J_contacts[3 * k + 2, col] = S[j, 5] + S[j, 0] * r1 - S[j, 1] * r0
            j = model.parent[j]
        # w_WB x r_P = -[r_P]x w_WB; v_WB moves every point alike.
        out.J_contacts[3 * k, vs + 1], out.J_contacts[3 * k, vs + 2] = r2, -r1
        out.J_contacts[3 * k + 1, vs + 0], out.J_contacts[3 * k + 1, vs + 2] = -r2, r0
        out.J_contacts[3 * k + 2, vs + 0], out.J_contacts[3 * k + 2, vs + 1] = r1, -r0
        for a in range(3):
            out.J_contacts[3 * k + a, vs + 3 + a] = 1.0

    # Calves: orientation, angular-velocity Jacobian and angular bias acceleration.
    out.J_w_calf[:, :, :] = 0.0
    for leg in range(model.calf_body.shape[0]):
        i = model.calf_body[leg]
        for a in range(3):
            out.Jdot_w_calf[leg, a] = A[i, a]
            out.J_w_calf[leg, a, vs + a] = 1.0
            for b in range(3):
                out.R_WC[leg, a, b] = R[i, a, b]
        j = i
        while j > 0:
            col = model.joint_v[j]
            for a in range(3):
                out.J_w_calf[leg, a, col] = S[j, a]
            j = model.parent[j]


class Go1Dynamics:
    """Owner of the Go1's parameter arrays for `go1_dynamics`; `update` returns a RobotSnapshot."""

    def __init__(self, prongs: ProngDesign | None = None) -> None:
        self.prongs = prongs
        plant, self.plant_map = robot.make_go1_plant(robot.design_key(prongs))
        self.model = Go1Model.from_plant(plant, self.plant_map, prongs)
        self.model_record = model_record(self.model)
        self.nq, self.nv = plant.num_positions(), plant.num_velocities()
        self.num_contacts = self.model.contact_body.shape[0]
        self.total_mass = float(self.model.mass.sum())
        self.last = self.new_output()  # the outputs of the last `update` (calf terms read from here)
        self.warm_up()

    def new_output(self) -> np.ndarray:
        """An output record sized for this model (for callers that keep their own and call the kernel)."""
        return new_record(output_dtype(self.nq, self.nv, self.num_contacts))

    def warm_up(self) -> None:
        """Compiles (or loads from cache) the kernel for these argument types: never inside a tick."""
        standing = np.concatenate([[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3], np.zeros(6)])
        go1_dynamics(self.model_record, standing, robot.STANDING_Q.astype(float), np.zeros(robot.NUM_JOINTS), self.last)

    def compute(self, base_state: np.ndarray, q_joints: np.ndarray, v_joints: np.ndarray) -> np.ndarray:
        """Runs the kernel into fresh arrays (earlier results stay valid) and keeps them as `last`."""
        out = self.new_output()
        go1_dynamics(
            self.model_record,
            np.ascontiguousarray(base_state, dtype=float),
            np.ascontiguousarray(q_joints, dtype=float),
            np.ascontiguousarray(v_joints, dtype=float),
            out,
        )
        self.last = out
        return out

    def update(self, base_state: np.ndarray, q_joints: np.ndarray, v_joints: np.ndarray) -> RobotSnapshot:
        """The dynamics terms at the estimate `base_state` (13,) and measured joints (12,) each."""
        out = self.compute(base_state, q_joints, v_joints)[0]
        return RobotSnapshot(
            q=out["q"],
            v=out["v"],
            M=out["M"],
            h=out["h"],
            J_contacts=out["J_contacts"],
            Jdot_v_contacts=out["Jdot_v_contacts"],
            p_contacts=out["p_contacts"],
            J_trunk=out["J_trunk"],
            Jdot_v_trunk=out["Jdot_v_trunk"],
            R_WB=out["R_WB"],
            p_WB=out["p_WB"],
            p_com=out["p_com"],
            J_com=out["J_com"],
            Jdot_v_com=out["Jdot_v_com"],
            q_joints=np.array(q_joints, dtype=float),
            v_joints=np.array(v_joints, dtype=float),
            V_trunk=out["V_trunk"],
            v_com=out["v_com"],
        )

    def calf_orientation(self, leg: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(R_WC, J_w (3, nv), Jdot_w v (3,)) of leg `leg`'s calf at the last `update`."""
        last = self.last[0]
        return last["R_WC"][leg], last["J_w_calf"][leg], last["Jdot_w_calf"][leg]
