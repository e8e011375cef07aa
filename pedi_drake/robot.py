"""Go1 constants, the model loader and the one place where joint orders are converted.

Every public joint vector in pedi_drake is in Unitree motor order: FR, FL, RR, RL, each
(hip, thigh, calf). The plant's own ordering is converted here, in `Go1PlantMap`, and nowhere
else.
"""

import dataclasses
import functools

import numpy as np
from pydrake.geometry import AddContactMaterial, Cylinder, ProximityProperties, Sphere
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia, UnitInertia

from pedi_drake.exceptions import PediError
from pedi_drake.prongs import ProngDesign
from pedi_drake.resources import models_dir

LEG_NAMES = ("FR", "FL", "RR", "RL")
JOINT_KINDS = ("hip", "thigh", "calf")
JOINT_NAMES = tuple(f"{leg}_{kind}_joint" for leg in LEG_NAMES for kind in JOINT_KINDS)
MOTOR_NAMES = tuple(name.replace("_joint", "_motor") for name in JOINT_NAMES)
FOOT_BODY_NAMES = tuple(f"{leg}_foot" for leg in LEG_NAMES)
TRUNK_BODY_NAME = "trunk"
IMU_BODY_NAME = "imu_link"
MODEL_INSTANCE_NAME = "go1"
GO1_URL = "package://pedi_drake/go1/go1.urdf"

NUM_JOINTS = 12
FOOT_RADIUS = 0.02  # [m]
# Half sizes of the trunk's collision box, centred on the trunk origin (models/go1/go1.urdf) [m].
TRUNK_HALF_EXTENTS = (0.1881, 0.04675, 0.057)
PRONG_ROD_RADIUS = 0.006  # [m] of a prong's rod (drawn; the tip sphere is its collision geometry)
TOTAL_MASS = 13.100448  # [kg] without prongs, rotors and IMU included.
GRAVITY = 9.81  # [m/s^2], the magnitude the simulated plant uses

# URDF limits in Unitree motor order.
Q_LOWER = np.tile([-0.863, -0.686, -2.818], 4)  # [rad]
Q_UPPER = np.tile([0.863, 4.501, -0.888], 4)  # [rad]
EFFORT_LIMIT = np.tile([23.7, 23.7, 35.55], 4)  # [N m]
VELOCITY_LIMIT = np.tile([30.1, 30.1, 20.06], 4)  # [rad/s]
# The Unitree SDK's own safety limits; hardware commands respect the intersection.
SDK_Q_LOWER = np.tile([-1.047, -0.663, -2.721], 4)  # [rad]
SDK_Q_UPPER = np.tile([1.047, 2.966, -0.837], 4)  # [rad]
HARDWARE_Q_LOWER = np.maximum(Q_LOWER, SDK_Q_LOWER)
HARDWARE_Q_UPPER = np.minimum(Q_UPPER, SDK_Q_UPPER)

# Poses in Unitree motor order [rad].
STANDING_Q = np.tile([0.0, 0.9, -1.8], 4)
# Lying: hips splayed outwards (right legs -y, left legs +y), legs folded under the trunk.
LYING_Q = np.array([-0.3, 1.2, -2.72, 0.3, 1.2, -2.72, -0.3, 1.2, -2.72, 0.3, 1.2, -2.72])


def leg_slice(leg: str) -> slice:
    """The three entries of `leg` in a Unitree-ordered 12-vector."""
    if leg not in LEG_NAMES:
        raise PediError(f"unknown leg {leg!r}; expected one of {LEG_NAMES}")
    i = LEG_NAMES.index(leg)
    return slice(3 * i, 3 * i + 3)


def trunk_height_for(thigh: float, calf: float, foot_radius: float = FOOT_RADIUS) -> float:
    """Trunk height above flat ground with the feet under the hips [m] (thigh, calf in [rad])."""
    return 0.213 * (np.cos(thigh) + np.cos(thigh + calf)) + foot_radius


def ConfigureParser(parser: Parser) -> None:
    """Makes `package://pedi_drake/...` resolve in `parser`."""
    package_map = parser.package_map()
    if not package_map.Contains("pedi_drake"):
        package_map.Add("pedi_drake", str(models_dir()))


def add_go1(plant: MultibodyPlant, *, prongs: ProngDesign | None = None) -> ModelInstanceIndex:
    """Adds the Go1 (floating trunk) and, if given, the prongs of `prongs` to `plant`.

    Call before `plant.Finalize()`. Geometry is registered only if the plant has a SceneGraph.
    Returns the Go1 model instance.
    """
    parser = Parser(plant)
    ConfigureParser(parser)
    (model,) = parser.AddModels(url=GO1_URL)
    if prongs is not None:
        prongs.validate()
        _add_prongs(plant, model, prongs)
    return model


def _add_prongs(plant: MultibodyPlant, model: ModelInstanceIndex, design: ProngDesign) -> None:
    trunk = plant.GetBodyByName(TRUNK_BODY_NAME, model)
    # Thin rod of the design's mass along -z, its COM at mid length.
    rod_inertia = UnitInertia.SolidCylinder(PRONG_ROD_RADIUS, design.length, [0, 0, 1])
    for i, p_BA in enumerate(design.attachment_points):
        inertia = SpatialInertia(
            design.mass,
            [0.0, 0.0, -design.length / 2],
            rod_inertia.ShiftFromCenterOfMass([0.0, 0.0, design.length / 2]),
        )
        body = plant.AddRigidBody(f"prong_{i}", model, inertia)
        plant.WeldFrames(trunk.body_frame(), body.body_frame(), RigidTransform(np.asarray(p_BA, float)))
        if plant.geometry_source_is_registered():
            X_rod = RigidTransform(RotationMatrix(), [0.0, 0.0, -design.length / 2])
            plant.RegisterVisualGeometry(
                body, X_rod, Cylinder(PRONG_ROD_RADIUS, design.length), f"prong_{i}_rod", [0.9, 0.5, 0.1, 1]
            )
            X_tip = RigidTransform([0.0, 0.0, -design.length])
            plant.RegisterVisualGeometry(body, X_tip, Sphere(design.tip_radius), f"prong_{i}_tip", [0.9, 0.5, 0.1, 1])
            properties = ProximityProperties()
            AddContactMaterial(friction=CoulombFriction(design.friction, design.friction), properties=properties)
            plant.RegisterCollisionGeometry(body, X_tip, Sphere(design.tip_radius), f"prong_{i}_tip", properties)


def prong_body_names(design: ProngDesign | None) -> tuple[str, ...]:
    """Names of the prong bodies that `add_go1` creates for `design` (tips at (0, 0, -length))."""
    return () if design is None else tuple(f"prong_{i}" for i in range(design.num_prongs))


@dataclasses.dataclass(frozen=True)
class Go1PlantMap:
    """Index maps between Unitree motor order and a finalized plant's own vectors.

    Build it once with `Go1PlantMap.from_plant`; then every conversion is a numpy take/put.
    """

    model: ModelInstanceIndex
    q_index: np.ndarray  # (12,) plant position index of each Unitree joint.
    v_index: np.ndarray  # (12,) plant velocity index of each Unitree joint.
    u_index: np.ndarray  # (12,) plant actuation index of each Unitree motor.
    base_q_start: int  # start of the trunk's quaternion (w, x, y, z) and position in q.
    base_v_start: int  # start of the trunk's angular and linear velocity in v.

    @staticmethod
    def from_plant(plant: MultibodyPlant, model: ModelInstanceIndex | None = None) -> "Go1PlantMap":
        if model is None:
            model = plant.GetModelInstanceByName(MODEL_INSTANCE_NAME)
        joints = [plant.GetJointByName(name, model) for name in JOINT_NAMES]
        actuators = [plant.GetJointActuatorByName(name, model) for name in MOTOR_NAMES]
        trunk = plant.GetBodyByName(TRUNK_BODY_NAME, model)
        if not trunk.is_floating_base_body():
            raise PediError("the Go1 trunk is not a floating body in this plant")
        return Go1PlantMap(
            model=model,
            q_index=np.array([j.position_start() for j in joints]),
            v_index=np.array([j.velocity_start() for j in joints]),
            u_index=np.array([a.input_start() for a in actuators]),
            base_q_start=trunk.floating_positions_start(),
            base_v_start=trunk.floating_velocities_start_in_v(),
        )

    def joint_positions(self, q_plant: np.ndarray) -> np.ndarray:
        """Unitree-ordered joint angles [rad] from the plant's full position vector."""
        return np.asarray(q_plant)[self.q_index]

    def joint_velocities(self, v_plant: np.ndarray) -> np.ndarray:
        """Unitree-ordered joint rates [rad/s] from the plant's full velocity vector."""
        return np.asarray(v_plant)[self.v_index]

    def actuation(self, tau_unitree: np.ndarray, num_actuators: int) -> np.ndarray:
        """The plant's actuation vector from Unitree-ordered motor torques [N m]."""
        u = np.zeros(num_actuators)
        u[self.u_index] = tau_unitree
        return u

    def base_pose(self, q_plant: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(quaternion w, x, y, z; position p_WB [m]) of the trunk from the plant's positions."""
        q = np.asarray(q_plant)
        return q[self.base_q_start : self.base_q_start + 4], q[self.base_q_start + 4 : self.base_q_start + 7]

    def full_positions(self, quaternion_wxyz, p_WB, q_joints, num_positions: int) -> np.ndarray:
        """The plant's full position vector from a trunk pose and Unitree-ordered joint angles."""
        q = np.zeros(num_positions)
        q[self.base_q_start : self.base_q_start + 4] = quaternion_wxyz
        q[self.base_q_start + 4 : self.base_q_start + 7] = p_WB
        q[self.q_index] = q_joints
        return q

    def full_velocities(self, w_WB, v_WB, qd_joints, num_velocities: int) -> np.ndarray:
        """The plant's full velocity vector from trunk angular/linear velocity (world) and joint rates."""
        v = np.zeros(num_velocities)
        v[self.base_v_start : self.base_v_start + 3] = w_WB
        v[self.base_v_start + 3 : self.base_v_start + 6] = v_WB
        v[self.v_index] = qd_joints
        return v


@functools.lru_cache(maxsize=8)
def make_go1_plant(prongs_key: tuple | None = None, time_step: float = 0.0) -> tuple[MultibodyPlant, Go1PlantMap]:
    """A finalized plant holding only the Go1 (no geometry), for kinematics and dynamics.

    `prongs_key` is `None` or `design_key(design)`; the result is cached, treat it as read-only.
    """
    plant = MultibodyPlant(time_step)
    design = None if prongs_key is None else ProngDesign(**dict(prongs_key))
    if design is not None:
        design.attachment_points = [list(p) for p in design.attachment_points]
    model = add_go1(plant, prongs=design)
    plant.Finalize()
    return plant, Go1PlantMap.from_plant(plant, model)


def design_key(design: ProngDesign | None) -> tuple | None:
    """A hashable key for `make_go1_plant` from a prong design."""
    if design is None:
        return None
    fields = dataclasses.asdict(design)
    fields["attachment_points"] = tuple(tuple(float(v) for v in p) for p in fields["attachment_points"])
    return tuple(sorted(fields.items()))
