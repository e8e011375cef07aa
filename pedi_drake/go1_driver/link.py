"""Go1Link: the driver's wire to the robot, with its own receive thread and guard.

The control loop (a Drake Simulator paced to the wall clock) can be late: a slow tick, a
garbage collection, a loaded machine. The robot's silence must not be judged by a clock that a
late loop stops reading, so the link has a thread of its own beside the loop:

  * status messages are decoded, checked and time-stamped (time.monotonic) by the loop at the
    start of every tick (`poll`), and, while the loop is late (it has not looked for
    LOOP_LOOK_LATE periods), by the thread, which looks every RECEIVE_POLL_PERIOD; so a message
    is stamped within a tick of its arrival, or within a few milliseconds while the loop stalls.
    `Inbox.snapshot` hands the newest to the loop. The loop does the receiving whenever it can
    because a thread that takes Python's lock at every message takes it from the loop as often
    (three datagrams a tick on the multicast group, the loop's own commands included), and the
    loop then waits whenever that thread, holding the lock, is kept off its CPU;
  * the link records when it last looked at the socket (`last_look`): a channel's silence is
    `last_look - receipt_time`, judged by the receiver's clock only. A stalled loop cannot make the
    robot look silent (the thread looks for it), and if the thread itself was held up (by the
    GIL), both stamps are late together and silence is not overestimated;
  * the guard: when the loop has not published for `command_timeout` the thread latches
    "controller_silence" and puts damping on the wire itself, every period, until the process
    leaves. The robot-side bridge (like walk-these-ways' `lcm_position`) holds the last command it
    received, so without this a hung loop would leave the robot on stale targets indefinitely;
  * `hold_damping(duration)` puts damping on the wire for a bounded time: every exit of a hardware
    run calls it before the process leaves;
  * the loop's lateness: every published command is stamped against its tick's wall-clock
    schedule, and `report()` gives the distribution, deadline misses and command inter-departure
    times.

Every rejected message is counted by channel and reason (REJECT_REASONS) at a cost of
microseconds: the size and fingerprint are checked before any decoding.

A channel whose messages carry the sender's stamp (its clock and a sequence number, `stamp`) is
also kept in order: while its sender is live (an accepted message within `takeover_silence`), a
message that is not newer than the newest accepted one in both sequence and time is late,
repeated or replayed ("out_of_order"), and one stamped further ahead of the newest accepted one
than the receiver's own clock allows (its time by more than the time since plus
`max_clock_lead`, its sequence number by more than `max_sequence_rate` times that) comes from a
broken sender ("stamp_ahead"). After that silence any valid message is taken: a restarted or new
sender.

`threaded=False` keeps the same path without the thread (no guard, and nothing received while
the loop stalls): lock-step runs on an in-process bus (`DrakeLcmTransport`) use it.
"""

import array
import dataclasses
import logging
import math
import threading
import time
import weakref
from collections.abc import Callable

import lcm as lcm_module
import numpy as np

from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.config import Go1DriverConfig
from pedi_drake.go1_driver.safety import SafetyLimits, command_timeout, damping_command

_log = logging.getLogger(__name__)

# Why a message was rejected (index = position in this tuple).
REJECT_REASONS = (
    "wrong_size",  # not the encoded size of the channel's type (truncated, padded, foreign)
    "wrong_fingerprint",  # right size, another type's fingerprint
    "undecodable",  # the type's decoder raised
    "nonfinite",  # NaN or Inf in a value the driver uses
    "out_of_range",  # finite, but outside the values the channel's reader accepts (an unknown code)
    "out_of_order",  # stamped (sequence, time) no later than the newest accepted one: late, repeated, replayed
    "stamp_ahead",  # stamped further ahead of the newest accepted one than the receiver's clock allows
)
_REASON_INDEX = {name: i for i, name in enumerate(REJECT_REASONS)}

# Messages the LCM library keeps per subscription between two looks at the socket: enough
# for a flood of malformed messages to be counted rather than silently displacing the valid ones.
QUEUE_CAPACITY = 4096

# How often the receive thread wakes [s]: it runs the guard, and looks at the socket when the
# loop is late (the silence judgement and the guard advance at this pace while the loop stalls).
RECEIVE_POLL_PERIOD = 0.002
# The loop looks at the socket at every tick; once it has not looked for this many periods (of
# wall time, at the run's real-time rate) the thread looks for it [-].
LOOP_LOOK_LATE = 1.5


class FloatFields:
    """Reads float fields of a message straight from its encoded bytes: the named fields,
    concatenated in the given order, as float64 values (n,).

    For a type whose fields up to the last one read are fixed-size float arrays (the bridge's
    status types), the same values as decoding the message and concatenating the fields, at a
    fraction of the cost: the generated decoder builds the message object and a tuple per field,
    for two channels at 500 Hz each. The
    bytes must have passed the size and fingerprint checks (Inbox.handle).
    """

    def __init__(self, lcm_type, names: tuple[str, ...]):
        blocks, count = {}, 0
        for name, typename, dims in zip(
            lcm_type.__slots__, lcm_type.__typenames__, lcm_type.__dimensions__, strict=True
        ):
            if typename != "float" or not all(isinstance(d, int) for d in dims or []):
                break  # later fields are not at a fixed place in float32 units
            size = math.prod(dims) if dims else 1
            blocks[name] = (count, size)
            count += size
        missing = [name for name in names if name not in blocks]
        if missing:
            raise ValueError(f"FloatFields: {lcm_type.__name__} has no fixed float field(s) {missing} before others")
        self.names = tuple(names)
        self._index = np.concatenate([np.arange(start, start + size) for start, size in map(blocks.get, names)])
        self._count = count

    def __call__(self, data: bytes) -> np.ndarray:
        # The fingerprint's 8 bytes first, then the fields, big-endian.
        return np.frombuffer(data, dtype=">f4", count=self._count, offset=8)[self._index].astype(np.float64)


class Inbox:
    """The newest valid message of one channel, its receipt stamp and the counts of what arrived.

    `handle` runs in the loop's look at the socket (or the link thread's); `snapshot` on the loop.
    `to_vector`: the channel's values from the decoded message, or a FloatFields, which reads them
    from the bytes without decoding.
    """

    def __init__(
        self,
        channel: str,
        lcm_type,
        to_vector: Callable[[object], np.ndarray] | FloatFields,
        *,
        sticky_max: bool = False,
        clock: Callable[[], float] = time.monotonic,
        encoded_size: int | None = None,
        in_range: Callable[[np.ndarray], bool] | None = None,
        stamp: Callable[[object], tuple[float, int]] | None = None,
        takeover_silence: float = math.inf,
        max_clock_lead: float = math.inf,
        max_sequence_rate: float = math.inf,
    ):
        """`stamp`: the decoded message -> (sender's time [s], sequence number), for the order
        check (module docstring) with `takeover_silence` and `max_clock_lead` [s] on `clock` and
        `max_sequence_rate` [1/s]."""
        self.channel = channel
        self._type = lcm_type
        # A type of fixed size: the bridge's reference size, or the given one for a type of our own.
        self._size = encoded_size if encoded_size is not None else c.REFERENCE_ENCODED_SIZE[lcm_type.__name__]
        # Rejects finite values the reader cannot use (e.g. an unknown mode code): "out_of_range".
        self._in_range = in_range
        self._fingerprint = lcm_type._get_packed_fingerprint()
        self._to_vector = to_vector
        self._stamp = stamp
        self._takeover_silence = takeover_silence
        self._max_clock_lead = max_clock_lead
        self._max_sequence_rate = max_sequence_rate
        self._newest_stamp: tuple[float, int] | None = None  # of the newest accepted message
        # sticky_max: keep the element-wise maximum of the values that arrived since the last
        # snapshot, so a button pressed between two control ticks is never missed.
        self._sticky_max = sticky_max
        self._taken = True
        self._clock = clock
        self._lock = threading.Lock()
        self.first = threading.Event()
        self.values: np.ndarray | None = None
        self.received = 0
        self.rejected = [0] * len(REJECT_REASONS)
        self._dropped = 0  # sum(self.rejected), kept so that a snapshot does not add it up
        self.receipt_time = -math.inf

    def _reject(self, reason: str, detail: str = "") -> None:
        i = _REASON_INDEX[reason]
        with self._lock:
            self.rejected[i] += 1
            self._dropped += 1
            count = self.rejected[i]
        # First occurrence, then every power of ten: counted always, never a flood of log lines.
        if count == 1 or math.log10(count).is_integer():
            _log.warning("rejected a message on %s: %s %s (%d so far)", self.channel, reason, detail, count)

    def handle(self, data: bytes) -> None:
        """Checks, decodes and stamps one message; a foreign or broken one is counted and dropped."""
        if len(data) != self._size:
            self._reject("wrong_size", f"{len(data)} bytes, expected {self._size}")
            return
        if data[:8] != self._fingerprint:
            self._reject("wrong_fingerprint")
            return
        try:
            reads_bytes = isinstance(self._to_vector, FloatFields)
            # Decoded only when something reads the message (a FloatFields reads the bytes).
            message = None if reads_bytes and self._stamp is None else self._type.decode(data)
            values = self._to_vector(data) if reads_bytes else np.asarray(self._to_vector(message), dtype=float)
            stamp = self._stamp(message) if self._stamp is not None else None
        except Exception as error:  # the type's own decoder: whatever it raises, the driver carries on
            self._reject("undecodable", str(error))
            return
        if not np.isfinite(values).all():
            self._reject("nonfinite")
            return
        if self._in_range is not None and not self._in_range(values):
            self._reject("out_of_range")
            return
        now = self._clock()
        with self._lock:
            disorder = self._disorder(stamp, now)
            if disorder is None:
                self._accept(values, stamp, now)
        if disorder is not None:
            self._reject(disorder)
            return
        self.first.set()

    def _disorder(self, stamp: tuple[float, int] | None, now: float) -> str | None:
        """Why a stamped message is out of order (module docstring), or None; under the lock."""
        newest, since = self._newest_stamp, now - self.receipt_time
        if stamp is None or newest is None or since > self._takeover_silence:
            return None
        (t, sequence), (t_newest, sequence_newest) = stamp, newest
        if sequence <= sequence_newest or t < t_newest:
            return "out_of_order"
        allowed = since + self._max_clock_lead
        if t - t_newest > allowed or sequence - sequence_newest > self._max_sequence_rate * allowed:
            return "stamp_ahead"
        return None

    def _accept(self, values: np.ndarray, stamp: tuple[float, int] | None, now: float) -> None:
        """Takes a valid message in; under the lock."""
        if self._sticky_max and not self._taken and self.values is not None:
            values = np.maximum(values, self.values)
        self._taken = False
        self.values = values
        self.received += 1
        self.receipt_time = now
        self._newest_stamp = stamp

    def snapshot(self) -> tuple[np.ndarray | None, int, int, float]:
        """(newest values or None, messages received, messages rejected, receipt time [s])."""
        with self._lock:
            self._taken = True
            return self.values, self.received, self._dropped, self.receipt_time

    def counts(self) -> dict:
        with self._lock:
            return {
                "received": self.received,
                "dropped": self._dropped,
                "rejected": {reason: n for reason, n in zip(REJECT_REASONS, self.rejected, strict=True) if n},
            }


# The status channels' values: [q, qd, tau_est] (36) and [quat, omegaBody, aBody, contact_estimate] (14).
LEG_CONTROL_FIELDS = ("q", "qd", "tau_est")
STATE_ESTIMATOR_FIELDS = ("quat", "omegaBody", "aBody", "contact_estimate")


def _estop_vector(fields: tuple[str, ...]) -> Callable[[object], np.ndarray]:
    for field in fields:
        if field not in c.CHANNEL_TYPES[c.RC_COMMAND_CHANNEL].__slots__:
            raise ValueError(f"rc_command_lcmt has no field {field!r}")

    # Only the switches are used (int16 on the wire, always finite): NaN sticks do not hide a press.
    def to_vector(message) -> np.ndarray:
        return np.array([1.0 if any(getattr(message, f) != 0 for f in fields) else 0.0])

    return to_vector


@dataclasses.dataclass
class LoopTiming:
    """The loop's publications: the wall time of each [s], its offset from its tick's schedule
    (wall time - diagram time / realtime rate) [s], its diagram time [s] and the loop thread's CPU
    time then, less what it spent busy-waiting [s]. Lateness follows in `report`: the offset less
    the earliest offset so far (the Simulator never runs ahead of its schedule, so the earliest
    tick sets the schedule's anchor);
    inter-departure times are the differences of the times, and the loop's CPU time between two
    publications tells a stall in which the loop computed from one in which it waited."""

    # array('d'): 8 bytes a tick and no Python objects for the garbage collector to walk.
    departures: array.array = dataclasses.field(default_factory=lambda: array.array("d"))
    offsets: array.array = dataclasses.field(default_factory=lambda: array.array("d"))
    times: array.array = dataclasses.field(default_factory=lambda: array.array("d"))
    loop_cpu: array.array = dataclasses.field(default_factory=lambda: array.array("d"))


def lateness_against_earliest(offsets) -> np.ndarray:
    """Each tick's lateness [s] from its offset to its schedule [s]: against the smallest offset so
    far, which stands for the loop's on-time tick (the offsets share an unknown constant, the
    time a tick takes when nothing delays it)."""
    offsets = np.asarray(offsets, dtype=float)
    return offsets - np.minimum.accumulate(offsets) if len(offsets) else offsets


def distribution_ms(values) -> dict | None:
    """Median, p99, p99.9 and max [ms] of `values` [s]; None when there are none."""
    if len(values) == 0:
        return None
    x = 1e3 * np.asarray(values)
    return {
        "median": float(np.median(x)),
        "p99": float(np.percentile(x, 99)),
        "p99_9": float(np.percentile(x, 99.9)),
        "max": float(np.max(x)),
    }


class Go1Link:
    """The bus to the Go1: status inboxes filled by the loop (and by a thread while it is late),
    commands out, the guard.

    `transport`: an `lcm.LCM` (or anything with its subscribe / publish / handle_timeout).
    `config`: the driver's settings (period, watchdogs, damping gain).
    """

    def __init__(
        self,
        transport,
        config: Go1DriverConfig,
        *,
        url: str = "",
        threaded: bool = True,
        clock: Callable[[], float] = time.monotonic,
    ):
        self._transport = transport
        self.url = url
        self._config = config
        self._period = config.safety.period
        self._limits = SafetyLimits.from_config(config.safety)
        self._shortest_command_timeout = min(config.safety.command_timeout, config.safety.warmup_command_timeout)
        self._threaded = threaded
        self._clock = clock
        self._publish_lock = threading.Lock()
        self._receive_lock = threading.Lock()  # the transport is read by one thread at a time
        # How many looks at the socket each side made: the thread's should be the loop's late ticks.
        self._looks = {"loop": 0, "thread": 0}
        # The pace of the loop against the wall clock (the Simulator's target real-time rate).
        self.realtime_rate = 1.0
        # The loop's scheduling while it ran (see pedi_drake.runtime.realtime_priority), for the report.
        self.scheduling = "normal scheduling"
        # CPU time the loop spent busy-waiting for its periods (go1_driver.wait: spin) [s]: not
        # counted as the loop's work in the report's stalls.
        self.busy_wait_cpu = 0.0
        self.leg_control = self._add(
            c.LEG_CONTROL_CHANNEL, FloatFields(c.CHANNEL_TYPES[c.LEG_CONTROL_CHANNEL], LEG_CONTROL_FIELDS)
        )
        self.state_estimator = self._add(
            c.STATE_ESTIMATOR_CHANNEL, FloatFields(c.CHANNEL_TYPES[c.STATE_ESTIMATOR_CHANNEL], STATE_ESTIMATOR_FIELDS)
        )
        self.rc_command = self._add(
            c.RC_COMMAND_CHANNEL, _estop_vector(tuple(config.safety.rc_estop_fields)), sticky_max=True
        )
        self.last_look = -math.inf
        self._timing = LoopTiming()
        self._last_publish: float | None = None  # wall time of the loop's last publication [s]
        self.guard_latched: str | None = None  # why the link itself put damping on the wire
        self._guard_published = 0
        self._shutdown_published = 0
        self._message_id = 0
        self._encoder = c.CommandEncoder()
        # Every message published, when a replay asked for them (keep_sent_messages).
        self.sent_messages: list[bytes] | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def config(self) -> Go1DriverConfig:
        return self._config

    @property
    def transport(self):
        """The bus itself (an `lcm.LCM`): for a replay on an in-process bus, which it shares."""
        return self._transport

    @staticmethod
    def from_url(url: str, config: Go1DriverConfig, *, threaded: bool = True) -> "Go1Link":
        return Go1Link(lcm_module.LCM(url), config, url=url, threaded=threaded)

    def _add(self, channel: str, to_vector, sticky_max: bool = False) -> Inbox:
        inbox = Inbox(channel, c.CHANNEL_TYPES[channel], to_vector, sticky_max=sticky_max, clock=self._clock)
        subscription = self._transport.subscribe(channel, lambda _channel, data: inbox.handle(data))
        if subscription is not None and hasattr(subscription, "set_queue_capacity"):
            subscription.set_queue_capacity(QUEUE_CAPACITY)
        return inbox

    @property
    def inboxes(self) -> tuple[Inbox, Inbox, Inbox]:
        """In the order of constants.STATUS_CHANNELS."""
        return self.leg_control, self.state_estimator, self.rc_command

    # -- receiving ---------------------------------------------------------------------------

    def start(self) -> None:
        """Starts the receive thread (idempotent; without `threaded` nothing to start)."""
        if not self._threaded or self._thread is not None:
            return
        self._stop.clear()
        self._thread = threading.Thread(
            target=_receive_loop, args=(weakref.ref(self), self._stop), name="go1_link_receive", daemon=True
        )
        self._thread.start()

    @property
    def loop_timing(self) -> LoopTiming:
        """The loop's publications so far, as `report` summarises them (read, do not modify)."""
        return self._timing

    def receive_cpu_time(self) -> float:
        """The CPU time the running receive thread has used so far [s]; 0 without one."""
        thread = self._thread
        if thread is None or thread.ident is None:
            return 0.0
        return time.clock_gettime(time.pthread_getcpuclockid(thread.ident))

    def close(self) -> None:
        """Stops the receive thread (the counts and timings stay readable)."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(1.0)
        self._thread = None

    def _look(self, by: str) -> None:
        """Handles every pending message, then stamps the look (`by`: "loop" or "thread")."""
        with self._receive_lock:
            while self._transport.handle_timeout(0) > 0:
                pass
            self.last_look = self._clock()
            self._looks[by] += 1

    def _look_if_the_loop_is_late(self) -> None:
        """The thread's look: only when the loop has not looked for LOOP_LOOK_LATE periods."""
        if self._clock() - self.last_look > LOOP_LOOK_LATE * self._period / self.realtime_rate:
            self._look("thread")

    def poll(self) -> None:
        """Handles what is pending (called by the loop at the start of every tick)."""
        self._look("loop")

    def silence(self, inbox: Inbox) -> float:
        """How long `inbox`'s channel has been silent when the receiver last looked [s] (inf before any)."""
        return max(0.0, self.last_look - inbox.receipt_time) if inbox.receipt_time > -math.inf else math.inf

    def wait_for_first(self, inbox: Inbox, timeout: float) -> bool:
        """Blocks until `inbox` has a valid message or `timeout` [s] passes; True when one came."""
        self.start()
        deadline = time.monotonic() + timeout
        while not inbox.first.is_set():
            remaining = deadline - time.monotonic()
            if remaining <= 0.0:
                return False
            if self._threaded:
                inbox.first.wait(min(remaining, 0.05))
            else:
                self._transport.handle_timeout(max(1, min(50, int(remaining * 1000))))
        return True

    # -- sending -----------------------------------------------------------------------------

    def _publish(self, command: np.ndarray, t_us: int) -> bool:
        """Puts `command` on the wire; False (nothing sent) when a value of it is not finite."""
        data = self._encoder.encode(command, t_us, self._message_id)
        if data is None:
            return False
        self._message_id += 1
        self._transport.publish(c.COMMAND_CHANNEL, data)
        if self.sent_messages is not None:
            self.sent_messages.append(data)
        return True

    def keep_sent_messages(self) -> None:
        """From now on every message this link publishes (the loop's and the guard's) is also kept
        in `sent_messages`, in order. For a replay that checks what went on the wire: a subscriber
        to the command channel on the link's own bus would wake the receive thread at every
        command, work a hardware run's driver does not do (nothing in its process subscribes)."""
        if self.sent_messages is None:
            self.sent_messages = []

    def _damping(self) -> np.ndarray:
        values = self.leg_control.snapshot()[0]
        q, qd = (values[0:12], values[12:24]) if values is not None else (np.zeros(12), np.zeros(12))
        return damping_command(q, qd, self._limits, self._config.safety.damping_kd)

    def publish_command(self, command: np.ndarray, t: float) -> bool:
        """Publishes the loop's (bounded) command of diagram time `t` [s] and stamps its lateness.

        A command with a non-finite value is refused: False, nothing sent or stamped (the guard
        then damps if the loop stays silent). After the guard latched, damping goes out instead:
        the loop's command is no longer trusted.
        """
        now = self._clock()
        with self._publish_lock:
            if self.guard_latched is not None:
                if not np.isfinite(command).all():
                    return False
                command = self._damping()
            if not self._publish(command, int(round(t * 1e6))):
                return False
            self._last_publish = now
        timing = self._timing
        timing.departures.append(now)
        timing.offsets.append(now - t / self.realtime_rate)
        timing.times.append(t)
        timing.loop_cpu.append(time.thread_time() - self.busy_wait_cpu)
        return True

    def _guard(self) -> None:
        """Runs on the receive thread at every wake: damping when the loop went silent."""
        if self._last_publish is None or self._stop.is_set():
            return
        now = self._clock()
        if self.guard_latched is None and now - self._last_publish <= self._shortest_command_timeout:
            # The loop published lately: nothing to do, and no wait for the lock the loop holds
            # while it publishes.
            return
        with self._publish_lock:
            silent = now - self._last_publish
            elapsed = self._message_id * self._period
            if self.guard_latched is None and silent > command_timeout(self._config.safety, elapsed):
                self.guard_latched = "controller_silence"
                _log.error("Go1 driver: the control loop has not published for %.0f ms, damping", 1e3 * silent)
            if self.guard_latched is not None and silent >= self._period:
                self._publish(self._damping(), 0)
                self._guard_published += 1
                self._last_publish = now

    def hold_damping(self, duration: float) -> int:
        """Puts damping (kp 0, kd > 0, tau 0) on the wire every period for `duration` [s]; returns
        the number sent. The loop's commands are refused from now on (the guard latches "shutdown")."""
        with self._publish_lock:
            if self.guard_latched is None:
                self.guard_latched = "shutdown"
        sent = 0
        end = time.monotonic() + max(duration, 0.0)
        while True:
            with self._publish_lock:
                self._publish(self._damping(), 0)
                self._last_publish = self._clock()
            sent += 1
            if time.monotonic() >= end:
                break
            time.sleep(self._period)
        self._shutdown_published += sent
        return sent

    # -- reporting ---------------------------------------------------------------------------

    def report(self) -> dict:
        """Messages by channel (received, dropped, rejected by reason), the loop's timing, the guard."""
        lateness = lateness_against_earliest(self._timing.offsets)
        misses = int(np.count_nonzero(lateness > self._period))
        return {
            "messages": {inbox.channel: inbox.counts() for inbox in self.inboxes},
            "loop": {
                "period_s": self._period,
                "scheduling": self.scheduling,
                "wait": self._config.wait,
                "busy_wait_cpu_s": self.busy_wait_cpu,
                "ticks": len(lateness),
                "lateness_ms": distribution_ms(lateness),
                "deadline_misses": misses,
                "deadline_misses_per_1000": 1000.0 * misses / len(lateness) if len(lateness) else 0.0,
                "longest_miss_ms": float(1e3 * lateness.max()) if misses else 0.0,
                "command_interdeparture_ms": distribution_ms(np.diff(np.asarray(self._timing.departures))),
                "stalls": loop_stalls(self._timing, self._period),
                "status_reads": dict(self._looks),
            },
            "guard": {
                "latched": self.guard_latched,
                "damping_sent": self._guard_published,
                "shutdown_damping_sent": self._shutdown_published,
            },
        }


# A gap between two publications longer than this many periods is a stall of the loop.
STALL_PERIODS = 2.0
# The longest stalls kept in a report.
STALLS_REPORTED = 20


def loop_stalls(timing: LoopTiming, period: float) -> dict:
    """The loop's stalls: gaps of more than STALL_PERIODS periods between two publications.

    `count`; `computing` and `waiting`: how many of them the loop thread spent mostly computing
    (its CPU time over half the gap: its own work was long) or mostly not (it waited: for a
    core, the interpreter lock, the kernel); `longest`: the STALLS_REPORTED longest, each the
    diagram time of the publication that ended it [s], the gap and the loop's CPU time in it [ms].
    """
    gaps = np.diff(np.asarray(timing.departures))
    cpu = np.diff(np.asarray(timing.loop_cpu))
    stalled = np.flatnonzero(gaps > STALL_PERIODS * period)
    computing = int(np.count_nonzero(cpu[stalled] > 0.5 * gaps[stalled]))
    longest = stalled[np.argsort(gaps[stalled])[::-1][:STALLS_REPORTED]]
    times = np.asarray(timing.times)
    return {
        "count": len(stalled),
        "computing": computing,
        "waiting": len(stalled) - computing,
        "longest": [
            {"t": float(times[k + 1]), "gap_ms": float(1e3 * gaps[k]), "loop_cpu_ms": float(1e3 * cpu[k])}
            for k in longest
        ],
    }


def _receive_loop(link_ref: "weakref.ref[Go1Link]", stop: threading.Event) -> None:
    # Holds the link only while looking, so a link nobody uses any more is collected and the
    # thread ends with it.
    while not stop.wait(RECEIVE_POLL_PERIOD):
        link = link_ref()
        if link is None:
            return
        try:
            link._look_if_the_loop_is_late()
            link._guard()
        except Exception:  # the thread must outlive anything a message or the transport does
            _log.exception("Go1 link receive thread")
        del link


class DrakeLcmTransport:
    """A DrakeLcm as a Go1Link transport, for a link polled by the loop (`threaded=False`).

    For lock-step runs in one process, where the simulator bridge's diagram and the driver share
    one in-process bus (`DrakeLcm("memq://")`); DrakeLcm dispatches only when polled, so it has
    no file descriptor for a receive thread.
    """

    def __init__(self, lcm):
        self.lcm = lcm

    def subscribe(self, channel: str, handler: Callable[[str, bytes], None]) -> None:
        self.lcm.Subscribe(channel, lambda data: handler(channel, data))

    def publish(self, channel: str, data: bytes) -> None:
        self.lcm.Publish(channel, data)

    def handle_timeout(self, timeout_ms: int) -> int:
        return self.lcm.HandleSubscriptions(timeout_ms)
