"""A joint-space PD that blends the Go1 from its measured pose to a standing pose and holds it.

The foundation's controller (scenario `controller: stand_pd`), and the simplest user of the
station: it reads only `go1.position_measured` and writes `go1.command`.
"""

import numpy as np
from pydrake.systems.framework import BasicVector, DiscreteValues

from pedi_drake.control.config import StandControllerConfig
from pedi_drake.control.static_feedforward import standing_feedforward_torque
from pedi_drake.go1_command import COMMAND_SIZE, pack_command
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.trajectory import min_jerk


class StandController(LeafSystemWithoutWitnesses):
    """go1.position_measured -> go1.command: quintic joint blend to `config.target_leg_pose`, then hold.

    State (discrete, in the Context): the measured pose at the first update and a flag saying
    it was captured, then nothing else changes: the command is a function of time and state.
    """

    def __init__(self, config: StandControllerConfig):
        super().__init__()
        self._config = config
        self._q_target = np.tile(np.asarray(config.target_leg_pose, float), 4)
        self._tau_hold = standing_feedforward_torque(self._q_target)
        self._measured = self.DeclareVectorInputPort("position_measured", 12)
        # [q_start (12), t_start, captured flag]
        self._start = self.DeclareDiscreteState(14)
        self.DeclarePeriodicDiscreteUpdateEvent(config.period, 0.0, self._capture_start)
        self.DeclareVectorOutputPort(
            "command", COMMAND_SIZE, self._calc_command, {self.time_ticket(), self.xd_ticket()}
        )

    def _capture_start(self, context, discrete_state: DiscreteValues) -> None:
        x = context.get_discrete_state(self._start).get_value()
        if x[13] == 0.0:
            discrete_state.set_value(
                self._start, np.concatenate([self._measured.Eval(context), [context.get_time(), 1.0]])
            )

    def _calc_command(self, context, output: BasicVector) -> None:
        x = context.get_discrete_state(self._start).get_value()
        config = self._config
        if x[13] == 0.0:
            # Before the first update: hold still with damping only.
            output.SetFromVector(pack_command(np.zeros(12), 0.0, 0.0, config.kd, 0.0))
            return
        q_start, t_start = x[:12], x[12]
        s, ds, _ = min_jerk((context.get_time() - t_start) / config.duration)
        q_des = q_start + s * (self._q_target - q_start)
        qd_des = ds / config.duration * (self._q_target - q_start)
        output.SetFromVector(pack_command(q_des, qd_des, config.kp, config.kd, s * self._tau_hold))
