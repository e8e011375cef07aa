"""The compiled kernels (pedi_drake.jit) against their own plain-Python source on random inputs.

With numba a kernel runs as machine code; `.py_func` is the same function run by the
interpreter, the reference. Both must agree: bit for bit where the kernel does elementwise float
arithmetic in the reference's order (command bounds, leg kinematics), to rounding where it uses
LAPACK (the Kalman correction).
"""

import numpy as np
import pytest

from pedi_drake import jit, robot
from pedi_drake.estimation import kalman_estimator as ke
from pedi_drake.estimation import leg_odometry
from pedi_drake.go1_driver import safety
from pedi_drake.go1_driver.config import Go1SafetyConfig

RNG_SEED = 20261202


def test_kernels_are_compiled_when_numba_is_installed():
    pytest.importorskip("numba")
    if not jit.ENABLED:
        pytest.skip("PEDI_DRAKE_JIT=0")
    assert safety._bound_command_kernel.py_func is not safety._bound_command_kernel


def _random_command(rng):
    return np.concatenate(
        [
            robot.STANDING_Q + rng.normal(0, 1.0, 12),
            rng.normal(0, 30, 12),
            rng.uniform(-20, 120, 12),
            rng.uniform(-1, 8, 12),
            rng.normal(0, 30, 12),
        ]
    )


def test_bound_command_kernel_equals_its_python_source_bit_for_bit():
    rng = np.random.default_rng(RNG_SEED)
    limits = safety.SafetyLimits.from_config(Go1SafetyConfig())
    kernel = safety._bound_command_kernel
    flags_seen = 0
    for k in range(3000):
        q = robot.STANDING_Q + rng.normal(0, 0.8, 12)
        qd = rng.normal(0, 10, 12)
        args = (
            _random_command(rng),
            q,
            qd,
            limits.q_lower,
            limits.q_upper,
            limits.qd_max,
            limits.effort,
            limits.kp_max,
            limits.kd_max,
            limits.max_target_step,
            robot.STANDING_Q + rng.normal(0, 0.3, 12),
            bool(k % 2),
        )
        compiled, bits = kernel(*args)
        reference, reference_bits = kernel.py_func(*args)
        np.testing.assert_array_equal(compiled, reference)
        assert bits == reference_bits
        flags_seen |= bits
    assert flags_seen == (1 << len(safety._BOUND_FLAGS)) - 1  # the inputs reached every branch


def test_foot_kinematics_kernel_equals_its_python_source_bit_for_bit():
    rng = np.random.default_rng(RNG_SEED)
    offsets = leg_odometry._offsets()
    kernel = leg_odometry._foot_kinematics_kernel
    for _ in range(2000):
        q = rng.uniform(-3.0, 3.0, 12)
        for compiled, reference in zip(kernel(q, offsets), kernel.py_func(q, offsets), strict=True):
            np.testing.assert_array_equal(compiled, reference)


def test_foot_kinematics_matches_the_model():
    """The closed form against the general forward kinematics of the model's joint frames."""
    from pedi_drake.leg_kinematics import foot_position_B

    rng = np.random.default_rng(RNG_SEED)
    for _ in range(200):
        q = rng.uniform(-2.0, 2.0, 12)
        feet, _ = leg_odometry.foot_kinematics_B(q)
        for i, leg in enumerate(robot.LEG_NAMES):
            np.testing.assert_allclose(feet[i], foot_position_B(leg, q[3 * i : 3 * i + 3]), atol=1e-12)


def _random_filter_inputs(rng):
    quaternion = rng.normal(size=4)
    quaternion /= np.linalg.norm(quaternion)
    R = ke.rotation_matrix_wxyz(quaternion)
    A = rng.normal(size=(18, 18))
    P = 1e-3 * A @ A.T + 1e-4 * np.eye(18)
    return R, rng.normal(0, 1, 3), rng.normal(0, 3, 3), rng.normal(0, 1, 18), P


def test_kalman_kernels_equal_their_python_source():
    rng = np.random.default_rng(RNG_SEED)
    tips = np.array([[0.1, 0.05, -0.1], [0.1, -0.05, -0.1]])
    filt = ke.FloatingBaseKalmanFilter(ke.KalmanEstimatorConfig(), ke.imu_offset_B(), prong_tips_B=tips)
    for k in range(500):
        R, w, f, x, P = _random_filter_inputs(rng)
        q, qd = robot.STANDING_Q + rng.normal(0, 0.3, 12), rng.normal(0, 2, 12)
        contact = rng.uniform(size=4) > 0.4
        rolling = ke._rolling_kernel(R, w, q, qd, 0.02)
        np.testing.assert_allclose(rolling, ke._rolling_kernel.py_func(R, w, q, qd, 0.02), rtol=0, atol=1e-15)
        args = (x, P, R, w, f, filt.p_BI, ke.GRAVITY_W, 0.002, rolling, contact, np.full(18, 1e-6))
        for compiled, reference in zip(ke._predict_kernel(*args), ke._predict_kernel.py_func(*args), strict=True):
            np.testing.assert_allclose(compiled, reference, rtol=0, atol=1e-14)
        num_tips = 2 * (k % 2)
        H, noise = filt._measurement_model(tuple(contact.tolist()), num_tips)
        p_BF, J = leg_odometry.foot_kinematics_B(q)
        args = (R, w, p_BF, J, qd, contact, rolling, True, True, 0.02, tips[:num_tips], 0.01, len(noise))
        y = ke._measurements_kernel(*args)
        np.testing.assert_allclose(y, ke._measurements_kernel.py_func(*args), rtol=0, atol=1e-14)
        for compiled, reference in zip(
            ke._correct_kernel(x, P, H, noise, y), ke._correct_kernel.py_func(x, P, H, noise, y), strict=True
        ):
            np.testing.assert_allclose(compiled, reference, rtol=1e-10, atol=1e-12)


def test_kalman_correction_is_the_textbook_update():
    """The correction kernel against K = P H^T (H P H^T + R)^-1 written with numpy.linalg."""
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(100):
        _, _, _, x, P = _random_filter_inputs(rng)
        H = rng.normal(size=(20, 18))
        noise = rng.uniform(1e-4, 1e-2, 20)
        y = rng.normal(size=20)
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + np.diag(noise))
        x_new, P_new = ke._correct_kernel(x, P, H, noise, y)
        np.testing.assert_allclose(x_new, x + K @ (y - H @ x), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(P_new, (np.eye(18) - K @ H) @ P, rtol=1e-9, atol=1e-12)
