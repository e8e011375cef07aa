"""The controller's view of the robot at one instant: the dynamics terms every task is built from.

`ControllerModel.update(base_state, q_joints, v_joints)` computes, from the state ESTIMATE and
the measured joints, a `RobotSnapshot` with the mass matrix, bias and gravity terms, contact
Jacobians and their bias accelerations, the trunk Jacobian and the centre of mass. Two paths
give the same terms to rounding:

* compiled (the default): one call of `go1_dynamics.go1_dynamics`, whose parameters are read
  from the same plant;
* Drake (`compiled=False`, the reference the tests compare against): a plant (from
  `make_go1_plant`, never the simulation's) and a scratch context overwritten from the inputs,
  then one Drake call per term. The context holds no information that survives a tick,
  so it is a computation workspace, not controller state.

Velocity coordinates are the plant's: v = [w_WB (3, world); v_WB (3, world); joint rates], with
the joints at `plant_map.v_index` in Unitree order.
"""

import math

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.systems.framework import Context

from pedi_drake import robot
from pedi_drake.dynamics.go1_dynamics import Go1Dynamics, contact_points
from pedi_drake.dynamics.robot_snapshot import RobotSnapshot
from pedi_drake.prongs import ProngDesign

__all__ = ["FOOT_CONTACTS", "ControllerModel", "RobotSnapshot", "contact_names"]

# Contact names: the four feet (Unitree order) then the prongs.
FOOT_CONTACTS = robot.LEG_NAMES


def contact_names(prongs: ProngDesign | None) -> tuple[str, ...]:
    """Contact names in the order of the controller's contact vectors: FR, FL, RR, RL, prong_0, ..."""
    return FOOT_CONTACTS + robot.prong_body_names(prongs)


class ControllerModel:
    """The whole-body controller's dynamics terms: compiled (`Go1Dynamics`) or, for reference,
    from a plant, a scratch context and the contact frames."""

    def __init__(self, prongs: ProngDesign | None = None, com_bias: bool = True, compiled: bool = True) -> None:
        """`com_bias` False returns Jdot_com v as zeros: it is costly on the Drake path and only
        enters the capture-point prediction scaled by horizon / omega (below 1 mm at standing
        speeds); the compiled path honours it too, so both paths give the same commands.
        `compiled` False computes every term with Drake calls (the reference)."""
        self.prongs = prongs
        self.com_bias = com_bias
        self.compiled = compiled
        self.plant, self.plant_map = robot.make_go1_plant(robot.design_key(prongs))
        self.context: Context = self.plant.CreateDefaultContext()
        plant, model = self.plant, self.plant_map.model
        self.world = plant.world_frame()
        self.trunk_frame = plant.GetBodyByName(robot.TRUNK_BODY_NAME, model).body_frame()
        self.contact_names = contact_names(prongs)
        frames, points = [], []
        for name, p_BP in contact_points(prongs):  # foot sphere centres, then prong tip sphere centres
            frames.append(plant.GetBodyByName(name, model).body_frame())
            points.append(p_BP)
        self.calf_frames = tuple(plant.GetBodyByName(f"{leg}_calf", model).body_frame() for leg in robot.LEG_NAMES)
        self.contact_frames = tuple(frames)
        self.contact_points = tuple(points)
        self._point_columns = tuple(p.reshape(3, 1) for p in points)
        self._origin = np.zeros(3)
        self.nv = plant.num_velocities()
        self.nq = plant.num_positions()
        self.total_mass = plant.CalcTotalMass(self.context)
        self._weight_W = self.total_mass * plant.gravity_field().gravity_vector()  # m g [N]
        # Viscous joint damping of the model [N m s/rad], part of the dynamics the plant integrates
        # but not of CalcBiasTerm: added to h so torques computed from the QP match the plant.
        self.damping = np.zeros(self.nv)
        for name, index in zip(robot.JOINT_NAMES, self.plant_map.v_index, strict=True):
            self.damping[index] = plant.GetJointByName(name, model).default_damping_vector()[0]
        self.dynamics = Go1Dynamics(prongs) if compiled else None

    @property
    def num_contacts(self) -> int:
        return len(self.contact_frames)

    def standing_rotational_inertia(self) -> np.ndarray:
        """(3, 3) the whole model's rotational inertia about the trunk origin, trunk frame, legs at
        `robot.STANDING_Q` [kg m^2]: what an angular acceleration of the standing robot costs."""
        context = self.plant.CreateDefaultContext()
        q = self.plant_map.full_positions(np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), robot.STANDING_Q, self.nq)
        self.plant.SetPositions(context, q)
        bodies = [self.plant.get_body(index).index() for index in self.plant.GetBodyIndices(self.plant_map.model)]
        inertia = self.plant.CalcSpatialInertia(context, self.trunk_frame, bodies)
        return inertia.CalcRotationalInertia().CopyToFullMatrix3()

    def update(self, base_state: np.ndarray, q_joints: np.ndarray, v_joints: np.ndarray) -> RobotSnapshot:
        """The dynamics terms at the estimate and measured joints (compiled or Drake path)."""
        if self.dynamics is None:
            return self.update_with_drake(base_state, q_joints, v_joints)
        snapshot = self.dynamics.update(base_state, q_joints, v_joints)
        if not self.com_bias:
            snapshot.Jdot_v_com[:] = 0.0
        return snapshot

    def update_with_drake(self, base_state: np.ndarray, q_joints: np.ndarray, v_joints: np.ndarray) -> RobotSnapshot:
        """The reference path: sets the scratch context from the estimate and measured joints and
        computes every term with Drake. Also makes `calf_orientation_with_drake` valid."""
        plant, context, pm = self.plant, self.context, self.plant_map
        base = np.asarray(base_state, float)  # layout: pedi_drake.estimation.base_state
        quaternion = base[0:4] / math.sqrt(float(base[0:4] @ base[0:4]))
        q = pm.full_positions(quaternion, base[4:7], q_joints, self.nq)
        v = pm.full_velocities(base[7:10], base[10:13], v_joints, self.nv)
        plant.SetPositionsAndVelocities(context, np.concatenate([q, v]))
        kV = JacobianWrtVariable.kV
        world = self.world
        M = plant.CalcMassMatrix(context)
        J_com = plant.CalcJacobianCenterOfMassTranslationalVelocity(context, kV, world, world)
        # Uniform gravity's generalised force is J_com^T m g (one less Drake call than
        # CalcGravityGeneralizedForces, the same to rounding).
        h = plant.CalcBiasTerm(context) - J_com.T @ self._weight_W + self.damping * v
        nc = self.num_contacts
        # Filled in place: stacking the per-contact results afterwards costs as much as one of them.
        J_contacts = np.empty((3 * nc, self.nv))
        Jdot_v_contacts = np.empty(3 * nc)
        p_contacts = np.empty((nc, 3))
        for i, (frame, point, column) in enumerate(
            zip(self.contact_frames, self.contact_points, self._point_columns, strict=True)
        ):
            rows = slice(3 * i, 3 * i + 3)
            J_contacts[rows] = plant.CalcJacobianTranslationalVelocity(context, kV, frame, point, world, world)
            Jdot_v_contacts[rows] = plant.CalcBiasTranslationalAcceleration(context, kV, frame, point, world, world)[
                :, 0
            ]
            p_contacts[i] = plant.CalcPointsPositions(context, frame, column, world)[:, 0]
        origin = self._origin
        J_trunk = plant.CalcJacobianSpatialVelocity(context, kV, self.trunk_frame, origin, world, world)
        A_bias_trunk = plant.CalcBiasSpatialAcceleration(context, kV, self.trunk_frame, origin, world, world)
        X_WB = plant.CalcRelativeTransform(context, world, self.trunk_frame)
        return RobotSnapshot(
            q=q,
            v=v,
            M=M,
            h=h,
            J_contacts=J_contacts,
            Jdot_v_contacts=Jdot_v_contacts,
            p_contacts=p_contacts,
            J_trunk=J_trunk,
            Jdot_v_trunk=A_bias_trunk.get_coeffs(),  # [angular; translational]
            R_WB=X_WB.rotation().matrix(),
            p_WB=X_WB.translation(),
            p_com=plant.CalcCenterOfMassPositionInWorld(context),
            J_com=J_com,
            Jdot_v_com=(
                plant.CalcBiasCenterOfMassTranslationalAcceleration(context, kV, world, world)
                if self.com_bias
                else np.zeros(3)
            ),
            q_joints=np.asarray(q_joints, float),
            v_joints=np.asarray(v_joints, float),
            V_trunk=J_trunk @ v,
            v_com=J_com @ v,
        )

    def calf_orientation(self, leg: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(R_WC (3, 3), J_w (3, nv), Jdot_w v (3,)) of the calf of leg `leg` (Unitree index) at
        the state of the last `update`: its orientation, angular-velocity Jacobian (world) and
        angular bias acceleration [rad/s^2]. Only a 5-D foot task needs it."""
        if self.dynamics is None:
            return self.calf_orientation_with_drake(leg)
        return self.dynamics.calf_orientation(leg)

    def calf_orientation_with_drake(self, leg: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """`calf_orientation` computed by Drake at the state of the last `update_with_drake`."""
        plant, context, frame, world = self.plant, self.context, self.calf_frames[leg], self.world
        kV = JacobianWrtVariable.kV
        J = plant.CalcJacobianSpatialVelocity(context, kV, frame, self._origin, world, world)
        bias = plant.CalcBiasSpatialAcceleration(context, kV, frame, self._origin, world, world)
        R = plant.CalcRelativeTransform(context, world, frame).rotation().matrix()
        return R, J[:3], bias.rotational()
