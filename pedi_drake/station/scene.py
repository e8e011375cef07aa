"""Scene objects: flat ground, terrain (pedi_drake.terrain) and the models of models/scenes,
placed as the Scenario says."""

import numpy as np
from pydrake.geometry import AddContactMaterial, Box, HalfSpace, ProximityProperties
from pydrake.math import RigidTransform, RollPitchYaw
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import CoulombFriction, MultibodyPlant
from pydrake.multibody.tree import ModelInstanceIndex, PrismaticSpring

from pedi_drake import robot
from pedi_drake.exceptions import ConfigError
from pedi_drake.scenario import SceneObject
from pedi_drake.terrain import is_terrain, terrain_box, terrain_colour

# Model file and the body welded to the world (None: the object is free) for each kind.
SCENE_MODELS = {
    "door": ("door.sdf", "frame_post"),
    "box": ("box.sdf", None),
    "target_panel": ("target_panel.sdf", None),
    "back_object": ("back_object.sdf", None),
    "fixed_obstacle": ("fixed_obstacle.sdf", "block"),
    "soft_obstacle": ("soft_obstacle.sdf", "base"),
    "mobile_obstacle": ("mobile_obstacle.sdf", None),
    "mobile_soft_obstacle": ("mobile_soft_obstacle.sdf", None),
    "hand": ("hand.sdf", "palm"),
    "estop_button": ("estop_button.sdf", "post"),
}
SOFT_OBSTACLE_STIFFNESS = 400.0  # [N/m] spring holding the soft obstacle's plate at rest.
# The kinds with the soft obstacle's sprung plate (joint "slide", spring SOFT_OBSTACLE_STIFFNESS).
SPRUNG_PLATE_KINDS = ("soft_obstacle", "mobile_soft_obstacle")
# The E-stop button's plunger (joint "travel", its position how far it is pushed in [m]): a spring
# of this stiffness holds it out against its stop with the force of ESTOP_BUTTON_PRELOAD of
# compression; the button trips when the plunger is in ESTOP_BUTTON_TRIP_TRAVEL, 4 mm short of its
# end stop. The spring then pushes back with 400 * 0.013 = 5.2 N, of which the plunger's own weight
# (0.05 kg) carries 0.5 N: a foot trips it with 4.7 N, under a third of the teleoperated foot's
# default force bound (15 N), so an operator can trip it without reaching the bound.
ESTOP_BUTTON_JOINT = "travel"
ESTOP_BUTTON_STIFFNESS = 400.0  # [N/m]
ESTOP_BUTTON_PRELOAD = 0.005  # [m]
ESTOP_BUTTON_TRIP_TRAVEL = 0.008  # [m]
TRUNK_TOP_Z = robot.TRUNK_HALF_EXTENTS[2]  # [m] top face of the trunk box above the trunk origin.


def root_body(plant: MultibodyPlant, model):
    """The one body of `model` that no joint between its own bodies moves: the body a free object
    floats by (before or after the plant is finalized, which adds a joint from the world)."""
    joints = [plant.get_joint(j) for j in plant.GetJointIndices(model)]
    children = {joint.child_body().index() for joint in joints if joint.parent_body().model_instance() == model}
    roots = [b for b in plant.GetBodyIndices(model) if b not in children]
    if len(roots) != 1:
        names = [plant.get_body(b).name() for b in roots]
        raise ConfigError(f"scene model {plant.GetModelInstanceName(model)!r}: expected one root body, found {names}")
    return plant.get_body(roots[0])


def add_ground(plant: MultibodyPlant, friction: float) -> None:
    """Flat ground: a half space at z = 0 (collision) and a thin grey slab (visual)."""
    properties = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(friction, friction), properties=properties)
    plant.RegisterCollisionGeometry(plant.world_body(), RigidTransform(), HalfSpace(), "ground", properties)
    plant.RegisterVisualGeometry(
        plant.world_body(), RigidTransform([0, 0, -0.005]), Box(6.0, 6.0, 0.01), "ground", [0.55, 0.6, 0.55, 1.0]
    )


def add_terrain(plant: MultibodyPlant, obj: SceneObject, ground_friction: float) -> ModelInstanceIndex:
    """Adds terrain object `obj` (before Finalize): a model instance of its name holding one body,
    welded to the world, with the object's box as collision (its own friction, or
    `ground_friction` [-]) and visual geometry. Returns the model instance."""
    model = plant.AddModelInstance(obj.instance_name)
    body = plant.AddRigidBody(obj.instance_name, model)
    box = terrain_box(obj, ground_friction)
    plant.WeldFrames(plant.world_frame(), body.body_frame(), box.X_WC)
    properties = ProximityProperties()
    AddContactMaterial(friction=CoulombFriction(box.friction, box.friction), properties=properties)
    shape = Box(*box.size)
    plant.RegisterCollisionGeometry(body, RigidTransform(), shape, obj.instance_name, properties)
    plant.RegisterVisualGeometry(body, RigidTransform(), shape, obj.instance_name, terrain_colour(obj, ground_friction))
    return model


def add_scene_object(
    plant: MultibodyPlant, obj: SceneObject, X_WB_initial: RigidTransform, ground_friction: float = 0.8
) -> ModelInstanceIndex:
    """Adds `obj` to `plant` (before Finalize) and returns its model instance.

    `position` and `yaw` place the model frame in the world, except for `back_object`, whose
    `position` is an offset from the centre of the trunk's top face in the trunk frame
    (`X_WB_initial` is the trunk's initial pose). Terrain without a friction of its own has
    `ground_friction` [-].
    """
    if is_terrain(obj):
        return add_terrain(plant, obj, ground_friction)
    filename, welded_body = SCENE_MODELS[obj.kind]
    parser = Parser(plant)
    parser.SetAutoRenaming(True)
    robot.ConfigureParser(parser)
    if obj.model.startswith("package://"):
        (model,) = parser.AddModels(url=obj.model)
    elif obj.model:
        (model,) = parser.AddModels(file_name=obj.model)
    else:
        (model,) = parser.AddModels(url=f"package://pedi_drake/scenes/{filename}")
    plant.RenameModelInstance(model, obj.instance_name)
    if obj.kind == "back_object":
        X_BO = RigidTransform(RollPitchYaw(0, 0, obj.yaw), np.asarray(obj.position) + [0, 0, TRUNK_TOP_Z + 0.001])
        X_WO = X_WB_initial @ X_BO
    else:
        X_WO = RigidTransform(RollPitchYaw(0, 0, obj.yaw), obj.position)
    if welded_body is not None:
        plant.WeldFrames(plant.world_frame(), plant.GetFrameByName(welded_body, model), X_WO)
    else:
        plant.SetDefaultFloatingBaseBodyPose(root_body(plant, model), X_WO)
    if obj.kind == "door":
        plant.GetJointByName("hinge", model).set_default_angle(obj.initial_angle)
    if obj.kind in SPRUNG_PLATE_KINDS:
        plant.AddForceElement(PrismaticSpring(plant.GetJointByName("slide", model), 0.0, SOFT_OBSTACLE_STIFFNESS))
    if obj.kind == "estop_button":
        plunger = plant.GetJointByName(ESTOP_BUTTON_JOINT, model)
        plant.AddForceElement(PrismaticSpring(plunger, -ESTOP_BUTTON_PRELOAD, ESTOP_BUTTON_STIFFNESS))
    return model
