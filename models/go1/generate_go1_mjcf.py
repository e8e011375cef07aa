"""Writes models/go1/go1.xml, the Go1 for MuJoCo, from the project's own models/go1/go1.urdf.

Kinematics, masses, inertias, limits and collision shapes are read from the URDF (xml.etree), so
the two engines simulate one robot description; welded URDF links (rotors, IMU, feet) become
MuJoCo bodies without a joint, keeping their names and masses. To that the file adds what a real
Go1 has and the URDF does not carry, with the figures MuJoCo Menagerie's `unitree_go1` model
(Google DeepMind, 2023) publishes for it:

- rotor armature 0.01 kg m^2 on every joint (the reflected inertia of the geared rotor; the URDF's
  Drake transmissions give 0.0045 for hip and thigh and 0.010 for the calf);
- joint damping 1 N m s/rad on the hip (abduction) joints and 2 N m s/rad on thigh and calf;
- friction loss 0.2 N m on every joint;
- torque motors in Unitree motor order (FR, FL, RR, RL x hip, thigh, calf), control range = the
  URDF's effort limits (23.7, 23.7, 35.55 N m);
- rubber foot spheres of radius 0.023 m (the URDF's collision sphere is 0.02 m) with friction 0.8
  and a soft contact (FOOT_SOLREF, FOOT_SOLIMP, tuned here, not Menagerie's): a standing Go1
  sinks its feet about 17 mm into the floor (tests/test_mujoco_bridge.py measures it);
- elliptic friction cones with impratio 100 (Menagerie's Go1 scene), so stance feet do not creep.

Plus a floor plane, an IMU site at the URDF's imu_link with gyro, accelerometer and frame
quaternion sensors, and joint position, velocity and actuator force sensors in Unitree order.
Collision filtering: robot geoms (contype 1, conaffinity 2) never touch each other, as in
Menagerie; the world's geoms (3, 3) touch the robot and each other. Regenerate with:

    python models/go1/generate_go1_mjcf.py
"""

import math
import xml.etree.ElementTree as ET
from pathlib import Path

HERE = Path(__file__).resolve().parent
URDF = HERE / "go1.urdf"
MJCF = HERE / "go1.xml"

LEGS = ("FR", "FL", "RR", "RL")
KINDS = ("hip", "thigh", "calf")
# Unitree motor order: the order of the actuators and of the joint sensors.
JOINTS = tuple(f"{leg}_{kind}_joint" for leg in LEGS for kind in KINDS)

ARMATURE = 0.01  # [kg m^2] every joint; MuJoCo Menagerie unitree_go1.
DAMPING = {"hip": 1.0, "thigh": 2.0, "calf": 2.0}  # [N m s/rad]; MuJoCo Menagerie unitree_go1.
FRICTION_LOSS = 0.2  # [N m] every joint; MuJoCo Menagerie unitree_go1.
FOOT_RADIUS = 0.023  # [m] rubber foot sphere; MuJoCo Menagerie unitree_go1.
FOOT_FRICTION = 0.8  # [-] rubber foot; MuJoCo Menagerie unitree_go1.
# Foot contact softness: solref (time constant [s], damping ratio), solimp (impedance at zero and
# full depth, width [m] over which it rises, midpoint, power). The impedance rising from 0.015 to
# 1 over 23 mm is Menagerie's foot; the time constant (Menagerie: MuJoCo's default, 0.02 s) is
# chosen so that the feet of a Go1 standing at (0, 0.9, -1.8) under a PD hold sink 16.7 (front) to
# 17.0 mm (rear) into the floor (tests/test_mujoco_bridge.py measures it).
FOOT_SOLREF = (0.03, 1.0)
FOOT_SOLIMP = (0.015, 1.0, 0.023, 0.5, 2.0)
# Friction: elliptic cones, frictional impedance 100 times the normal one (impratio). MuJoCo's
# constraints are soft, so a foot under a steady sideways load below the friction limit creeps;
# standing, with 30 N pushing the trunk forward for 3 s, the feet slid 360 mm with MuJoCo's
# default pyramidal cones (impratio 1), 130 mm with elliptic ones, 15 mm at impratio 10 and 2 mm
# at 100 (the value MuJoCo Menagerie's Go1 scene sets): a stance foot of a real Go1 does not slide.
IMPRATIO = 100.0
TRUNK_START_HEIGHT = 0.3  # [m] the model's default pose; the bridge sets its own initial state.
TIMESTEP = 0.001  # [s] default physics step (pedi_drake.apps.mujoco_go1 says why).

ROBOT_GEOM = {"contype": "1", "conaffinity": "2"}
WORLD_GEOM = {"contype": "3", "conaffinity": "3"}


def _floats(text: str | None, default=(0.0, 0.0, 0.0)) -> tuple[float, ...]:
    return tuple(float(v) for v in text.split()) if text else tuple(default)


def _f(values) -> str:
    return " ".join(f"{v:.12g}" for v in values)


def rpy_to_quaternion(rpy) -> tuple[float, float, float, float]:
    """(w, x, y, z) of the URDF rotation rpy (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    r, p, y = (0.5 * a for a in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def _pose(element: ET.Element, origin: ET.Element | None) -> None:
    """Sets `element`'s pos (and quat, if rotated) from a URDF <origin>."""
    xyz = _floats(origin.get("xyz")) if origin is not None else (0.0, 0.0, 0.0)
    rpy = _floats(origin.get("rpy")) if origin is not None else (0.0, 0.0, 0.0)
    element.set("pos", _f(xyz))
    if any(rpy):
        element.set("quat", _f(rpy_to_quaternion(rpy)))


def _geom(shape: ET.Element) -> dict[str, str]:
    """MJCF type and size of a URDF <geometry>'s primitive."""
    (primitive,) = list(shape)
    if primitive.tag == "box":
        return {"type": "box", "size": _f(0.5 * v for v in _floats(primitive.get("size")))}
    if primitive.tag == "cylinder":
        radius, length = float(primitive.get("radius")), float(primitive.get("length"))
        return {"type": "cylinder", "size": _f((radius, 0.5 * length))}
    if primitive.tag == "sphere":
        return {"type": "sphere", "size": _f((float(primitive.get("radius")),))}
    raise ValueError(f"generate_go1_mjcf: no MJCF shape for URDF <{primitive.tag}>")


def _add_link(parent: ET.Element, link: ET.Element, joint: ET.Element | None, children: dict, links: dict) -> None:
    name = link.get("name")
    body = ET.SubElement(parent, "body", name=name)
    if joint is None:  # the root
        body.set("pos", _f((0.0, 0.0, TRUNK_START_HEIGHT)))
        body.set("childclass", "go1")
        ET.SubElement(body, "freejoint", name="floating_base")
    else:
        _pose(body, joint.find("origin"))
        if joint.get("type") == "revolute":
            kind = next(k for k in KINDS if joint.get("name").endswith(f"_{k}_joint"))
            limit = joint.find("limit")
            ET.SubElement(
                body,
                "joint",
                name=joint.get("name"),
                axis=_f(_floats(joint.find("axis").get("xyz"))),
                range=_f((float(limit.get("lower")), float(limit.get("upper")))),
                damping=f"{DAMPING[kind]:g}",
            )
        elif joint.get("type") != "fixed":
            raise ValueError(f"generate_go1_mjcf: joint {joint.get('name')} of type {joint.get('type')}")
    inertial = link.find("inertial")
    i = inertial.find("inertia").attrib
    element = ET.SubElement(body, "inertial", mass=inertial.find("mass").get("value"))
    _pose(element, inertial.find("origin"))
    element.set("fullinertia", " ".join(i[k] for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")))
    for visual in link.findall("visual"):
        shape = _geom(visual.find("geometry"))
        if name.endswith("_foot"):
            shape["size"] = _f((FOOT_RADIUS,))
        geom = ET.SubElement(body, "geom", name=f"{name}_visual_{len(body.findall('geom'))}", **shape)
        _pose(geom, visual.find("origin"))
        color = visual.find("material/color")
        geom.set("class", "visual")
        if color is not None:
            geom.set("rgba", color.get("rgba"))
    for k, collision in enumerate(link.findall("collision")):
        shape = _geom(collision.find("geometry"))
        foot = name.endswith("_foot")
        if foot:
            shape["size"] = _f((FOOT_RADIUS,))
        geom = ET.SubElement(body, "geom", name=name if foot else f"{name}_collision_{k}", **shape)
        _pose(geom, collision.find("origin"))
        geom.set("class", "foot" if foot else "collision")
    if name == "trunk":
        imu = next(j for j in children.get("trunk", []) if j.find("child").get("link") == "imu_link")
        site = ET.SubElement(body, "site", name="imu", size="0.01")
        _pose(site, imu.find("origin"))
    for child_joint in children.get(name, []):
        _add_link(body, links[child_joint.find("child").get("link")], child_joint, children, links)


def make_mjcf(urdf_text: str) -> str:
    """The Go1 MJCF text for the URDF text `urdf_text`."""
    robot = ET.fromstring(urdf_text)
    links = {link.get("name"): link for link in robot.findall("link")}
    children: dict[str, list[ET.Element]] = {}
    for joint in robot.findall("joint"):
        children.setdefault(joint.find("parent").get("link"), []).append(joint)
    child_links = {joint.find("child").get("link") for joint in robot.findall("joint")}
    (root,) = [name for name in links if name not in child_links]
    limits = {
        joint.get("name"): joint.find("limit") for joint in robot.findall("joint") if joint.get("type") == "revolute"
    }

    mujoco = ET.Element("mujoco", model="go1")
    ET.SubElement(mujoco, "compiler", angle="radian", autolimits="true")
    ET.SubElement(
        mujoco, "option", timestep=f"{TIMESTEP:g}", integrator="implicitfast", cone="elliptic", impratio=f"{IMPRATIO:g}"
    )
    default = ET.SubElement(mujoco, "default")
    go1 = ET.SubElement(default, "default", {"class": "go1"})
    ET.SubElement(go1, "joint", armature=f"{ARMATURE:g}", frictionloss=f"{FRICTION_LOSS:g}")
    ET.SubElement(go1, "motor", gear="1", ctrllimited="true")
    visual = ET.SubElement(go1, "default", {"class": "visual"})
    ET.SubElement(visual, "geom", contype="0", conaffinity="0", group="2", density="0")
    collision = ET.SubElement(go1, "default", {"class": "collision"})
    ET.SubElement(collision, "geom", group="3", density="0", rgba="0.8 0.2 0.2 0.3", **ROBOT_GEOM)
    foot = ET.SubElement(go1, "default", {"class": "foot"})
    ET.SubElement(
        foot,
        "geom",
        group="3",
        density="0",
        rgba="0.1 0.1 0.1 1",
        priority="1",
        condim="3",
        friction=f"{FOOT_FRICTION:g} 0.005 0.0001",
        solref=_f(FOOT_SOLREF),
        solimp=_f(FOOT_SOLIMP),
        **ROBOT_GEOM,
    )
    world = ET.SubElement(default, "default", {"class": "world"})
    ET.SubElement(world, "geom", **WORLD_GEOM)

    asset = ET.SubElement(mujoco, "asset")
    ET.SubElement(asset, "texture", name="grid", type="2d", builtin="checker", width="256", height="256")
    ET.SubElement(asset, "material", name="floor", texture="grid", texrepeat="8 8", rgba="0.55 0.6 0.55 1")

    worldbody = ET.SubElement(mujoco, "worldbody")
    ET.SubElement(worldbody, "light", pos="0 0 3", dir="0 0 -1", directional="true")
    ET.SubElement(
        worldbody, "geom", {"name": "floor", "type": "plane", "size": "0 0 0.05", "material": "floor", "class": "world"}
    )
    _add_link(worldbody, links[root], None, children, links)

    actuator = ET.SubElement(mujoco, "actuator")
    for name in JOINTS:
        effort = float(limits[name].get("effort"))
        ET.SubElement(
            actuator,
            "motor",
            {
                "name": name.replace("_joint", "_motor"),
                "joint": name,
                "class": "go1",
                "ctrlrange": _f((-effort, effort)),
            },
        )

    sensor = ET.SubElement(mujoco, "sensor")
    for kind in ("jointpos", "jointvel"):
        for name in JOINTS:
            ET.SubElement(sensor, kind, name=f"{name}_{kind[5:]}", joint=name)
    for name in JOINTS:
        ET.SubElement(
            sensor,
            "actuatorfrc",
            name=f"{name.replace('_joint', '_motor')}_force",
            actuator=name.replace("_joint", "_motor"),
        )
    ET.SubElement(sensor, "framequat", name="imu_quat", objtype="site", objname="imu")
    ET.SubElement(sensor, "gyro", name="imu_gyro", site="imu")
    ET.SubElement(sensor, "accelerometer", name="imu_acc", site="imu")

    ET.indent(mujoco, space="  ")
    comment = "<!-- Generated by models/go1/generate_go1_mjcf.py from models/go1/go1.urdf; do not edit. -->\n"
    return comment + ET.tostring(mujoco, encoding="unicode") + "\n"


if __name__ == "__main__":
    MJCF.write_text(make_mjcf(URDF.read_text()))
    print(f"wrote {MJCF}")
