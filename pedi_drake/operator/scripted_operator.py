"""ScriptedOperator: publishes a fixed sequence of foot commands on LCM, like an operator would.

For tests, benchmarks and the example app: the script is a list of steps, each holding from its
start time until the next one's; after the last step's `until` nothing more is published (the
operator falls silent). Messages go out every `period` [s] of diagram time, with a sequence
number, on a DrakeLcm (memq:// in one process, udpm:// to another). `script_stream` makes the
same messages as data, for a MessagePlayer or a file.
"""

import dataclasses

import numpy as np
from pydrake.lcm import DrakeLcmInterface
from pydrake.systems.framework import EventStatus

from pedi_drake.go1_driver.lcmtypes import foot_command_lcmt
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.operator.command import CONTROLLER_NONE, FRAME_TRUNK, KIND_VELOCITY, MODE_NONE
from pedi_drake.operator.config import DEFAULT_FOOT_COMMAND_CHANNEL
from pedi_drake.operator.message_stream import TimedMessage


@dataclasses.dataclass(frozen=True)
class ScriptStep:
    """One step of the script: the command sent from `start` [s] (diagram time) on."""

    start: float
    value: tuple[float, float, float] = (0.0, 0.0, 0.0)  # [m/s] or [m]
    mode_request: int = MODE_NONE
    frame: int = FRAME_TRUNK
    kind: int = KIND_VELOCITY
    estop: bool = False
    controller_request: int = CONTROLLER_NONE
    friction_request: float = 0.0  # [-] a ground friction coefficient for the controllers; 0: none


def script_command(steps: list[ScriptStep], t: float) -> ScriptStep | None:
    """The step in force at `t` [s] (the last one started), None before the first."""
    current = None
    for step in steps:
        if step.start <= t:
            current = step
    return current


def foot_command_message(step: ScriptStep, t: float, sequence: int) -> foot_command_lcmt:
    message = foot_command_lcmt()
    message.timestamp_us = int(round(t * 1e6))
    message.sequence = sequence
    message.mode_request, message.frame, message.kind = step.mode_request, step.frame, step.kind
    message.value = [float(v) for v in step.value]
    message.estop = 1 if step.estop else 0
    message.controller_request = step.controller_request
    message.friction_request = float(step.friction_request)
    return message


def script_stream(steps: list[ScriptStep], rate: float, end: float, channel: str) -> list[TimedMessage]:
    """The messages of `steps` sent at `rate` [Hz] from 0 to `end` [s] (both ends) on `channel`,
    sequence numbers from 1: the script as a stream (pedi_drake.operator.message_stream)."""
    times = np.arange(int(np.floor(end * rate + 1e-9)) + 1) / rate
    return [
        TimedMessage(float(t), channel, foot_command_message(script_command(steps, t), float(t), k + 1).encode())
        for k, t in enumerate(times)
    ]


class ScriptedOperator(LeafSystemWithoutWitnesses):
    """Publishes `steps` on `channel` every `period` [s] until `until` [s] (diagram time)."""

    def __init__(
        self,
        lcm: DrakeLcmInterface,
        steps: list[ScriptStep],
        *,
        until: float = np.inf,
        period: float = 0.01,
        channel: str = DEFAULT_FOOT_COMMAND_CHANNEL,
    ):
        super().__init__()
        self._lcm, self._steps, self._until, self._channel = lcm, list(steps), until, channel
        self._sequence = self.DeclareDiscreteState(1)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._publish)

    def _publish(self, context, discrete_state) -> EventStatus:
        t = context.get_time()
        step = script_command(self._steps, t)
        if step is None or t > self._until:
            return EventStatus.DidNothing()
        sequence = int(context.get_discrete_state(self._sequence).get_value()[0])
        self._lcm.Publish(self._channel, foot_command_message(step, t, sequence).encode())
        discrete_state.set_value(self._sequence, [sequence + 1])
        return EventStatus.Succeeded()
