"""The scenario's scene objects for MuJoCo: the SDF models of models/scenes converted to MJCF bodies.

`Scenario.scene` places models/scenes/*.sdf objects (kind, position, yaw, the door's initial
angle); the Drake station adds them with its SDF parser (pedi_drake.station.scene). Here the same
files are read with xml.etree and turned into MJCF bodies at run time, so that every scene the
Drake station can build, MuJoCo can too, from the same data:

- links -> bodies named "<instance>/<link>", nested along the joints (the SDF's joint tree), with
  their inertials (pose, mass, full inertia);
- box, cylinder and sphere collisions -> geoms with the SDF's `drake:mu_dynamic` as friction,
  given priority 2, so that an object's own friction and (MuJoCo's default, stiff) contact
  softness govern every contact it makes (with the floor, the feet, the trunk); visuals -> geoms
  that do not collide;
- revolute / prismatic joints -> hinge / slide joints with the SDF's axis, limits, damping and
  spring (`spring_stiffness`, `spring_reference`), if present; the two bodies a joint connects
  never collide with each other (a contact exclude), as Drake's MultibodyPlant filters them. MuJoCo
  would otherwise let them collide when the parent is fixed in the world: the door's leaf would
  stop against its own post at about 0.9 rad;
- the kind's welded body (station.scene.SCENE_MODELS) -> a body without a joint, fixed in the
  world; an object without one -> a free body;
- what the Drake station adds in code, added here from the same constants: the soft obstacle's
  plate spring (SOFT_OBSTACLE_STIFFNESS [N/m] about rest: the obstacle's softness is that spring,
  a MuJoCo joint stiffness with spring reference 0, plus the SDF's joint damping, not a soft
  contact), the E-stop button's preloaded plunger spring (stiffness ESTOP_BUTTON_STIFFNESS,
  reference -ESTOP_BUTTON_PRELOAD), the door's initial angle (an initial joint position), and the
  back object's placement on the trunk's top face;
- terrain (pedi_drake.terrain: slopes, platforms, friction patches) -> one static box geom each,
  the box and friction the Drake station builds.
"""

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

from pedi_drake.exceptions import ConfigError
from pedi_drake.resources import models_dir
from pedi_drake.scenario import SceneObject
from pedi_drake.station.scene import (
    ESTOP_BUTTON_JOINT,
    ESTOP_BUTTON_PRELOAD,
    ESTOP_BUTTON_STIFFNESS,
    SCENE_MODELS,
    SOFT_OBSTACLE_STIFFNESS,
    SPRUNG_PLATE_KINDS,
    TRUNK_TOP_Z,
)
from pedi_drake.terrain import is_terrain, terrain_box, terrain_colour

# Geom settings of scene objects: collide with the robot (contype 1 / conaffinity 2) and with the
# world (floor, other objects); priority 2: the object's friction and softness govern its contacts.
OBJECT_GEOM = {"contype": "3", "conaffinity": "3", "priority": "2", "group": "3"}
VISUAL_GEOM = {"contype": "0", "conaffinity": "0", "group": "2", "density": "0"}
DEFAULT_FRICTION = 1.0  # [-] for a collision without drake:mu_dynamic
_DRAKE = "{http://drake.mit.edu}"


@dataclasses.dataclass
class SceneBodies:
    """What the MuJoCo model needs to know of one scene object after conversion."""

    name: str  # the object's instance name (Scenario.scene)
    bodies: list[str]  # its MJCF body names
    initial_joint_positions: dict[str, float]  # MJCF joint name -> initial position [rad] or [m]
    jointed_pairs: list[tuple[str, str]]  # (parent, child) MJCF body names joined by a joint


def scene_model_path(obj: SceneObject) -> Path:
    """The SDF file of `obj`: its `model` (a package://pedi_drake/ URL or a path) or its kind's."""
    if obj.kind not in SCENE_MODELS:
        raise ConfigError(f"scene object {obj.instance_name!r}: no model for kind {obj.kind!r}")
    if obj.model.startswith("package://pedi_drake/"):
        return models_dir() / obj.model.removeprefix("package://pedi_drake/")
    if obj.model:
        return Path(obj.model)
    return models_dir() / "scenes" / SCENE_MODELS[obj.kind][0]


def _floats(text: str | None) -> list[float]:
    return [float(v) for v in text.split()] if text else []


def _f(values) -> str:
    return " ".join(f"{float(v):.12g}" for v in values)


def sdf_pose(element: ET.Element) -> RigidTransform:
    """The pose of an SDF element's <pose> child (x y z roll pitch yaw), identity if none."""
    pose = element.find("pose")
    values = _floats(pose.text) if pose is not None else []
    if not values:
        return RigidTransform()
    if len(values) != 6:
        raise ConfigError(f"SDF <pose> {pose.text!r}: expected x y z roll pitch yaw")
    return RigidTransform(RollPitchYaw(values[3:]), values[:3])


def _set_pose(element: ET.Element, X: RigidTransform) -> None:
    element.set("pos", _f(X.translation()))
    element.set("quat", _f(X.rotation().ToQuaternion().wxyz()))


def _shape(geometry: ET.Element, where: str) -> dict[str, str]:
    """MJCF type and size of an SDF <geometry>'s box, cylinder or sphere."""
    box, cylinder, sphere = geometry.find("box"), geometry.find("cylinder"), geometry.find("sphere")
    if box is not None:
        return {"type": "box", "size": _f(0.5 * np.array(_floats(box.findtext("size"))))}
    if cylinder is not None:
        radius, length = float(cylinder.findtext("radius")), float(cylinder.findtext("length"))
        return {"type": "cylinder", "size": _f([radius, 0.5 * length])}
    if sphere is not None:
        return {"type": "sphere", "size": _f([float(sphere.findtext("radius"))])}
    shapes = [child.tag for child in geometry]
    raise ConfigError(f"{where}: MuJoCo scene conversion handles box, cylinder and sphere, not {shapes}")


def _friction(collision: ET.Element) -> float:
    properties = collision.find(f"{_DRAKE}proximity_properties")
    mu = properties.findtext(f"{_DRAKE}mu_dynamic") if properties is not None else None
    return float(mu) if mu is not None else DEFAULT_FRICTION


def _add_link_contents(body: ET.Element, link: ET.Element, prefix: str, where: str) -> None:
    inertial = link.find("inertial")
    if inertial is not None:
        X_LI = sdf_pose(inertial)
        element = ET.SubElement(body, "inertial", mass=f"{float(inertial.findtext('mass', '1')):.12g}")
        element.set("pos", _f(X_LI.translation()))
        inertia = inertial.find("inertia")
        ixx, iyy, izz, ixy, ixz, iyz = (
            float(inertia.findtext(k, "0")) for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
        )
        # About the COM in the inertial frame, re-expressed in the link frame (MJCF takes one or the other).
        R = X_LI.rotation().matrix()
        I_L = R @ np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]) @ R.T
        element.set("fullinertia", _f([I_L[0, 0], I_L[1, 1], I_L[2, 2], I_L[0, 1], I_L[0, 2], I_L[1, 2]]))
    for collision in link.findall("collision"):
        shape = _shape(collision.find("geometry"), f"{where} collision {collision.get('name')}")
        geom = ET.SubElement(body, "geom", name=f"{prefix}{collision.get('name')}", **shape, **OBJECT_GEOM)
        _set_pose(geom, sdf_pose(collision))
        geom.set("friction", f"{_friction(collision):.12g} 0.005 0.0001")
    for visual in link.findall("visual"):
        try:
            shape = _shape(visual.find("geometry"), where)
        except ConfigError:
            continue  # a visual MuJoCo cannot draw here changes no physics
        geom = ET.SubElement(body, "geom", name=f"{prefix}{visual.get('name')}", **shape, **VISUAL_GEOM)
        _set_pose(geom, sdf_pose(visual))
        diffuse = _floats(visual.findtext("material/diffuse"))
        if len(diffuse) == 4:
            geom.set("rgba", _f(diffuse))


def _add_joint(body: ET.Element, joint: ET.Element, prefix: str, spring: tuple[float, float] | None, where: str):
    kinds = {"revolute": "hinge", "prismatic": "slide"}
    if joint.get("type") not in kinds:
        raise ConfigError(f"{where} joint {joint.get('name')}: type {joint.get('type')!r} is not converted")
    X_CJ = sdf_pose(joint)  # the joint frame in the child link's frame
    axis = joint.find("axis")
    direction = X_CJ.rotation().matrix() @ np.array(_floats(axis.findtext("xyz")) or [0.0, 0.0, 1.0])
    element = ET.SubElement(
        body,
        "joint",
        name=f"{prefix}{joint.get('name')}",
        type=kinds[joint.get("type")],
        pos=_f(X_CJ.translation()),
        axis=_f(direction),
    )
    limit = axis.find("limit")
    if limit is not None and limit.find("lower") is not None and limit.find("upper") is not None:
        element.set("range", _f([float(limit.findtext("lower")), float(limit.findtext("upper"))]))
        element.set("limited", "true")
    dynamics = axis.find("dynamics")
    if dynamics is not None:
        element.set("damping", f"{float(dynamics.findtext('damping', '0')):.12g}")
        stiffness = float(dynamics.findtext("spring_stiffness", "0"))
        if stiffness > 0.0 and spring is None:
            spring = (stiffness, float(dynamics.findtext("spring_reference", "0")))
    if spring is not None:
        element.set("stiffness", f"{spring[0]:.12g}")
        element.set("springref", f"{spring[1]:.12g}")


def _kind_springs(obj: SceneObject) -> dict[str, tuple[float, float]]:
    """The springs the Drake station adds in code to `obj`'s joints: {joint: (stiffness, reference)}."""
    if obj.kind in SPRUNG_PLATE_KINDS:
        return {"slide": (SOFT_OBSTACLE_STIFFNESS, 0.0)}
    if obj.kind == "estop_button":
        return {ESTOP_BUTTON_JOINT: (ESTOP_BUTTON_STIFFNESS, -ESTOP_BUTTON_PRELOAD)}
    return {}


def object_placement(obj: SceneObject, X_WB_initial: RigidTransform) -> RigidTransform:
    """X_WO of `obj`'s model frame, as pedi_drake.station.scene places it (the back object on the
    top face of the trunk at its initial pose `X_WB_initial`)."""
    if obj.kind == "back_object":
        X_BO = RigidTransform(RollPitchYaw(0, 0, obj.yaw), np.asarray(obj.position) + [0, 0, TRUNK_TOP_Z + 0.001])
        return X_WB_initial @ X_BO
    return RigidTransform(RollPitchYaw(0, 0, obj.yaw), obj.position)


def add_terrain(worldbody: ET.Element, obj: SceneObject, ground_friction: float) -> SceneBodies:
    """Adds terrain object `obj` (pedi_drake.terrain) to the MJCF `worldbody` as one static box
    geom of the box Drake's plant gets, with its friction (`ground_friction` [-] if none)."""
    box = terrain_box(obj, ground_friction)
    geom = ET.SubElement(worldbody, "geom", name=obj.instance_name, type="box", size=_f(0.5 * box.size), **OBJECT_GEOM)
    _set_pose(geom, box.X_WC)
    geom.set("friction", f"{box.friction:.12g} 0.005 0.0001")
    geom.set("rgba", _f(terrain_colour(obj, ground_friction)))
    return SceneBodies(obj.instance_name, [], {}, [])


def add_scene_object(
    worldbody: ET.Element, obj: SceneObject, X_WB_initial: RigidTransform, ground_friction: float = 0.8
) -> SceneBodies:
    """Adds `obj` to the MJCF `worldbody` as bodies converted from its SDF (terrain: a static geom,
    of `ground_friction` [-] unless it has its own); returns their names."""
    if is_terrain(obj):
        return add_terrain(worldbody, obj, ground_friction)
    path = scene_model_path(obj)
    where = f"scene object {obj.instance_name!r} ({path.name})"
    model = ET.parse(path).getroot().find("model")
    if model is None:
        raise ConfigError(f"{where}: no <model> in the SDF")
    links = {link.get("name"): link for link in model.findall("link")}
    joints = model.findall("joint")
    for joint in joints:
        if joint.get("type") == "fixed":
            raise ConfigError(f"{where}: fixed joint {joint.get('name')} is not converted")
    child_joint = {joint.findtext("child"): joint for joint in joints}
    roots = [name for name in links if name not in child_joint]
    if len(roots) != 1:
        raise ConfigError(f"{where}: expected one root link, found {roots}")
    welded = SCENE_MODELS[obj.kind][1]
    if welded is not None and welded != roots[0]:
        raise ConfigError(f"{where}: the welded body {welded!r} is not the root link {roots[0]!r}")
    prefix = f"{obj.instance_name}/"
    X_MLink = {name: sdf_pose(link) for name, link in links.items()}  # link poses in the model frame
    springs = _kind_springs(obj)
    bodies: list[str] = []

    def add(parent: ET.Element, name: str, X_PL: RigidTransform) -> None:
        body = ET.SubElement(parent, "body", name=f"{prefix}{name}")
        bodies.append(body.get("name"))
        _set_pose(body, X_PL)
        if name in child_joint:
            joint = child_joint[name]
            _add_joint(body, joint, prefix, springs.get(joint.get("name")), where)
        elif welded is None:
            ET.SubElement(body, "freejoint", name=f"{prefix}{name}")
        _add_link_contents(body, links[name], prefix, where)
        for joint in joints:
            if joint.findtext("parent") == name:
                child = joint.findtext("child")
                add(body, child, X_MLink[name].inverse() @ X_MLink[child])

    X_WO = object_placement(obj, X_WB_initial)
    add(worldbody, roots[0], X_WO @ X_MLink[roots[0]])
    initial = {f"{prefix}hinge": obj.initial_angle} if obj.kind == "door" else {}
    pairs = [(f"{prefix}{joint.findtext('parent')}", f"{prefix}{joint.findtext('child')}") for joint in joints]
    return SceneBodies(obj.instance_name, bodies, initial, pairs)


def add_scene(
    root: ET.Element, scene: list[SceneObject], X_WB_initial: RigidTransform, ground_friction: float = 0.8
) -> list[SceneBodies]:
    """Adds every object of `scene`, in order, to the MJCF `root`'s worldbody, with a contact
    exclude for every pair of bodies a joint connects; returns what each object became (terrain
    without a friction of its own has `ground_friction` [-])."""
    added = [add_scene_object(root.find("worldbody"), obj, X_WB_initial, ground_friction) for obj in scene]
    pairs = [pair for bodies in added for pair in bodies.jointed_pairs]
    if pairs:
        contact = root.find("contact")
        if contact is None:
            contact = ET.SubElement(root, "contact")
        for parent, child in pairs:
            ET.SubElement(contact, "exclude", body1=parent, body2=child)
    return added
