"""Model error as scenario data: how the simulated Go1 differs from the Go1 the controllers model.

The controllers, the estimator and the IK use `pedi_drake.robot`'s Go1 (13.1 kg, motors that
apply exactly the commanded torque, rigid feet of radius robot.FOOT_RADIUS). A real Go1 differs:
it carries things, its motors are weaker than their rating and respond late, its joints lose
torque to friction, its rubber feet are larger and soft. `ModelErrorConfig` (the scenario's
`model_error:`, pedi_drake.model_error_config) says by how much, and the simulated station applies
it here to its own plant (`apply_plant_error`) and in its motor model (`Go1MotorModel`) only:
never to the controllers' model, the estimator or the hardware path. Every default is no error,
and with the defaults the station is built exactly as without this module.
"""

import numpy as np
from pydrake.geometry import ProximityProperties, RoleAssign, SceneGraph, Sphere
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia, UnitInertia

from pedi_drake import robot
from pedi_drake.model_error_config import ModelErrorConfig

# The joint friction ramps linearly from -f to +f over |qd| < FRICTION_VELOCITY_BAND [rad/s]:
# Coulomb friction smoothed so that it is a bounded damping near rest (f / band at most), which
# the motor model, applying it from the state at the start of each plant step, keeps stable.
FRICTION_VELOCITY_BAND = 0.1
# Name of the payload body welded to the trunk (in the Go1's model instance).
PAYLOAD_BODY_NAME = "payload"
# Radius of the sphere that shows the payload in the replay (illustration only, no contact) [m].
PAYLOAD_VISUAL_RADIUS = 0.03


def joint_loss_torque(qd: np.ndarray, damping: float, friction: float) -> np.ndarray:
    """Torque the joints lose at rates qd [rad/s] to viscous damping [N m s/rad] and smoothed
    Coulomb friction [N m] (see FRICTION_VELOCITY_BAND), opposing the motion [N m]."""
    qd = np.asarray(qd, dtype=float)
    return damping * qd + friction * np.clip(qd / FRICTION_VELOCITY_BAND, -1.0, 1.0)


def apply_plant_error(
    plant: MultibodyPlant, scene_graph: SceneGraph | None, model: ModelInstanceIndex, error: ModelErrorConfig
) -> None:
    """Adds the payload to the Go1 `model` of `plant` and gives its feet the error's radius and
    contact properties. Call after `robot.add_go1`, before `plant.Finalize()`; `scene_graph` is the
    plant's (None for a plant without geometry: only the payload is added). No error: no change."""
    if error.payload_mass > 0.0:
        _add_payload(plant, model, error)
    if scene_graph is None or not plant.geometry_source_is_registered():
        return
    if error.foot_radius != robot.FOOT_RADIUS:
        _change_foot_radius(plant, scene_graph, model, error.foot_radius)
    contact = {
        "point_contact_stiffness": error.foot_contact_stiffness,
        "hunt_crossley_dissipation": error.foot_contact_dissipation,
        "relaxation_time": error.foot_contact_relaxation_time,
    }
    contact = {name: value for name, value in contact.items() if value is not None}
    if contact:
        _change_foot_contact(plant, scene_graph, model, contact)


def _add_payload(plant: MultibodyPlant, model: ModelInstanceIndex, error: ModelErrorConfig) -> None:
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME, model)
    inertia = SpatialInertia(error.payload_mass, np.zeros(3), UnitInertia(0.0, 0.0, 0.0))  # a point mass
    payload = plant.AddRigidBody(PAYLOAD_BODY_NAME, model, inertia)
    plant.WeldFrames(trunk.body_frame(), payload.body_frame(), RigidTransform(np.asarray(error.payload_offset, float)))
    if plant.geometry_source_is_registered():
        plant.RegisterVisualGeometry(
            payload, RigidTransform(), Sphere(PAYLOAD_VISUAL_RADIUS), PAYLOAD_BODY_NAME, [0.8, 0.2, 0.2, 0.6]
        )


def _foot_geometries(plant: MultibodyPlant, model: ModelInstanceIndex, visual: bool) -> list:
    ids = []
    for name in robot.FOOT_BODY_NAMES:
        body = plant.GetBodyByName(name, model)
        ids += plant.GetVisualGeometriesForBody(body) if visual else plant.GetCollisionGeometriesForBody(body)
    return ids


def _change_foot_radius(plant: MultibodyPlant, scene_graph: SceneGraph, model: ModelInstanceIndex, radius: float):
    # The visual spheres too, so that a replay shows the feet the plant simulates.
    for geometry in _foot_geometries(plant, model, visual=False) + _foot_geometries(plant, model, visual=True):
        scene_graph.ChangeShape(plant.get_source_id(), geometry, Sphere(radius))


def _change_foot_contact(plant: MultibodyPlant, scene_graph: SceneGraph, model: ModelInstanceIndex, contact: dict):
    inspector = scene_graph.model_inspector()
    for geometry in _foot_geometries(plant, model, visual=False):
        # A copy of the foot's own properties (its friction stays), with the error's material.
        properties = ProximityProperties(inspector.GetProximityProperties(geometry))
        for name, value in contact.items():
            properties.UpdateProperty("material", name, float(value))
        scene_graph.AssignRole(plant.get_source_id(), geometry, properties, RoleAssign.kReplace)
