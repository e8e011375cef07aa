"""Receivers of Go1 LCM messages: latch the newest valid message of each channel into the Context.

`Go1LcmReceiver` reads one or more `Inbox`es (pedi_drake.go1_driver.link): on the driver the
link fills them, checking, decoding and time-stamping each message, when the receiver's update
polls it at every tick (and from its own thread while the loop is late); on the simulator bridge
a DrakeLcm subscription does. A periodic unrestricted update at
the control rate copies every inbox into one discrete state vector, so outputs are functions of
the Context only, and the systems that read them at the same tick see that tick's status.
Messages of the wrong size or fingerprint, that fail to decode or carry NaN, are dropped and
counted by reason: a foreign publisher on the channel can never crash the driver.

`MakeLcmReceiver` puts a Selector (Drake's, compiled) behind the receiver that splits the latched
vector into named outputs (and bundles of them): a tick runs one Python call for all the
channels, and none when the outputs are evaluated.

`MakeStatusReceiver` builds the driver's receiver of its three status channels (Unitree motor
order throughout):
  leg_control_data      -> position_measured [rad], velocity_measured [rad/s], torque_estimated [N m]
  state_estimator_data  -> imu (quat w,x,y,z; gyro [rad/s]; accelerometer [m/s^2]), foot_contact (raw)
  rc_command            -> estop (1 while a configured switch of the remote is on)
with silence (2) of the first two, message_counts (6) of all three, and robot_status, the bundle
Go1SafetyFilter reads.
"""

import dataclasses
import logging
import math
import time
from collections.abc import Sequence

import numpy as np
from pydrake.systems.framework import Diagram, DiagramBuilder, DiscreteValues, State
from pydrake.systems.primitives import Selector, SelectorParams

from pedi_drake.exceptions import LcmTimeout
from pedi_drake.go1_driver.link import Go1Link, Inbox
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses

_log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class ReceiverChannel:
    """One channel a Go1LcmReceiver latches."""

    inbox: Inbox
    # The channel's values before its first message (their size is the decoded vector's).
    initial_values: np.ndarray
    # Output name -> part of the channel's values.
    outputs: dict[str, slice]
    # Its silence is in the `silence` output: a watchdog judges it (an optional channel's is not).
    watched: bool = True
    # Initialisation waits (up to the receiver's wait_timeout) for its first message.
    wait: bool = False


class Go1LcmReceiver(LeafSystemWithoutWitnesses):
    """Inboxes of `channels` -> one latched vector, at the control rate.

    Discrete state, the output `latched`: [values of every channel (in order), silence of every
    channel [s], received and dropped messages of every channel]. A channel's silence is how long
    it had been silent when last looked at (inf before any message); with a `link`, judged by its
    receive thread's clock (Go1Link.silence), so a late tick of the loop does not make the robot
    look silent. `output_selections()` names the parts (see MakeLcmReceiver).
    With `wait_timeout` > 0 (needs a `link`), initialisation blocks until a first message of every
    channel marked `wait` arrives and raises LcmTimeout naming the channel and URL when none does.
    """

    def __init__(
        self,
        channels: Sequence[ReceiverChannel],
        *,
        link: Go1Link | None = None,
        period: float,
        wait_timeout: float = 0.0,
    ):
        super().__init__()
        self._channels = tuple(channels)
        self._link = link
        self._wait_timeout = wait_timeout
        sizes = [len(channel.initial_values) for channel in self._channels]
        starts = np.cumsum([0, *sizes]).tolist()
        num_values, k = starts[-1], len(self._channels)
        # Per channel: (inbox, its values' start and end, its silence's index, its counts' index).
        self._latch_plan = tuple(
            (channel.inbox, starts[i], starts[i + 1], num_values + i, num_values + k + 2 * i)
            for i, channel in enumerate(self._channels)
        )
        self._selections: dict[str, list[int]] = {}
        for i, channel in enumerate(self._channels):
            for name, part in channel.outputs.items():
                if name in self._selections or name in ("silence", "message_counts"):
                    raise ValueError(f"Go1LcmReceiver: two outputs named {name!r}")
                self._selections[name] = list(range(starts[i], starts[i + 1])[part])
        self._selections["silence"] = [num_values + i for i, c in enumerate(self._channels) if c.watched]
        self._selections["message_counts"] = list(range(num_values + k, num_values + 3 * k))
        initial = np.concatenate([*(c.initial_values for c in self._channels), np.full(k, math.inf), np.zeros(2 * k)])
        self._state = self.DeclareDiscreteState(initial)
        # Unrestricted updates: at an instant the Simulator applies those before any system's
        # discrete update, so the systems that read the receiver (the state estimator, the
        # controller's joint measurements) use the status latched at the same tick, not the one
        # a tick older, as they would beside a discrete latch. The same holds at initialisation:
        # the estimator's own initialisation sees the robot's first status (with a discrete latch
        # it saw the receiver's zeros, started from an unset estimate, and the mission's first
        # update planned from a trunk at z = 0).
        self.DeclarePeriodicUnrestrictedUpdateEvent(period, 0.0, self._latch_tick)
        self.DeclareInitializationUnrestrictedUpdateEvent(self._initialize)
        self.latched = self.DeclareStateOutputPort("latched", self._state)

    @property
    def channels(self) -> tuple[str, ...]:
        return tuple(channel.inbox.channel for channel in self._channels)

    def output_selections(self) -> dict[str, list[int]]:
        """Output name -> indices into `latched`: every channel's named outputs, `silence` of the
        watched channels [s], `message_counts` ([received, dropped] of every channel)."""
        return {name: list(indices) for name, indices in self._selections.items()}

    def _latch(self, context, discrete_state: DiscreteValues) -> None:
        link = self._link
        if link is not None:
            link.poll()
        # Holds the current state on entry: a channel without a message keeps its values.
        x = discrete_state.get_mutable_value(self._state)
        for inbox, start, end, silence, counts in self._latch_plan:
            values, received, dropped, receipt_time = inbox.snapshot()
            if values is not None:
                x[start:end] = values
            x[silence] = link.silence(inbox) if link is not None else time.monotonic() - receipt_time
            x[counts] = received
            x[counts + 1] = dropped

    def _latch_tick(self, context, state: State) -> None:
        self._latch(context, state.get_mutable_discrete_state())

    def _initialize(self, context, state: State) -> None:
        if self._wait_timeout > 0.0 and self._link is not None:
            for channel in self._channels:
                if channel.wait and not self._link.wait_for_first(channel.inbox, self._wait_timeout):
                    raise LcmTimeout(
                        f"no valid message on LCM channel {channel.inbox.channel!r} at {self._link.url} "
                        f"within {self._wait_timeout:g} s: is the Go1 bridge (or "
                        "`python -m pedi_drake.apps.sim_bridge`) running on that URL?"
                    )
        self._latch(context, state.get_mutable_discrete_state())


def MakeLcmReceiver(
    channels: Sequence[ReceiverChannel],
    *,
    link: Go1Link | None = None,
    period: float,
    wait_timeout: float = 0.0,
    bundles: dict[str, Sequence[str]] | None = None,
) -> Diagram:
    """A Go1LcmReceiver of `channels` (see it for the arguments) whose outputs are its named parts:
    every channel's `outputs`, silence (the watched channels' [s]) and message_counts ([received,
    dropped] per channel), split off the latched vector by a Selector; and each of `bundles`
    (output name -> names of those parts, concatenated in that order)."""
    builder = DiagramBuilder()
    receiver = builder.AddNamedSystem(
        "latch", Go1LcmReceiver(channels, link=link, period=period, wait_timeout=wait_timeout)
    )
    params = SelectorParams()
    latched = SelectorParams.InputPortParams()
    latched.name, latched.size = "latched", receiver.latched.size()
    params.inputs = [latched]
    selections = receiver.output_selections()
    for name, parts in (bundles or {}).items():
        if name in selections:
            raise ValueError(f"MakeLcmReceiver: the bundle {name!r} has the name of an output")
        selections[name] = [index for part in parts for index in selections[part]]
    outputs = []
    for name, indices in selections.items():
        output = SelectorParams.OutputPortParams()
        output.name = name
        selections = []
        for index in indices:
            selection = SelectorParams.OutputSelection()
            selection.input_port_index, selection.input_offset = 0, index
            selections.append(selection)
        output.selections = selections
        outputs.append(output)
    params.outputs = outputs
    selector = builder.AddNamedSystem("outputs", Selector(params))
    builder.Connect(receiver.latched, selector.get_input_port(0))
    for i in range(selector.num_output_ports()):
        port = selector.get_output_port(i)
        builder.ExportOutput(port, port.get_name())
    diagram = builder.Build()
    diagram.set_name("lcm_receiver")
    return diagram


def MakeStatusReceiver(link: Go1Link, *, period: float, wait_timeout: float = 0.0) -> Diagram:
    """leg_control_data, state_estimator_data and rc_command of `link` -> position_measured,
    velocity_measured, torque_estimated (12 each), imu (10: quat w,x,y,z, gyro, accelerometer),
    foot_contact (4), estop (1), silence (2: leg_control_data, state_estimator_data [s]),
    message_counts (6, in the order of constants.STATUS_CHANNELS) and robot_status (27:
    position_measured, velocity_measured, silence, estop: Go1SafetyFilter's input).

    Initialisation waits up to `wait_timeout` [s] for the first leg_control_data and
    state_estimator_data; the remote is optional (its silence trips nothing).
    """
    state_estimator_initial = np.zeros(14)
    state_estimator_initial[0] = 1.0  # identity orientation until the first message
    channels = (
        ReceiverChannel(
            link.leg_control,
            np.zeros(36),
            {"position_measured": slice(0, 12), "velocity_measured": slice(12, 24), "torque_estimated": slice(24, 36)},
            wait=True,
        ),
        ReceiverChannel(
            link.state_estimator,
            state_estimator_initial,
            {"imu": slice(0, 10), "foot_contact": slice(10, 14)},
            wait=True,
        ),
        # 1 while any of the link's E-stop switch fields is on.
        ReceiverChannel(link.rc_command, np.zeros(1), {"estop": slice(0, 1)}, watched=False),
    )
    robot_status = ("position_measured", "velocity_measured", "silence", "estop")
    return MakeLcmReceiver(
        channels, link=link, period=period, wait_timeout=wait_timeout, bundles={"robot_status": robot_status}
    )
