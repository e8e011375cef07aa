"""Whole-body task rows against finite differences and Drake's own forward dynamics."""

import numpy as np
import pytest
import reference_tasks as tasks
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RollPitchYaw, RotationMatrix
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce

from pedi_drake import robot
from pedi_drake.control.robot_model import ControllerModel
from pedi_drake.polygon import polygon_halfplanes
from pedi_drake.prongs import ProngDesign
from pedi_drake.vector3 import orientation_error_W


def random_state(rng):
    rpy = RollPitchYaw(*rng.uniform(-0.3, 0.3, 3))
    base = np.concatenate(
        [rpy.ToQuaternion().wxyz(), [0.1, -0.2, 0.3], rng.normal(size=3) * 0.5, rng.normal(size=3) * 0.3]
    )
    q = robot.STANDING_Q + rng.uniform(-0.2, 0.2, 12)
    qd = rng.normal(size=12)
    return base, q, qd


def shifted(model: ControllerModel, base, q, qd, h):
    """(base, q) after moving for time h at constant velocity (quaternion renormalised)."""
    plant, context = model.plant, model.context
    pm = model.plant_map
    qf = pm.full_positions(base[:4], base[4:7], q, model.nq)
    vf = pm.full_velocities(base[7:10], base[10:13], qd, model.nv)
    plant.SetPositions(context, qf)
    qdot = plant.MapVelocityToQDot(context, vf)
    qn = qf + h * qdot
    quat, p = pm.base_pose(qn)
    quat = quat / np.linalg.norm(quat)
    return np.concatenate([quat, p, base[7:]]), pm.joint_positions(qn)


@pytest.fixture(params=[None, ProngDesign()], ids=["no_prongs", "prongs"])
def model(request):
    return ControllerModel(request.param)


def layout_for(model):
    return tasks.VariableLayout(model.nv, model.num_contacts, model.plant_map.v_index)


def test_contact_jacobians_match_finite_differences(model):
    rng = np.random.default_rng(0)
    base, q, qd = random_state(rng)
    s = model.update(base, q, qd)
    h = 1e-6
    bp, qp = shifted(model, base, q, qd, h)
    bm, qm = shifted(model, base, q, qd, -h)
    sp, sm = model.update(bp, qp, qd), model.update(bm, qm, qd)
    v_fd = (sp.p_contacts - sm.p_contacts).ravel() / (2 * h)
    np.testing.assert_allclose(s.J_contacts @ s.v, v_fd, atol=1e-6)
    # Jdot v: derivative of J(q) v along the motion at constant v.
    jdotv_fd = (sp.J_contacts @ sp.v - sm.J_contacts @ sm.v) / (2 * h)
    np.testing.assert_allclose(s.Jdot_v_contacts, jdotv_fd, atol=1e-4)


def test_trunk_and_com_rows_match_finite_differences(model):
    rng = np.random.default_rng(1)
    base, q, qd = random_state(rng)
    s = model.update(base, q, qd)
    h = 1e-6
    bp, qp = shifted(model, base, q, qd, h)
    bm, qm = shifted(model, base, q, qd, -h)
    sp, sm = model.update(bp, qp, qd), model.update(bm, qm, qd)
    np.testing.assert_allclose(s.J_com @ s.v, (sp.p_com - sm.p_com) / (2 * h), atol=1e-6)
    np.testing.assert_allclose(s.Jdot_v_com, (sp.J_com @ sp.v - sm.J_com @ sm.v) / (2 * h), atol=1e-4)
    np.testing.assert_allclose(s.V_trunk[3:], (sp.p_WB - sm.p_WB) / (2 * h), atol=1e-6)
    W = (sp.R_WB - sm.R_WB) / (2 * h) @ s.R_WB.T
    np.testing.assert_allclose(s.V_trunk[:3], [W[2, 1], W[0, 2], W[1, 0]], atol=1e-6)
    np.testing.assert_allclose(s.Jdot_v_trunk, (sp.J_trunk @ sp.v - sm.J_trunk @ sm.v) / (2 * h), atol=1e-4)
    # The task rows are the Jacobians: trunk orientation/position and foot rows act on vdot only.
    layout = layout_for(model)
    gains = tasks.PdGains(0.0, 0.0)
    row = tasks.TrunkPosition(gains).rows(s, layout, s.p_WB, s.V_trunk[3:], np.zeros(3))
    np.testing.assert_allclose(row.A[:, : model.nv], s.J_trunk[3:])
    np.testing.assert_allclose(row.b, -s.Jdot_v_trunk[3:])


def test_dynamics_rows_hold_for_drake_forward_dynamics(model):
    """Forward dynamics of the plant with torques and contact forces satisfies the unactuated rows
    and the torque map reproduces the applied torques."""
    rng = np.random.default_rng(2)
    base, q, qd = random_state(rng)
    s = model.update(base, q, qd)
    layout = layout_for(model)
    plant = model.plant
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, s.q)
    plant.SetVelocities(context, s.v)
    tau = rng.uniform(-5, 5, 12)
    forces = rng.uniform(-10, 10, (model.num_contacts, 3))
    forces[:, 2] = rng.uniform(10, 40, model.num_contacts)
    plant.get_actuation_input_port().FixValue(context, model.plant_map.actuation(tau, plant.num_actuators()))
    applied = []
    for frame, point, f in zip(model.contact_frames, model.contact_points, forces, strict=True):
        F = ExternallyAppliedSpatialForce()
        F.body_index = frame.body().index()
        F.p_BoBq_B = point
        F.F_Bq_W = SpatialForce(np.zeros(3), f)
        applied.append(F)
    plant.get_applied_spatial_force_input_port().FixValue(context, applied)
    vdot = plant.EvalTimeDerivatives(context).get_vector().CopyToVector()[model.nq :]
    x = np.concatenate([vdot, forces.ravel()])
    dyn = tasks.FloatingBaseDynamics().rows(s, layout)
    np.testing.assert_allclose(dyn.A @ x, dyn.b, atol=1e-7)
    T, t0 = tasks.torque_map(s, layout)
    np.testing.assert_allclose(T @ x + t0, tau, atol=1e-7)


def test_contact_no_motion_rows_give_zero_point_acceleration(model):
    rng = np.random.default_rng(3)
    base, q, qd = random_state(rng)
    s = model.update(base, q, qd)
    layout = layout_for(model)
    in_contact = np.zeros(model.num_contacts, bool)
    in_contact[[1, 2]] = True
    row = tasks.ContactNoMotion(kd=0.0).rows(s, layout, in_contact)
    # Any vdot meeting the rows gives zero acceleration of those points: check with a solution.
    x = np.linalg.lstsq(row.A, row.b, rcond=None)[0]
    acc = s.J_contacts @ x[: model.nv] + s.Jdot_v_contacts
    np.testing.assert_allclose(acc[3:9], 0.0, atol=1e-9)


def test_capture_point_rows_predict_capture_point():
    model = ControllerModel()
    rng = np.random.default_rng(4)
    base, q, qd = random_state(rng)
    s = model.update(base, q, qd)
    layout = layout_for(model)
    balance = tasks.CapturePointBalance(horizon=0.05)
    N, d = polygon_halfplanes(np.array([[0.0, -0.05], [0.2, -0.05], [0.2, 0.05], [0.0, 0.05]]))
    row = balance.rows(s, layout, N, d, ground_height=0.0)
    vdot = rng.normal(size=model.nv)
    x = np.concatenate([vdot, np.zeros(3 * model.num_contacts)])
    xi, omega = balance.capture_point(s, 0.0)
    cdd = s.J_com @ vdot + s.Jdot_v_com
    predicted = xi + 0.05 * (s.v_com[:2] + cdd[:2] / omega)
    np.testing.assert_allclose(row.G @ x - row.h, N @ predicted - d, atol=1e-9)


def test_polygon_halfplanes_contain_inside_points_only():
    square = np.array([[1.0, 1.0], [-1.0, 1.0], [0.0, 0.0], [1.0, -1.0], [-1.0, -1.0]])
    N, d = polygon_halfplanes(square, margin=0.1)
    assert len(d) == 4
    assert np.all(N @ [0.85, 0.0] <= d)
    assert not np.all(N @ [0.95, 0.0] <= d)


def test_orientation_error_is_the_rotation_vector():
    R = RotationMatrix(RollPitchYaw(0.2, -0.1, 0.5))
    theta = np.array([0.1, -0.2, 0.15])
    R_ref = RotationMatrix(AngleAxis(np.linalg.norm(theta), theta / np.linalg.norm(theta))).multiply(R)
    np.testing.assert_allclose(orientation_error_W(R_ref.matrix(), R.matrix()), theta, atol=1e-12)


def test_joint_limit_bounds_keep_joints_inside_over_the_horizon():
    model = ControllerModel()
    rng = np.random.default_rng(5)
    base, q, qd = random_state(rng)
    q = np.clip(q, robot.Q_LOWER + 0.05, robot.Q_UPPER - 0.05)
    s = model.update(base, q, qd * 3)
    layout = layout_for(model)
    limits = tasks.JointLimits(horizon=0.05, margin=0.0)
    row = limits.rows(s, layout, robot.Q_LOWER, robot.Q_UPPER, robot.VELOCITY_LIMIT)
    n = 12
    upper, lower = row.h[:n], -row.h[n:]
    T = 0.05
    for qdd in (upper, lower):
        ok = lower <= upper
        q_end = s.q_joints + s.v_joints * T + 0.5 * qdd * T**2
        assert np.all((q_end <= robot.Q_UPPER + 1e-9)[ok])
        assert np.all((q_end >= robot.Q_LOWER - 1e-9)[ok])


def test_friction_pyramid_rows():
    layout = tasks.VariableLayout(18, 4, np.arange(6, 18))
    limits = tasks.ContactForceLimits(f_min=5.0, f_max=100.0, inscribed=False)
    row = limits.rows(layout, np.array([1.0, 1.0, 0.5, 0.0]), mu=0.5)
    x = np.zeros(layout.size)
    x[layout.force(0)] = [4.9, 0.0, 10.0]  # inside: |fx| <= 0.5 fz
    x[layout.force(1)] = [0.0, 0.0, 50.0]
    x[layout.force(2)] = [0.0, 0.0, 2.6]  # ramp 0.5: fz in [2.5, 50]
    assert np.all(row.G @ x <= row.h + 1e-12)
    x[layout.force(0)] = [5.1, 0.0, 10.0]
    assert not np.all(row.G @ x <= row.h + 1e-12)
    x[layout.force(0)] = [4.9, 0.0, 10.0]
    x[layout.force(3)] = [0.0, 0.0, 0.1]  # ramp 0: no force at all
    assert not np.all(row.G @ x <= row.h + 1e-12)
