"""Publishes the (already bounded) `go1.command` to the Go1 bridge on `pd_plustau_targets` at 500 Hz.

The 60-vector (q_des, qd_des, kp, kd, tau_ff; Unitree order) becomes a `pd_tau_targets_lcmt`
in the wire order (q_des, qd_des, tau_ff, kp, kd) via go1_lcm_constants.command_to_message.
The sender checks nothing: Go1SafetyFilter upstream guarantees the limits. As a last line of
defence it refuses to publish a non-finite command (the bridge would hold its previous one).
"""

import logging

import numpy as np
from pydrake.lcm import DrakeLcmInterface
from pydrake.systems.framework import EventStatus, LeafSystem

from pedi_drake.go1_command import COMMAND_SIZE
from pedi_drake.go1_driver import constants as c

_log = logging.getLogger(__name__)


class Go1CommandSender(LeafSystem):
    """command (60) -> pd_plustau_targets, published every `period` [s] (and not at initialisation).

    timestamp_us is the diagram time [us]; id is the tick number, so a log shows gaps.
    """

    def __init__(self, lcm: DrakeLcmInterface, *, period: float = c.BRIDGE_PERIOD, channel: str = c.COMMAND_CHANNEL):
        super().__init__()
        self._lcm = lcm
        self._channel = channel
        self._period = period
        self._command = self.DeclareVectorInputPort("command", COMMAND_SIZE)
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish)

    def _publish(self, context) -> EventStatus:
        command = self._command.Eval(context)
        t = context.get_time()
        if not np.all(np.isfinite(command)):
            return EventStatus.Failed(self, "refusing to publish a non-finite go1.command")
        message = c.command_to_message(
            command, timestamp_us=int(round(t * 1e6)), message_id=int(round(t / self._period))
        )
        self._lcm.Publish(self._channel, message.encode(), t)
        return EventStatus.Succeeded()
