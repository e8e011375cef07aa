"""Ground-truth floating-base 'estimate' from the simulated plant state (debugging only)."""

import numpy as np
from pydrake.systems.framework import BasicVector

from pedi_drake import robot
from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses


class GroundTruthEstimator(LeafSystemWithoutWitnesses):
    """sim.plant_state -> base_state (13): selected by a scenario's `estimator: ground_truth`."""

    def __init__(self, plant):
        super().__init__()
        self._map = robot.Go1PlantMap.from_plant(plant)
        self._nq = plant.num_positions()
        self._state = self.DeclareVectorInputPort("plant_state", plant.num_positions() + plant.num_velocities())
        self.DeclareVectorOutputPort("base_state", BASE_STATE_SIZE, self._calc)

    def _calc(self, context, output: BasicVector) -> None:
        x = self._state.Eval(context)
        q0, v0 = self._map.base_q_start, self._nq + self._map.base_v_start
        output.SetFromVector(np.concatenate([x[q0 : q0 + 7], x[v0 : v0 + 6]]))
