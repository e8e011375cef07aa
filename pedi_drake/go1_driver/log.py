"""Record and read Go1 LCM traffic in the lcm-logger file format (the program: `pedi_drake.apps.go1_log`).

Logs are standard LCM event logs (lcm.EventLog), so `lcm-logger`, `lcm-logplayer` and
`lcm-spy` read the files written here, and `read_go1_log` reads files `lcm-logger` wrote.
Event times are the wall clock at receipt [us], as lcm-logger records them.
"""

import dataclasses
import math
import threading
import time
from pathlib import Path

import lcm
import numpy as np

from pedi_drake.go1_driver import constants as c


def record_log(
    lcm_url: str,
    path: str | Path,
    *,
    duration: float = math.inf,
    channels: str = ".*",
    stop: threading.Event | None = None,
    ready: threading.Event | None = None,
) -> int:
    """Writes every message on `lcm_url` matching the regex `channels` to `path` until `duration` [s]
    has passed or `stop` is set; returns the number of events written. `ready` is set once subscribed."""
    log = lcm.EventLog(str(path), "w", overwrite=True)
    bus = lcm.LCM(lcm_url)
    count = 0

    def handle(channel: str, data: bytes) -> None:
        nonlocal count
        log.write_event(int(time.time() * 1e6), channel, data)
        count += 1

    subscription = bus.subscribe(channels, handle)
    if ready is not None:
        ready.set()
    end = time.monotonic() + duration
    try:
        while time.monotonic() < end and not (stop is not None and stop.is_set()):
            bus.handle_timeout(20)
    finally:
        bus.unsubscribe(subscription)
        log.close()
    return count


class Go1LogRecorder:
    """Records all traffic of `lcm_url` to `path` in a background thread while in a `with` block."""

    def __init__(self, lcm_url: str, path: str | Path, channels: str = ".*"):
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._thread = threading.Thread(
            target=record_log,
            args=(lcm_url, path),
            kwargs={"channels": channels, "stop": self._stop, "ready": self._ready},
            daemon=True,
        )

    def __enter__(self) -> "Go1LogRecorder":
        self._thread.start()
        self._ready.wait(5.0)
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(5.0)


@dataclasses.dataclass
class ChannelLog:
    """The decoded messages of one channel, in arrival order."""

    times: np.ndarray  # (N,) event time [s] (wall clock at receipt)
    messages: list

    def field(self, name: str) -> np.ndarray:
        """(N, ...) array of one message field."""
        return np.array([getattr(m, name) for m in self.messages], dtype=float)


@dataclasses.dataclass
class Go1Log:
    """A Go1 LCM log: decoded channels of the Go1 protocol, and how many events could not be decoded."""

    channels: dict[str, ChannelLog]
    malformed: dict[str, int]
    other_events: int  # events on channels outside the Go1 protocol

    def commands(self) -> np.ndarray:
        """(N, 60) `go1.command` vectors of the pd_plustau_targets messages."""
        log = self.channels.get(c.COMMAND_CHANNEL)
        if log is None:
            return np.zeros((0, 60))
        return np.array([c.message_to_command(m) for m in log.messages])


def read_go1_log(path: str | Path) -> Go1Log:
    """Decodes the Go1 channels of an LCM log; undecodable events are counted, never raised."""
    times: dict[str, list[float]] = {}
    messages: dict[str, list] = {}
    malformed: dict[str, int] = {}
    other = 0
    log = lcm.EventLog(str(path), "r")
    try:
        for event in log:
            lcm_type = c.CHANNEL_TYPES.get(event.channel)
            if lcm_type is None:
                other += 1
                continue
            try:
                message = lcm_type.decode(event.data)
            except Exception:
                malformed[event.channel] = malformed.get(event.channel, 0) + 1
                continue
            times.setdefault(event.channel, []).append(event.timestamp * 1e-6)
            messages.setdefault(event.channel, []).append(message)
    finally:
        log.close()
    channels = {name: ChannelLog(np.array(times[name]), messages[name]) for name in messages}
    return Go1Log(channels=channels, malformed=malformed, other_events=other)
