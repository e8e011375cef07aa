"""Receivers of Go1 LCM messages: decode defensively, latch the latest values into the Context.

`Go1LcmReceiver` subscribes to one channel on a DrakeLcm. Its handler (run by the diagram's
LcmInterfaceSystem, or by the wait at initialisation) decodes each message and keeps the newest
in an inbox, the way Drake's LcmSubscriberSystem keeps its received message; a periodic update
at the control rate copies the inbox into the discrete state, so outputs are functions of the
Context only. Messages of the wrong size or fingerprint, or that fail to decode, are dropped
and counted: a foreign publisher on the channel can never crash the driver.

Factories build the three receivers the driver uses (Unitree motor order throughout):
  leg_control_data      -> position_measured [rad], velocity_measured [rad/s], torque_estimated [N m]
  state_estimator_data  -> imu (quat w,x,y,z; gyro [rad/s]; accelerometer [m/s^2]), foot_contact (raw)
  rc_command            -> estop (1 while a configured switch of the remote is on)
"""

import logging
import math
import threading
import time
from collections.abc import Callable, Sequence

import numpy as np
from pydrake.lcm import DrakeLcmInterface
from pydrake.systems.framework import BasicVector, DiscreteValues, LeafSystem

from pedi_drake.exceptions import LcmTimeout
from pedi_drake.go1_driver import constants as c

_log = logging.getLogger(__name__)


class _Inbox:
    """The newest valid message of one channel and the message counts, filled by the LCM handler.

    This is the I/O boundary (like LcmSubscriberSystem's received message): it only mirrors what
    arrived; the system's Context takes a copy at every update.
    """

    def __init__(self, channel: str, lcm_type, to_vector: Callable[[object], np.ndarray], clock, sticky_max: bool):
        self.channel = channel
        # sticky_max: keep the element-wise maximum of the values that arrived since the last
        # snapshot, so a button pressed between two control ticks is never missed.
        self._sticky_max = sticky_max
        self._taken = True
        self._type = lcm_type
        self._size = c.REFERENCE_ENCODED_SIZE[lcm_type.__name__]
        self._to_vector = to_vector
        self._clock = clock
        self._lock = threading.Lock()
        self.values: np.ndarray | None = None
        self.received = 0
        self.malformed = 0
        self.receipt_time = -math.inf

    def handle(self, data: bytes) -> None:
        try:
            if len(data) != self._size:
                raise ValueError(f"{len(data)} bytes, expected {self._size}")
            values = np.asarray(self._to_vector(self._type.decode(data)), dtype=float)
        except Exception as error:  # a foreign or truncated message: drop it, count it, carry on
            with self._lock:
                self.malformed += 1
                count = self.malformed
            if count == 1 or math.log10(count).is_integer():
                _log.warning("dropped malformed message on %s (%s); %d so far", self.channel, error, count)
            return
        now = self._clock()
        with self._lock:
            if self._sticky_max and not self._taken and self.values is not None:
                values = np.maximum(values, self.values)
            self._taken = False
            self.values = values
            self.received += 1
            self.receipt_time = now

    def snapshot(self) -> tuple[np.ndarray | None, int, int, float]:
        with self._lock:
            self._taken = True
            return self.values, self.received, self.malformed, self.receipt_time


class Go1LcmReceiver(LeafSystem):
    """One LCM channel -> vector outputs, latched at the control rate.

    Discrete state: [values (n), messages received, messages dropped, receipt wall time [s]].
    Outputs: one vector port per entry of `outputs` (name -> slice of the values), plus
      receipt_time (1): time.monotonic() when the latched message arrived (-inf before any);
      message_counts (2): [received, dropped as malformed].
    With `sticky_max`, values that arrive between two ticks are merged by element-wise maximum.
    With `wait_timeout` > 0, initialisation blocks until a first message arrives and raises
    LcmTimeout naming the channel and URL when none does.
    """

    def __init__(
        self,
        lcm: DrakeLcmInterface,
        channel: str,
        lcm_type,
        to_vector: Callable[[object], np.ndarray],
        initial_values: np.ndarray,
        outputs: dict[str, slice],
        *,
        period: float = c.BRIDGE_PERIOD,
        wait_timeout: float = 0.0,
        sticky_max: bool = False,
        clock: Callable[[], float] = time.monotonic,
    ):
        super().__init__()
        self._lcm = lcm
        self._channel = channel
        self._n = len(initial_values)
        self._wait_timeout = wait_timeout
        self._inbox = _Inbox(channel, lcm_type, to_vector, clock, sticky_max)
        lcm.Subscribe(channel, self._inbox.handle)
        self._state = self.DeclareDiscreteState(np.concatenate([initial_values, [0.0, 0.0, -math.inf]]))
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._latch)
        self.DeclareInitializationDiscreteUpdateEvent(self._initialize)
        for name, part in outputs.items():
            size = len(range(self._n)[part])
            self.DeclareVectorOutputPort(name, size, self._make_calc(part), {self.xd_ticket()})
        self.DeclareVectorOutputPort("receipt_time", 1, self._make_calc(slice(self._n + 2, self._n + 3)))
        self.DeclareVectorOutputPort("message_counts", 2, self._make_calc(slice(self._n, self._n + 2)))

    @property
    def channel(self) -> str:
        return self._channel

    def _make_calc(self, part: slice):
        def calc(context, output: BasicVector) -> None:
            output.SetFromVector(context.get_discrete_state(self._state).get_value()[part])

        return calc

    def _latch(self, context, discrete_state: DiscreteValues) -> None:
        values, received, malformed, receipt_time = self._inbox.snapshot()
        x = context.get_discrete_state(self._state).get_value().copy()
        if values is not None:
            x[: self._n] = values
        x[self._n :] = [received, malformed, receipt_time]
        discrete_state.set_value(self._state, x)

    def _initialize(self, context, discrete_state: DiscreteValues) -> None:
        if self._wait_timeout > 0.0:
            deadline = time.monotonic() + self._wait_timeout
            while self._inbox.snapshot()[0] is None:
                remaining = deadline - time.monotonic()
                if remaining <= 0.0:
                    raise LcmTimeout(
                        f"no valid message on LCM channel {self._channel!r} at {self._lcm.get_lcm_url()} "
                        f"within {self._wait_timeout:g} s: is the Go1 bridge (or "
                        "`python -m pedi_drake.apps.sim_bridge`) running on that URL?"
                    )
                self._lcm.HandleSubscriptions(max(1, min(50, int(remaining * 1000))))
        self._latch(context, discrete_state)


def _leg_control_vector(message) -> np.ndarray:
    return np.concatenate([message.q, message.qd, message.tau_est])


def _state_estimator_vector(message) -> np.ndarray:
    return np.concatenate([message.quat, message.omegaBody, message.aBody, message.contact_estimate])


def MakeLegControlReceiver(lcm: DrakeLcmInterface, **kwargs) -> Go1LcmReceiver:
    """leg_control_data -> position_measured, velocity_measured, torque_estimated (12 each)."""
    return Go1LcmReceiver(
        lcm,
        c.LEG_CONTROL_CHANNEL,
        c.CHANNEL_TYPES[c.LEG_CONTROL_CHANNEL],
        _leg_control_vector,
        np.zeros(36),
        {"position_measured": slice(0, 12), "velocity_measured": slice(12, 24), "torque_estimated": slice(24, 36)},
        **kwargs,
    )


def MakeStateEstimatorReceiver(lcm: DrakeLcmInterface, **kwargs) -> Go1LcmReceiver:
    """state_estimator_data -> imu (10: quat w,x,y,z, gyro, accelerometer), foot_contact (4)."""
    initial = np.zeros(14)
    initial[0] = 1.0  # identity orientation until the first message
    return Go1LcmReceiver(
        lcm,
        c.STATE_ESTIMATOR_CHANNEL,
        c.CHANNEL_TYPES[c.STATE_ESTIMATOR_CHANNEL],
        _state_estimator_vector,
        initial,
        {"imu": slice(0, 10), "foot_contact": slice(10, 14)},
        **kwargs,
    )


def MakeRcCommandReceiver(lcm: DrakeLcmInterface, estop_fields: Sequence[str], **kwargs) -> Go1LcmReceiver:
    """rc_command -> estop (1): 1 while any of `estop_fields` (switch fields of rc_command_lcmt) is on."""
    fields = tuple(estop_fields)
    for field in fields:
        if field not in c.CHANNEL_TYPES[c.RC_COMMAND_CHANNEL].__slots__:
            raise ValueError(f"rc_command_lcmt has no field {field!r}")

    def to_vector(message) -> np.ndarray:
        return np.array([1.0 if any(getattr(message, f) != 0 for f in fields) else 0.0])

    return Go1LcmReceiver(
        lcm,
        c.RC_COMMAND_CHANNEL,
        c.CHANNEL_TYPES[c.RC_COMMAND_CHANNEL],
        to_vector,
        np.zeros(1),
        {"estop": slice(0, 1)},
        sticky_max=True,
        **kwargs,
    )
