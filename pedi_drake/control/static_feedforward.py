"""Static joint torques that hold the Go1 in a pose on four feet (a model-based feed-forward)."""

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable

from pedi_drake import robot


def standing_feedforward_torque(q_joints: np.ndarray, trunk_height: float | None = None) -> np.ndarray:
    """Motor torques [N m] (Unitree order) that balance gravity with all four feet on flat ground.

    The vertical foot forces are the least-norm solution of the trunk's force and moment balance
    (vertical force, roll and pitch moments) for a level trunk; the torques then follow from the
    joint rows of the static equations. Computed from the model, never from simulation state.
    """
    plant, plant_map = robot.make_go1_plant()
    context = plant.CreateDefaultContext()
    height = 0.3 if trunk_height is None else trunk_height
    plant.SetPositions(context, plant_map.full_positions([1, 0, 0, 0], [0, 0, height], q_joints, plant.num_positions()))
    tau_g = plant.CalcGravityGeneralizedForces(context)  # generalised gravity forces (on the left: -tau_g)
    world = plant.world_frame()
    J_z = []
    for name in robot.FOOT_BODY_NAMES:
        frame = plant.GetBodyByName(name, plant_map.model).body_frame()
        J = plant.CalcJacobianTranslationalVelocity(
            context, JacobianWrtVariable.kV, frame, [0, 0, -robot.FOOT_RADIUS], world, world
        )
        J_z.append(J[2])
    J_z = np.array(J_z)  # (4, nv): vertical contact rows.
    base = slice(plant_map.base_v_start, plant_map.base_v_start + 6)
    # Base rows: sum_i J_z[i, base] f_i = -tau_g[base] (forces on the feet balance gravity).
    f, *_ = np.linalg.lstsq(J_z[:, base].T, -tau_g[base], rcond=None)
    # Joint rows: B tau + J_z^T f + tau_g = 0.
    tau_full = -(J_z.T @ f) - tau_g
    return tau_full[plant_map.v_index]
