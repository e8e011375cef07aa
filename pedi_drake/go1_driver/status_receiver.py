"""Receivers of Go1 LCM messages: latch the newest valid message of a channel into the Context.

`Go1LcmReceiver` reads one `Inbox` (pedi_drake.go1_driver.link): on the driver the link's receive
thread fills it, checking, decoding and time-stamping each message as it arrives; on the
simulator bridge a DrakeLcm subscription does. A periodic update at the control rate copies the
inbox into the discrete state, so outputs are functions of the Context only. Messages of the
wrong size or fingerprint, that fail to decode or carry NaN, are dropped and counted by reason:
a foreign publisher on the channel can never crash the driver.

Factories build the three receivers the driver uses (Unitree motor order throughout):
  leg_control_data      -> position_measured [rad], velocity_measured [rad/s], torque_estimated [N m]
  state_estimator_data  -> imu (quat w,x,y,z; gyro [rad/s]; accelerometer [m/s^2]), foot_contact (raw)
  rc_command            -> estop (1 while a configured switch of the remote is on)
"""

import logging
import math
import time

import numpy as np
from pydrake.systems.framework import BasicVector, DiscreteValues, LeafSystem

from pedi_drake.exceptions import LcmTimeout
from pedi_drake.go1_driver.link import Go1Link, Inbox

_log = logging.getLogger(__name__)


class Go1LcmReceiver(LeafSystem):
    """One channel's inbox -> vector outputs, latched at the control rate.

    Discrete state: [values (n), messages received, messages dropped, silence [s]].
    Outputs: one vector port per entry of `outputs` (name -> slice of the values), plus
      silence (1): how long the channel had been silent when last looked at [s] (inf before any
        message); with a `link`, judged by its receive thread's clock (Go1Link.silence), so a late
        tick of the loop does not make the robot look silent;
      message_counts (2): [received, dropped].
    With `wait_timeout` > 0 (needs a `link`), initialisation blocks until a first message arrives
    and raises LcmTimeout naming the channel and URL when none does.
    """

    def __init__(
        self,
        inbox: Inbox,
        initial_values: np.ndarray,
        outputs: dict[str, slice],
        *,
        link: Go1Link | None = None,
        period: float,
        wait_timeout: float = 0.0,
    ):
        super().__init__()
        self._inbox = inbox
        self._link = link
        self._n = len(initial_values)
        self._wait_timeout = wait_timeout
        self._state = self.DeclareDiscreteState(np.concatenate([initial_values, [0.0, 0.0, math.inf]]))
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._latch)
        self.DeclareInitializationDiscreteUpdateEvent(self._initialize)
        for name, part in outputs.items():
            size = len(range(self._n)[part])
            self.DeclareVectorOutputPort(name, size, self._make_calc(part), {self.xd_ticket()})
        self.DeclareVectorOutputPort("silence", 1, self._make_calc(slice(self._n + 2, self._n + 3)))
        self.DeclareVectorOutputPort("message_counts", 2, self._make_calc(slice(self._n, self._n + 2)))

    @property
    def channel(self) -> str:
        return self._inbox.channel

    def _make_calc(self, part: slice):
        def calc(context, output: BasicVector) -> None:
            output.SetFromVector(context.get_discrete_state(self._state).get_value()[part])

        return calc

    def _latch(self, context, discrete_state: DiscreteValues) -> None:
        if self._link is not None:
            self._link.poll()
        values, received, dropped, receipt_time = self._inbox.snapshot()
        if self._link is not None:
            silence = self._link.silence(self._inbox)
        else:
            silence = time.monotonic() - receipt_time
        x = context.get_discrete_state(self._state).get_value().copy()
        if values is not None:
            x[: self._n] = values
        x[self._n :] = [received, dropped, silence]
        discrete_state.set_value(self._state, x)

    def _initialize(self, context, discrete_state: DiscreteValues) -> None:
        if self._wait_timeout > 0.0 and self._link is not None:
            if not self._link.wait_for_first(self._inbox, self._wait_timeout):
                raise LcmTimeout(
                    f"no valid message on LCM channel {self.channel!r} at {self._link.url} "
                    f"within {self._wait_timeout:g} s: is the Go1 bridge (or "
                    "`python -m pedi_drake.apps.sim_bridge`) running on that URL?"
                )
        self._latch(context, discrete_state)


def MakeLegControlReceiver(link: Go1Link, **kwargs) -> Go1LcmReceiver:
    """leg_control_data -> position_measured, velocity_measured, torque_estimated (12 each)."""
    return Go1LcmReceiver(
        link.leg_control,
        np.zeros(36),
        {"position_measured": slice(0, 12), "velocity_measured": slice(12, 24), "torque_estimated": slice(24, 36)},
        link=link,
        **kwargs,
    )


def MakeStateEstimatorReceiver(link: Go1Link, **kwargs) -> Go1LcmReceiver:
    """state_estimator_data -> imu (10: quat w,x,y,z, gyro, accelerometer), foot_contact (4)."""
    initial = np.zeros(14)
    initial[0] = 1.0  # identity orientation until the first message
    return Go1LcmReceiver(
        link.state_estimator, initial, {"imu": slice(0, 10), "foot_contact": slice(10, 14)}, link=link, **kwargs
    )


def MakeRcCommandReceiver(link: Go1Link, **kwargs) -> Go1LcmReceiver:
    """rc_command -> estop (1): 1 while any of the link's E-stop switch fields is on."""
    return Go1LcmReceiver(link.rc_command, np.zeros(1), {"estop": slice(0, 1)}, link=link, **kwargs)
