"""What the mission knows about the robot (the state estimate and the `go1.*` measurements), the
operator's command and the live SUF.

Everything here is computed from the base-state estimate and the joint sensors through the
model, never from simulation ground truth.

The whole-robot quantities (centre of mass, gravity torques) need a Context of the Go1 plant:
making one is too costly for a mission update (a press or a teleoperated foot
reads a force estimate at every one), so each thread keeps one to compute in (`_plant_context`);
every use sets the positions it reads first, so nothing is carried from one use to the next.
"""

import dataclasses
import functools
import threading

import numpy as np
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import Context

from pedi_drake import robot
from pedi_drake.estimation.base_state import BaseState
from pedi_drake.estimation.leg_odometry import foot_kinematics_B
from pedi_drake.leg_kinematics import joint_frames, leg_geometry
from pedi_drake.operator.command import OperatorCommand
from pedi_drake.suf.live import LiveSufReading

_workspace = threading.local()


def _plant_context(plant: MultibodyPlant) -> Context:
    """This thread's Context of `plant` to compute in (see the module docstring)."""
    contexts = _workspace.__dict__.setdefault("contexts", {})
    if id(plant) not in contexts:
        contexts[id(plant)] = plant.CreateDefaultContext()
    return contexts[id(plant)]


@dataclasses.dataclass(frozen=True)
class RobotView:
    """One sample of the robot as the mission sees it."""

    time: float  # [s]
    base: BaseState
    q: np.ndarray  # (12,) joint angles [rad], Unitree order
    qd: np.ndarray  # (12,) joint rates [rad/s]
    tau: np.ndarray  # (12,) estimated joint torques [N m]
    foot_force: np.ndarray  # (4,) foot sensor values (normal force [N] in simulation)
    # (4, 3) paper 002's impedance-based estimate of the force on each foot, world [N]; None
    # when the controller does not make one.
    impedance_forces: np.ndarray | None = None
    # The operator's command (pedi_drake.operator); None when the run has no operator input.
    operator: OperatorCommand | None = None
    # The live SUF of the stance (pedi_drake.suf.live), from an update a few ms old; None when
    # the run computes none.
    suf: LiveSufReading | None = None

    @functools.cached_property
    def X_WB(self) -> RigidTransform:
        """The trunk pose estimate (made once per view: phases read it several times)."""
        return self.base.pose()

    def leg_q(self, leg: str) -> np.ndarray:
        return self.q[robot.leg_slice(leg)]

    @functools.cached_property
    def _feet_kinematics_B(self) -> tuple[np.ndarray, np.ndarray]:
        """Every foot centre (4, 3) [m] and its Jacobian wrt its leg's joints (4, 3, 3), trunk
        frame, Unitree leg order (made once per view: the stance polygon alone reads three or four
        feet every mission update)."""
        feet, jacobians = foot_kinematics_B(self.q)
        feet.flags.writeable = jacobians.flags.writeable = False
        return feet, jacobians

    @property
    def _feet_B(self) -> np.ndarray:
        return self._feet_kinematics_B[0]

    def foot_B(self, leg: str) -> np.ndarray:
        """Foot centre in the trunk frame [m]."""
        return self._feet_B[robot.LEG_NAMES.index(leg)].copy()

    @functools.cached_property
    def _feet_W(self) -> np.ndarray:
        """(4, 3) every foot centre in the world [m], Unitree leg order (made once per view)."""
        feet = self._feet_B @ self.X_WB.rotation().matrix().T + self.X_WB.translation()
        feet.flags.writeable = False
        return feet

    def foot_W(self, leg: str) -> np.ndarray:
        """Foot centre in the world [m]."""
        return self._feet_W[robot.LEG_NAMES.index(leg)].copy()

    def calf_rotation_W(self, leg: str) -> np.ndarray:
        """(3, 3) orientation of the calf of `leg` in the world, R_WC (estimate and joint angles)."""
        _, rotations = joint_frames(leg_geometry(leg), self.leg_q(leg))
        return self.X_WB.rotation().matrix() @ rotations[2]

    def feet_W(self) -> dict[str, np.ndarray]:
        return {leg: self.foot_W(leg) for leg in robot.LEG_NAMES}

    def feet_W_array(self) -> np.ndarray:
        """(4, 3) every foot centre in the world [m], Unitree leg order (read-only)."""
        return self._feet_W

    def com_W(self) -> np.ndarray:
        """Whole-robot centre of mass in the world [m] (plain Go1 model)."""
        plant, plant_map = robot.make_go1_plant()
        context = _plant_context(plant)
        q = plant_map.full_positions(self.base.quaternion_wxyz, self.base.p_WB, self.q, plant.num_positions())
        plant.SetPositions(context, q)
        return plant.CalcCenterOfMassPositionInWorld(context)

    def foot_external_force_W(self, leg: str) -> np.ndarray:
        """Estimated force of the environment on the foot of `leg`, in the world [N].

        Quasi-static: the leg's motor torques balance the leg's own gravity and the contact force,
        tau + tau_g + J^T F = 0, so F = -J^-T (tau + tau_g). Valid for slow leg motions.
        """
        plant, plant_map = robot.make_go1_plant()
        context = _plant_context(plant)
        q = plant_map.full_positions(self.base.quaternion_wxyz, self.base.p_WB, self.q, plant.num_positions())
        plant.SetPositions(context, q)
        tau_g = plant.CalcGravityGeneralizedForces(context)[plant_map.v_index][robot.leg_slice(leg)]
        J_W = self.X_WB.rotation().matrix() @ self._feet_kinematics_B[1][robot.LEG_NAMES.index(leg)]
        tau = self.tau[robot.leg_slice(leg)]
        return -np.linalg.solve(J_W.T, tau + tau_g)

    def foot_force_estimates_W(self, leg: str) -> dict[str, np.ndarray]:
        """Every available estimate of the environment's force on the foot of `leg`, world [N]:
        "joint_torque" always, "impedance" when the controller makes one."""
        estimates = {"joint_torque": self.foot_external_force_W(leg)}
        if self.impedance_forces is not None:
            estimates["impedance"] = self.impedance_forces[robot.LEG_NAMES.index(leg)]
        return estimates
