"""ControllerSwitch: both whole-body controllers run side by side, and the motors get the one asked for.

Paper 002 switches between its controllers at runtime. With `controller_switch: {enabled: true}`
in the scenario, the diagram builds the HQP (papers 000 / 003) and paper 002's projected-impedance
controller on the same inputs, both ticking every period (each stays warm: its integrated joint
reference, contact ramps and held trunk pose follow the robot whichever drives it), and this
system passes one controller's go1.command on to the motors.

A request names a controller (pedi_drake.operator.command's CONTROLLER_* codes) and comes from
the mission (a `switch_controller` phase) or the operator (the Meshcat panel's buttons, keys 1
and 2 of the keyboard operator, `controller_request` of a foot_command_lcmt); the newer change
of the two wins. The hand-over is a blend, not a step: the output is the weighted sum of the two
commands (every field: targets, gains and feed-forward torque), and the weight moves towards the
requested controller at 1 / blend_time per second. A request that reverses a blend under way
turns the weight back from where it is, so the command is continuous whatever the timing: its
change in one period is at most period / blend_time times the two commands' difference beyond
their own change. The two controllers keep their joint targets within a few hundredths of a
radian of the measured joints, so at blend_time 0.1 s the targets move well under the safety
filter's rate limit (8 rad/s) while the weight moves.

Inputs: `command_whole_body` (60), `command_projected_impedance` (60), `mission_request` (1),
`operator_command` (OPERATOR_COMMAND_SIZE; unconnected: no operator).
Outputs: `command` (60), go1.command; `switch_state` (3) = [active controller code, weight of the
HQP's command [-], switches so far].
"""

import dataclasses
import math

import numpy as np
from pydrake.systems.framework import BasicVector, Context, DiscreteValues

from pedi_drake.exceptions import ConfigError
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.operator.command import (
    CONTROLLER_NAMES,
    CONTROLLER_NONE,
    CONTROLLER_PROJECTED_IMPEDANCE,
    CONTROLLER_WHOLE_BODY,
    OPERATOR_COMMAND_SIZE,
)

COMMAND_SIZE = 60
# operator_command's entry holding the operator's controller request (pedi_drake.operator.command).
_OPERATOR_CONTROLLER = 10
# Discrete state: [active code, weight of the HQP, switches, last mission request, last operator request].
_ACTIVE, _WEIGHT, _SWITCHES, _MISSION_SEEN, _OPERATOR_SEEN = range(5)
SWITCH_STATE_SIZE = 3


@dataclasses.dataclass
class ControllerSwitchConfig:
    """Both whole-body controllers in one run, switched at runtime (scenario `controller_switch:`)."""

    # On: the diagram builds both controllers, the scenario's `controller` driving the motors at
    # the start, and switches on requests. Off: one controller, the scenario's.
    enabled: bool = False
    # How long a hand-over blends the two commands [s] (0: a step).
    blend_time: float = 0.1

    def problems(self) -> list[tuple[str, str]]:
        """(field, problem) for every bad value."""
        if not (math.isfinite(self.blend_time) and 0.0 <= self.blend_time <= 2.0):
            return [("blend_time", f"must be in [0, 2] s, got {self.blend_time}")]
        return []


def controller_code(name: str) -> int:
    """The request code of the controller the scenario names `name`."""
    codes = {value: code for code, value in CONTROLLER_NAMES.items()}
    if name not in codes:
        raise ConfigError(f"controller: switching needs one of {tuple(codes)}, got {name!r}")
    return codes[name]


def next_request(active: int, seen: tuple[int, int], requests: tuple[int, int]) -> int:
    """The controller to drive the motors: the newest changed non-zero request of (mission,
    operator) against the ones `seen` at the previous update, else `active`."""
    for previous, request in zip(seen, requests, strict=True):
        if request != previous and request != CONTROLLER_NONE:
            active = request
    return active


def step_weight(weight: float, active: int, period: float, blend_time: float) -> float:
    """The HQP's weight [-] after one `period` [s] of moving towards `active` at 1 / blend_time."""
    target = 1.0 if active == CONTROLLER_WHOLE_BODY else 0.0
    if blend_time <= 0.0:
        return target
    step = period / blend_time
    return min(weight + step, target) if target > weight else max(weight - step, target)


class ControllerSwitch(LeafSystemWithoutWitnesses):
    """The two controllers' commands blended into one by the requests (see the module docstring)."""

    def __init__(self, initial: str, period: float, blend_time: float):
        """`initial`: the controller driving the motors at the start ("whole_body" or
        "projected_impedance"); `period`: the controllers' period [s]; `blend_time`: how long a
        hand-over takes [s] (0: a step)."""
        super().__init__()
        if not period > 0.0 or not blend_time >= 0.0:
            raise ConfigError(f"controller_switch: period must be > 0, blend_time >= 0 s: got {period}, {blend_time}")
        code = controller_code(initial)
        self._period, self._blend_time = float(period), float(blend_time)
        self.command_ports = {
            name: self.DeclareVectorInputPort(f"command_{name}", COMMAND_SIZE) for name in CONTROLLER_NAMES.values()
        }
        self.mission_request_port = self.DeclareVectorInputPort("mission_request", 1)
        self.operator_port = self.DeclareVectorInputPort("operator_command", OPERATOR_COMMAND_SIZE)
        weight = 1.0 if code == CONTROLLER_WHOLE_BODY else 0.0
        self._state = self.DeclareDiscreteState(np.array([code, weight, 0.0, CONTROLLER_NONE, CONTROLLER_NONE]))
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        # The output reads this period's commands (no extra tick of delay) with the updated weight.
        self.DeclareVectorOutputPort("command", COMMAND_SIZE, self._calc_command)
        self.DeclareVectorOutputPort(
            "switch_state", SWITCH_STATE_SIZE, self._calc_switch_state, prerequisites_of_calc={self.xd_ticket()}
        )

    def _requests(self, context: Context) -> tuple[int, int]:
        mission = int(self.mission_request_port.Eval(context)[0]) if self.mission_request_port.HasValue(context) else 0
        operator = (
            int(self.operator_port.Eval(context)[_OPERATOR_CONTROLLER]) if self.operator_port.HasValue(context) else 0
        )
        known = (CONTROLLER_WHOLE_BODY, CONTROLLER_PROJECTED_IMPEDANCE)
        return tuple(request if request in known else CONTROLLER_NONE for request in (mission, operator))

    def _update(self, context: Context, discrete_state: DiscreteValues) -> None:
        x = context.get_discrete_state(self._state).get_value().copy()
        requests = self._requests(context)
        active = next_request(int(x[_ACTIVE]), (int(x[_MISSION_SEEN]), int(x[_OPERATOR_SEEN])), requests)
        if active != int(x[_ACTIVE]):
            x[_SWITCHES] += 1
        x[_ACTIVE] = active
        x[_WEIGHT] = step_weight(float(x[_WEIGHT]), active, self._period, self._blend_time)
        x[_MISSION_SEEN], x[_OPERATOR_SEEN] = requests
        discrete_state.set_value(self._state, x)

    def _calc_command(self, context: Context, output: BasicVector) -> None:
        weight = float(context.get_discrete_state(self._state).get_value()[_WEIGHT])
        # A controller at weight 0 is not read at all: a command it holds cannot leak in.
        if weight >= 1.0:
            output.SetFromVector(self.command_ports["whole_body"].Eval(context))
        elif weight <= 0.0:
            output.SetFromVector(self.command_ports["projected_impedance"].Eval(context))
        else:
            whole_body = self.command_ports["whole_body"].Eval(context)
            projected = self.command_ports["projected_impedance"].Eval(context)
            output.SetFromVector(weight * whole_body + (1.0 - weight) * projected)

    def _calc_switch_state(self, context: Context, output: BasicVector) -> None:
        x = context.get_discrete_state(self._state).get_value()
        output.SetFromVector(x[[_ACTIVE, _WEIGHT, _SWITCHES]])
