"""An operator's messages as data: a stream of timed raw LCM messages, played in lock step or live.

A stream is a list of TimedMessage (time from the stream's start [s], channel, the bytes on the
wire), so a scripted operator, a recorded session and a fuzzed stream with broken bytes are all
played the same way:

  * `MessagePlayer` publishes a stream on a DrakeLcm at diagram times, inside a lock-step
    simulation (an in-process memq:// bus): every message whose time has come, each `period`;
  * `play_messages` publishes it on the wall clock, from a given start (pedi_drake.apps.teleop_lcm
    plays a stream from a file this way, as a person's operator program would send it);
  * `write_lcm_log` / `read_lcm_log` keep it in a standard LCM event log (lcm-logger's format,
    event times in microseconds from the stream's start), which lcm-logplayer and lcm-spy read.
"""

import dataclasses
import time
from collections.abc import Callable, Iterable
from pathlib import Path

import lcm as lcm_module
import numpy as np
from pydrake.lcm import DrakeLcmInterface
from pydrake.systems.framework import DiscreteValues, EventStatus

from pedi_drake.leaf_system import LeafSystemWithoutWitnesses


@dataclasses.dataclass(frozen=True)
class TimedMessage:
    """One message of a stream: sent `t` [s] after the stream's start on `channel`."""

    t: float
    channel: str
    data: bytes


def write_lcm_log(messages: Iterable[TimedMessage], path: Path) -> Path:
    """Writes the stream to `path` as an LCM event log (times in us from the stream's start)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    log = lcm_module.EventLog(str(path), "w", overwrite=True)
    for message in messages:
        log.write_event(int(round(message.t * 1e6)), message.channel, message.data)
    log.close()
    return path


def read_lcm_log(path: Path) -> list[TimedMessage]:
    """The stream in the LCM event log `path`, its times from the log's first event [s]."""
    log = lcm_module.EventLog(str(path), "r")
    events = [(event.timestamp, event.channel, bytes(event.data)) for event in log]
    log.close()
    if not events:
        return []
    first = events[0][0]
    return [TimedMessage((stamp - first) * 1e-6, channel, data) for stamp, channel, data in events]


def play_messages(
    messages: list[TimedMessage],
    publish: Callable[[str, bytes], None],
    start: float,
    sleep: Callable[[float], None] = time.sleep,
    clock: Callable[[], float] = time.monotonic,
) -> int:
    """Publishes each message at `start` + its time on `clock` [s]; the number published.

    A message whose time has already passed goes out at once (the stream catches up, in order)."""
    for message in messages:
        sleep(max(0.0, start + message.t - clock()))
        publish(message.channel, message.data)
    return len(messages)


class MessagePlayer(LeafSystemWithoutWitnesses):
    """Publishes `messages` on `lcm` at their diagram times, checked every `period` [s].

    Discrete state: the index of the next message to send (the stream itself is fixed data).
    """

    def __init__(self, lcm: DrakeLcmInterface, messages: list[TimedMessage], period: float = 0.002):
        super().__init__()
        self._lcm = lcm
        self._messages = sorted(messages, key=lambda message: message.t)
        self._times = np.array([message.t for message in self._messages])
        self._next = self.DeclareDiscreteState(1)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._publish)

    def sent(self, context) -> int:
        """Messages published so far in `context` (this system's context)."""
        return int(context.get_discrete_state(self._next).get_value()[0])

    def _publish(self, context, discrete_state: DiscreteValues) -> EventStatus:
        first = self.sent(context)
        # A hair of tolerance: the stream's times and the diagram's are sums of different steps.
        last = int(np.searchsorted(self._times, context.get_time() + 1e-9, side="right"))
        if last <= first:
            return EventStatus.DidNothing()
        for message in self._messages[first:last]:
            self._lcm.Publish(message.channel, message.data)
        discrete_state.set_value(self._next, [last])
        return EventStatus.Succeeded()
