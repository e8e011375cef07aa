"""Floating-base state estimation from the IMU and leg kinematics: a linear Kalman filter.

The filter of Bloesch et al. (2013) in its linear form (as in MIT Cheetah 3): the IMU gives the
orientation R_WB (its quaternion) and the angular velocity (gyro); the filter estimates

    x = [p_WB (3), v_WB (3), p_WF for the four feet (12)]   (world frame, 18 states)

* predict: p += v dt + a dt^2 / 2, v += a dt with a = R_WB (f_I - w x (w x p_BI)) + g, the
  accelerometer's specific force moved from the IMU to the trunk origin; feet stand still, with
  a small random walk in contact and a large one in the air;
* update, every foot: p_WF - p_WB = R_WB p_BF(q) (leg kinematics);
  every foot in contact: v_WB = -R_WB (J(q) qd + w_B x p_BF) + (its rolling velocity) (the
  contact point does not move), and, on flat ground, p_WF,z = foot radius; every loaded prong
  tip likewise (it does not move and touches the ground); with no foot and no prong loaded the
  trunk rests on the ground (lying): v_WB = 0.

A foot is in contact when the mission's contact schedule (if connected) loads it and its sensor
reads above a threshold; a prong tip when the schedule loads that prong. Each prong counts on
its own: a trunk turning about one tip lifts the others, and pinning those to the ground too
would pull the height estimate between contradicting measurements.
Only go1.* signals are read, in simulation and on hardware alike.
"""

import dataclasses
import math

import numpy as np
from pydrake.math import RotationMatrix
from pydrake.systems.framework import BasicVector, Context, DiscreteValues, LeafSystem

from pedi_drake import robot
from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.estimation.config import KalmanEstimatorConfig
from pedi_drake.estimation.leg_odometry import foot_kinematics_B
from pedi_drake.jit import kernel
from pedi_drake.prongs import ProngDesign
from pedi_drake.vector3 import rotation_matrix_wxyz

GRAVITY_W = np.array([0.0, 0.0, -9.81])  # [m/s^2]
NUM_STATES = 18
_P, _V = slice(0, 3), slice(3, 6)


_I3 = np.eye(3)
_I3.flags.writeable = False


def _foot(i: int) -> slice:
    return slice(6 + 3 * i, 9 + 3 * i)


_FEET = slice(6, 18)
_DIAGONAL = np.diag_indices(NUM_STATES)
# Rows of the four foot-position measurements p_WF - p_WB (they do not change).
_FOOT_POSITION_ROWS = np.zeros((12, NUM_STATES))
for _i in range(4):
    _FOOT_POSITION_ROWS[3 * _i : 3 * _i + 3, _P] = -_I3
    _FOOT_POSITION_ROWS[3 * _i : 3 * _i + 3, _foot(_i)] = _I3
_FOOT_POSITION_ROWS.flags.writeable = False


def imu_offset_B() -> np.ndarray:
    """The IMU's position in the trunk frame, read from the model [m]."""
    plant, plant_map = robot.make_go1_plant()
    context = plant.CreateDefaultContext()
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME, plant_map.model)
    imu = plant.GetBodyByName(robot.IMU_BODY_NAME, plant_map.model)
    return plant.CalcRelativeTransform(context, trunk.body_frame(), imu.body_frame()).translation().copy()


@dataclasses.dataclass(frozen=True)
class ImuSample:
    """One go1.imu sample: orientation R_WB, gyro w_B [rad/s], specific force f_B [m/s^2] (trunk frame)."""

    R_WB: np.ndarray
    w_B: np.ndarray
    f_B: np.ndarray
    # R_WB's quaternion (unit norm, w >= 0); from R_WB when not given.
    quaternion_wxyz: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.quaternion_wxyz is None:
            object.__setattr__(self, "quaternion_wxyz", RotationMatrix(self.R_WB).ToQuaternion().wxyz())

    @staticmethod
    def from_vector(imu: np.ndarray) -> "ImuSample | None":
        """None when the quaternion is not usable (all zeros before the first message, NaN)."""
        imu = np.asarray(imu, dtype=float)
        if imu.shape != (10,) or not np.isfinite(imu).all():
            return None
        norm = math.sqrt(float(imu[0:4] @ imu[0:4]))
        if norm < 0.5:
            return None
        quaternion = imu[0:4] / (norm if imu[0] >= 0.0 else -norm)
        return ImuSample(rotation_matrix_wxyz(quaternion), imu[4:7].copy(), imu[7:10].copy(), quaternion)


def rolling_velocities_W(R_WB: np.ndarray, w_B: np.ndarray, q: np.ndarray, qd: np.ndarray, radius: float) -> np.ndarray:
    """(4, 3) world velocity of each foot sphere's centre when it rolls without slipping [m/s].

    A foot sphere turns with its calf: w_calf = w_B + x qd_hip + Rx(q_hip) y (qd_thigh + qd_calf)
    (trunk frame), and its centre moves at w_calf x (radius z) above the contact point on flat
    ground. Standing up turns the calves by about a radian: 2 cm of travel the filter must expect.
    """
    return _rolling_kernel(
        np.asarray(R_WB, dtype=float),
        np.asarray(w_B, dtype=float),
        np.asarray(q, dtype=float),
        np.asarray(qd, dtype=float),
        float(radius),
    )


@kernel
def _rolling_kernel(R_WB, w_B, q, qd, radius):
    rolling = np.zeros((4, 3))
    for i in range(4):
        rate_sagittal = qd[3 * i + 1] + qd[3 * i + 2]
        w0 = qd[3 * i] + w_B[0]
        w1 = math.cos(q[3 * i]) * rate_sagittal + w_B[1]
        w2 = math.sin(q[3 * i]) * rate_sagittal + w_B[2]
        # w_W = R_WB w_B; w x (0, 0, radius) = radius (w_y, -w_x, 0)
        rolling[i, 0] = radius * (R_WB[1, 0] * w0 + R_WB[1, 1] * w1 + R_WB[1, 2] * w2)
        rolling[i, 1] = -radius * (R_WB[0, 0] * w0 + R_WB[0, 1] * w1 + R_WB[0, 2] * w2)
    return rolling


def _plausible_joint_angles(q: np.ndarray, slack: float = 0.2) -> bool:
    """Whether q lies within the joint limits (+- slack [rad]); all zeros (the calf cannot be at 0) is not."""
    return bool(np.all(q >= robot.Q_LOWER - slack) and np.all(q <= robot.Q_UPPER + slack))


_NO_ROLLING = np.zeros((4, 3))
_NO_ROLLING.flags.writeable = False


@kernel
def _predict_kernel(x, P, R_WB, w_B, f_B, p_BI, gravity_W, dt, rolling, in_contact, process_noise):
    """`FloatingBaseKalmanFilter.predict` on plain arrays: the new (x, P)."""
    # Specific force at the trunk origin: f - w x (w x p_BI).
    wp = np.array(
        [w_B[1] * p_BI[2] - w_B[2] * p_BI[1], w_B[2] * p_BI[0] - w_B[0] * p_BI[2], w_B[0] * p_BI[1] - w_B[1] * p_BI[0]]
    )
    wwp = np.array([w_B[1] * wp[2] - w_B[2] * wp[1], w_B[2] * wp[0] - w_B[0] * wp[2], w_B[0] * wp[1] - w_B[1] * wp[0]])
    x = x.copy()
    for r in range(3):
        a_W = gravity_W[r]
        for k in range(3):
            a_W += R_WB[r, k] * (f_B[k] - wwp[k])
        x[r] += x[3 + r] * dt + 0.5 * a_W * dt * dt
        x[3 + r] += a_W * dt
    for i in range(4):
        if in_contact[i]:
            for k in range(3):
                x[6 + 3 * i + k] += rolling[i, k] * dt
    # F = I + dt E_pv: P <- F P F^T + Q, written out instead of two 18x18 products.
    n = P.shape[0]
    P = P.copy()
    for r in range(3):
        for c in range(n):
            P[r, c] += dt * P[3 + r, c]
    for r in range(n):
        for c in range(3):
            P[r, c] += dt * P[r, 3 + c]
    for i in range(n):
        P[i, i] += process_noise[i]
    return x, P


@kernel
def _measurements_kernel(
    R, w_B, p_BF, J, qd, in_contact, rolling, use_rolling, use_height, foot_radius, tips_B, tip_radius, m
):
    """The measurement vector y (m,) of `FloatingBaseKalmanFilter.update`, in the row order of its
    `_measurement_model`: every foot's R p_BF, the stance feet's trunk velocities (and heights),
    the loaded prong tips' trunk velocity and height, or the resting trunk's zero velocity."""
    y = np.zeros(m)
    row = 0
    for i in range(4):  # every foot: p_WF - p_WB = R p_BF
        for r in range(3):
            y[row + r] = R[r, 0] * p_BF[i, 0] + R[r, 1] * p_BF[i, 1] + R[r, 2] * p_BF[i, 2]
        row += 3
    stance = 0
    for i in range(4):  # feet in contact do not slip: v_WB = -R (J qd + w x p_BF) + rolling
        if not in_contact[i]:
            continue
        stance += 1
        p = p_BF[i]
        v_B = np.array([w_B[1] * p[2] - w_B[2] * p[1], w_B[2] * p[0] - w_B[0] * p[2], w_B[0] * p[1] - w_B[1] * p[0]])
        for r in range(3):
            for k in range(3):
                v_B[r] += J[i, r, k] * qd[3 * i + k]
        for r in range(3):
            y[row + r] = -(R[r, 0] * v_B[0] + R[r, 1] * v_B[1] + R[r, 2] * v_B[2])
            if use_rolling:
                y[row + r] += rolling[i, r]
        row += 3
    if use_height:  # flat ground under the feet in contact
        for i in range(stance):
            y[row + i] = foot_radius
        row += stance
    for t in range(tips_B.shape[0]):
        # A loaded prong tip does not move and touches the ground: v_WB = -R (w x p_BT) and
        # p_WB,z = tip radius - (R p_BT)_z.
        p = tips_B[t]
        v_B = np.array([w_B[1] * p[2] - w_B[2] * p[1], w_B[2] * p[0] - w_B[0] * p[2], w_B[0] * p[1] - w_B[1] * p[0]])
        for r in range(3):
            y[row + r] = -(R[r, 0] * v_B[0] + R[r, 1] * v_B[1] + R[r, 2] * v_B[2])
        y[row + 3] = tip_radius - (R[2, 0] * p[0] + R[2, 1] * p[1] + R[2, 2] * p[2])
        row += 4
    # With nothing loaded the trunk rests on the ground: the remaining rows (zero velocity) stay 0.
    return y


@kernel
def _correct_kernel(x, P, H, noise, y):
    """The Kalman correction of (x, P) by measurements y = H x + noise (variances `noise`)."""
    innovation = y - H @ x
    PHt = P @ np.ascontiguousarray(H.T)
    S = H @ PHt
    for i in range(len(y)):
        S[i, i] += noise[i]
    # S is symmetric positive definite: by Cholesky, S = L L^T, K^T = S^-1 (P H^T)^T.
    L = np.linalg.cholesky(S)
    KT = _cholesky_solve(L, np.ascontiguousarray(PHt.T))
    x = x + KT.T @ innovation
    P = P - KT.T @ np.ascontiguousarray(PHt.T)
    return x, 0.5 * (P + P.T)


@kernel
def _cholesky_solve(L, B):
    """X with L L^T X = B, L lower triangular (forward then back substitution)."""
    n, k = B.shape
    X = B.copy()
    for c in range(k):
        for i in range(n):
            value = X[i, c]
            for j in range(i):
                value -= L[i, j] * X[j, c]
            X[i, c] = value / L[i, i]
        for i in range(n - 1, -1, -1):
            value = X[i, c]
            for j in range(i + 1, n):
                value -= L[j, i] * X[j, c]
            X[i, c] = value / L[i, i]
    return X


class FloatingBaseKalmanFilter:
    """The filter's maths on plain arrays (no Drake state): `initial_state`, `predict`, `update`."""

    def __init__(
        self,
        config: KalmanEstimatorConfig,
        p_BI: np.ndarray,
        foot_radius: float = robot.FOOT_RADIUS,
        prong_tips_B: np.ndarray | None = None,
        prong_tip_radius: float = 0.0,
    ):
        self.config = config
        self.p_BI = np.asarray(p_BI, dtype=float)
        self.foot_radius = foot_radius
        # Prong tip centres in the trunk frame (k, 3) [m]: a loaded tip pins the trunk like a foot.
        self.prong_tips_B = np.zeros((0, 3)) if prong_tips_B is None else np.asarray(prong_tips_B, dtype=float)
        self.prong_tip_radius = prong_tip_radius
        self._process_noise_cache: dict[tuple, np.ndarray] = {}
        self._measurement_models: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}

    def warm_up(self) -> None:
        """Runs one predict and update of every kind, so the compiled kernels are compiled (or
        loaded from numba's cache) now, not in the first control tick."""
        imu = ImuSample(np.eye(3), np.zeros(3), -GRAVITY_W)
        x, P = self.initial_state(imu, robot.STANDING_Q, np.zeros(2))
        rolling = rolling_velocities_W(imu.R_WB, imu.w_B, robot.STANDING_Q, np.zeros(12), self.foot_radius)
        for contact in (np.ones(4, bool), np.zeros(4, bool)):
            x, P = self.predict(x, P, imu, contact, 0.002, rolling)
            self.update(
                x, P, imu, robot.STANDING_Q, np.zeros(12), contact, rolling, np.ones(len(self.prong_tips_B), bool)
            )

    def initial_state(self, imu: ImuSample, q: np.ndarray, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x, P) for a robot at rest with its lowest foot on the ground, trunk at `xy` [m]."""
        p_BF, _ = foot_kinematics_B(q)
        feet_W = p_BF @ imu.R_WB.T
        p = np.array([xy[0], xy[1], self.foot_radius - float(np.min(feet_W[:, 2]))])
        x = np.concatenate([p, np.zeros(3), (feet_W + p).ravel()])
        variances = np.concatenate([np.full(3, 0.01**2), np.full(3, 0.1**2), np.full(12, 0.01**2)])
        return x, np.diag(variances)

    def predict(
        self,
        x: np.ndarray,
        P: np.ndarray,
        imu: ImuSample,
        contact: np.ndarray,
        dt: float,
        rolling: np.ndarray | None = None,
    ):
        """Propagates (x, P) over dt [s] with the IMU acceleration; feet in contact move by their
        `rolling` velocities (4, 3) [m/s] (see rolling_velocities_W), when given."""
        in_contact = np.asarray(contact[:4], bool)
        return _predict_kernel(
            x,
            P,
            imu.R_WB,
            imu.w_B,
            imu.f_B,
            self.p_BI,
            GRAVITY_W,
            dt,
            _NO_ROLLING if rolling is None else np.asarray(rolling, dtype=float),
            in_contact,
            self._process_noise(tuple(in_contact.tolist()), dt),
        )

    def _process_noise(self, contact: tuple[bool, ...], dt: float) -> np.ndarray:
        """Diagonal of Q over dt [s] for the feet in `contact` (one of 16 patterns: kept once made)."""
        key = (contact, dt)
        q = self._process_noise_cache.get(key)
        if q is None:
            c = self.config
            q = np.empty(NUM_STATES)
            q[_P] = c.position_process_noise**2 * dt
            q[_V] = c.accelerometer_noise**2 * dt
            sigma = np.where(contact, c.stance_foot_process_noise, c.swing_foot_process_noise)
            q[_FEET] = np.repeat(sigma * sigma * dt, 3)
            q.flags.writeable = False
            if len(self._process_noise_cache) > 64:
                self._process_noise_cache.clear()  # dt keeps changing: do not grow without bound
            self._process_noise_cache[key] = q
        return q

    def _measurement_model(self, contact: tuple[bool, ...], num_tips: int) -> tuple[np.ndarray, np.ndarray]:
        """(H, measurement noise variances) for the feet in `contact` and `num_tips` loaded prong
        tips, in the row order of `update`. Constant for a contact pattern: made once each (the
        tip rows depend on how many tips are loaded, not which: their values carry the geometry)."""
        key = (contact, num_tips)
        model = self._measurement_models.get(key)
        if model is not None:
            return model
        c = self.config
        stance = [i for i in range(4) if contact[i]]
        use_height = c.ground_height_measurement
        # No foot or prong loaded: the trunk rests on the ground (on its belly or knees) while
        # the legs move freely; it does not slide, so a zero horizontal velocity keeps the IMU
        # from drifting while the legs unfold (the knees may push it up: z is left to the IMU).
        resting = not stance and not num_tips
        m = 12 + 3 * len(stance) + (len(stance) if use_height else 0) + (2 if resting else 0) + 4 * num_tips
        H = np.zeros((m, NUM_STATES))
        noise = np.empty(m)
        # Every foot's position; a foot in the air is carried by the kinematics: a loose
        # measurement of it costs nothing.
        H[:12] = _FOOT_POSITION_ROWS
        for i in range(4):
            noise[3 * i : 3 * i + 3] = c.foot_position_noise**2 * (1.0 if contact[i] else 4.0)
        row = 12
        for _ in stance:  # no-slip velocity rows
            H[row : row + 3, _V] = _I3
            noise[row : row + 3] = c.foot_velocity_noise**2
            row += 3
        if use_height:
            for i in stance:  # flat ground under the feet in contact
                H[row, 6 + 3 * i + 2] = 1.0
                noise[row] = c.ground_height_noise**2
                row += 1
        for _ in range(num_tips):  # tip velocity (3) and height (1)
            H[row : row + 3, _V] = _I3
            noise[row : row + 3] = c.foot_velocity_noise**2
            H[row + 3, 2] = 1.0
            noise[row + 3] = c.ground_height_noise**2
            row += 4
        if resting:
            H[row : row + 2, _V] = _I3[:2]
            noise[row : row + 2] = c.resting_velocity_noise**2
            row += 2
        H.flags.writeable = False
        noise.flags.writeable = False
        self._measurement_models[key] = (H, noise)
        return H, noise

    def update(
        self,
        x: np.ndarray,
        P: np.ndarray,
        imu: ImuSample,
        q: np.ndarray,
        qd: np.ndarray,
        contact: np.ndarray,
        rolling: np.ndarray | None = None,
        tips_loaded: np.ndarray | None = None,
    ):
        """Corrects (x, P) with the leg kinematics of all feet and the no-slip of the feet in contact
        (whose centres move at their `rolling` velocities (4, 3) [m/s], when given), and with each
        prong tip flagged in `tips_loaded` (one bool per prong; None: none loaded): it does not
        move, and touches the ground."""
        p_BF, J = foot_kinematics_B(q)
        in_contact = np.asarray(contact[:4], bool)
        tips = self.prong_tips_B[np.asarray(tips_loaded, bool)] if tips_loaded is not None else self.prong_tips_B[:0]
        num_tips = len(tips)
        H, noise = self._measurement_model(tuple(in_contact.tolist()), num_tips)
        y = _measurements_kernel(
            imu.R_WB,
            imu.w_B,
            p_BF,
            J,
            np.asarray(qd, dtype=float),
            in_contact,
            _NO_ROLLING if rolling is None else np.asarray(rolling, dtype=float),
            rolling is not None,
            self.config.ground_height_measurement,
            self.foot_radius,
            tips,
            self.prong_tip_radius,
            len(noise),
        )
        return _correct_kernel(x, P, H, noise, y)

    @staticmethod
    def contact_flags(foot_sensor: np.ndarray, schedule: np.ndarray | None, threshold: float) -> np.ndarray:
        """Feet in contact: scheduled (when a schedule is given) and sensed."""
        scheduled = np.ones(4, dtype=bool) if schedule is None else np.asarray(schedule[:4]) > 0.5
        return scheduled & (np.asarray(foot_sensor) > threshold)


class KalmanEstimator(LeafSystem):
    """go1.imu, go1.position_measured, go1.velocity_measured, go1.foot_contact (+ optional
    contact_set) -> base_state (13: quaternion, p_WB, w_WB, v_WB; see base_state.py).

    Periodic discrete update at `config.period`; base_state is computed from the discrete state
    alone, so the loop estimator -> mission manager -> contact_set -> estimator has a delay.
    State: [initialised flag, x (18), P (18 x 18), quaternion (4), w_W (3)].
    """

    def __init__(self, config: KalmanEstimatorConfig, initial_xy=(0.0, 0.0), prongs: ProngDesign | None = None):
        super().__init__()
        self.config = config
        self._xy = np.asarray(config.initial_xy if config.initial_xy is not None else initial_xy, dtype=float)
        tips = None if prongs is None else prongs.tip_positions_B()
        radius = 0.0 if prongs is None else prongs.tip_radius
        self.filter = FloatingBaseKalmanFilter(config, imu_offset_B(), prong_tips_B=tips, prong_tip_radius=radius)
        self.filter.warm_up()
        num_contacts = 4 + (0 if prongs is None else prongs.num_prongs)
        self.imu_port = self.DeclareVectorInputPort("imu", 10)
        self.position_port = self.DeclareVectorInputPort("position_measured", 12)
        self.velocity_port = self.DeclareVectorInputPort("velocity_measured", 12)
        self.foot_contact_port = self.DeclareVectorInputPort("foot_contact", 4)
        # Optional: the mission's contact schedule (feet first, then prongs).
        self.contact_set_port = self.DeclareVectorInputPort("contact_set", num_contacts)
        n = NUM_STATES
        self._layout = {"flag": 0, "x": slice(1, 1 + n), "P": slice(1 + n, 1 + n + n * n)}
        self._quat = slice(1 + n + n * n, 5 + n + n * n)
        self._w = slice(5 + n + n * n, 8 + n + n * n)
        initial = np.zeros(8 + n + n * n)
        initial[self._quat] = [1.0, 0.0, 0.0, 0.0]
        self._state = self.DeclareDiscreteState(initial)
        self.DeclareInitializationDiscreteUpdateEvent(self._update)
        self.DeclarePeriodicDiscreteUpdateEvent(config.period, 0.0, self._update)
        # The same step on demand (CalcForcedDiscreteVariableUpdate), for tests.
        self.DeclareForcedDiscreteUpdateEvent(self._update)
        self.base_state_port = self.DeclareVectorOutputPort(
            "base_state", BASE_STATE_SIZE, self._calc_base_state, {self.xd_ticket()}
        )

    def _measurements(self, context: Context):
        imu = ImuSample.from_vector(self.imu_port.Eval(context))
        q = np.asarray(self.position_port.Eval(context), dtype=float)
        qd = np.asarray(self.velocity_port.Eval(context), dtype=float)
        force = np.asarray(self.foot_contact_port.Eval(context), dtype=float)
        schedule = self.contact_set_port.Eval(context) if self.contact_set_port.HasValue(context) else None
        finite = bool(np.isfinite(q).all() and np.isfinite(qd).all() and np.isfinite(force).all())
        return imu, q, qd, force, schedule, finite

    def _update(self, context: Context, discrete_state: DiscreteValues) -> None:
        s = context.get_discrete_state(self._state).get_value().copy()
        imu, q, qd, force, schedule, finite = self._measurements(context)
        if imu is None or not finite:
            return  # hold the last estimate: a bad sample (or none yet) never reaches the output
        if s[0] == 0.0 and not _plausible_joint_angles(q):
            return  # no leg_control_data yet (all zeros on hardware): initialise from a real sample
        n = NUM_STATES
        contact = self.filter.contact_flags(force, schedule, self.config.foot_contact_threshold)
        rolling = rolling_velocities_W(imu.R_WB, imu.w_B, q, qd, self.filter.foot_radius)
        if s[0] == 0.0:
            x, P = self.filter.initial_state(imu, q, self._xy)
        else:
            x, P = s[self._layout["x"]], s[self._layout["P"]].reshape(n, n)
            x, P = self.filter.predict(x, P, imu, contact, self.config.period, rolling)
        tips_loaded = None if schedule is None else np.asarray(schedule[4:]) > 0.5
        x, P = self.filter.update(x, P, imu, q, qd, contact, rolling, tips_loaded)
        if not (np.isfinite(x).all() and np.isfinite(P).all()):
            return
        s[0] = 1.0
        s[self._layout["x"]] = x
        s[self._layout["P"]] = P.ravel()
        s[self._quat] = imu.quaternion_wxyz
        s[self._w] = imu.R_WB @ imu.w_B
        discrete_state.get_mutable_vector(self._state).SetFromVector(s)

    def _calc_base_state(self, context: Context, output: BasicVector) -> None:
        s = context.get_discrete_state(self._state).get_value()
        x = s[self._layout["x"]]
        output.SetFromVector(np.concatenate([s[self._quat], x[_P], s[self._w], x[_V]]))

    def covariance(self, context: Context) -> np.ndarray:
        """The filter's covariance P (18 x 18) in `context` (this system's)."""
        n = NUM_STATES
        return context.get_discrete_state(self._state).get_value()[self._layout["P"]].reshape(n, n)
