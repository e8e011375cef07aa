"""OperatorEstopGate: the controller's command to the motors, or damping once the operator's E-stop came.

In simulation there is no driver between the controller and the motors, so this gate gives the
operator's E-stop the driver's behaviour (pedi_drake.go1_driver.safety): from the first control
tick that sees the E-stop, every command is the driver's damping command (kp = 0, kd > 0,
tau_ff = 0) at the measured state, to the end of the run. On hardware the operator's E-stop goes
to the driver's own `driver.estop` input instead, and this gate is not used.
"""

import numpy as np
from pydrake.systems.framework import BasicVector, DiscreteValues

from pedi_drake.go1_command import COMMAND_SIZE
from pedi_drake.go1_driver.config import Go1SafetyConfig
from pedi_drake.go1_driver.safety import SafetyLimits, damping_command
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.operator.command import OPERATOR_COMMAND_SIZE, OperatorCommand


class OperatorEstopGate(LeafSystemWithoutWitnesses):
    """command (60), operator_command, position_measured (12), velocity_measured (12) -> command (60).

    Discrete state: [latched (0 or 1), diagram time it latched [s], damping command (60)], updated
    every `period` [s]: the damping command is made from the state measured at that tick, so the
    output depends on the measurements only through the state (the station's command input is
    conservatively direct-feedthrough to its measurements).
    """

    def __init__(self, safety: Go1SafetyConfig, period: float):
        super().__init__()
        self._limits = SafetyLimits.from_config(safety)
        self._damping_kd = safety.damping_kd
        self._command = self.DeclareVectorInputPort("command", COMMAND_SIZE)
        self._operator = self.DeclareVectorInputPort("operator_command", OPERATOR_COMMAND_SIZE)
        self._q = self.DeclareVectorInputPort("position_measured", 12)
        self._qd = self.DeclareVectorInputPort("velocity_measured", 12)
        self._latch = self.DeclareDiscreteState(np.concatenate([[0.0, np.nan], np.zeros(COMMAND_SIZE)]))
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareVectorOutputPort(
            "command",
            COMMAND_SIZE,
            self._calc_command,
            prerequisites_of_calc={self._command.ticket(), self.xd_ticket()},
        )
        self.DeclareVectorOutputPort("latched", 1, self._calc_latched, prerequisites_of_calc={self.xd_ticket()})

    def _update(self, context, discrete_state: DiscreteValues) -> None:
        x = context.get_discrete_state(self._latch).get_value().copy()
        if x[0] == 0.0 and not OperatorCommand.from_vector(self._operator.Eval(context)).estop:
            return
        if x[0] == 0.0:
            x[0:2] = 1.0, context.get_time()
        q, qd = np.asarray(self._q.Eval(context)), np.asarray(self._qd.Eval(context))
        x[2:] = damping_command(q, qd, self._limits, self._damping_kd)
        discrete_state.set_value(self._latch, x)

    def _calc_command(self, context, output: BasicVector) -> None:
        x = context.get_discrete_state(self._latch).get_value()
        output.SetFromVector(self._command.Eval(context) if x[0] == 0.0 else x[2:])

    def _calc_latched(self, context, output: BasicVector) -> None:
        output.SetFromVector(context.get_discrete_state(self._latch).get_value()[0:1])
