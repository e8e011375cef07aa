"""Publishes the (already bounded) `go1.command` to the Go1 bridge on `pd_plustau_targets` at 500 Hz,
in the same tick as the controller computed it (after the safety filter: c.COMMAND_SEND_OFFSET).

The 60-vector (q_des, qd_des, kp, kd, tau_ff; Unitree order) becomes a `pd_tau_targets_lcmt`
in the wire order (q_des, qd_des, tau_ff, kp, kd) via constants.CommandEncoder, through the
driver's Go1Link, which stamps each publication against its tick's wall-clock schedule. The
sender checks nothing: Go1SafetyFilter upstream guarantees the limits. As a last line of defence
it refuses to publish a non-finite command (the encoder gives no bytes for one; the link's guard
then damps when the loop stays silent).
"""

from pydrake.systems.framework import EventStatus

from pedi_drake.go1_command import COMMAND_SIZE
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.link import Go1Link
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses


class Go1CommandSender(LeafSystemWithoutWitnesses):
    """command (60) -> pd_plustau_targets, published every `period` [s] (and not at initialisation).

    timestamp_us is the diagram time of the tick [us]; id counts the messages, so a log shows gaps.
    """

    def __init__(self, link: Go1Link, *, period: float = c.BRIDGE_PERIOD):
        super().__init__()
        # The I/O boundary, kept here so a run can reach it at shutdown (`hardware_link`).
        self.link = link
        self._command = self.DeclareVectorInputPort("command", COMMAND_SIZE)
        # Made once: Drake copies the status a handler returns.
        self._succeeded = EventStatus.Succeeded()
        self.DeclarePeriodicPublishEvent(period, c.COMMAND_SEND_OFFSET, self._publish)

    def _publish(self, context) -> EventStatus:
        tick_time = context.get_time() - c.COMMAND_SEND_OFFSET
        if not self.link.publish_command(self._command.Eval(context), tick_time):
            return EventStatus.Failed(self, "refusing to publish a non-finite go1.command")
        return self._succeeded
