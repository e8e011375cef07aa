"""Paper 002's maths on plain arrays: projector, constrained dynamics, prioritised impedance,
contact-force QP and the impedance force estimate, at random Go1 states."""

import numpy as np
import pytest
import reference_projected_dynamics as pd

from pedi_drake import robot
from pedi_drake.control.robot_model import ControllerModel
from pedi_drake.exceptions import QpInfeasible
from pedi_drake.prongs import ProngDesign
from pedi_drake.scenario import RobotConfig
from pedi_drake.station.initial_state import initial_trunk_pose


def _rows(contacts) -> np.ndarray:
    return np.concatenate([np.arange(3 * i, 3 * i + 3) for i in contacts]).astype(int)


def _snapshot(model: ControllerModel, rng, height_drop: float = 0.0, speed: float = 0.3):
    X = initial_trunk_pose(RobotConfig(initial_pose="standing"))
    p = X.translation() - [0.0, 0.0, height_drop]
    base = np.concatenate([X.rotation().ToQuaternion().wxyz(), p, 0.05 * rng.standard_normal(6)])
    return model.update(base, robot.STANDING_Q + 0.05 * rng.standard_normal(12), speed * rng.standard_normal(12))


def _selection(model: ControllerModel) -> np.ndarray:
    S = np.zeros((12, model.nv))
    S[np.arange(12), model.plant_map.v_index] = 1.0
    return S


@pytest.fixture(scope="module")
def go1_model():
    return ControllerModel()


@pytest.fixture(scope="module")
def prong_model():
    return ControllerModel(ProngDesign())


def _assert_projector(Jc: np.ndarray, projection: pd.ConstraintProjection) -> None:
    P = projection.P
    np.testing.assert_allclose(P @ Jc.T, 0.0, atol=1e-10)
    np.testing.assert_allclose(P @ P, P, atol=1e-10)
    np.testing.assert_allclose(P, P.T, atol=1e-12)


def test_projector_annihilates_three_feet_and_is_idempotent(go1_model, rng):
    s = _snapshot(go1_model, rng)
    Jc = s.J_contacts[_rows([0, 2, 3])]
    projection = pd.constraint_projection(Jc)
    _assert_projector(Jc, projection)
    assert projection.rank == 9


def test_projector_drops_the_dependent_rows_of_two_prongs_and_two_feet(prong_model, rng):
    s = _snapshot(prong_model, rng)
    # Both prong tips sit on the rigid trunk: 6 rows of rank 5 (the roll about their line is free).
    Jc = s.J_contacts[_rows([2, 3, 4, 5])]
    assert np.linalg.matrix_rank(Jc, tol=1e-8) == 11
    projection = pd.constraint_projection(Jc)
    _assert_projector(Jc, projection)
    assert projection.rank == 11
    assert np.trace(projection.P) == pytest.approx(prong_model.nv - 11, abs=1e-9)


def test_constrained_acceleration_holds_the_contacts(go1_model, rng):
    s = _snapshot(go1_model, rng)
    rows = _rows([0, 2, 3])
    Jc, Jcdot_v = s.J_contacts[rows], s.Jdot_v_contacts[rows]
    dynamics = pd.constrained_dynamics(s.M, s.h, Jc, Jcdot_v, s.v, contact_damping=10.0)
    np.testing.assert_allclose(dynamics.A, dynamics.A.T, atol=1e-9)
    assert np.linalg.eigvalsh(dynamics.A).min() > -1e-9
    u = dynamics.projection.P @ rng.standard_normal(go1_model.nv)
    vdot = dynamics.A @ u + dynamics.vdot_0
    np.testing.assert_allclose(Jc @ vdot, -(Jcdot_v + 10.0 * Jc @ s.v), atol=1e-8)


def _foot_task(s, leg: int, stiffness: float, damping: float, rng) -> pd.ImpedanceTask:
    rows = slice(3 * leg, 3 * leg + 3)
    return pd.ImpedanceTask(
        "foot",
        s.J_contacts[rows],
        s.Jdot_v_contacts[rows],
        0.02 * rng.standard_normal(3),
        0.1 * rng.standard_normal(3),
        rng.standard_normal(3),
        np.full(3, stiffness),
        np.full(3, damping),
    )


def _torso_task(s, desired: np.ndarray) -> pd.AccelerationTask:
    return pd.AccelerationTask("torso", s.J_trunk, s.Jdot_v_trunk, desired)


def test_torso_task_does_not_change_the_foot_acceleration(go1_model, rng):
    s = _snapshot(go1_model, rng)
    rows = _rows([0, 2, 3])
    dynamics = pd.constrained_dynamics(s.M, s.h, s.J_contacts[rows], s.Jdot_v_contacts[rows], s.v, 10.0)
    foot = _foot_task(s, 1, 500.0, 20.0, rng)
    S = _selection(go1_model)
    accelerations = []
    for torso_desired in (np.zeros(6), 5.0 * rng.standard_normal(6)):
        law = pd.prioritized_force(dynamics, s.v, foot, [_torso_task(s, torso_desired)])
        vdot = pd.constraint_free_torque(dynamics, law.u, S).vdot
        accelerations.append((foot.J @ vdot + foot.Jdot_v, s.J_trunk @ vdot + s.Jdot_v_trunk))
    np.testing.assert_allclose(accelerations[0][0], accelerations[1][0], atol=1e-8)
    assert np.linalg.norm(accelerations[0][1] - accelerations[1][1]) > 1.0  # the torso did respond


def test_impedance_closed_loop_and_force_estimate_recover_an_external_force(go1_model, rng):
    s = _snapshot(go1_model, rng)
    rows = _rows([0, 2, 3])
    dynamics = pd.constrained_dynamics(s.M, s.h, s.J_contacts[rows], s.Jdot_v_contacts[rows], s.v, 10.0)
    K, D = 600.0, 25.0
    foot = _foot_task(s, 1, K, D, rng)
    law = pd.prioritized_force(dynamics, s.v, foot, [_torso_task(s, np.zeros(6))])
    S = _selection(go1_model)
    torque = pd.constraint_free_torque(dynamics, law.u, S)
    F_ext = np.array([8.0, -3.0, 5.0])  # [N] on the foot
    vdot = torque.vdot + dynamics.A @ (foot.J.T @ F_ext)
    eddot = foot.J @ vdot + foot.Jdot_v - foot.acceleration_ref
    # The closed loop is the commanded impedance: Lambda eddot + D edot + K e = F_ext.
    estimate = pd.impedance_force_estimate(
        law.impedance_inertia, foot.stiffness, foot.damping, foot.error, foot.error_rate, eddot
    )
    np.testing.assert_allclose(estimate, F_ext, atol=1e-6)


def test_torque_split_satisfies_the_dynamics_and_tau_c_stays_out_of_the_free_space(go1_model, rng):
    s = _snapshot(go1_model, rng, speed=0.05)
    held = [0, 2, 3]
    rows = _rows(held)
    Jc = s.J_contacts[rows]
    dynamics = pd.constrained_dynamics(s.M, s.h, Jc, s.Jdot_v_contacts[rows], s.v, 10.0)
    foot = _foot_task(s, 1, 500.0, 20.0, rng)
    law = pd.prioritized_force(dynamics, s.v, foot, [_torso_task(s, np.zeros(6))])
    S = _selection(go1_model)
    torque = pd.constraint_free_torque(dynamics, law.u, S)
    r = s.M @ torque.vdot + s.h
    v_index = go1_model.plant_map.v_index
    unactuated = np.setdiff1d(np.arange(go1_model.nv), v_index)
    problem = pd.ContactForceProblem(
        Jc=Jc,
        r=r,
        unactuated=unactuated,
        actuated=v_index,
        ramp=np.ones(3),
        friction=0.6 / np.sqrt(2.0),
        f_min=5.0,
        f_max=250.0,
        torque_limit=0.9 * robot.EFFORT_LIMIT,
        force_share=np.tile([0.0, 0.0, go1_model.total_mass * 9.81 / 3], 3),
    )
    solution = pd.solve_contact_forces(problem)
    tau = solution.tau
    np.testing.assert_allclose(s.M @ torque.vdot + s.h, S.T @ tau + Jc.T @ solution.lam, atol=1e-6)
    tau_c = tau - torque.tau_m
    np.testing.assert_allclose(dynamics.projection.P @ S.T @ tau_c, 0.0, atol=1e-6)
    f = solution.lam.reshape(-1, 3)
    assert np.all(f[:, 2] >= 5.0 - 1e-6)
    mu = problem.friction
    assert np.all(np.abs(f[:, :2]) <= mu * f[:, 2:3] + 1e-6)
    assert np.all(np.abs(tau) <= problem.torque_limit + 1e-6)


def test_contact_force_qp_reports_an_impossible_minimum_force(go1_model, rng):
    s = _snapshot(go1_model, rng, speed=0.0)
    rows = _rows([0, 1, 2, 3])
    Jc = s.J_contacts[rows]
    dynamics = pd.constrained_dynamics(s.M, s.h, Jc, s.Jdot_v_contacts[rows], s.v)
    r = s.M @ dynamics.vdot_0 + s.h
    v_index = go1_model.plant_map.v_index
    problem = pd.ContactForceProblem(
        Jc=Jc,
        r=r,
        unactuated=np.setdiff1d(np.arange(go1_model.nv), v_index),
        actuated=v_index,
        ramp=np.ones(4),
        friction=0.4,
        # Four times 200 N cannot balance a 13 kg robot's weight, and a tenth of the effort limits
        # cannot press the feet that hard: no forces at all, not even a relaxed balance.
        f_min=200.0,
        f_max=250.0,
        torque_limit=0.1 * robot.EFFORT_LIMIT,
        force_share=np.zeros(12),
    )
    with pytest.raises(QpInfeasible):
        pd.solve_contact_forces(problem)
