"""The operator's LCM messages as vectors, and which values a reader accepts.

Each message type becomes the same 9 numbers, [mode_request, frame, kind, value (3), estop,
controller_request, friction_request] (the `operator_command` layout's entries of those names,
pedi_drake.operator.command), so the input system treats both sources alike:

  foot_command_lcmt (the project's own type): copied; codes outside their sets, and a friction
    request other than 0 outside FRICTION_RANGE, are out of range.
  rc_command_lcmt (the Go1 remote, walk-these-ways layout): sticks -> a foot velocity, or a base
    twist with `sticks: walk`, buttons -> a mode request and the E-stop (RemoteMapping), no
    controller or friction request; a tenth number, the largest stick deflection, lets `remote_in_range`
    reject sticks outside [-1, 1].
"""

from collections.abc import Callable

import numpy as np

from pedi_drake.friction import FRICTION_RANGE
from pedi_drake.operator.command import (
    CONTROLLER_NONE,
    CONTROLLER_REQUESTS,
    FRAME_TRUNK,
    FRAME_WORLD,
    KIND_TWIST,
    KIND_VELOCITY,
    KINDS,
    MODE_AUTONOMOUS,
    MODE_NONE,
    MODE_TELEOP,
    MODES,
)
from pedi_drake.operator.config import RemoteMapping

MESSAGE_VECTOR_SIZE = 9
# Sticks are floats in [-1, 1] on the wire; this much beyond counts as rounding.
_STICK_TOLERANCE = 1e-3


def foot_command_vector(message) -> np.ndarray:
    """[mode_request, frame, kind, value (3), estop, controller_request, friction_request] of a
    foot_command_lcmt."""
    estop = 1.0 if message.estop else 0.0
    return np.array(
        [
            message.mode_request,
            message.frame,
            message.kind,
            *message.value,
            estop,
            message.controller_request,
            message.friction_request,
        ],
        float,
    )


def foot_command_stamp(message) -> tuple[float, int]:
    """(sender's time [s], sequence number) of a foot_command_lcmt: the order the receiver keeps."""
    return message.timestamp_us * 1e-6, message.sequence


def foot_command_in_range(values: np.ndarray) -> bool:
    """Whether the codes of a foot command vector are known ones (its values are checked finite before)."""
    return bool(
        values[0] in MODES
        and values[1] in (FRAME_TRUNK, FRAME_WORLD)
        and values[2] in KINDS
        and values[7] in CONTROLLER_REQUESTS
        and (values[8] == 0.0 or FRICTION_RANGE[0] <= values[8] <= FRICTION_RANGE[1])
    )


def _deadband(stick: float, deadband: float) -> float:
    """The stick value with the dead band removed and the rest rescaled to [-1, 1] [-] (NaN stays NaN)."""
    magnitude = abs(stick)
    if magnitude != magnitude:
        return float("nan")
    if magnitude <= deadband:
        return 0.0
    return float(np.sign(stick) * (min(magnitude, 1.0) - deadband) / (1.0 - deadband))


def remote_command_vector(mapping: RemoteMapping) -> Callable[[object], np.ndarray]:
    """The function rc_command_lcmt -> [mode_request, frame, kind, value (3), estop,
    controller_request, friction_request] for `mapping`.

    The tenth entry is the largest stick deflection (see `remote_in_range`); a stick that is not
    finite makes the velocity non-finite (rejected by the inbox).
    """
    frame = FRAME_TRUNK if mapping.frame == "trunk" else FRAME_WORLD

    def to_vector(message) -> np.ndarray:
        sticks = np.abs(np.array([*message.left_stick, *message.right_stick], float))
        forward = _deadband(message.left_stick[1], mapping.deadband)
        right = _deadband(message.left_stick[0], mapping.deadband)
        if mapping.sticks == "walk":
            # Walk-these-ways: the left stick drives the trunk forward and sideways, the right
            # stick's x turns it (right is a negative yaw rate).
            turn_right = _deadband(message.right_stick[0], mapping.deadband)
            value, kind = np.asarray(mapping.walk_speeds, float) * [forward, -right, -turn_right], KIND_TWIST
        else:
            up = _deadband(message.right_stick[1], mapping.deadband)
            value, kind = mapping.max_speed * np.array([forward, -right, up]), KIND_VELOCITY
            speed = float(np.linalg.norm(value))
            if speed > mapping.max_speed:  # both sticks at full: still the mapping's top speed
                value *= mapping.max_speed / speed
        if getattr(message, mapping.teleop_button) != 0:
            mode = MODE_TELEOP
        elif getattr(message, mapping.autonomous_button) != 0:
            mode = MODE_AUTONOMOUS
        else:
            mode = MODE_NONE
        estop = any(getattr(message, button) != 0 for button in mapping.estop_buttons)
        return np.array([mode, frame, kind, *value, 1.0 if estop else 0.0, CONTROLLER_NONE, 0.0, sticks.max()], float)

    return to_vector


def remote_in_range(values: np.ndarray) -> bool:
    """Whether every stick of a remote vector (its tenth entry) is within [-1, 1]."""
    return bool(values[MESSAGE_VECTOR_SIZE] <= 1.0 + _STICK_TOLERANCE)
