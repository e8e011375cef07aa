"""OperatorInput: the operator's messages on LCM -> the `operator_command` port, read at its period.

The source is the scenario's (`operator.source`): the project's foot_command_lcmt on a channel
("lcm"), or the Go1 remote's rc_command ("remote"). Messages are checked as the Go1 driver checks
its own (`pedi_drake.go1_driver.link.Inbox`): a message of the wrong size or fingerprint, that
fails to decode, carries NaN or Inf, or an unknown code is dropped and counted by reason
(`counts()`), so a foreign or broken publisher can never reach the foot. Foot commands are also
kept in the order their sender stamped them (timestamp_us and sequence; the Inbox's order check):
while the operator is live, a late, repeated or replayed message, or one stamped ahead of what the
receiver's clock allows, is dropped too ("out_of_order", "stamp_ahead"); after
SENDER_TAKEOVER_SILENCE without a valid message a restarted or new sender is taken, whatever its
stamps.

A periodic update takes in what arrived (polling the bus: the diagram's time is the only
clock, so a lock-step simulation and a real-time run see the same ages) and keeps in the discrete
state: the newest command, the last mode the operator asked for, the latched E-stop and the
diagram time of the last valid message, the last controller and friction coefficient asked for. `age` on the output is
the time since then [s].
"""

import math
import time

import lcm as lcm_module
import numpy as np
from pydrake.lcm import DrakeLcmInterface
from pydrake.systems.framework import BasicVector, DiscreteValues

from pedi_drake.go1_driver.constants import RC_COMMAND_CHANNEL
from pedi_drake.go1_driver.lcmtypes import foot_command_lcmt, rc_command_lcmt
from pedi_drake.go1_driver.link import QUEUE_CAPACITY, DrakeLcmTransport, Inbox
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.operator.command import CONTROLLER_NONE, MODE_NONE, OPERATOR_COMMAND_SIZE
from pedi_drake.operator.config import OperatorConfig
from pedi_drake.operator.messages import (
    MESSAGE_VECTOR_SIZE,
    foot_command_in_range,
    foot_command_stamp,
    foot_command_vector,
    remote_command_vector,
    remote_in_range,
)

# Discrete state: [mode_request, frame, kind, value (3), estop, t_last [s], received, dropped,
# controller_request, friction_request].
_MODE, _FRAME_KIND_VALUE, _ESTOP, _T_LAST, _RECEIVED, _DROPPED, _CONTROLLER, _FRICTION = (
    0, slice(1, 6), 6, 7, 8, 9, 10, 11
)  # fmt: skip
FOOT_COMMAND_ENCODED_SIZE = len(foot_command_lcmt().encode())
# Silence after which a foot command is taken whatever its stamps (a restarted or new sender) [s]:
# longer than any delivery delay, and the foot already holds after the teleop phase's hold_after.
SENDER_TAKEOVER_SILENCE = 0.5
# How far a foot command's time may run ahead of the newest accepted one's beyond the time the
# receiver saw pass [s]: the jitter of delivery and of a late control loop catching up.
MAX_CLOCK_LEAD = 0.5
# The sequence numbers of foot commands advance at most this fast [1/s]: no operator sends faster.
MAX_SEQUENCE_RATE = 10_000.0


def operator_inbox(config: OperatorConfig, clock=time.monotonic) -> Inbox:
    """The checked inbox of the configured source (foot_command_lcmt or the remote's rc_command);
    `clock` [s] judges the foot commands' order (the remote's messages carry no stamps)."""
    if config.source == "lcm":
        return Inbox(
            config.channel,
            foot_command_lcmt,
            foot_command_vector,
            encoded_size=FOOT_COMMAND_ENCODED_SIZE,
            in_range=foot_command_in_range,
            stamp=foot_command_stamp,
            clock=clock,
            takeover_silence=SENDER_TAKEOVER_SILENCE,
            max_clock_lead=MAX_CLOCK_LEAD,
            max_sequence_rate=MAX_SEQUENCE_RATE,
        )
    if config.source == "remote":
        return Inbox(
            RC_COMMAND_CHANNEL, rc_command_lcmt, remote_command_vector(config.remote), in_range=remote_in_range
        )
    raise ValueError(f"operator source {config.source!r} has no inbox")


class OperatorInput(LeafSystemWithoutWitnesses):
    """The operator's command (port `operator_command`, layout in pedi_drake.operator.command)."""

    def __init__(self, config: OperatorConfig, lcm: DrakeLcmInterface):
        """`lcm`: the bus the commands arrive on (polled by this system's update)."""
        super().__init__()
        # The diagram time of the poll under way: messages are handled only inside `_take_in`'s
        # poll, so this is their receipt time, on the one clock of a lock-step or real-time run.
        self._poll_time = -math.inf
        self._inbox = operator_inbox(config, clock=lambda: self._poll_time)
        url = lcm.get_lcm_url()
        if url.startswith("memq://"):
            # An in-process bus hands over every message published since the last poll.
            self._receiver = DrakeLcmTransport(lcm)
        else:
            # On a UDP bus a DrakeLcm subscription keeps one message between two polls, and
            # pydrake gives no handle to raise that: at 1 kHz nine operator messages in ten would
            # be lost (E-stops among them) and never counted. An lcm.LCM on the same URL keeps
            # QUEUE_CAPACITY, as the Go1 driver's link does.
            self._receiver = lcm_module.LCM(url)
        subscription = self._receiver.subscribe(self._inbox.channel, lambda _channel, data: self._inbox.handle(data))
        if subscription is not None:
            subscription.set_queue_capacity(QUEUE_CAPACITY)
        initial = np.zeros(OPERATOR_COMMAND_SIZE)
        initial[_T_LAST] = -math.inf
        self._state = self.DeclareDiscreteState(initial)
        self.DeclarePeriodicDiscreteUpdateEvent(config.period, 0.0, self._take_in)
        self.DeclareVectorOutputPort(
            "operator_command",
            OPERATOR_COMMAND_SIZE,
            self._calc_command,
            prerequisites_of_calc={self.xd_ticket(), self.time_ticket()},
        )

    @property
    def channel(self) -> str:
        return self._inbox.channel

    def counts(self) -> dict:
        """Messages received and dropped on the channel, the drops by reason."""
        return self._inbox.counts()

    def _take_in(self, context, discrete_state: DiscreteValues) -> None:
        self._poll_time = context.get_time()
        while self._receiver.handle_timeout(0) > 0:
            pass
        values, received, dropped, _ = self._inbox.snapshot()
        x = context.get_discrete_state(self._state).get_value().copy()
        if values is not None and received > x[_RECEIVED]:
            values = values[:MESSAGE_VECTOR_SIZE]
            if values[0] != MODE_NONE:  # a mode request stands until the operator asks for another
                x[_MODE] = values[0]
            x[_FRAME_KIND_VALUE] = values[1:6]
            x[_ESTOP] = max(x[_ESTOP], values[6])  # latched
            if values[7] != CONTROLLER_NONE:  # as a mode request, it stands until another
                x[_CONTROLLER] = values[7]
            if values[8] != 0.0:  # so does a friction coefficient
                x[_FRICTION] = values[8]
            x[_T_LAST] = context.get_time()
        x[_RECEIVED], x[_DROPPED] = received, dropped
        discrete_state.set_value(self._state, x)

    def _calc_command(self, context, output: BasicVector) -> None:
        x = context.get_discrete_state(self._state).get_value().copy()
        x[_T_LAST] = context.get_time() - x[_T_LAST]  # the age [s]; inf before any message
        output.SetFromVector(x)
