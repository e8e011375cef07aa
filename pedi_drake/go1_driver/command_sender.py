"""Publishes the (already bounded) `go1.command` to the Go1 bridge on `pd_plustau_targets` at 500 Hz,
in the same tick as the controller computed it, right after the safety filter bounded it.

The 60-vector (q_des, qd_des, kp, kd, tau_ff; Unitree order) becomes a `pd_tau_targets_lcmt`
in the wire order (q_des, qd_des, tau_ff, kp, kd) via constants.CommandEncoder, through the
driver's Go1Link, which stamps each publication against its tick's wall-clock schedule. The
sender checks nothing: Go1SafetyFilter upstream guarantees the limits. As a last line of defence
it refuses to publish a non-finite command (the encoder gives no bytes for one; the link's guard
then damps when the loop stays silent).

The publication is a discrete update with no state, not a publish event: at c.COMMAND_OFFSET
after each tick the safety filter's unrestricted update bounds the command, and Drake computes the
discrete updates of an instant after applying its unrestricted ones, so the sender reads the
command bounded in this tick within the same simulator step. A publish event sees an instant's
state before its updates, so it would need an instant (a simulator step) of its own.
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
        self._period = period
        self._command = self.DeclareVectorInputPort("command", COMMAND_SIZE)
        # Made once: Drake copies the status a handler returns.
        self._succeeded = EventStatus.Succeeded()
        self.DeclarePeriodicDiscreteUpdateEvent(period, c.COMMAND_OFFSET, self._publish)

    def _publish(self, context, _discrete_state) -> EventStatus:
        # The tick's own time, on the tick grid (the event's time less the offset rounds off it).
        tick_time = round((context.get_time() - c.COMMAND_OFFSET) / self._period) * self._period
        if not self.link.publish_command(self._command.Eval(context), tick_time):
            return EventStatus.Failed(self, "refusing to publish a non-finite go1.command")
        return self._succeeded
