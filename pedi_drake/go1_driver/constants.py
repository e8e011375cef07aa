"""Constants of the Go1 LCM interface (walk-these-ways `lcm_position` bridge).

Channels, message types and their reference fingerprints/sizes, the bridge rate, and the
conversion between the station's 60-vector `go1.command` and the wire order of
`pd_tau_targets_lcmt`. The conventions are written down in this package's README.md.
"""

import math
import sys

import numpy as np

from pedi_drake.go1_driver.lcmtypes import (
    leg_control_data_lcmt,
    pd_tau_targets_lcmt,
    rc_command_lcmt,
    state_estimator_lcmt,
)
from pedi_drake.runtime.jit import kernel

# Channels (controller <-> robot bridge).
COMMAND_CHANNEL = "pd_plustau_targets"
LEG_CONTROL_CHANNEL = "leg_control_data"
STATE_ESTIMATOR_CHANNEL = "state_estimator_data"
RC_COMMAND_CHANNEL = "rc_command"

# The bridge ticks at 500 Hz: it publishes every state channel and applies the last command.
BRIDGE_PERIOD = 0.002  # [s]

# The driver's output stage runs within the control tick, after the controller. Drake handles the
# publish events of an instant before that instant's updates, and computes every discrete update
# of an instant from the same context: a safety filter and a sender at the tick's own instant
# would put on the wire the controller's command of two ticks before. One microsecond of diagram
# time after the tick, the filter bounds the command computed from the tick's own status in an
# unrestricted update, and the sender, a discrete update of the same instant (Drake computes those
# after the unrestricted ones are applied), publishes it: one simulator step for both, where a
# publish event of its own would take another step a tick.
COMMAND_OFFSET = 1e-6  # [s] after each tick

# Name of the LCM bus in Scenario.lcm_buses that carries the Go1 traffic, and its default URL
# (ttl=0: the traffic stays on this host; a real Go1 needs ttl=255).
GO1_BUS_NAME = "go1"
DEFAULT_GO1_LCM_URL = "udpm://239.255.76.67:7667?ttl=0"

_COMMAND_FINGERPRINT = pd_tau_targets_lcmt._get_packed_fingerprint()

# Message type by channel.
# Status channels in the order of the driver's `driver.message_counts` output ([received, dropped] each).
STATUS_CHANNELS = (LEG_CONTROL_CHANNEL, STATE_ESTIMATOR_CHANNEL, RC_COMMAND_CHANNEL)

CHANNEL_TYPES = {
    COMMAND_CHANNEL: pd_tau_targets_lcmt,
    LEG_CONTROL_CHANNEL: leg_control_data_lcmt,
    STATE_ESTIMATOR_CHANNEL: state_estimator_lcmt,
    RC_COMMAND_CHANNEL: rc_command_lcmt,
}

# Base hashes (before lcm-gen's rotate-left) and encoded sizes [bytes] of the bridge's types.
REFERENCE_BASE_HASH = {
    "pd_tau_targets_lcmt": 0x6D88128EF1291CC1,
    "leg_control_data_lcmt": 0xA9A928B534BFC487,
    "state_estimator_lcmt": 0xEA87C8282EFFE5B6,
    "rc_command_lcmt": 0xC7726B02EC3E7DE2,
}
REFERENCE_ENCODED_SIZE = {
    "pd_tau_targets_lcmt": 544,
    "leg_control_data_lcmt": 272,
    "state_estimator_lcmt": 160,
    "rc_command_lcmt": 46,
}

# Remote (rc_command) E-stop: the walk-these-ways remote maps its buttons to these switch fields;
# any of them non-zero latches damping. L2 + B on the Unitree remote sets right_lower_right_switch.
RC_ESTOP_FIELDS = ("right_lower_right_switch",)


# go1.command blocks (q_des, qd_des, kp, kd, tau_ff) in the wire order (q_des, qd_des, tau_ff, kp, kd).
_WIRE_ORDER = np.concatenate([np.arange(0, 24), np.arange(48, 60), np.arange(24, 48)])
_WIRE_ORDER.flags.writeable = False


def command_to_message(command: np.ndarray, timestamp_us: int = 0, message_id: int = 0) -> pd_tau_targets_lcmt:
    """The wire message for a 60-vector `go1.command` (q_des, qd_des, kp, kd, tau_ff; Unitree order).

    The wire order is q_des, qd_des, tau_ff, kp, kd; this is the one place it is converted.
    """
    wire = np.asarray(command, dtype=float)[_WIRE_ORDER].tolist()
    message = pd_tau_targets_lcmt()
    message.q_des, message.qd_des, message.tau_ff = wire[0:12], wire[12:24], wire[24:36]
    message.kp, message.kd = wire[36:48], wire[48:60]
    message.timestamp_us = int(timestamp_us)
    message.id = int(message_id)
    return message


# The encoded pd_tau_targets_lcmt after its fingerprint: five double[12] in wire order (480 bytes),
# then timestamp_us, id, robot_id (int64) and se_contactState (double[4]); lcm-gen's layout, big-endian.
_COMMAND_VALUES_OFFSET = 8
_COMMAND_INTEGERS_OFFSET = _COMMAND_VALUES_OFFSET + 8 * 60
# numba reads module constants at compile time: the byte order of this machine's doubles.
_LITTLE_ENDIAN = sys.byteorder == "little"


@kernel
def _encode_command_kernel(command, timestamp_us, message_id, buffer):
    """Writes the 60 values of `command` in wire order, then timestamp_us and message_id, big-endian,
    into buffer[8:504] (uint8); False (and the buffer partly written) when a value is not finite."""
    values = np.empty(60)
    for i in range(60):
        value = command[_WIRE_ORDER[i]]
        if not math.isfinite(value):
            return False
        values[i] = value
    raw = values.view(np.uint8)
    for i in range(60):
        for b in range(8):
            buffer[_COMMAND_VALUES_OFFSET + 8 * i + b] = raw[8 * i + (7 - b if _LITTLE_ENDIAN else b)]
    for k, integer in enumerate((timestamp_us, message_id)):
        for b in range(8):
            buffer[_COMMAND_INTEGERS_OFFSET + 8 * k + b] = (integer >> (56 - 8 * b)) & 0xFF
    return True


class CommandEncoder:
    """The bytes of `command_to_message(command, timestamp_us, message_id)`, for the driver's every tick.

    The same bytes (tested) in one compiled call on a reused buffer, without building the message,
    and no bytes at all for a command with a non-finite value: nothing but finite commands can go on
    the wire through this encoder.
    """

    def __init__(self):
        self._buffer = bytearray(REFERENCE_ENCODED_SIZE[pd_tau_targets_lcmt.__name__])
        self._buffer[:_COMMAND_VALUES_OFFSET] = _COMMAND_FINGERPRINT  # robot_id and se_contactState stay 0
        self._bytes = np.frombuffer(self._buffer, dtype=np.uint8)
        # Compiled here (or loaded from numba's cache), not at the first publication.
        self.encode(np.zeros(60))

    def encode(self, command: np.ndarray, timestamp_us: int = 0, message_id: int = 0) -> bytes | None:
        """The encoded message for a 60-vector `go1.command`, or None when a value of it is not finite."""
        if not _encode_command_kernel(command, timestamp_us, message_id, self._bytes):
            return None
        return bytes(self._buffer)


def message_to_command(message: pd_tau_targets_lcmt) -> np.ndarray:
    """The 60-vector `go1.command` (q_des, qd_des, kp, kd, tau_ff) of a wire message."""
    return np.concatenate(
        [
            np.asarray(message.q_des, float),
            np.asarray(message.qd_des, float),
            np.asarray(message.kp, float),
            np.asarray(message.kd, float),
            np.asarray(message.tau_ff, float),
        ]
    )
