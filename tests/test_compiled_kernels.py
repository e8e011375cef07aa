"""The compiled kernels (pedi_drake.runtime.jit) against their own plain-Python source on random inputs.

With numba a kernel runs as machine code; `.py_func` is the same function run by the
interpreter, the reference. Both must agree: bit for bit where the kernel does elementwise float
arithmetic in the reference's order (command bounds, leg kinematics), to rounding where it uses
LAPACK (the Kalman correction).
"""

import numpy as np
import pytest

from pedi_drake import robot
from pedi_drake.estimation import kalman_estimator as ke
from pedi_drake.estimation import leg_odometry
from pedi_drake.go1_driver import safety
from pedi_drake.go1_driver.config import Go1SafetyConfig
from pedi_drake.runtime import jit
from pedi_drake.vector3 import rotation_matrix_wxyz

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


def test_safety_filter_step_kernel_equals_its_python_source_bit_for_bit():
    """Sequences of filter ticks, compiled and interpreted from the same state: soft start, bounds,
    NaN in the command or the measurements, stale status, hung loops and E-stops."""
    config = Go1SafetyConfig()
    filt = safety.Go1SafetyFilter(config)
    kernel = safety._filter_step_kernel
    rng = np.random.default_rng(RNG_SEED)
    fired_latches = set()
    for sequence in range(40):
        published, memory = np.zeros(60), np.zeros(safety._MEMORY_SIZE)
        now = 0.0
        for k in range(60):
            command = _random_command(rng)
            if rng.uniform() < 0.05:
                command[rng.integers(60)] = np.nan
            q, qd = robot.STANDING_Q + rng.normal(0, 0.8, 12), rng.normal(0, 10, 12)
            if rng.uniform() < 0.03:
                qd[rng.integers(12)] = np.inf
            silence = rng.uniform(0, 1.1 * config.status_timeout, 2) if sequence % 4 == 1 else np.zeros(2)
            estop = np.array([float(sequence % 4 == 2 and rng.uniform() < 0.05)])
            remote_estop = float(sequence % 4 == 3 and rng.uniform() < 0.05)
            hung = rng.uniform() < 0.02  # longer than the loop-silence limit, even while warming up
            now += config.period + (config.warmup_command_timeout + 0.01 if hung else 0.0)
            status = safety.robot_status_vector(q, qd, silence, remote_estop)
            inputs = (command, status, estop, now, k * config.period, filt._bounds, filt._settings)
            compiled_state, reference_state = (published.copy(), memory.copy()), (published.copy(), memory.copy())
            compiled = kernel(*compiled_state, *inputs)
            reference = kernel.py_func(*reference_state, *inputs)
            assert compiled == reference
            for a, b in zip(compiled_state, reference_state, strict=True):
                np.testing.assert_array_equal(a, b)
            published, memory = compiled_state
            if compiled[1] >= 0:
                fired_latches.add(safety.INTERVENTIONS[compiled[1]])
    assert fired_latches == set(safety.LATCHING)  # the inputs reached every latch


def test_foot_kinematics_kernel_equals_its_python_source_bit_for_bit():
    rng = np.random.default_rng(RNG_SEED)
    offsets = leg_odometry.leg_offsets()
    kernel = leg_odometry.foot_kinematics_kernel
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
    R = rotation_matrix_wxyz(quaternion)
    n = ke.NUM_STATES
    A = rng.normal(size=(n, n))
    P = 1e-3 * A @ A.T + 1e-4 * np.eye(n)
    return R, rng.normal(0, 1, 3), rng.normal(0, 3, 3), rng.normal(0, 1, n), P


def test_kalman_kernels_equal_their_python_source():
    rng = np.random.default_rng(RNG_SEED)
    tips = np.array([[0.1, 0.05, -0.1, 0.01], [0.1, -0.05, -0.1, 0.01]])  # position [m], radius [m]
    noise_std = np.array([0.003, 0.05, 0.003, 0.05])
    process_std = np.array([0.005, 0.5, 0.002, 1.0, 2e-5, 1e-4])
    p_BI = ke.imu_offset_B()
    for k in range(500):
        R, w, f, x, P = _random_filter_inputs(rng)
        q, qd = robot.STANDING_Q + rng.normal(0, 0.3, 12), rng.normal(0, 2, 12)
        contact = rng.uniform(size=4) > 0.4
        rolling = ke._rolling_kernel(R, w, q, qd, 0.02)
        np.testing.assert_allclose(rolling, ke._rolling_kernel.py_func(R, w, q, qd, 0.02), rtol=0, atol=1e-15)
        args = (x, P, R, w, f, p_BI, 0.002, rolling, contact, process_std)
        for compiled, reference in zip(ke._predict_kernel(*args), ke._predict_kernel.py_func(*args), strict=True):
            np.testing.assert_allclose(compiled, reference, rtol=0, atol=1e-14)
        num_tips = 2 * (k % 2)
        loads = rng.uniform(0, 40, 4)
        resting, learn = bool(k % 3 == 0), bool(k % 5 != 0)
        args = (contact, num_tips, True, noise_std, loads, resting, learn, bool(k % 4 != 0))
        rows = ke._measurement_rows(*args)
        for compiled, reference in zip(rows, ke._measurement_rows.py_func(*args), strict=True):
            np.testing.assert_array_equal(compiled, reference)
        p_BF, J = leg_odometry.foot_kinematics_B(q)
        sinks = rng.uniform(0, 0.02, 4)
        rest = 0.057 if resting else 0.0
        args = (R, w, p_BF, J, qd, contact, rolling, True, True, 0.02, tips[:num_tips], rest, sinks, len(rows[2]))
        y = ke._measurements_kernel(*args)
        np.testing.assert_allclose(y, ke._measurements_kernel.py_func(*args), rtol=0, atol=1e-14)
        compiled, reference = ke._correct_kernel(x, P, *rows, y), ke._correct_kernel.py_func(x, P, *rows, y)
        assert compiled[2] and reference[2]
        np.testing.assert_allclose(compiled[0], reference[0], rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(compiled[1], reference[1], rtol=1e-10, atol=1e-12)


def test_imu_kernel_normalises_the_quaternion_as_the_shared_rotation_does():
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(500):
        imu = rng.normal(0, 2, 10)
        usable, quaternion, R = ke._imu_kernel(imu)
        assert usable == (np.linalg.norm(imu[:4]) >= 0.5)
        if usable:
            np.testing.assert_allclose(quaternion, np.sign(imu[0]) * imu[:4] / np.linalg.norm(imu[:4]), rtol=1e-15)
            np.testing.assert_array_equal(R, rotation_matrix_wxyz(quaternion))
            for compiled, reference in zip((usable, quaternion, R), ke._imu_kernel.py_func(imu), strict=True):
                np.testing.assert_array_equal(compiled, reference)
    for bad in (np.zeros(10), np.full(10, np.nan), np.r_[1.0, 0, 0, 0, np.inf, 0, 0, 0, 0, 0]):
        assert not ke._imu_kernel(bad)[0]


def _measurement_matrix(columns: np.ndarray, coefficients: np.ndarray) -> np.ndarray:
    """The dense H (m, NUM_STATES) of a measurement model in the form of `_measurement_rows`."""
    H = np.zeros((len(columns), ke.NUM_STATES))
    for row, (cols, coefs) in enumerate(zip(columns, coefficients, strict=True)):
        for col, coef in zip(cols, coefs, strict=True):
            H[row, col] += coef
    return H


def test_kalman_correction_is_the_textbook_update():
    """The row-by-row correction against K = P H^T (H P H^T + R)^-1 written with numpy.linalg, for
    measurements of one state or of a weighted pair (the form of every row of the filter's H)."""
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(100):
        _, _, _, x, P = _random_filter_inputs(rng)
        m = 30
        columns = np.array([rng.choice(ke.NUM_STATES, 2, replace=False) for _ in range(m)])
        coefficients = rng.normal(size=(m, 2))
        coefficients[rng.uniform(size=m) < 0.4, 1] = 0.0  # rows that measure one state
        H = _measurement_matrix(columns, coefficients)
        noise = rng.uniform(1e-4, 1e-2, m)
        y = rng.normal(size=m)
        K = P @ H.T @ np.linalg.inv(H @ P @ H.T + np.diag(noise))
        x_new, P_new, corrected = ke._correct_kernel(x, P, columns, coefficients, noise, y)
        assert corrected
        np.testing.assert_allclose(x_new, x + K @ (y - H @ x), rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(P_new, (np.eye(ke.NUM_STATES) - K @ H) @ P, rtol=1e-9, atol=1e-12)
        np.testing.assert_array_equal(P_new, P_new.T)


def test_kalman_measurement_rows_are_the_filter_measurement_model():
    """Every contact pattern: the rows' H against the model written out (feet relative to the trunk,
    the stance feet's trunk velocity and height with their sink s + c F, the tips' velocity and
    height, with nothing loaded and the trunk low enough to rest its horizontal velocity, and a
    resting trunk's height)."""
    noise_std = np.array([0.003, 0.05, 0.004, 0.06])
    loads = np.array([10.0, 20.0, 30.0, 40.0])
    n = ke.NUM_STATES
    for pattern in range(16):
        contact = np.array([pattern >> i & 1 for i in range(4)], dtype=bool)
        for num_tips in (0, 1, 2):
            for resting_trunk in (False, True):
                for learn, may_rest in ((False, True), (True, True), (True, False)):
                    args = (contact, num_tips, True, noise_std, loads, resting_trunk, learn, may_rest)
                    rows = ke._measurement_rows(*args)
                    columns, coefficients, noise = rows
                    H = _measurement_matrix(columns, coefficients)
                    stance = np.flatnonzero(contact)
                    expected, variances = [], []
                    for i in range(4):
                        for k in range(3):
                            row = np.zeros(n)
                            row[k], row[6 + 3 * i + k] = -1.0, 1.0
                            expected.append(row)
                            variances.append(0.003**2 * (1.0 if contact[i] else 4.0))
                    velocity = list(np.eye(n)[3:6])
                    for _ in stance:
                        expected += velocity
                        variances += [0.05**2] * 3
                    for i in stance:
                        row = np.eye(n)[6 + 3 * i + 2].copy()
                        if learn:  # c F always; s only against a rigid reference
                            row[ke.COMPLIANCE] = loads[i]
                            row[ke.SINK] = 1.0 if (resting_trunk or num_tips) else 0.0
                        expected.append(row)
                        variances.append(0.004**2)
                    for _ in range(num_tips):
                        expected += velocity + [np.eye(n)[2]]
                        variances += [0.05**2] * 3 + [0.004**2]
                    if not len(stance) and not num_tips and may_rest:
                        expected += velocity[:2]
                        variances += [0.06**2] * 2
                    if resting_trunk:
                        expected.append(np.eye(n)[2])
                        variances.append(0.004**2)
                    np.testing.assert_array_equal(H, np.array(expected))
                    np.testing.assert_array_equal(noise, variances)


def test_kalman_step_kernel_equals_its_python_source():
    """A whole estimator tick, compiled and interpreted, from the same state on random samples."""
    rng = np.random.default_rng(RNG_SEED)
    tips = np.array([[0.1, 0.05, -0.1], [0.1, -0.05, -0.1]])
    filt = ke.FloatingBaseKalmanFilter(ke.KalmanEstimatorConfig(), ke.imu_offset_B(), prong_tips_B=tips)
    constants = (np.array([0.3, -0.1]), *filt._step_constants)
    state = [np.zeros(ke.FILTER_STATE_SIZE), np.zeros(ke.BASE_STATE_SIZE)]
    for k in range(300):
        quaternion = rng.normal(size=4)
        imu = np.concatenate([quaternion, rng.normal(0, 1, 3), rng.normal(0, 3, 3) + [0, 0, 9.81]])
        q, qd = robot.STANDING_Q + rng.normal(0, 0.3, 12), rng.normal(0, 2, 12)
        force = rng.uniform(0, 40, 4)
        schedule = np.zeros(0) if k % 3 == 0 else (rng.uniform(size=6) > 0.3).astype(float)
        compiled = [s.copy() for s in state]
        reference = [s.copy() for s in state]
        tau = rng.normal(0, 3, 12)
        updated = ke._step_kernel(*compiled, imu, q, qd, tau, force, schedule, *constants)
        assert updated == ke._step_kernel.py_func(*reference, imu, q, qd, tau, force, schedule, *constants)
        for a, b in zip(compiled, reference, strict=True):
            np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-12)
        state = compiled
    assert state[0][0] == 1.0
