"""A haptic device as the teleoperated foot's operator: the adapter interface and a simulated device.

The controller's side of teleoperation is two LCM messages (pedi_drake/go1_driver/lcmtypes):
`foot_command_lcmt` in (the operator's foot command, on `operator.channel`) and
`foot_feedback_lcmt` out (the estimated force on the driven foot and the limit it is held under,
on `operator.feedback_channel`). Any device drives a foot through them; a `DeviceAdapter` does it
for a device that implements `HapticDevice`:

  * `read()`: where the handle is, relative to its centre [m], and whether its button is held;
  * `render(force)`: the force [N] the handle pushes the hand with.

The device's axes are the world's (x forward from where the robot started, y left, z up): the
foot command goes out in the world frame and the feedback's force comes in it, so what the hand
pushes and what it feels agree however the trunk turns. Rate control, as for the remote's
sticks: the handle's offset from the centre (beyond a dead band) asks for a foot velocity,
`velocity_gain` metres per second per metre, at most `max_speed`; the button asks for the
teleoperated mode, its release for the autonomous mission. The feedback's force, `force_scale`
device newtons per foot newton, is rendered against the hand: a foot held against a wall pushes
the handle back to where the hand's push balances it, so the operator feels the wall and the foot
pushes with what the hand does.

`SpringDevice` is a simulated device, the adapter's worked example and its test: a handle of
mass `mass` between the rendered force and a hand that holds it like a spring (`hand_stiffness`,
`hand_damping`) around where the hand wants it (`hand_target`, set by a script or a test).
A real device's driver implements the same two methods.
"""

import dataclasses
from typing import Protocol

import numpy as np
from pydrake.lcm import DrakeLcmInterface

from pedi_drake.go1_driver.lcmtypes import foot_command_lcmt, foot_feedback_lcmt
from pedi_drake.operator.command import FRAME_WORLD, KIND_VELOCITY, MODE_AUTONOMOUS, MODE_TELEOP


@dataclasses.dataclass(frozen=True)
class DeviceReading:
    """What a device reports: the handle's offset from its centre [m], its button."""

    offset: np.ndarray  # (3,) the world's axes
    button: bool


class HapticDevice(Protocol):
    """The two methods a device's driver gives the adapter (see the module docstring)."""

    def read(self) -> DeviceReading: ...

    def render(self, force: np.ndarray) -> None: ...


@dataclasses.dataclass
class AdapterConfig:
    """How handle offsets become foot velocities and foot forces handle forces."""

    velocity_gain: float = 2.5  # [m/s per m of offset]: 2 cm of offset asks for 5 cm/s
    max_speed: float = 0.1  # [m/s], the teleop phase's own bound is the one that counts
    deadband: float = 0.002  # [m] of offset that asks for nothing (a resting hand's tremor)
    force_scale: float = 0.5  # [N on the handle per N on the foot]


def offset_velocity(offset: np.ndarray, config: AdapterConfig) -> np.ndarray:
    """The foot velocity [m/s] a handle `offset` [m] asks for: zero inside the dead band, then
    proportional to the offset beyond it, at most `max_speed`."""
    offset = np.asarray(offset, float)
    size = float(np.linalg.norm(offset))
    if size <= config.deadband:
        return np.zeros(3)
    velocity = config.velocity_gain * (size - config.deadband) * offset / size
    speed = float(np.linalg.norm(velocity))
    return velocity if speed <= config.max_speed else velocity * (config.max_speed / speed)


class DeviceAdapter:
    """Bridges a `HapticDevice` and the controller's two operator channels (module docstring).

    `step(t)` is one cycle: take the newest feedback, render it, read the device, publish a
    command stamped `t` [s]. A real-time loop calls it at its rate (pedi_drake.apps.haptic_device),
    a DeviceOperator in a diagram's lock step (pedi_drake.operator.device_operator)."""

    def __init__(
        self,
        device: HapticDevice,
        lcm: DrakeLcmInterface,
        command_channel: str,
        feedback_channel: str,
        config: AdapterConfig | None = None,
    ):
        self.device, self.config = device, config or AdapterConfig()
        self._lcm, self._channel = lcm, command_channel
        self._sequence = 0
        self.force = np.zeros(3)  # the foot's force last fed back, world [N]
        self.limit = float("nan")  # the limit it is held under [N]
        lcm.Subscribe(feedback_channel, self._take_feedback)

    def _take_feedback(self, data: bytes) -> None:
        message = foot_feedback_lcmt.decode(data)
        force = np.array(message.force, float)
        if message.leg >= 0 and np.all(np.isfinite(force)):
            self.force, self.limit = force, float(message.force_limit)

    def step(self, t: float) -> foot_command_lcmt:
        self._lcm.HandleSubscriptions(0)
        self.device.render(self.config.force_scale * self.force)
        reading = self.device.read()
        message = foot_command_lcmt()
        self._sequence += 1
        message.timestamp_us, message.sequence = int(round(t * 1e6)), self._sequence
        message.mode_request = MODE_TELEOP if reading.button else MODE_AUTONOMOUS
        message.frame, message.kind = FRAME_WORLD, KIND_VELOCITY
        message.value = [float(v) for v in offset_velocity(reading.offset, self.config)]
        self._lcm.Publish(self._channel, message.encode())
        return message


@dataclasses.dataclass
class SpringDevice:
    """A simulated haptic device held by a simulated hand (module docstring). `step(dt)` advances
    the handle; `hand_target` [m] is where the hand wants it."""

    mass: float = 0.2  # [kg] of the handle
    hand_stiffness: float = 400.0  # [N/m]: a relaxed arm
    hand_damping: float = 15.0  # [N s/m]
    button: bool = True
    hand_target: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    offset: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    velocity: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    rendered: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))

    def read(self) -> DeviceReading:
        return DeviceReading(self.offset.copy(), self.button)

    def render(self, force: np.ndarray) -> None:
        self.rendered = np.asarray(force, float).copy()

    def hand_force(self) -> np.ndarray:
        """The force of the hand on the handle [N]."""
        return self.hand_stiffness * (self.hand_target - self.offset) - self.hand_damping * self.velocity

    def step(self, dt: float) -> None:
        """Advances the handle by `dt` [s] (semi-implicit Euler, in substeps of at most 1 ms)."""
        substeps = max(1, int(np.ceil(dt / 1e-3)))
        h = dt / substeps
        for _ in range(substeps):
            acceleration = (self.hand_force() + self.rendered) / self.mass
            self.velocity = self.velocity + h * acceleration
            self.offset = self.offset + h * self.velocity
