"""OperatorFeedback: the teleoperated foot's haptic feedback, published on LCM at the operator period.

The mission manager writes, at each of its updates, the `operator_feedback` vector (FEEDBACK_SIZE):

    [leg, force (3), force_limit, suf, suf_status, bound_active]

leg           the foot a phase drives (Unitree index), -1 when none
force         the estimated force of the environment on that foot, world, bias removed [N]
force_limit   the limit the foot's force is held under [N]: the tighter of the force bound's
              (pedi_drake.mission.estimate_noise) and the balance bound's along the force's
              direction (NaN: no bound)
suf           the live SUF [N] (NaN: none) and suf_status its status (pedi_drake.suf.live)
bound_active  1 when the balance bound changed the foot's motion at that update

`OperatorFeedback` publishes it as a foot_feedback_lcmt (the answer to the operator's
foot_command_lcmt) on the operator's bus every `period` of diagram time, with a sequence number,
so a haptic device feels what the foot feels and how close it is to the balance bound.
"""

import numpy as np
from pydrake.lcm import DrakeLcmInterface
from pydrake.systems.framework import EventStatus

from pedi_drake.go1_driver.lcmtypes import foot_feedback_lcmt
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses

FEEDBACK_SIZE = 8


def feedback_vector(
    leg: int, force_W: np.ndarray | None, limit: float, suf: float, suf_status: int, bound_active: bool
) -> np.ndarray:
    """The `operator_feedback` vector (see the module docstring); `force_W` None: zeros."""
    force = np.zeros(3) if force_W is None else np.asarray(force_W, float)
    return np.array([leg, *force, limit, suf, suf_status, 1.0 if bound_active else 0.0], float)


def feedback_message(x: np.ndarray, t: float, sequence: int) -> foot_feedback_lcmt:
    """The foot_feedback_lcmt of the vector `x` at diagram time `t` [s]."""
    message = foot_feedback_lcmt()
    message.timestamp_us = int(round(t * 1e6))
    message.sequence = sequence
    message.leg = int(x[0])
    message.force = [float(v) for v in x[1:4]]
    message.force_limit = float(x[4])
    message.suf = float(x[5])
    message.suf_status = int(x[6])
    message.bound_active = 1 if x[7] > 0.5 else 0
    return message


def feedback_from_message(message: foot_feedback_lcmt) -> np.ndarray:
    """The vector a foot_feedback_lcmt carries (the inverse of `feedback_message`)."""
    return feedback_vector(
        message.leg,
        np.array(message.force, float),
        message.force_limit,
        message.suf,
        message.suf_status,
        message.bound_active != 0,
    )


class OperatorFeedback(LeafSystemWithoutWitnesses):
    """operator_feedback (FEEDBACK_SIZE) -> foot_feedback_lcmt on `channel` every `period` [s]."""

    def __init__(self, lcm: DrakeLcmInterface, channel: str, period: float):
        super().__init__()
        self._lcm, self._channel = lcm, channel
        self._feedback = self.DeclareVectorInputPort("operator_feedback", FEEDBACK_SIZE)
        # The next message's sequence number: the first message is number 1.
        self._sequence = self.DeclareDiscreteState(np.ones(1))
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._publish)

    @property
    def channel(self) -> str:
        return self._channel

    def _publish(self, context, discrete_state) -> EventStatus:
        x = np.asarray(self._feedback.Eval(context))
        sequence = int(context.get_discrete_state(self._sequence).get_value()[0])
        message = feedback_message(x, context.get_time(), sequence)
        self._lcm.Publish(self._channel, message.encode())
        discrete_state.set_value(self._sequence, [sequence + 1])
        return EventStatus.Succeeded()
