"""Standalone ticks of either whole-body controller on a robot standing in its initial pose."""

import numpy as np

from pedi_drake import robot
from pedi_drake.scenario import RobotConfig
from pedi_drake.station.initial_state import initial_trunk_pose


def standing_context(controller):
    """A new Context of `controller` whose state estimate and joint readings are the Go1 standing
    still in its initial pose (the other inputs unconnected)."""
    context = controller.CreateDefaultContext()
    X = initial_trunk_pose(RobotConfig(initial_pose="standing"))
    base = np.concatenate([X.rotation().ToQuaternion().wxyz(), X.translation(), np.zeros(6)])
    controller.base_state_port.FixValue(context, base)
    controller.position_port.FixValue(context, robot.STANDING_Q)
    controller.velocity_port.FixValue(context, np.zeros(12))
    return context


def tick(controller, context, n: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """(command, diagnostics) after `n` forced ticks of `controller` on `context`."""
    values = controller.AllocateDiscreteVariables()
    for _ in range(n):
        controller.CalcForcedDiscreteVariableUpdate(context, values)
        context.SetDiscreteState(values)
    return controller.command_port.Eval(context).copy(), controller.diagnostics_port.Eval(context).copy()
