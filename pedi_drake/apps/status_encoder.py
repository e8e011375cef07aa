"""The simulator bridge's two status messages, encoded straight into reused byte buffers.

The bridge publishes leg_control_data and state_estimator_data at 500 Hz. Filling the generated
message objects (lists from numpy slices) and their `encode` (a struct.pack per field) is Python
work at every tick, in a process that can need most of a core already.
Every field the bridge fills is at a fixed place in the encoded message (the fingerprint's 8
bytes, then the fields in declaration order, big-endian), so `StatusEncoder` writes the values
there through numpy views and hands out copies of the buffers: the same bytes as
`sim_bridge.status_messages(...)` encoded (tests/test_status_encoder.py).
"""

import math

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RollPitchYaw

from pedi_drake.apps.status_sample import IMU_ACCELEROMETER, IMU_GYRO, IMU_QUATERNION, SAMPLE
from pedi_drake.go1_driver.lcmtypes import leg_control_data_lcmt, state_estimator_lcmt

_FINGERPRINT_BYTES = 8
_SIZES = {"float": 4, "int64_t": 8}


def field_offsets(lcm_type) -> dict[str, tuple[int, int, str]]:
    """Byte offset in the encoded message, element count and type name of each field of
    `lcm_type`, for types whose fields are all fixed-size floats and int64s."""
    offsets, at = {}, _FINGERPRINT_BYTES
    for name, typename, dims in zip(lcm_type.__slots__, lcm_type.__typenames__, lcm_type.__dimensions__, strict=True):
        if typename not in _SIZES or not all(isinstance(d, int) for d in dims or []):
            raise ValueError(f"field_offsets: {lcm_type.__name__}.{name} ({typename}) is not at a fixed place")
        count = math.prod(dims) if dims else 1
        offsets[name] = (at, count, typename)
        at += count * _SIZES[typename]
    return offsets


class _Buffer:
    """One message's encoded bytes (all fields zero at first) with a view per field."""

    def __init__(self, lcm_type):
        self.data = bytearray(lcm_type().encode())
        dtypes = {"float": ">f4", "int64_t": ">i8"}
        self.fields = {
            name: np.frombuffer(self.data, dtype=dtypes[typename], count=count, offset=offset)
            for name, (offset, count, typename) in field_offsets(lcm_type).items()
        }


class StatusEncoder:
    """Encodes the bridge's status sample (`status_sample`: q, qd, tau_est, IMU quaternion w x y z,
    gyro, accelerometer, foot sensors) and its tick into the two status messages' bytes, filled as
    the real bridge fills them (`sim_bridge.status_messages`)."""

    def __init__(self):
        self._leg = _Buffer(leg_control_data_lcmt)
        self._estimator = _Buffer(state_estimator_lcmt)

    def encode(self, sample: np.ndarray, tick: int) -> tuple[bytes, bytes]:
        """(leg_control_data bytes, state_estimator_data bytes) of `sample` (50,) at `tick`."""
        leg = self._leg.fields
        leg["q"][:] = sample[SAMPLE["go1.position_measured"]]
        leg["qd"][:] = sample[SAMPLE["go1.velocity_measured"]]
        leg["tau_est"][:] = sample[SAMPLE["go1.torque_estimated"]]
        leg["id"][0] = tick
        estimator = self._estimator.fields
        quaternion = sample[IMU_QUATERNION] / np.linalg.norm(sample[IMU_QUATERNION])
        estimator["quat"][:] = quaternion
        estimator["rpy"][:] = RollPitchYaw(Quaternion(quaternion)).vector()
        estimator["omegaBody"][:] = sample[IMU_GYRO]
        estimator["aBody"][:] = sample[IMU_ACCELEROMETER]
        estimator["contact_estimate"][:] = sample[SAMPLE["go1.foot_contact"]]
        estimator["id"][0] = tick
        return bytes(self._leg.data), bytes(self._estimator.data)
