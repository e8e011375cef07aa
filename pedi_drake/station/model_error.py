"""Model error as scenario data: how the simulated Go1 differs from the Go1 the controllers model.

The controllers, the estimator and the IK use `pedi_drake.robot`'s Go1 (13.1 kg, motors that
apply exactly the commanded torque, rigid feet of radius robot.FOOT_RADIUS). A real Go1 differs:
it carries things, its motors are weaker than their rating and respond late, its joints lose
torque to friction, its rubber feet are larger and soft. `ModelErrorConfig` (the scenario's
`model_error:`) says by how much, and the simulated station applies it to its own plant
(`apply_plant_error`) and motor model (`Go1MotorModel`) only: never to the controllers' model,
the estimator or the hardware path. Every default is no error, and with the defaults the station
is built exactly as without this module.
"""

import dataclasses
import math

import numpy as np
from pydrake.geometry import ProximityProperties, RoleAssign, SceneGraph, Sphere
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant, MultibodyPlantConfig
from pydrake.multibody.tree import ModelInstanceIndex, SpatialInertia, UnitInertia

from pedi_drake import robot

# A motor at most this much stronger than its rating [-]: beyond it the law would clamp at
# torques the Go1's motors cannot reach.
MAX_MOTOR_STRENGTH = 1.5
# The longest command latency a scenario may ask for [s]: ten times the Go1's measured
# round trip, and far past where the controllers hold (their period is 2 ms).
MAX_COMMAND_LATENCY = 0.1
# Foot radii the plant accepts [m]: a foot much smaller or larger than the Go1's 2 cm is another robot.
FOOT_RADIUS_RANGE = (0.01, 0.04)
# The joint friction ramps linearly from -f to +f over |qd| < FRICTION_VELOCITY_BAND [rad/s]:
# Coulomb friction smoothed so that it is a bounded damping near rest (f / band at most), which
# the motor model, applying it from the state at the start of each plant step, keeps stable.
FRICTION_VELOCITY_BAND = 0.1
# Upper bounds of the joint losses [N m s/rad, N m]. The motor model applies them explicitly (from
# the state at the start of a step), stable while (damping + friction / band) * time_step stays well
# below twice the lightest joint's inertia (about 0.016 kg m^2 at the calf, rotor included): at
# 1 ms these bounds give at most 12 N m s/rad against a limit of about 30.
MAX_JOINT_DAMPING = 2.0
MAX_JOINT_FRICTION = 1.0
# Name of the payload body welded to the trunk (in the Go1's model instance).
PAYLOAD_BODY_NAME = "payload"
# Radius of the sphere that shows the payload in the replay (illustration only, no contact) [m].
PAYLOAD_VISUAL_RADIUS = 0.03


@dataclasses.dataclass
class ModelErrorConfig:
    """How the simulated Go1 differs from the controllers' model (simulation only; defaults: none)."""

    # Mass of a payload welded to the trunk, a point mass [kg] (>= 0; 0: none). Its own rotational
    # inertia is left out: a 3 kg, 10 cm box adds 0.005 kg m^2, a tenth of the trunk's.
    payload_mass: float = 0.0
    # Where the payload sits, from the trunk origin (the trunk centre) in the trunk frame [m].
    payload_offset: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Strength of each leg's motors, FR, FL, RR, RL [-] (in (0, MAX_MOTOR_STRENGTH]): the motors
    # apply this factor times the torque they are commanded, their effort limit scaled with it.
    motor_strength: list[float] = dataclasses.field(default_factory=lambda: [1.0, 1.0, 1.0, 1.0])
    # How late the motors apply a command [s] (0 to MAX_COMMAND_LATENCY): a delay line of whole
    # plant steps, the latency rounded to the nearest step (halves up); see Go1MotorModel.
    command_latency: float = 0.0
    # Point-contact stiffness of the foot spheres [N/m] (> 0), in series with the ground's;
    # null: the plant's rigid default (from plant_config.penetration_allowance).
    foot_contact_stiffness: float | None = None
    # Hunt-Crossley dissipation of the foot spheres [s/m] (>= 0), read by the discrete contact
    # approximations tamsi, similar and lagged; SAP models dissipation by foot_contact_relaxation_time
    # instead. null: the plant's default.
    foot_contact_dissipation: float | None = None
    # Relaxation time of the foot spheres' contact, SAP's linear Kelvin-Voigt dissipation [s]
    # (>= 0); null: the plant's default.
    foot_contact_relaxation_time: float | None = None
    # Viscous damping in every joint [N m s/rad] (0 to MAX_JOINT_DAMPING), torque lost to the joint.
    joint_damping: float = 0.0
    # Coulomb friction in every joint [N m] (0 to MAX_JOINT_FRICTION), torque lost to the joint,
    # smoothed over |qd| < FRICTION_VELOCITY_BAND (a linear ramp).
    joint_friction: float = 0.0
    # Radius of the plant's foot spheres [m] (in FOOT_RADIUS_RANGE); the controllers keep
    # robot.FOOT_RADIUS (a Go1 rubber foot is about 0.023).
    foot_radius: float = robot.FOOT_RADIUS

    def problems(self, plant_config: MultibodyPlantConfig | None = None) -> list[tuple[str, str]]:
        """(field, problem) for every invalid value; empty when the config is valid.

        `plant_config`: the scenario's, to check the dissipation against its contact approximation.
        """
        found = []

        def number_in(name: str, value, low: float, high: float, *, low_open: bool = False) -> None:
            ok = isinstance(value, int | float) and math.isfinite(value) and value <= high
            ok = ok and (value > low if low_open else value >= low)
            if not ok:
                if high == math.inf:
                    allowed = f"{'>' if low_open else '>='} {low:g}"
                else:
                    allowed = f"in {'(' if low_open else '['}{low:g}, {high:g}]"
                found.append((name, f"must be a finite number {allowed}, got {value!r}"))

        number_in("payload_mass", self.payload_mass, 0.0, math.inf)
        if len(self.payload_offset) != 3 or not all(math.isfinite(v) for v in self.payload_offset):
            found.append(
                ("payload_offset", f"expected a finite [x, y, z] in metres (trunk frame), got {self.payload_offset}")
            )
        if len(self.motor_strength) != len(robot.LEG_NAMES):
            found.append(
                ("motor_strength", f"expected one factor per leg {robot.LEG_NAMES}, got {self.motor_strength}")
            )
        for leg, value in zip(robot.LEG_NAMES, self.motor_strength, strict=False):
            number_in(f"motor_strength[{leg}]", value, 0.0, MAX_MOTOR_STRENGTH, low_open=True)
        number_in("command_latency", self.command_latency, 0.0, MAX_COMMAND_LATENCY)
        for name in ("foot_contact_stiffness", "foot_contact_dissipation", "foot_contact_relaxation_time"):
            value = getattr(self, name)
            if value is not None:
                number_in(name, value, 0.0, math.inf, low_open=(name == "foot_contact_stiffness"))
        number_in("joint_damping", self.joint_damping, 0.0, MAX_JOINT_DAMPING)
        number_in("joint_friction", self.joint_friction, 0.0, MAX_JOINT_FRICTION)
        number_in("foot_radius", self.foot_radius, *FOOT_RADIUS_RANGE)
        if (
            plant_config is not None
            and self.foot_contact_dissipation is not None
            and plant_config.discrete_contact_approximation == "sap"
        ):
            found.append(
                (
                    "foot_contact_dissipation",
                    "SAP (plant_config.discrete_contact_approximation) has no Hunt-Crossley dissipation: "
                    "set foot_contact_relaxation_time, or choose the approximation similar or lagged",
                )
            )
        return found

    def torque_scale(self) -> np.ndarray:
        """(12,) each motor's strength, Unitree order [-]."""
        return np.repeat(np.asarray(self.motor_strength, dtype=float), len(robot.JOINT_KINDS))

    def latency_steps(self, time_step: float) -> int:
        """The command latency in whole plant steps of `time_step` [s] (the nearest, halves up)."""
        return int(math.floor(self.command_latency / time_step + 0.5))

    def has_joint_losses(self) -> bool:
        """Whether the joints lose torque to damping or friction."""
        return self.joint_damping > 0.0 or self.joint_friction > 0.0


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
