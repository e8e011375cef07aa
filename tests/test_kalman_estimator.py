"""The floating-base Kalman estimator: leg odometry, the filter on synthetic data, bad inputs, and
the LeafSystem in a simulated diagram against ground truth."""

import numpy as np
import pytest
from pydrake.math import RollPitchYaw, RotationMatrix
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.estimation.config import KalmanEstimatorConfig
from pedi_drake.estimation.kalman_estimator import (
    COMPLIANCE,
    GRAVITY_W,
    FloatingBaseKalmanFilter,
    ImuSample,
    KalmanEstimator,
    _vertical_forces_kernel,
    imu_offset_B,
)
from pedi_drake.estimation.leg_odometry import foot_kinematics_B
from pedi_drake.evaluation.estimator_accuracy import estimate_errors
from pedi_drake.exceptions import ScenarioError
from pedi_drake.ik.analytic import solve_leg_ik_analytic
from pedi_drake.leg_kinematics import foot_jacobian_B, foot_position_B
from pedi_drake.prongs import ProngDesign
from pedi_drake.scenario import load_scenario

DT = 0.002


def test_leg_odometry_matches_the_general_leg_kinematics(rng):
    for _ in range(50):
        q = rng.uniform(robot.Q_LOWER, robot.Q_UPPER)
        positions, jacobians = foot_kinematics_B(q)
        for i, leg in enumerate(robot.LEG_NAMES):
            np.testing.assert_allclose(positions[i], foot_position_B(leg, q[3 * i : 3 * i + 3]), atol=1e-12)
            np.testing.assert_allclose(jacobians[i], foot_jacobian_B(leg, q[3 * i : 3 * i + 3]), atol=1e-12)


def _feet_W(p_WB: np.ndarray) -> np.ndarray:
    """The standing feet in world for a trunk at p_WB, level (the feet never move)."""
    p_BF, _ = foot_kinematics_B(robot.STANDING_Q)
    return p_BF + p_WB


def _joint_angles_for(p_WB: np.ndarray, feet_W: np.ndarray) -> np.ndarray:
    """Joint angles that put the feet at feet_W with a level trunk at p_WB (closed-form IK)."""
    q = np.empty(12)
    for i, leg in enumerate(robot.LEG_NAMES):
        sl = robot.leg_slice(leg)
        q[sl] = solve_leg_ik_analytic(leg, feet_W[i] - p_WB, robot.STANDING_Q[sl])
    return q


def _synthetic_run(trajectory, duration: float, rng, noise: bool):
    """Feeds the filter a trunk moving along `trajectory(t) -> (p, v, a)` (level, feet planted)."""
    config = KalmanEstimatorConfig()
    kf = FloatingBaseKalmanFilter(config, np.zeros(3))
    feet = _feet_W(trajectory(0.0)[0])
    contact = np.ones(4, dtype=bool)
    estimates, truths = [], []
    x = P = None
    q_prev = None
    for k in range(int(duration / DT)):
        t = k * DT
        p, v, a = trajectory(t)
        q = _joint_angles_for(p, feet)
        qd = np.zeros(12) if q_prev is None else (q - q_prev) / DT
        q_prev = q
        f_B = a - GRAVITY_W
        if noise:
            f_B = f_B + rng.normal(0.0, 0.05, 3)
            q = q + rng.normal(0.0, 0.0005, 12)
        imu = ImuSample(np.eye(3), np.zeros(3), f_B)
        if x is None:
            x, P = kf.initial_state(imu, q, p[:2])
        else:
            x, P = kf.predict(x, P, imu, contact, DT)
        x, P = kf.update(x, P, imu, q, qd, contact)
        estimates.append(x[:6].copy())
        truths.append(np.concatenate([p, v]))
    return np.array(estimates), np.array(truths)


def test_a_robot_at_rest_stays_put_under_sensor_noise(rng):
    p0 = np.array([0.3, -0.2, robot.trunk_height_for(0.9, -1.8)])
    est, truth = _synthetic_run(lambda t: (p0, np.zeros(3), np.zeros(3)), 2.0, rng, noise=True)
    assert np.max(np.linalg.norm(est[:, :3] - truth[:, :3], axis=1)) < 0.002
    assert np.sqrt(np.mean(np.sum(est[-250:, 3:] ** 2, axis=1))) < 0.01


def test_a_trunk_swaying_over_planted_feet_is_tracked(rng):
    h = robot.trunk_height_for(0.9, -1.8)
    w = 2.0 * np.pi * 0.5  # 0.5 Hz, 3 cm sway in x

    def sway(t):
        return (
            np.array([0.03 * np.sin(w * t), 0.0, h]),
            np.array([0.03 * w * np.cos(w * t), 0.0, 0.0]),
            np.array([-0.03 * w * w * np.sin(w * t), 0.0, 0.0]),
        )

    est, truth = _synthetic_run(sway, 2.0, rng, noise=False)
    assert np.max(np.linalg.norm(est[:, :3] - truth[:, :3], axis=1)) < 0.001
    settled = slice(100, None)
    assert np.max(np.linalg.norm(est[settled, 3:] - truth[settled, 3:], axis=1)) < 0.01


def _pivot_about_one_prong(tips_loaded: np.ndarray, duration: float = 2.0) -> np.ndarray:
    """Height error [m] of the filter over a trunk pitching +-0.1 rad about the front prong's tip
    (at 0.14 rad nose down, the rear tip 4 cm clear of the floor), the rear feet planted and the
    front feet held in the air, told that the prongs in `tips_loaded` are loaded."""
    prongs = ProngDesign()
    tips_B = prongs.tip_positions_B()
    kf = FloatingBaseKalmanFilter(
        KalmanEstimatorConfig(), np.zeros(3), prong_tips_B=tips_B, prong_tip_radius=prongs.tip_radius
    )
    w = 2.0 * np.pi * 0.5

    def pitch(t):  # (angle, rate, acceleration) [rad, rad/s, rad/s^2]
        return 0.14 + 0.1 * np.sin(w * t), 0.1 * w * np.cos(w * t), -0.1 * w * w * np.sin(w * t)

    tip_W = np.array([0.0, 0.0, prongs.tip_radius])

    def trunk(t):  # p_WB, v_WB, a_WB, R_WB of the trunk turning about the front tip
        theta, rate, acceleration = pitch(t)
        R = RotationMatrix.MakeYRotation(theta).matrix()
        r = R @ tips_B[0]  # tip from the trunk origin, world
        w_W = np.array([0.0, rate, 0.0])
        alpha_W = np.array([0.0, acceleration, 0.0])
        # p_WB = tip_W - r, with r turning at w_W.
        return tip_W - r, -np.cross(w_W, r), -np.cross(alpha_W, r) - np.cross(w_W, np.cross(w_W, r)), R, w_W

    p0, _, _, R0, _ = trunk(0.0)
    rear = [robot.LEG_NAMES.index(leg) for leg in ("RR", "RL")]
    p_BF0, _ = foot_kinematics_B(robot.STANDING_Q)
    feet_W = p_BF0 @ R0.T + p0
    feet_W[:, 2] = 0.10  # the front feet held 10 cm up ...
    feet_W[rear, 2] = robot.FOOT_RADIUS  # ... the rear feet on the floor, under where they stand
    contact = np.zeros(4, dtype=bool)
    contact[rear] = True
    errors, x, P, q_prev = [], None, None, None
    for k in range(int(duration / DT)):
        t = k * DT
        p, _, a, R, w_W = trunk(t)
        q = np.empty(12)
        for i in range(4):
            sl = robot.leg_slice(robot.LEG_NAMES[i])
            q[sl] = solve_leg_ik_analytic(robot.LEG_NAMES[i], R.T @ (feet_W[i] - p), robot.STANDING_Q[sl])
        qd = np.zeros(12) if q_prev is None else (q - q_prev) / DT
        q_prev = q
        imu = ImuSample(R, R.T @ w_W, R.T @ (a - GRAVITY_W))
        if x is None:
            x, P = kf.initial_state(imu, q, p[:2])  # the rear feet, the lowest, on the floor
        else:
            x, P = kf.predict(x, P, imu, contact, DT)
        x, P = kf.update(x, P, imu, q, qd, contact, tips_loaded=tips_loaded)
        errors.append(x[2] - p[2])
    return np.array(errors)


def test_a_trunk_turning_about_one_loaded_prong_keeps_its_height():
    # Only the front prong loaded: the lifted rear tip is not pinned to the floor.
    errors = _pivot_about_one_prong(np.array([True, False]))
    assert np.max(np.abs(errors)) < 0.002


def test_pinning_a_lifted_prong_tip_to_the_floor_would_pull_the_height_off():
    # The contradiction the per-prong flags avoid: both tips taken as on the floor.
    errors = _pivot_about_one_prong(np.array([True, True]))
    assert np.max(np.abs(errors)) > 0.01


def test_contact_comes_from_the_schedule_and_the_sensor_together():
    flags = FloatingBaseKalmanFilter.contact_flags
    assert flags(np.array([50, 50, 50, 50]), np.array([0, 1, 1, 1, 0, 0]), 10.0).tolist() == [0, 1, 1, 1]
    assert flags(np.array([0, 50, 50, 50]), None, 10.0).tolist() == [0, 1, 1, 1]
    # Nothing sensed (lying on the belly, the legs in the air): no foot is in contact.
    assert flags(np.zeros(4), np.array([1, 1, 1, 1]), 10.0).tolist() == [0, 0, 0, 0]


def test_unusable_imu_samples_are_rejected():
    assert ImuSample.from_vector(np.zeros(10)) is None  # before the first hardware message
    assert ImuSample.from_vector(np.full(10, np.nan)) is None
    sample = ImuSample.from_vector(np.array([2.0, 0, 0, 0, 0, 0, 0, 0, 0, 9.81]))
    np.testing.assert_allclose(sample.R_WB, np.eye(3))


def _estimator_context(config=None):
    estimator = KalmanEstimator(config or KalmanEstimatorConfig(), initial_xy=(0.5, 0.2))
    context = estimator.CreateDefaultContext()
    q = robot.STANDING_Q.copy()
    R = RotationMatrix(RollPitchYaw(0.0, 0.0, 0.3))
    imu = np.concatenate([R.ToQuaternion().wxyz(), np.zeros(3), R.matrix().T @ -GRAVITY_W])
    estimator.imu_port.FixValue(context, imu)
    estimator.position_port.FixValue(context, q)
    estimator.velocity_port.FixValue(context, np.zeros(12))
    estimator.torque_port.FixValue(context, np.zeros(12))
    estimator.foot_contact_port.FixValue(context, np.full(4, 30.0))
    return estimator, context


def _tick(estimator, context):
    values = estimator.AllocateDiscreteVariables()
    estimator.CalcForcedDiscreteVariableUpdate(context, values)
    context.SetDiscreteState(values)
    return estimator.base_state_port.Eval(context)


def test_the_first_sample_puts_the_feet_on_the_ground_at_the_scenario_position():
    estimator, context = _estimator_context()
    base = _tick(estimator, context)
    np.testing.assert_allclose(base[4:6], [0.5, 0.2], atol=1e-3)
    np.testing.assert_allclose(base[6], robot.trunk_height_for(0.9, -1.8), atol=1e-3)
    np.testing.assert_allclose(abs(RollPitchYaw(RotationMatrix(_quaternion(base[0:4]))).yaw_angle()), 0.3, atol=1e-9)


def _velocity_after_a_moment_unloaded(height: float) -> tuple[float, float]:
    """A trunk at `height` [m] moving at 0.5 m/s along x over planted feet for 0.4 s, then for 20 ms
    with no foot sensed (a trot's pairs changing over, or a robot lifted off its feet): the
    estimated forward velocity [m/s] before and after the unloaded moment (the feet's centres
    here stand still, where the filter takes them to roll: it reads the stance a few per cent
    fast)."""
    estimator, context = _estimator_context()
    imu = np.concatenate([[1.0, 0.0, 0.0, 0.0], np.zeros(3), -GRAVITY_W])
    estimator.imu_port.FixValue(context, imu)
    start = np.array([0.5, 0.2, height])
    feet = _feet_W(np.array([0.5, 0.2, robot.trunk_height_for(0.9, -1.8)]))
    feet[:, 2] = 0.0
    feet += np.array([0.0, 0.0, robot.FOOT_RADIUS])
    q_prev = None
    for k in range(200):
        p = start + np.array([0.5 * k * DT, 0.0, 0.0])
        q = _joint_angles_for(p, feet)
        estimator.position_port.FixValue(context, q)
        estimator.velocity_port.FixValue(context, np.zeros(12) if q_prev is None else (q - q_prev) / DT)
        q_prev = q
        before = _tick(estimator, context)[10]
    estimator.foot_contact_port.FixValue(context, np.zeros(4))
    estimator.velocity_port.FixValue(context, np.zeros(12))
    for _ in range(10):
        after = _tick(estimator, context)[10]
    return float(before), float(after)


def test_a_trunk_carried_high_with_no_foot_loaded_keeps_its_velocity():
    before, after = _velocity_after_a_moment_unloaded(0.27)
    assert before == pytest.approx(0.5, rel=0.1)
    assert after == pytest.approx(before, abs=0.01)


def test_a_low_trunk_with_no_foot_loaded_is_taken_to_rest_on_the_ground():
    # On its folded legs (a trunk this low can only be resting), the IMU's drift is held at zero.
    before, after = _velocity_after_a_moment_unloaded(0.12)
    assert before == pytest.approx(0.5, rel=0.1)
    assert after < before - 0.1


def _quaternion(wxyz):
    from pydrake.common.eigen_geometry import Quaternion

    return Quaternion(np.asarray(wxyz) / np.linalg.norm(wxyz))


@pytest.mark.parametrize("port", ["imu", "position_measured", "velocity_measured", "torque_estimated", "foot_contact"])
def test_non_finite_inputs_hold_the_last_estimate(port):
    estimator, context = _estimator_context()
    before = _tick(estimator, context).copy()
    size = estimator.GetInputPort(port).size()
    estimator.GetInputPort(port).FixValue(context, np.full(size, np.nan))
    after = _tick(estimator, context)
    np.testing.assert_array_equal(after, before)
    assert np.all(np.isfinite(after))


def test_before_any_imu_message_the_output_is_finite():
    estimator, context = _estimator_context()
    estimator.imu_port.FixValue(context, np.zeros(10))
    base = _tick(estimator, context)
    assert np.all(np.isfinite(base)) and base[0] == 1.0


def test_bad_settings_name_the_field():
    with pytest.raises(ScenarioError, match=r"kalman\.foot_position_noise"):
        load_scenario(scenario_text="{kalman: {foot_position_noise: -1.0}}")


def test_estimate_follows_the_simulated_robot_standing_up_with_sensor_noise():
    scenario = load_scenario(
        scenario_name="stand",
        scenario_text="{estimator: kalman, simulation_duration: 3.0, sensor_noise: {enabled: true}, random_seed: 4}",
    )
    built = MakePedipulationDiagram(scenario)
    simulator = Simulator(built.diagram)
    simulator.AdvanceTo(3.0)
    context = simulator.get_context()

    logs = built.logs(context)
    plant = built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    errors = estimate_errors(
        logs["base_state"], logs["sim.plant_state"], robot.Go1PlantMap.from_plant(plant), plant.num_positions()
    )
    assert errors["position_error_max_m"] < 0.01, errors
    assert errors["velocity_rms_m_s"] < 0.03, errors
    assert errors["orientation_error_max_deg"] < 1.0, errors


def test_imu_offset_is_read_from_the_model():
    np.testing.assert_allclose(imu_offset_B(), [-0.01592, -0.06659, -0.00617], atol=1e-9)


# A quarter of the Go1's weight sinks a rubber foot of MuJoCo Menagerie's Go1 by about 17 mm [m/N].
RUBBER_FOOT_COMPLIANCE = 0.017 / (robot.TOTAL_MASS * 9.81 / 4)


def _sinking_feet_run(compliance: float, duration: float, rng, noise: bool, config=None):
    """Height error [m] and compliance estimate [m/N] of the filter, per tick, over a trunk swaying
    +-2 cm in x at 0.5 Hz on feet that sink `compliance` [m/N] times their load; the front and rear
    loads swing by +-30 % with the sway. The joint torques are those that hold the feet's loads."""
    kf = FloatingBaseKalmanFilter(config or KalmanEstimatorConfig(), np.zeros(3))
    weight = robot.TOTAL_MASS * 9.81
    h = robot.trunk_height_for(0.9, -1.8)
    w = 2.0 * np.pi * 0.5
    nominal = _feet_W(np.array([0.0, 0.0, h]))
    front = np.array([1.0, 1.0, -1.0, -1.0])  # FR, FL, RR, RL
    contact = np.ones(4, dtype=bool)
    errors, compliances = [], []
    x = P = q_prev = None
    for k in range(int(duration / DT)):
        t = k * DT
        p = np.array([0.02 * np.sin(w * t), 0.0, h])
        a = np.array([-0.02 * w * w * np.sin(w * t), 0.0, 0.0])
        loads = weight / 4 * (1.0 + 0.3 * front * np.sin(w * t))
        feet = nominal.copy()
        feet[:, 2] = robot.FOOT_RADIUS - compliance * loads
        q = _joint_angles_for(p, feet)
        qd = np.zeros(12) if q_prev is None else (q - q_prev) / DT
        q_prev = q
        _, jacobians = foot_kinematics_B(q)
        tau = np.concatenate([-jacobians[i].T @ [0.0, 0.0, loads[i]] for i in range(4)])
        f_B = a - GRAVITY_W
        if noise:
            f_B = f_B + rng.normal(0.0, 0.05, 3)
            q = q + rng.normal(0.0, 0.0005, 12)
            tau = tau + rng.normal(0.0, 0.1, 12)
        imu = ImuSample(np.eye(3), np.zeros(3), f_B)
        if x is None:
            x, P = kf.initial_state(imu, q, p[:2])
        else:
            x, P = kf.predict(x, P, imu, contact, DT)
        x, P = kf.update(x, P, imu, q, qd, contact, tau=tau)
        errors.append(x[2] - p[2])
        compliances.append(x[COMPLIANCE])
    return np.array(errors), np.array(compliances)


def test_feet_that_sink_under_load_do_not_lift_the_estimated_world(rng):
    errors, compliances = _sinking_feet_run(RUBBER_FOOT_COMPLIANCE, 4.0, rng, noise=True)
    settled = slice(int(1.0 / DT), None)
    assert np.max(np.abs(errors[settled])) < 0.003, np.max(np.abs(errors[settled]))
    assert abs(compliances[-1] - RUBBER_FOOT_COMPLIANCE) < 0.2 * RUBBER_FOOT_COMPLIANCE


def test_taking_the_sinking_feet_as_rigid_puts_the_world_too_high_by_the_sink(rng):
    # The same robot with the compliance held at 0 (the filter before it estimated one).
    rigid = KalmanEstimatorConfig(
        foot_compliance_std=0.0, foot_compliance_process_noise=0.0, foot_sink_std=0.0, foot_sink_process_noise=0.0
    )
    errors, _ = _sinking_feet_run(RUBBER_FOOT_COMPLIANCE, 4.0, rng, noise=True, config=rigid)
    assert np.median(errors[int(1.0 / DT) :]) > 0.012


def test_rigid_feet_are_estimated_rigid(rng):
    errors, compliances = _sinking_feet_run(0.0, 4.0, rng, noise=True)
    assert np.max(np.abs(errors[int(1.0 / DT) :])) < 0.002
    assert compliances[-1] < 0.05 * RUBBER_FOOT_COMPLIANCE


def test_vertical_loads_come_from_the_joint_torques_that_hold_them(rng):
    R = RotationMatrix(RollPitchYaw(0.05, -0.08, 0.3)).matrix()
    _, jacobians = foot_kinematics_B(robot.STANDING_Q)
    loads_W = rng.uniform(5.0, 60.0, 4)
    tau = np.concatenate([-jacobians[i].T @ (R.T @ [0.0, 0.0, loads_W[i]]) for i in range(4)])
    np.testing.assert_allclose(_vertical_forces_kernel(R, jacobians, tau), loads_W, rtol=1e-9)
    # A leg pulled upwards (no ground can do that) reads as no load.
    assert _vertical_forces_kernel(R, jacobians, -tau).tolist() == [0.0] * 4


def test_bad_compliance_settings_name_the_field():
    with pytest.raises(ScenarioError, match=r"kalman\.foot_compliance_std"):
        load_scenario(scenario_text="{kalman: {foot_compliance_std: -1.0}}")
