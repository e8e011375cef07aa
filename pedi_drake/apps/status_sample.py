"""The status sample: the station's status outputs of one tick in one vector (50 values).

The simulator bridge samples it every tick and publishes it as `leg_control_data` and
`state_estimator_data` (`status_encoder.StatusEncoder`, `sim_bridge.status_messages`); the
controller-side benchmark records it from a simulated run and replays it.
"""

from pedi_drake.station_interface import STATION_PORTS

# The station outputs in a sample, in order (Unitree motor order within each).
STATUS_SIGNALS = (
    "go1.position_measured",  # q [rad]
    "go1.velocity_measured",  # qd [rad/s]
    "go1.torque_estimated",  # tau_est [N m]
    "go1.imu",  # quaternion w, x, y, z; gyro [rad/s]; accelerometer [m/s^2]
    "go1.foot_contact",  # the foot sensors' raw values
)


def _signal_slices() -> dict[str, slice]:
    slices, start = {}, 0
    for name in STATUS_SIGNALS:
        size = STATION_PORTS[name][1]
        slices[name] = slice(start, start + size)
        start += size
    return slices


# Where each signal is in a sample.
SAMPLE = _signal_slices()
SAMPLE_SIZE = SAMPLE[STATUS_SIGNALS[-1]].stop

# The parts of go1.imu, within a sample.
_IMU = SAMPLE["go1.imu"].start
IMU_QUATERNION = slice(_IMU, _IMU + 4)
IMU_GYRO = slice(_IMU + 4, _IMU + 7)
IMU_ACCELEROMETER = slice(_IMU + 7, _IMU + 10)
