"""Pushes on the simulated world: the scenario's `pushes` as forces on the plant's bodies.

A disturbance belongs to the world, not to the robot: the station feeds it to the plant's
applied-spatial-force input and exports what it applied as `sim.push_force` (for plots and
evaluation). No controller or estimator reads it; on hardware it does not exist.

The profile of one push is a trapezoid in time: zero before `start`, a linear ramp to full force
over `ramp`, full force for `duration`, a linear ramp back to zero over `ramp`.
"""

import numpy as np
from pydrake.common.value import Value
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce, MultibodyPlant
from pydrake.systems.framework import BasicVector, Context

from pedi_drake.exceptions import ScenarioError
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.scenario import Push

PUSH_FORCE_SIZE = 3  # sim.push_force: the sum of the pushes' forces, world frame [N]


def push_scale(push: Push, t: float) -> float:
    """Fraction of the full force that `push` applies at time `t` [s] (0 to 1)."""
    rise, full_end = push.start + push.ramp, push.start + push.ramp + push.duration
    if t < push.start or t > full_end + push.ramp:
        return 0.0
    if t < rise:
        return (t - push.start) / push.ramp
    if t > full_end:
        return (full_end + push.ramp - t) / push.ramp
    return 1.0


def push_force_W(push: Push, t: float) -> np.ndarray:
    """The force `push` applies at time `t`, in the world [N]."""
    direction = np.asarray(push.direction, float)
    return push_scale(push, t) * push.force * direction / np.linalg.norm(direction)


def _body_index(plant: MultibodyPlant, push: Push, where: str):
    count = plant.NumBodiesWithName(push.body)
    if count != 1:
        problem = "no body has that name" if count == 0 else f"{count} bodies have that name"
        raise ScenarioError(f"{where}.body: {push.body!r}: {problem} in the simulated plant")
    return plant.GetBodyByName(push.body).index()


class PushDisturbance(LeafSystemWithoutWitnesses):
    """Ports: output `forces` (list of ExternallyAppliedSpatialForce, for the plant) and output
    `push_force` (PUSH_FORCE_SIZE, the summed force in the world [N], for logging)."""

    def __init__(self, plant: MultibodyPlant, pushes: list[Push]) -> None:
        super().__init__()
        self._pushes = list(pushes)
        self._bodies = [_body_index(plant, push, f"pushes[{i}]") for i, push in enumerate(self._pushes)]
        # Functions of time alone: recomputed when the time changes, not when the state does.
        self.forces_port = self.DeclareAbstractOutputPort(
            "forces",
            lambda: Value([ExternallyAppliedSpatialForce()]),
            self._calc_forces,
            prerequisites_of_calc={self.time_ticket()},
        )
        self.push_force_port = self.DeclareVectorOutputPort(
            "push_force", PUSH_FORCE_SIZE, self._calc_push_force, prerequisites_of_calc={self.time_ticket()}
        )

    def _calc_forces(self, context: Context, output) -> None:
        t = context.get_time()
        forces = []
        for push, body in zip(self._pushes, self._bodies, strict=True):
            force = ExternallyAppliedSpatialForce()
            force.body_index = body
            force.p_BoBq_B = np.asarray(push.point, float)
            force.F_Bq_W = SpatialForce(np.zeros(3), push_force_W(push, t))
            forces.append(force)
        output.set_value(forces)

    def _calc_push_force(self, context: Context, output: BasicVector) -> None:
        t = context.get_time()
        total = np.zeros(PUSH_FORCE_SIZE)
        for push in self._pushes:
            total += push_force_W(push, t)
        output.SetFromVector(total)
