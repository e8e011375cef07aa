"""MeshcatOperatorPanel: the operator's command from controls in the Meshcat page (`operator: {source: meshcat}`).

The panel adds to the Meshcat's control pane (`run_sim.py --meshcat --teleop` opens it):

  sliders  the foot velocity along x, y, z [m/s] (the scenario's `operator.meshcat.frame`), each
           in [-max_speed, max_speed]; keys w/s, a/d, r/f step them (as pedi_drake.apps.teleop_lcm);
           with `operator.meshcat.sliders: walk` the trunk's twist for a walk_teleop phase
           instead (forward, sideways [m/s], yaw rate [rad/s], each within +-walk_speeds), the
           keys w/s, a/d, q/z
  buttons  "Teleop (t)" and "Autonomous (g)" ask for a mode, "Stop foot (space)" sets the sliders
           to zero, "E-stop (e)" latches the E-stop; with `controller_buttons` (a scenario with
           controller_switch, pedi_drake.control.controller_switch) "HQP controller (1)" and
           "Paper 002 controller (2)" ask for a whole-body controller

and reads them at its period into the same `operator_command` port as OperatorInput (layout in
pedi_drake.operator.command), so the mission manager and the E-stop gate cannot tell the sources
apart. A button counts clicks (Meshcat keeps the count): every click since the last update is
taken, so a click between two updates is never missed; with both mode buttons clicked in one
period the autonomous mission wins (the foot goes back rather than out).

The heartbeat: the operator is there while a browser is connected to the Meshcat (`age` is the
time since the last update that saw a connection). A closed tab or a lost network is a silent
operator: the teleoperated foot holds, then returns to support, as with a silent LCM source.

What the page sends is checked as an LCM message is: a slider value that is not finite or lies
outside the slider's range (the page cannot send one, but the WebSocket carries whatever a client
writes) is dropped and counted by reason (`counts()`), and the slider is put back to the value in
force, so the page shows the command the robot follows. `received` counts the operator's actions
taken in: clicks, and updates that found the sliders moved.
"""

import math

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.framework import BasicVector, DiscreteValues

from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.operator.command import (
    CONTROLLER_PROJECTED_IMPEDANCE,
    CONTROLLER_WHOLE_BODY,
    FRAME_TRUNK,
    FRAME_WORLD,
    KIND_TWIST,
    KIND_VELOCITY,
    MODE_AUTONOMOUS,
    MODE_TELEOP,
    OPERATOR_COMMAND_SIZE,
)
from pedi_drake.operator.config import MeshcatPanelConfig

# The controls: (label, decrement key, increment key) of each slider, x, y, z; (label, key) of each
# button. Key codes are the browser's KeyboardEvent.code values.
SLIDERS = (
    ("foot x velocity [m/s] (s/w)", "KeyS", "KeyW"),
    ("foot y velocity [m/s] (d/a)", "KeyD", "KeyA"),
    ("foot z velocity [m/s] (f/r)", "KeyF", "KeyR"),
)
WALK_SLIDERS = (
    ("walk forward [m/s] (s/w)", "KeyS", "KeyW"),
    ("walk sideways [m/s] (d/a)", "KeyD", "KeyA"),
    ("walk yaw rate [rad/s] (z/q)", "KeyZ", "KeyQ"),
)
TELEOP_BUTTON = "Teleop (t)"
AUTONOMOUS_BUTTON = "Autonomous (g)"
STOP_BUTTON = "Stop foot (space)"
ESTOP_BUTTON = "E-stop (e)"
WHOLE_BODY_BUTTON = "HQP controller (1)"
PROJECTED_IMPEDANCE_BUTTON = "Paper 002 controller (2)"
BUTTONS = (
    (TELEOP_BUTTON, "KeyT"),
    (AUTONOMOUS_BUTTON, "KeyG"),
    (STOP_BUTTON, "Space"),
    (ESTOP_BUTTON, "KeyE"),
    (WHOLE_BODY_BUTTON, "Digit1"),
    (PROJECTED_IMPEDANCE_BUTTON, "Digit2"),
)
PANEL_REJECT_REASONS = ("nonfinite", "out_of_range")

# Discrete state: the operator_command layout with t_last [s] in place of the age (as OperatorInput).
_MODE, _VALUE, _ESTOP, _T_LAST, _RECEIVED, _DROPPED, _CONTROLLER = 0, slice(3, 6), 6, 7, 8, 9, 10
# A slider value this far beyond the range is rounding, not a foreign value [m/s].
_RANGE_TOLERANCE = 1e-9


class MeshcatOperatorPanel(LeafSystemWithoutWitnesses):
    """The operator's command from the Meshcat panel (port `operator_command`; see the module docstring)."""

    def __init__(self, config: MeshcatPanelConfig, meshcat: Meshcat, period: float, controller_buttons: bool = False):
        """`period`: how often the panel is read [s]; `controller_buttons`: the run has both
        whole-body controllers, and the panel the buttons that switch them."""
        super().__init__()
        self._meshcat = meshcat
        walking = config.sliders == "walk"
        self._sliders = WALK_SLIDERS if walking else SLIDERS
        # Each slider's bound: the foot speed, or the twist's components.
        self._bounds = np.asarray(config.walk_speeds if walking else [config.max_speed] * 3, float)
        for label, _, _ in SLIDERS + WALK_SLIDERS:
            # A Meshcat keeps its controls: a panel made again on it (another run) starts afresh.
            meshcat.DeleteSlider(label, strict=False)
        for (label, decrement, increment), bound in zip(self._sliders, self._bounds, strict=True):
            step = min(config.step, bound / 10.0)
            meshcat.AddSlider(label, -bound, bound, step, 0.0, decrement, increment)
        self._buttons = BUTTONS if controller_buttons else BUTTONS[:4]
        for label, _ in BUTTONS:
            meshcat.DeleteButton(label, strict=False)
        for label, key in self._buttons:
            meshcat.AddButton(label, key)
        initial = np.zeros(OPERATOR_COMMAND_SIZE)
        initial[1] = FRAME_TRUNK if config.frame == "trunk" else FRAME_WORLD
        initial[2] = KIND_TWIST if walking else KIND_VELOCITY
        initial[_T_LAST] = -math.inf
        self._state = self.DeclareDiscreteState(initial)
        # Clicks of each button taken in so far, and drops by reason (PANEL_REJECT_REASONS).
        self._clicks = self.DeclareDiscreteState(len(self._buttons))
        self._rejected = self.DeclareDiscreteState(len(PANEL_REJECT_REASONS))
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._take_in)
        self.DeclareVectorOutputPort(
            "operator_command",
            OPERATOR_COMMAND_SIZE,
            self._calc_command,
            prerequisites_of_calc={self.xd_ticket(), self.time_ticket()},
        )

    def counts(self, context) -> dict:
        """Actions taken in and slider values dropped, the drops by reason, in `context`."""
        x = context.get_discrete_state(self._state).get_value()
        rejected = context.get_discrete_state(self._rejected).get_value()
        return {
            "received": int(x[_RECEIVED]),
            "dropped": int(x[_DROPPED]),
            "rejected": {reason: int(n) for reason, n in zip(PANEL_REJECT_REASONS, rejected, strict=True) if n},
        }

    def _take_in(self, context, discrete_state: DiscreteValues) -> None:
        meshcat = self._meshcat
        x = context.get_discrete_state(self._state).get_value().copy()
        seen = context.get_discrete_state(self._clicks).get_value()
        rejected = context.get_discrete_state(self._rejected).get_value().copy()
        clicks = np.array([meshcat.GetButtonClicks(label) for label, _ in self._buttons], float)
        # A button added again (another panel on this Meshcat) counts from zero again.
        new = np.where(clicks >= seen, clicks - seen, clicks)
        pressed = [k < len(new) and new[k] > 0 for k in range(len(BUTTONS))]
        teleop, autonomous, stop, estop, whole_body, projected_impedance = pressed
        x[_RECEIVED] += new.sum()
        if estop:
            x[_ESTOP] = 1.0
        if autonomous:
            x[_MODE] = MODE_AUTONOMOUS
        elif teleop:
            x[_MODE] = MODE_TELEOP
        # Both clicked in one period: the HQP, the controller every mission runs on.
        if whole_body:
            x[_CONTROLLER] = CONTROLLER_WHOLE_BODY
        elif projected_impedance:
            x[_CONTROLLER] = CONTROLLER_PROJECTED_IMPEDANCE
        if stop:
            for label, _, _ in self._sliders:
                meshcat.SetSliderValue(label, 0.0)
            x[_VALUE] = 0.0
        else:
            values = np.array([meshcat.GetSliderValue(label) for label, _, _ in self._sliders])
            if not np.isfinite(values).all():
                reason = 0
            elif np.any(np.abs(values) > self._bounds + _RANGE_TOLERANCE):
                reason = 1
            else:
                reason = None
            if reason is not None:
                rejected[reason] += 1
                x[_DROPPED] += 1
                for (label, _, _), value in zip(self._sliders, x[_VALUE], strict=True):
                    meshcat.SetSliderValue(label, value)
            elif not np.array_equal(values, x[_VALUE]):
                x[_RECEIVED] += 1
                x[_VALUE] = values
        if meshcat.GetNumActiveConnections() > 0:
            x[_T_LAST] = context.get_time()
        discrete_state.set_value(self._state, x)
        discrete_state.set_value(self._clicks, clicks)
        discrete_state.set_value(self._rejected, rejected)

    def _calc_command(self, context, output: BasicVector) -> None:
        x = context.get_discrete_state(self._state).get_value().copy()
        x[_T_LAST] = context.get_time() - x[_T_LAST]  # the age [s]; inf before any connection
        output.SetFromVector(x)
