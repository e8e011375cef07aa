"""The operator's command as one vector: the `operator_command` port of OperatorInput.

  operator_command (12) = [mode_request, frame, kind, value (3), estop, age, received, dropped,
                           controller_request, friction_request]

mode_request  the last mode the operator asked for: MODE_NONE (nothing asked yet),
              MODE_AUTONOMOUS (the mission's phases), MODE_TELEOP (the teleoperated foot) or
              MODE_SEMI_AUTONOMOUS (value is a foot target the mission serves on its own)
frame         FRAME_TRUNK or FRAME_WORLD: the frame of `value`
kind          KIND_VELOCITY (value is a foot velocity [m/s]), KIND_POSITION (a foot centre [m]) or
              KIND_TWIST (value is a base twist for a walk_teleop phase: forward and sideways
              speed [m/s] and yaw rate [rad/s] in the trunk's heading frame; `frame` is ignored)
estop         1 once any message asked for an E-stop (latched for the rest of the run)
age           time since the last valid message [s] (inf before any): the operator's heartbeat
received, dropped   valid messages taken in, and messages rejected (malformed, non-finite, ...)
controller_request  the last whole-body controller the operator asked for: CONTROLLER_NONE
              (nothing asked yet), CONTROLLER_WHOLE_BODY or CONTROLLER_PROJECTED_IMPEDANCE (taken
              by a scenario that runs both, pedi_drake.control.controller_switch)
friction_request  the last ground friction coefficient the operator gave the controllers [-]
              (0: none yet; the mission manager passes a new one on at once)
"""

import dataclasses
import math

import numpy as np

MODE_NONE, MODE_AUTONOMOUS, MODE_TELEOP, MODE_SEMI_AUTONOMOUS = 0, 1, 2, 3
MODES = (MODE_NONE, MODE_AUTONOMOUS, MODE_TELEOP, MODE_SEMI_AUTONOMOUS)
FRAME_TRUNK, FRAME_WORLD = 0, 1
KIND_VELOCITY, KIND_POSITION, KIND_TWIST = 0, 1, 2
KINDS = (KIND_VELOCITY, KIND_POSITION, KIND_TWIST)
CONTROLLER_NONE, CONTROLLER_WHOLE_BODY, CONTROLLER_PROJECTED_IMPEDANCE = 0, 1, 2
# The scenario's name of each controller a request can name.
CONTROLLER_NAMES = {CONTROLLER_WHOLE_BODY: "whole_body", CONTROLLER_PROJECTED_IMPEDANCE: "projected_impedance"}
CONTROLLER_REQUESTS = (CONTROLLER_NONE, *CONTROLLER_NAMES)
OPERATOR_COMMAND_SIZE = 12


@dataclasses.dataclass(frozen=True)
class OperatorCommand:
    """One sample of the operator's command (see the module docstring for the fields)."""

    mode_request: int = MODE_NONE
    frame: int = FRAME_TRUNK
    kind: int = KIND_VELOCITY
    value: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))  # [m/s] or [m]
    estop: bool = False
    age: float = math.inf  # [s]
    received: int = 0
    dropped: int = 0
    controller_request: int = CONTROLLER_NONE
    friction_request: float = 0.0  # [-]

    @staticmethod
    def from_vector(x: np.ndarray) -> "OperatorCommand":
        x = np.asarray(x, float)
        return OperatorCommand(
            mode_request=int(x[0]),
            frame=int(x[1]),
            kind=int(x[2]),
            value=x[3:6].copy(),
            estop=bool(x[6] > 0.5),
            age=float(x[7]),
            received=int(x[8]),
            dropped=int(x[9]),
            controller_request=int(x[10]),
            friction_request=float(x[11]),
        )

    def to_vector(self) -> np.ndarray:
        return np.array(
            [
                self.mode_request,
                self.frame,
                self.kind,
                *self.value,
                float(self.estop),
                self.age,
                self.received,
                self.dropped,
                self.controller_request,
                self.friction_request,
            ],
            float,
        )
