"""ScriptedOperator: publishes a fixed sequence of foot commands on LCM, like an operator would.

For tests, benchmarks and the example app: the script is a list of steps, each holding from its
start time until the next one's; after the last step's `until` nothing more is published (the
operator falls silent). Messages go out every `period` [s] of diagram time, with a sequence
number, on a DrakeLcm (memq:// in one process, udpm:// to another). `script_stream` makes the
same messages as data, for a MessagePlayer or a file.

With `start_on_leg`, the operator waits, silent, until the robot offers it that foot: the first
haptic feedback (foot_feedback_lcmt on `feedback_channel`) that reports the leg driven, as a
teleop_foot phase's does from its first update. The script's times then count from that
feedback's diagram time, as an operator at the end of a long mission starts when the robot is
ready, whenever that is.

Instead of fixed steps it may run a `program` that reacts to what it feels: an object with
`initial_state()` and `command(state, t, force_W) -> (ScriptStep | None, state)`, given the time
from the offer and the latest feedback's force on the foot (pedi_drake.operator.button_search);
its state is kept in the Context.
"""

import dataclasses

import numpy as np
from pydrake.common.value import Value
from pydrake.lcm import DrakeLcmInterface
from pydrake.systems.framework import EventStatus

from pedi_drake.go1_driver.lcmtypes import foot_command_lcmt, foot_feedback_lcmt
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.operator.command import CONTROLLER_NONE, FRAME_TRUNK, KIND_VELOCITY, MODE_NONE
from pedi_drake.operator.config import DEFAULT_FOOT_COMMAND_CHANNEL, DEFAULT_FOOT_FEEDBACK_CHANNEL
from pedi_drake.operator.message_stream import TimedMessage
from pedi_drake.robot import LEG_NAMES


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
    """Publishes `steps` on `channel` every `period` [s] until `until` [s] (script time: diagram
    time, or from the robot's offer of the foot `start_on_leg`, read on `feedback_channel`)."""

    def __init__(
        self,
        lcm: DrakeLcmInterface,
        steps: list[ScriptStep] | None = None,
        *,
        program=None,
        until: float = np.inf,
        period: float = 0.01,
        channel: str = DEFAULT_FOOT_COMMAND_CHANNEL,
        start_on_leg: str = "",
        feedback_channel: str = DEFAULT_FOOT_FEEDBACK_CHANNEL,
    ):
        super().__init__()
        if start_on_leg and start_on_leg not in LEG_NAMES:
            raise ValueError(f"start_on_leg must be one of {LEG_NAMES}, got {start_on_leg!r}")
        if (steps is None) == (program is None):
            raise ValueError("give the operator either steps or a program")
        if program is not None and not start_on_leg:
            raise ValueError("a program reads the feedback of the foot it is offered: give start_on_leg")
        self._lcm, self._steps, self._until, self._channel = lcm, list(steps or []), until, channel
        self._program = program
        if program is not None:
            self._program_state = self.DeclareAbstractState(Value(program.initial_state()))
        self._sequence = self.DeclareDiscreteState(1)
        # The diagram time the script starts at: 0, or NaN until the robot offers the foot.
        self._start = self.DeclareDiscreteState([np.nan if start_on_leg else 0.0])
        # Feedback times [s] that reported the leg driven, since the last update (the bus's
        # poller, the operator input, hands them over), and the latest such feedback's force [N].
        self._offers: list[float] = []
        self._force: list[np.ndarray] = []
        if start_on_leg:
            leg = LEG_NAMES.index(start_on_leg)

            def take(data: bytes) -> None:
                message = foot_feedback_lcmt.decode(data)
                if message.leg == leg:
                    self._offers.append(message.timestamp_us * 1e-6)
                    self._force[:] = [np.array(message.force, float)]

            lcm.Subscribe(feedback_channel, take)
        if program is None:
            self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._publish_steps)
        else:
            # A program's state is abstract: only an unrestricted update may change it.
            self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._publish_program)

    def _publish_steps(self, context, discrete_state) -> EventStatus:
        return self._publish(context, discrete_state, None)

    def _publish_program(self, context, state) -> EventStatus:
        return self._publish(context, state.get_mutable_discrete_state(), state)

    def _publish(self, context, discrete, state) -> EventStatus:
        """Publishes the command at the context's time into `discrete` (the discrete state); with
        a program, its next state goes into `state` (the whole state: an unrestricted update)."""
        t = context.get_time()
        start = float(context.get_discrete_state(self._start).get_value()[0])
        if np.isnan(start):
            if not self._offers:
                return EventStatus.DidNothing()
            start = min(self._offers)
            self._offers.clear()
            discrete.set_value(self._start, [start])
        if self._program is None:
            step = script_command(self._steps, t - start)
        else:
            force = self._force[0] if self._force else None
            previous = context.get_abstract_state(self._program_state).get_value()
            step, following = self._program.command(previous, t - start, force)
            state.get_mutable_abstract_state(self._program_state).set_value(following)
        if step is None or t - start > self._until:
            return EventStatus.Succeeded()
        sequence = int(context.get_discrete_state(self._sequence).get_value()[0])
        self._lcm.Publish(self._channel, foot_command_message(step, t, sequence).encode())
        discrete.set_value(self._sequence, [sequence + 1])
        return EventStatus.Succeeded()
