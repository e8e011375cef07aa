"""DeviceOperator: a simulated haptic device and its adapter as an operator in a diagram's lock step.

Every `period` of diagram time a discrete update advances the SpringDevice's handle from the
state in the Context and runs one adapter cycle (pedi_drake.operator.haptic_device.
DeviceAdapter.step) on an in-process LCM bus shared with the controller's operator input and
feedback, so a simulation and its operator run in one process without the wall clock (tests,
benchmarks). `hand_targets`: (start [s], where the hand wants the handle [m]) steps, the last
one started in force; `button_release`: when the hand lets go of the button [s].

Discrete state and the `handle` output (9): [offset (3) [m], velocity (3) [m/s], rendered force
(3) [N]]. The adapter's side (the feedback it last heard, its message count) lives with the
LCM bus, outside the simulation, as a real device's driver does.
"""

import dataclasses
import math

import numpy as np
from pydrake.systems.framework import DiscreteValues

from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.operator.haptic_device import DeviceAdapter, SpringDevice

HANDLE_SIZE = 9


class DeviceOperator(LeafSystemWithoutWitnesses):
    """A SpringDevice, its hand and its DeviceAdapter, stepped every `period` [s] (module docstring)."""

    def __init__(
        self,
        adapter: DeviceAdapter,
        device: SpringDevice,
        hand_targets: list[tuple[float, tuple[float, float, float]]],
        period: float = 0.01,
        button_release: float = math.inf,
    ):
        """`device` gives the handle's constants (mass, the hand's stiffness and damping); its
        state is the Context's. `adapter` must drive `device`."""
        super().__init__()
        self._adapter, self._device, self._period = adapter, device, period
        self._targets = sorted(hand_targets)
        self._release = button_release
        self._state = self.DeclareDiscreteState(HANDLE_SIZE)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._step)
        self.DeclareStateOutputPort("handle", self._state)

    def _step(self, context, discrete_state: DiscreteValues) -> None:
        t = context.get_time()
        x = context.get_discrete_state(self._state).get_value()
        target = np.zeros(3)
        for start, where in self._targets:
            if start <= t:
                target = np.asarray(where, float)
        # The device object is the adapter's view of the handle: loaded from the Context, stepped,
        # and its new state written back (nothing carries over in it between updates).
        device = dataclasses.replace(
            self._device,
            hand_target=target,
            offset=x[0:3].copy(),
            velocity=x[3:6].copy(),
            rendered=x[6:9].copy(),
            button=t < self._release,
        )
        self._adapter.device = device
        device.step(self._period)
        self._adapter.step(t)
        discrete_state.set_value(self._state, np.concatenate([device.offset, device.velocity, device.rendered]))
