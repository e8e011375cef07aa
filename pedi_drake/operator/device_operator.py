"""DeviceOperator: a haptic device and its adapter as an operator in a diagram's lock step.

Every `period` of diagram time it advances a simulated device (`SpringDevice.step`) and runs
one adapter cycle (pedi_drake.operator.haptic_device.DeviceAdapter.step) on an in-process LCM
bus shared with the controller's operator input and feedback, so a simulation and its operator
run in one process without the wall clock (tests, benchmarks). `hand_targets`: (start [s],
where the hand wants the handle [m]) steps, the last one started in force.
"""

import numpy as np
from pydrake.systems.framework import EventStatus

from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.operator.haptic_device import DeviceAdapter, SpringDevice


class DeviceOperator(LeafSystemWithoutWitnesses):
    """A SpringDevice, its hand and its DeviceAdapter, stepped every `period` [s] (module docstring)."""

    def __init__(
        self,
        adapter: DeviceAdapter,
        device: SpringDevice,
        hand_targets: list[tuple[float, tuple[float, float, float]]],
        period: float = 0.01,
    ):
        super().__init__()
        self.adapter, self.device, self._period = adapter, device, period
        self._targets = sorted(hand_targets)
        # What the hand and the handle did, for the caller: (t [s], offset [m], rendered force [N]).
        self.trace: list[tuple[float, np.ndarray, np.ndarray]] = []
        self.DeclarePeriodicPublishEvent(period, 0.0, self._step)

    def _step(self, context) -> EventStatus:
        t = context.get_time()
        for start, target in self._targets:
            if start <= t:
                self.device.hand_target = np.asarray(target, float)
        self.device.step(self._period)
        self.adapter.step(t)
        self.trace.append((t, self.device.offset.copy(), self.device.rendered.copy()))
        return EventStatus.Succeeded()
