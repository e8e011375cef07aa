"""Floating-base state estimation from the IMU and leg kinematics: a linear Kalman filter.

The filter of Bloesch et al. (2013) in its linear form (as in MIT Cheetah 3): the IMU gives the
orientation R_WB (its quaternion) and the angular velocity (gyro); the filter estimates

    x = [p_WB (3), v_WB (3), p_WF for the four feet (12), c, s]   (world frame, 20 states)

Feet that sink into the ground (rubber feet, carpet, soft soil): a stance foot under a vertical
load F has its centre at foot radius - s - c F, with c [m/N] the feet's compliance and s [m] a
sink they reach under any load (a soft layer that bottoms out, as MuJoCo's soft foot contact and
a carpet's pile do);

* predict: p += v dt + a dt^2 / 2, v += a dt with a = R_WB (f_I - w x (w x p_BI)) + g, the
  accelerometer's specific force moved from the IMU to the trunk origin; feet stand still, with
  a small random walk in contact and a large one in the air;
* update, every foot: p_WF - p_WB = R_WB p_BF(q) (leg kinematics);
  every foot in contact: v_WB = -R_WB (J(q) qd + w_B x p_BF) + (its rolling velocity) (the
  contact point does not move), and p_WF,z + s + c F = h + foot radius, F the foot's vertical
  load from the joint torques (F = -J^-T tau, quasi-static), h the height of the ground under the
  foot's estimate (0 on flat ground; on terrain, the map of it the estimator is given,
  pedi_drake.terrain: the scene's slopes and platforms); every loaded prong
  tip likewise (it does not move and touches the ground); with no foot and no prong loaded the
  trunk rests on the ground (lying): v_WB = 0; and while the trunk rests on the ground with the
  feet loaded (the feet carry a share of the weight within `RESTING_LOAD_SHARES`, the trunk lower
  than `RESTING_HEIGHT_SLACK` above its resting height, for `RESTING_TICKS`; a robot without
  prongs, whose prong tips the mission schedules instead), p_WB,z = the height at which its
  lowest box corner touches flat ground.

The height rows make c observable wherever the feet carry different loads (the trunk's centre of
mass is never exactly amid them, a lifted leg moves its load onto the others): the IMU fixes the
trunk's tilt, the kinematics each foot's height under it, so a foot carrying 10 N more that sits
lower than the others by 10 c says what c is. s is the same under every load, so the feet alone
cannot tell it from a higher floor: it is calibrated against something rigid on the ground, the
trunk resting on it (the stand-up begins by settling the trunk on the ground,
pedi_drake.mission.phases.StandUpRunner) or loaded prong tips. Without both the filter takes
every stance foot to sit at its radius, and a robot whose feet sink puts its whole world too high
by the sink.

A foot is in contact when the mission's contact schedule (if connected) loads it and its sensor
reads above a threshold; a prong tip when the schedule loads that prong. Each prong counts on
its own: a trunk turning about one tip lifts the others, and pinning those to the ground too
would pull the height estimate between contradicting measurements.
Only go1.* signals are read, in simulation and on hardware alike.

The measurements are uncorrelated (a diagonal noise covariance), so the correction takes them one
row at a time: the same estimate as the batch formula K = P H^T (H P H^T + R)^-1, without the
(m x m) factorisation, and every row of H has one or two non-zeros (a state, or a foot relative to
the trunk), so P H^T is a column or a difference of two. A control tick is one compiled call
(`FloatingBaseKalmanFilter.step`) that reads the inputs and writes the Context's state in place.
"""

import dataclasses
import math

import numpy as np
from pydrake.math import RotationMatrix
from pydrake.systems.framework import Context, DiscreteValues

from pedi_drake import robot
from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.estimation.config import KalmanEstimatorConfig
from pedi_drake.estimation.leg_odometry import foot_kinematics_kernel, leg_offsets
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.prongs import ProngDesign
from pedi_drake.runtime.jit import kernel
from pedi_drake.terrain import terrain_height, terrain_map
from pedi_drake.vector3 import rotation_matrix_kernel

GRAVITY_W = np.array([0.0, 0.0, -9.81])  # [m/s^2]
NUM_STATES = 20
FEET = 6  # index of the first foot position p_WF (3 per foot) in x
COMPLIANCE = 18  # index of the feet's compliance c [m/N] in x
SINK = 19  # index of the feet's sink s [m] in x
# s is kept within +-this [m]: no foot sinks further than its radius.
MAX_SINK = 0.03
# The trunk rests on the ground, its feet loaded, when the feet carry between these shares of the
# robot's weight (below the lower one the legs are limp or in the air, and the feet's sink, which
# the resting trunk measures, is not there to measure; above the upper one the trunk may be on its
# feet alone: the joint-torque loads of a robot lying on its folded legs read 85 % of its weight) ...
RESTING_LOAD_SHARES = (0.02, 0.7)
# ... it is at most this far above the height at which its lowest point touches the ground [m] ...
RESTING_HEIGHT_SLACK = 0.03
# ... and both have held for this many ticks in a row (a load passes through the band as the legs
# take the weight, without the trunk resting).
RESTING_TICKS = 50
# With no foot or prong in contact the trunk is taken to rest on the ground (not sliding) only
# while its estimate is at most this far above its resting height [m]: a Go1 on its folded legs
# holds its trunk up to about 0.07 m above it, a walking one 0.2 m and more.
UNLOADED_REST_SLACK = 0.1
# c and s are learnt, and a resting trunk recognised, only while the robot is still: every joint
# and the trunk turning slower than this [rad/s], by the encoders and the gyro (measurements, not
# the estimate: a trunk pinned to its resting height by the estimate would otherwise confirm
# itself). In a motion the joint torques carry the legs' own dynamics, not only the feet's loads,
# and a rising or sinking trunk's kinematics would be taken for feet sinking; then c and s are
# held, and the feet's heights use them as they are.
STILL_RATE = 0.1
# c is kept within +-this [m/N]: no foot sinks 2 mm per newton (60 mm under a standing Go1's
# quarter weight, which no foot of a walking robot does).
MAX_COMPLIANCE = 2e-3
# Layout of the filter's discrete state: [initialised flag, x (20), P (20 x 20) row by row, ticks the
# trunk has rested].
FILTER_STATE_SIZE = 1 + NUM_STATES + NUM_STATES * NUM_STATES + 1
# A joint angle further than this outside its limits is no real sample (all zeros before the
# first leg_control_data: the calf cannot be at 0) [rad].
_PLAUSIBLE_SLACK = 0.2
# The initial covariance's standard deviations: trunk position [m], velocity [m/s], feet [m].
_INITIAL_STD = (0.01, 0.1, 0.01)


def imu_offset_B() -> np.ndarray:
    """The IMU's position in the trunk frame, read from the model [m]."""
    plant, plant_map = robot.make_go1_plant()
    context = plant.CreateDefaultContext()
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME, plant_map.model)
    imu = plant.GetBodyByName(robot.IMU_BODY_NAME, plant_map.model)
    return plant.CalcRelativeTransform(context, trunk.body_frame(), imu.body_frame()).translation().copy()


@kernel
def _imu_kernel(imu):
    """(usable, unit quaternion (w >= 0), R_WB (3, 3)) of a go1.imu vector (10,).

    Not usable: a non-finite value, or a quaternion of norm < 0.5 (all zeros before the first
    message).
    """
    quaternion = np.zeros(4)
    R = np.eye(3)
    for i in range(10):
        if not math.isfinite(imu[i]):
            return False, quaternion, R
    norm = math.sqrt(imu[0] * imu[0] + imu[1] * imu[1] + imu[2] * imu[2] + imu[3] * imu[3])
    if norm < 0.5:
        return False, quaternion, R
    signed = norm if imu[0] >= 0.0 else -norm
    for i in range(4):
        quaternion[i] = imu[i] / signed
    return True, quaternion, rotation_matrix_kernel(quaternion)


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
        if imu.shape != (10,):
            return None
        usable, quaternion, R = _imu_kernel(imu)
        if not usable:
            return None
        return ImuSample(R, imu[4:7].copy(), imu[7:10].copy(), quaternion)


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


@kernel
def _contact_kernel(foot_sensor, schedule, threshold):
    """Feet in contact (4,): sensed above `threshold`, and loaded by `schedule` unless it is empty."""
    in_contact = np.empty(4, dtype=np.bool_)
    for i in range(4):
        scheduled = schedule.shape[0] == 0 or schedule[i] > 0.5
        in_contact[i] = scheduled and foot_sensor[i] > threshold
    return in_contact


@kernel
def _vertical_forces_kernel(R_WB, J, tau):
    """(4,) the vertical force of the ground on each foot [N], >= 0: F = -J^-T tau (the motor
    torques of a still leg balance its contact force), turned into the world by R_WB; 0 for a leg
    whose Jacobian is singular. Only F's world z is needed: z^T R J^-T = (J^-1 R^T z)^T, so one
    3x3 solve (Cramer's rule) per leg."""
    forces = np.zeros(4)
    for i in range(4):
        A = J[i]
        # u solves A u = R^T z (the world's vertical in the trunk frame); F_z = -u . tau.
        b0, b1, b2 = R_WB[2, 0], R_WB[2, 1], R_WB[2, 2]
        det = (
            A[0, 0] * (A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1])
            - A[0, 1] * (A[1, 0] * A[2, 2] - A[1, 2] * A[2, 0])
            + A[0, 2] * (A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0])
        )
        if abs(det) < 1e-9:
            continue
        u0 = (
            b0 * (A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1])
            - A[0, 1] * (b1 * A[2, 2] - A[1, 2] * b2)
            + A[0, 2] * (b1 * A[2, 1] - A[1, 1] * b2)
        ) / det
        u1 = (
            A[0, 0] * (b1 * A[2, 2] - A[1, 2] * b2)
            - b0 * (A[1, 0] * A[2, 2] - A[1, 2] * A[2, 0])
            + A[0, 2] * (A[1, 0] * b2 - b1 * A[2, 0])
        ) / det
        u2 = (
            A[0, 0] * (A[1, 1] * b2 - b1 * A[2, 1])
            - A[0, 1] * (A[1, 0] * b2 - b1 * A[2, 0])
            + b0 * (A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0])
        ) / det
        value = -(u0 * tau[3 * i] + u1 * tau[3 * i + 1] + u2 * tau[3 * i + 2])
        forces[i] = max(value, 0.0)
    return forces


@kernel
def _process_noise_kernel(in_contact, dt, noise_std):
    """Diagonal of Q over dt [s] for the feet in contact; `noise_std` = the config's position,
    accelerometer, stance-foot, swing-foot and foot-compliance process noises."""
    q = np.empty(NUM_STATES)
    for k in range(3):
        q[k] = noise_std[0] ** 2 * dt
        q[3 + k] = noise_std[1] ** 2 * dt
    for i in range(4):
        sigma = noise_std[2] if in_contact[i] else noise_std[3]
        for k in range(3):
            q[6 + 3 * i + k] = sigma * sigma * dt
    q[COMPLIANCE] = noise_std[4] ** 2 * dt
    q[SINK] = noise_std[5] ** 2 * dt
    return q


@kernel
def _predict_kernel(x, P, R_WB, w_B, f_B, p_BI, dt, rolling, in_contact, noise_std):
    """`FloatingBaseKalmanFilter.predict` on plain arrays: the new (x, P)."""
    process_noise = _process_noise_kernel(in_contact, dt, noise_std)
    # Specific force at the trunk origin: f - w x (w x p_BI).
    wp = np.array(
        [w_B[1] * p_BI[2] - w_B[2] * p_BI[1], w_B[2] * p_BI[0] - w_B[0] * p_BI[2], w_B[0] * p_BI[1] - w_B[1] * p_BI[0]]
    )
    wwp = np.array([w_B[1] * wp[2] - w_B[2] * wp[1], w_B[2] * wp[0] - w_B[0] * wp[2], w_B[0] * wp[1] - w_B[1] * wp[0]])
    x = x.copy()
    for r in range(3):
        a_W = GRAVITY_W[r]
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
def _measurement_rows(
    in_contact, num_tips, use_height, noise_std, vertical_forces, resting_trunk, learn_sink, may_rest
):
    """The measurement model of `update` for the feet `in_contact` and `num_tips` loaded prong tips:
    (columns (m, 3), coefficients (m, 3), variances (m,)), row i of H being coefficients[i, j] at
    columns[i, j] summed over j (a coefficient 0 where a row has fewer non-zeros).

    `noise_std`: the config's foot position [m], foot velocity [m/s], ground height [m] and resting
    velocity [m/s] noises; `vertical_forces` (4,) the feet's loads [N]. Rows: every foot's position
    relative to the trunk, the stance feet's trunk velocities, their heights with their sink
    (`use_height`: p_WF,z + s + c F; with `learn_sink` false, p_WF,z alone, s and c held, and s
    held too unless the trunk rests or a prong tip is loaded), each
    loaded tip's trunk velocity and height, with nothing loaded and the trunk low enough to rest
    (`may_rest`) the resting trunk's horizontal velocity, and the resting trunk's height
    (`resting_trunk`).
    """
    foot_position, foot_velocity = noise_std[0], noise_std[1]
    ground_height, resting_velocity = noise_std[2], noise_std[3]
    stance = 0
    for i in range(4):
        if in_contact[i]:
            stance += 1
    # No foot or prong loaded, the trunk low: it rests on the ground (on its belly or knees) while
    # the legs move freely; it does not slide, so a zero horizontal velocity keeps the IMU from
    # drifting while the legs unfold (the knees may push it up: z is left to the IMU). A trunk
    # higher up with nothing loaded is between steps (a trot's diagonal pairs change over in a
    # few ticks in which neither pair is both scheduled and sensed) or falling: it moves.
    resting = stance == 0 and num_tips == 0 and may_rest
    m = 12 + 3 * stance + (stance if use_height else 0) + (2 if resting else 0) + 4 * num_tips
    m += 1 if resting_trunk else 0
    columns = np.zeros((m, 3), dtype=np.int64)
    coefficients = np.zeros((m, 3))
    noise = np.empty(m)
    # Every foot's position p_WF - p_WB; a foot in the air is carried by the kinematics: a loose
    # measurement of it costs nothing.
    for i in range(4):
        for k in range(3):
            row = 3 * i + k
            columns[row, 0], coefficients[row, 0] = k, -1.0
            columns[row, 1], coefficients[row, 1] = 6 + 3 * i + k, 1.0
            noise[row] = foot_position**2 * (1.0 if in_contact[i] else 4.0)
    row = 12
    for i in range(4):  # no-slip velocity rows
        if in_contact[i]:
            for k in range(3):
                columns[row + k, 0], coefficients[row + k, 0] = 3 + k, 1.0
                noise[row + k] = foot_velocity**2
            row += 3
    if use_height:
        for i in range(4):  # flat ground under the feet in contact
            if in_contact[i]:
                columns[row, 0], coefficients[row, 0] = 6 + 3 * i + 2, 1.0
                if learn_sink:
                    columns[row, 1], coefficients[row, 1] = COMPLIANCE, vertical_forces[i]
                    # s only against something rigid on the ground: the feet alone cannot tell it
                    # from a higher floor, and would move it by whatever else they get wrong.
                    if resting_trunk or num_tips > 0:
                        columns[row, 2], coefficients[row, 2] = SINK, 1.0
                noise[row] = ground_height**2
                row += 1
    for _ in range(num_tips):  # tip velocity (3) and height (1)
        for k in range(3):
            columns[row + k, 0], coefficients[row + k, 0] = 3 + k, 1.0
            noise[row + k] = foot_velocity**2
        columns[row + 3, 0], coefficients[row + 3, 0] = 2, 1.0
        noise[row + 3] = ground_height**2
        row += 4
    if resting:
        for k in range(2):
            columns[row + k, 0], coefficients[row + k, 0] = 3 + k, 1.0
            noise[row + k] = resting_velocity**2
        row += 2
    if resting_trunk:
        columns[row, 0], coefficients[row, 0] = 2, 1.0
        noise[row] = ground_height**2
    return columns, coefficients, noise


@kernel
def _measurements_kernel(
    R, w_B, p_BF, J, qd, in_contact, rolling, use_rolling, use_height, foot_radius, tips_B, resting_height, sinks, m
):
    """The measurement vector y (m,) of `FloatingBaseKalmanFilter.update`, in the row order of
    `_measurement_rows`: every foot's R p_BF, the stance feet's trunk velocities (and heights),
    the loaded prong tips' trunk velocity and height (radius - (R p_BT)_z: `tips_B` (k, 4) holds
    each loaded tip's position [m] and radius [m]), or the resting trunk's zero velocity."""
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
    if use_height:  # flat ground under the feet in contact, each foot sunk by `sinks` (held s + c F)
        k = 0
        for i in range(4):
            if in_contact[i]:
                y[row + k] = foot_radius - sinks[i]
                k += 1
        row += stance
    for t in range(tips_B.shape[0]):
        # A loaded prong tip does not move and touches the ground: v_WB = -R (w x p_BT) and
        # p_WB,z = tip radius - (R p_BT)_z.
        p = tips_B[t]
        v_B = np.array([w_B[1] * p[2] - w_B[2] * p[1], w_B[2] * p[0] - w_B[0] * p[2], w_B[0] * p[1] - w_B[1] * p[0]])
        for r in range(3):
            y[row + r] = -(R[r, 0] * v_B[0] + R[r, 1] * v_B[1] + R[r, 2] * v_B[2])
        y[row + 3] = p[3] - (R[2, 0] * p[0] + R[2, 1] * p[1] + R[2, 2] * p[2])
        row += 4
    # With nothing loaded the trunk rests on the ground: the zero-velocity rows stay 0. A resting
    # trunk's height row (`resting_height` > 0) is the last.
    if resting_height > 0.0:
        y[m - 1] = resting_height
    return y


@kernel
def _correct_kernel(x, P, columns, coefficients, noise, y):
    """The Kalman correction of (x, P) by measurements y = H x + noise (variances `noise`, H as
    `_measurement_rows` gives it): (x, P, True), or (x, P, False) as given when an innovation
    variance is not positive (P no longer positive definite).

    Uncorrelated measurements are taken one row at a time, each by the scalar update
    K = P h^T / (h P h^T + r): the batch update's estimate, without factorising H P H^T + R.
    P is symmetrised first, and each update (P h^T)(P h^T)^T / (h P h^T + r) keeps it exactly so.
    """
    n = x.shape[0]
    x_new = x.copy()
    P_new = 0.5 * (P + P.T)
    ph = np.empty(n)
    for i in range(y.shape[0]):
        for r in range(n):
            ph[r] = 0.0
        variance, innovation = noise[i], y[i]
        for j in range(columns.shape[1]):
            coefficient = coefficients[i, j]
            if coefficient != 0.0:
                column = columns[i, j]
                for r in range(n):
                    ph[r] += coefficient * P_new[r, column]
                innovation -= coefficient * x_new[column]
        for j in range(columns.shape[1]):
            if coefficients[i, j] != 0.0:
                variance += coefficients[i, j] * ph[columns[i, j]]
        if not variance > 0.0:
            return x, P, False
        inverse = 1.0 / variance
        step = innovation * inverse
        for r in range(n):
            x_new[r] += ph[r] * step
            for c in range(n):
                P_new[r, c] -= (ph[r] * ph[c]) * inverse
    return x_new, P_new, True


@kernel
def _initial_state_kernel(R_WB, q, xy, offsets, foot_radius, sink_prior):
    """`FloatingBaseKalmanFilter.initial_state` on plain arrays: (x, P)."""
    p_BF, _ = foot_kinematics_kernel(q, offsets)
    feet_W = np.empty((4, 3))
    lowest = np.inf
    for i in range(4):
        for r in range(3):
            feet_W[i, r] = R_WB[r, 0] * p_BF[i, 0] + R_WB[r, 1] * p_BF[i, 1] + R_WB[r, 2] * p_BF[i, 2]
        lowest = min(lowest, feet_W[i, 2])
    x = np.zeros(NUM_STATES)
    x[0], x[1], x[2] = xy[0], xy[1], foot_radius - lowest
    for i in range(4):
        for r in range(3):
            x[6 + 3 * i + r] = feet_W[i, r] + x[r]
    P = np.zeros((NUM_STATES, NUM_STATES))
    for k in range(3):
        P[k, k] = _INITIAL_STD[0] ** 2
        P[3 + k, 3 + k] = _INITIAL_STD[1] ** 2
    for k in range(6, COMPLIANCE):
        P[k, k] = _INITIAL_STD[2] ** 2
    # sink_prior: c's and s's prior means and standard deviations, [c, std c, s, std s].
    x[COMPLIANCE], x[SINK] = sink_prior[0], sink_prior[2]
    P[COMPLIANCE, COMPLIANCE] = sink_prior[1] * sink_prior[1]
    P[SINK, SINK] = sink_prior[3] * sink_prior[3]
    return x, P


@kernel
def _resting_height(R_WB, rest_points):
    """The trunk height [m] at which the lowest of `rest_points` (k, 4: position in the trunk frame
    [m], radius [m]) touches flat ground at the attitude R_WB."""
    height = 0.0
    for k in range(rest_points.shape[0]):
        p = rest_points[k]
        height = max(height, p[3] - (R_WB[2, 0] * p[0] + R_WB[2, 1] * p[1] + R_WB[2, 2] * p[2]))
    return height


@kernel
def _update_kernel(
    x,
    P,
    R_WB,
    w_B,
    q,
    qd,
    tau,
    in_contact,
    rolling,
    use_rolling,
    tips_B,
    offsets,
    use_height,
    foot_radius,
    noise_std,
    resting_height,
    learn_sink,
    ground,
    may_rest,
):
    """`FloatingBaseKalmanFilter.update` on plain arrays: (x, P, whether the correction succeeded).

    `tau` (12,) the joint torques [N m] (the feet's loads); `tips_B` (k, 4): the loaded prong tips'
    positions in the trunk frame [m] and radii [m]; `resting_height` [m]: the height of a trunk
    resting on the ground (`_resting_height`), 0 when it does not rest; `learn_sink`: whether the
    feet's heights correct c and s (else they are held); `ground` (4,) [m]: the height of the
    ground under each foot (0 on flat ground; the terrain's, pedi_drake.terrain); `may_rest`:
    whether the trunk is low enough to rest on the ground (with nothing loaded it then does not
    slide). The compliance and the sink are kept within +-MAX_COMPLIANCE and +-MAX_SINK.
    """
    p_BF, J = foot_kinematics_kernel(q, offsets)
    forces = _vertical_forces_kernel(R_WB, J, tau)
    resting_trunk = use_height and resting_height > 0.0
    columns, coefficients, noise = _measurement_rows(
        in_contact, tips_B.shape[0], use_height, noise_std, forces, resting_trunk, learn_sink, may_rest
    )
    # The held parts of each foot's sink (s, c F) go into the measurement itself, and a held state
    # is decorrelated from the others first, so that no row moves it through its covariance (a
    # block-diagonal P stays positive definite).
    holds_sink = not (learn_sink and (resting_trunk or tips_B.shape[0] > 0))
    sinks = np.zeros(4)
    for i in range(4):
        # A foot on terrain sits that much higher: a negative sink, for the height row.
        sinks[i] = (x[SINK] if holds_sink else 0.0) + (0.0 if learn_sink else x[COMPLIANCE] * forces[i]) - ground[i]
    P = P.copy()
    for held, index in ((holds_sink, SINK), (not learn_sink, COMPLIANCE)):
        if held:
            for k in range(P.shape[0]):
                if k != index:
                    P[index, k] = 0.0
                    P[k, index] = 0.0
    y = _measurements_kernel(
        R_WB,
        w_B,
        p_BF,
        J,
        qd,
        in_contact,
        rolling,
        use_rolling,
        use_height,
        foot_radius,
        tips_B,
        resting_height if resting_trunk else 0.0,
        sinks,
        noise.shape[0],
    )
    x, P, corrected = _correct_kernel(x, P, columns, coefficients, noise, y)
    # Bounds against a runaway only, not at zero: with every foot under about the same load, s and
    # c F are told apart by the priors alone, and cutting one off at zero each tick would let the
    # other drift along the pair's sum.
    x[COMPLIANCE] = min(max(x[COMPLIANCE], -MAX_COMPLIANCE), MAX_COMPLIANCE)
    x[SINK] = min(max(x[SINK], -MAX_SINK), MAX_SINK)
    return x, P, corrected


@kernel
def _loaded_tips(tips_B, schedule):
    """(k, 4) the prong tips (position [m], radius [m]) the schedule loads (its entries after the
    four feet); none without a schedule (empty)."""
    loaded = 0
    if schedule.shape[0] > 0:
        for t in range(tips_B.shape[0]):
            if schedule[4 + t] > 0.5:
                loaded += 1
    tips = np.empty((loaded, 4))
    row = 0
    if schedule.shape[0] > 0:
        for t in range(tips_B.shape[0]):
            if schedule[4 + t] > 0.5:
                tips[row] = tips_B[t]
                row += 1
    return tips


@kernel
def _step_kernel(
    filter_state,
    base_state,
    imu,
    q,
    qd,
    tau,
    foot_sensor,
    schedule,
    xy,
    dt,
    threshold,
    p_BI,
    offsets,
    tips_B,
    foot_radius,
    use_height,
    process_noise_std,
    measurement_noise_std,
    plausible_q,
    sink_prior,
    rest_points,
    weight,
    terrain,
):
    """One tick of the estimator on its state, in place: True when the estimate was updated.

    filter_state (1 + 20 + 20 * 20): [initialised flag, x, P row by row]; base_state (13): the
    output (see base_state.py). Both are left as they are (the last estimate held) when a sample
    is not usable: a non-finite input, an unusable IMU quaternion, joint angles outside
    `plausible_q` (2, 12: lower, upper [rad]) before the first estimate (no leg_control_data
    yet), or a correction that failed. `terrain` (k, 9): pedi_drake.terrain's table of the ground's
    terrain, whose height under each foot's estimate the feet's height rows take.
    """
    usable, quaternion, R = _imu_kernel(imu)
    if not usable:
        return False
    for i in range(12):
        if not (math.isfinite(q[i]) and math.isfinite(qd[i]) and math.isfinite(tau[i])):
            return False
    for i in range(4):
        if not math.isfinite(foot_sensor[i]):
            return False
    initialised = filter_state[0] != 0.0
    if not initialised:
        for i in range(12):
            if not (plausible_q[0, i] <= q[i] <= plausible_q[1, i]):
                return False
    w_B = imu[4:7]
    in_contact = _contact_kernel(foot_sensor, schedule, threshold)
    rolling = _rolling_kernel(R, w_B, q, qd, foot_radius)
    n = NUM_STATES
    if initialised:
        x, P = _predict_kernel(
            filter_state[1 : 1 + n],
            filter_state[1 + n : 1 + n + n * n].reshape((n, n)),
            R,
            w_B,
            imu[7:10],
            p_BI,
            dt,
            rolling,
            in_contact,
            process_noise_std,
        )
    else:
        x, P = _initial_state_kernel(R, q, xy, offsets, foot_radius, sink_prior)
    tips = _loaded_tips(tips_B, schedule)
    # A trunk resting on the ground with its feet loaded (the module docstring), for RESTING_TICKS.
    p_BF, J = foot_kinematics_kernel(q, offsets)
    load = _vertical_forces_kernel(R, J, tau).sum()
    rest_height = _resting_height(R, rest_points)
    still = True
    for i in range(12):
        still = still and abs(qd[i]) < STILL_RATE
    for k in range(3):
        still = still and abs(w_B[k]) < STILL_RATE
    # A robot with prongs rests on them: the mission schedules their tips (rows of their own).
    resting = (
        still
        and tips_B.shape[0] == 0
        and RESTING_LOAD_SHARES[0] * weight < load < RESTING_LOAD_SHARES[1] * weight
        and x[2] < rest_height + RESTING_HEIGHT_SLACK
    )
    rested = filter_state[-1] + 1.0 if resting else 0.0
    ground = np.zeros(4)
    for i in range(4):
        ground[i] = terrain_height(terrain, x[FEET + 3 * i], x[FEET + 3 * i + 1])
    may_rest = x[2] - terrain_height(terrain, x[0], x[1]) < rest_height + UNLOADED_REST_SLACK
    x, P, corrected = _update_kernel(
        x,
        P,
        R,
        w_B,
        q,
        qd,
        tau,
        in_contact,
        rolling,
        True,
        tips,
        offsets,
        use_height,
        foot_radius,
        measurement_noise_std,
        rest_height if rested >= RESTING_TICKS else 0.0,
        still,
        ground,
        may_rest,
    )
    if not corrected:
        return False
    for i in range(n):
        if not math.isfinite(x[i]):
            return False
        for j in range(n):
            if not math.isfinite(P[i, j]):
                return False
    filter_state[0] = 1.0
    filter_state[1 : 1 + n] = x
    filter_state[1 + n : 1 + n + n * n] = P.ravel()
    filter_state[-1] = rested
    base_state[0:4] = quaternion
    base_state[4:7] = x[0:3]
    for r in range(3):  # w_W = R_WB w_B
        base_state[7 + r] = R[r, 0] * w_B[0] + R[r, 1] * w_B[1] + R[r, 2] * w_B[2]
    base_state[10:13] = x[3:6]
    return True


class FloatingBaseKalmanFilter:
    """The filter's maths on plain arrays (no Drake state): `initial_state`, `predict`, `update`,
    and `step`, all of a tick at once on the estimator's state vectors."""

    def __init__(
        self,
        config: KalmanEstimatorConfig,
        p_BI: np.ndarray,
        foot_radius: float = robot.FOOT_RADIUS,
        prong_tips_B: np.ndarray | None = None,
        prong_tip_radius: float = 0.0,
        weight: float = robot.TOTAL_MASS * -GRAVITY_W[2],
        terrain: np.ndarray | None = None,
    ):
        """`weight` [N]: the robot's (prongs included), against which the feet's loads tell a
        trunk resting on the ground; `terrain`: pedi_drake.terrain's table of the ground's terrain,
        whose height under each stance foot its height row takes (None: flat ground)."""
        self.config = config
        self.terrain = terrain_map(terrain)
        self.p_BI = np.array(p_BI, dtype=float)
        self.foot_radius = float(foot_radius)
        # Prong tip centres in the trunk frame (k, 3) [m]: a loaded tip pins the trunk like a foot.
        self.prong_tips_B = np.zeros((0, 3)) if prong_tips_B is None else np.array(prong_tips_B, dtype=float)
        self.prong_tip_radius = float(prong_tip_radius)
        # The constants of every tick, as the kernels take them (writable: numba checks a
        # read-only array's type on every call, several microseconds).
        self._tips = np.column_stack([self.prong_tips_B, np.full(len(self.prong_tips_B), self.prong_tip_radius)])
        # Where the trunk can rest on the ground: its collision box's corners and the prong tips.
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=float)
        corners = corners * np.array(robot.TRUNK_HALF_EXTENTS)
        self._rest_points = np.vstack([np.column_stack([corners, np.zeros(8)]), self._tips])
        self._weight = float(weight)
        self._leg_offsets = np.array(leg_offsets())
        c = config
        self._process_noise_std = np.array(
            [
                c.position_process_noise,
                c.accelerometer_noise,
                c.stance_foot_process_noise,
                c.swing_foot_process_noise,
                c.foot_compliance_process_noise,
                c.foot_sink_process_noise,
            ]
        )
        self._sink_prior = np.array(
            [c.foot_compliance_prior, c.foot_compliance_std, c.foot_sink_prior, c.foot_sink_std], dtype=float
        )
        self._measurement_noise_std = np.array(
            [c.foot_position_noise, c.foot_velocity_noise, c.ground_height_noise, c.resting_velocity_noise]
        )
        self._use_height = bool(c.ground_height_measurement)
        self._plausible_q = np.array([robot.Q_LOWER - _PLAUSIBLE_SLACK, robot.Q_UPPER + _PLAUSIBLE_SLACK])
        # `_step_kernel`'s arguments after the tick's inputs, in its order.
        self._step_constants = (
            float(c.period),
            float(c.foot_contact_threshold),
            self.p_BI,
            self._leg_offsets,
            self._tips,
            self.foot_radius,
            self._use_height,
            self._process_noise_std,
            self._measurement_noise_std,
            self._plausible_q,
            self._sink_prior,
            self._rest_points,
            self._weight,
            self.terrain,
        )

    def warm_up(self) -> None:
        """Runs one predict, update and step of every kind, so the compiled kernels are compiled (or
        loaded from numba's cache) now, not in the first control tick."""
        imu = ImuSample(np.eye(3), np.zeros(3), -GRAVITY_W)
        x, P = self.initial_state(imu, robot.STANDING_Q, np.zeros(2))
        rolling = rolling_velocities_W(imu.R_WB, imu.w_B, robot.STANDING_Q, np.zeros(12), self.foot_radius)
        for contact in (np.ones(4, bool), np.zeros(4, bool)):
            x, P = self.predict(x, P, imu, contact, 0.002, rolling)
            self.update(
                x, P, imu, robot.STANDING_Q, np.zeros(12), contact, rolling, np.ones(len(self.prong_tips_B), bool)
            )
        self.contact_flags(np.zeros(4), None, 0.0)
        ImuSample.from_vector(np.array([1.0, 0, 0, 0, 0, 0, 0, 0, 0, 9.81]))
        filter_state, base_state = np.zeros(FILTER_STATE_SIZE), np.zeros(BASE_STATE_SIZE)
        imu_vector, q, rates = np.array([1.0, 0, 0, 0, 0, 0, 0, 0, 0, 9.81]), robot.STANDING_Q, np.zeros(12)
        for schedule in (np.zeros(0), np.ones(4 + len(self.prong_tips_B))):
            for _ in range(2):  # initialise, then predict and correct
                self.step(filter_state, base_state, imu_vector, q, rates, rates, np.ones(4), schedule, np.zeros(2))

    def initial_state(self, imu: ImuSample, q: np.ndarray, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x, P) for a robot at rest with its lowest foot on the ground, trunk at `xy` [m]."""
        return _initial_state_kernel(
            np.asarray(imu.R_WB, dtype=float),
            np.asarray(q, dtype=float),
            np.asarray(xy, dtype=float),
            self._leg_offsets,
            self.foot_radius,
            self._sink_prior,
        )

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
        return _predict_kernel(
            np.asarray(x, dtype=float),
            np.asarray(P, dtype=float),
            np.asarray(imu.R_WB, dtype=float),
            np.asarray(imu.w_B, dtype=float),
            np.asarray(imu.f_B, dtype=float),
            self.p_BI,
            float(dt),
            np.zeros((4, 3)) if rolling is None else np.asarray(rolling, dtype=float),
            np.asarray(contact[:4], dtype=bool),
            self._process_noise_std,
        )

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
        tau: np.ndarray | None = None,
        trunk_resting: bool = False,
        learn_sink: bool = True,
        may_rest: bool = True,
    ):
        """Corrects (x, P) with the leg kinematics of all feet and the no-slip of the feet in contact
        (whose centres move at their `rolling` velocities (4, 3) [m/s], when given), and with each
        prong tip flagged in `tips_loaded` (one bool per prong; None: none loaded): it does not
        move, and touches the ground. `tau` (12,): the joint torques [N m] that give the feet's
        loads, and with them their sink; None: no load known, so the compliance is left as it is.
        `trunk_resting`: the trunk rests on flat ground (its lowest rigid point touches it);
        `learn_sink`: the feet's heights correct c and s (the robot is nearly still), else hold them;
        `may_rest`: the trunk is low enough to rest on the ground (with no foot or prong in contact
        it then does not slide; higher up it is between steps or falling).
        Raises np.linalg.LinAlgError when P is not positive definite."""
        tips = self._tips[np.asarray(tips_loaded, bool)] if tips_loaded is not None else self._tips[:0]
        x, P, corrected = _update_kernel(
            np.asarray(x, dtype=float),
            np.asarray(P, dtype=float),
            np.asarray(imu.R_WB, dtype=float),
            np.asarray(imu.w_B, dtype=float),
            np.asarray(q, dtype=float),
            np.asarray(qd, dtype=float),
            np.zeros(12) if tau is None else np.asarray(tau, dtype=float),
            np.asarray(contact[:4], dtype=bool),
            np.zeros((4, 3)) if rolling is None else np.asarray(rolling, dtype=float),
            rolling is not None,
            np.ascontiguousarray(tips),
            self._leg_offsets,
            self._use_height,
            self.foot_radius,
            self._measurement_noise_std,
            _resting_height(np.asarray(imu.R_WB, dtype=float), self._rest_points) if trunk_resting else 0.0,
            learn_sink,
            np.zeros(4),
            may_rest,
        )
        if not corrected:
            raise np.linalg.LinAlgError("Kalman correction: an innovation variance is not positive")
        return x, P

    def step(
        self,
        filter_state: np.ndarray,
        base_state: np.ndarray,
        imu: np.ndarray,
        q: np.ndarray,
        qd: np.ndarray,
        tau: np.ndarray,
        foot_sensor: np.ndarray,
        schedule: np.ndarray,
        xy: np.ndarray,
    ) -> bool:
        """One estimator tick on its state vectors, in place (see `_step_kernel`): True when updated.

        Inputs as the estimator's ports give them: go1.imu (10), q [rad], qd [rad/s], tau [N m]
        (12), go1.foot_contact (4), and the contact schedule (4 feet, then one per prong; empty:
        none); `xy` [m]: where the trunk starts (see `initial_state`).
        """
        return _step_kernel(filter_state, base_state, imu, q, qd, tau, foot_sensor, schedule, xy, *self._step_constants)

    @staticmethod
    def contact_flags(foot_sensor: np.ndarray, schedule: np.ndarray | None, threshold: float) -> np.ndarray:
        """Feet in contact: scheduled (when a schedule is given) and sensed."""
        return _contact_kernel(
            np.asarray(foot_sensor, dtype=float),
            np.zeros(0) if schedule is None else np.asarray(schedule, dtype=float),
            float(threshold),
        )


class KalmanEstimator(LeafSystemWithoutWitnesses):
    """go1.imu, go1.position_measured, go1.velocity_measured, go1.torque_estimated, go1.foot_contact
    (+ optional contact_set) -> base_state (13: quaternion, p_WB, w_WB, v_WB; see base_state.py).

    Periodic discrete update at `config.period`; base_state is a discrete state of its own (the
    output port reads it without computing), so the loop estimator -> mission manager ->
    contact_set -> estimator has a delay. Filter state: [initialised flag, x (18), P (18 x 18)].
    """

    def __init__(
        self,
        config: KalmanEstimatorConfig,
        initial_xy=(0.0, 0.0),
        prongs: ProngDesign | None = None,
        terrain: np.ndarray | None = None,
    ):
        super().__init__()
        self.config = config
        self._xy = np.array(config.initial_xy if config.initial_xy is not None else initial_xy, dtype=float)
        tips = None if prongs is None else prongs.tip_positions_B()
        radius = 0.0 if prongs is None else prongs.tip_radius
        mass = robot.TOTAL_MASS + (0.0 if prongs is None else prongs.num_prongs * prongs.mass)
        self.filter = FloatingBaseKalmanFilter(
            config,
            imu_offset_B(),
            prong_tips_B=tips,
            prong_tip_radius=radius,
            weight=mass * -GRAVITY_W[2],
            terrain=terrain,
        )
        self.filter.warm_up()
        num_contacts = 4 + (0 if prongs is None else prongs.num_prongs)
        self.imu_port = self.DeclareVectorInputPort("imu", 10)
        self.position_port = self.DeclareVectorInputPort("position_measured", 12)
        self.velocity_port = self.DeclareVectorInputPort("velocity_measured", 12)
        self.torque_port = self.DeclareVectorInputPort("torque_estimated", 12)
        self.foot_contact_port = self.DeclareVectorInputPort("foot_contact", 4)
        # Optional: the mission's contact schedule (feet first, then prongs).
        self.contact_set_port = self.DeclareVectorInputPort("contact_set", num_contacts)
        self._no_schedule = np.zeros(0)
        self._filter_state = self.DeclareDiscreteState(FILTER_STATE_SIZE)
        initial_base = np.zeros(BASE_STATE_SIZE)
        initial_base[0] = 1.0  # identity orientation until the first estimate
        self._base_state = self.DeclareDiscreteState(initial_base)
        self.DeclareInitializationDiscreteUpdateEvent(self._update)
        self.DeclarePeriodicDiscreteUpdateEvent(config.period, 0.0, self._update)
        # The same step on demand (CalcForcedDiscreteVariableUpdate), for tests.
        self.DeclareForcedDiscreteUpdateEvent(self._update)
        self.base_state_port = self.DeclareStateOutputPort("base_state", self._base_state)

    def _update(self, context: Context, discrete_state: DiscreteValues) -> None:
        # `discrete_state` holds the current state on entry: the step writes it only when the
        # sample is usable, so a bad sample (or none yet) never reaches the output.
        schedule = self.contact_set_port.Eval(context) if self.contact_set_port.HasValue(context) else self._no_schedule
        self.filter.step(
            discrete_state.get_mutable_value(self._filter_state),
            discrete_state.get_mutable_value(self._base_state),
            self.imu_port.Eval(context),
            self.position_port.Eval(context),
            self.velocity_port.Eval(context),
            self.torque_port.Eval(context),
            self.foot_contact_port.Eval(context),
            schedule,
            self._xy,
        )

    def foot_compliance(self, context: Context) -> float:
        """The feet's compliance c the filter holds in `context` (this system's) [m/N]."""
        return float(context.get_discrete_state(self._filter_state).get_value()[1 + COMPLIANCE])

    def foot_sink(self, context: Context) -> float:
        """The feet's sink s the filter holds in `context` (this system's) [m]."""
        return float(context.get_discrete_state(self._filter_state).get_value()[1 + SINK])

    def covariance(self, context: Context) -> np.ndarray:
        """The filter's covariance P (18 x 18) in `context` (this system's)."""
        n = NUM_STATES
        return context.get_discrete_state(self._filter_state).get_value()[1 + n : 1 + n + n * n].reshape(n, n)
