"""Writes models/go1/go1.urdf from the published Go1 figures.

The numbers are those of unitree_ros `robots/go1_description` (revision of 2022-11,
"reconfirm Go1 inertial params"), which example-robot-data 6.0.0 ships unchanged and the tests
compare against. Every mass of that description is here, rotors and IMU included, as welded
links of the same names, except its Gazebo sensor placeholders (five cameras and three
ultrasound sensors of 1e-5 kg each) and its 1e-6 kg dummy `base` link. Geometry is
primitive (boxes, cylinders, spheres) so that the model has no mesh dependency and Meshcat
still shows a recognisable Go1. Regenerate with:

    python models/go1/generate_go1_urdf.py

The Drake extension tags on the transmissions add the motors' reflected rotor inertia
(rotor spin inertia times the squared gear ratio), which the reference description omits.
"""

from pathlib import Path

LEGS = ("FR", "FL", "RR", "RL")
HIP_ORIGIN = {"FR": (0.1881, -0.04675), "FL": (0.1881, 0.04675), "RR": (-0.1881, -0.04675), "RL": (-0.1881, 0.04675)}
HIP_ROTOR_X = 0.11215  # [m] hip rotor centre along trunk x (front legs; rear legs negative).
THIGH_OFFSET = 0.08  # [m] lateral thigh joint offset in the hip frame.
LINK_LENGTH = 0.213  # [m] thigh and calf lengths.
FOOT_RADIUS = 0.02  # [m]
ROTOR_MASS = 0.089  # [kg]
ROTOR_I_SPIN = 1.11842e-4  # [kg m^2] about the spin axis.
ROTOR_I_OTHER = 5.9647e-5  # [kg m^2] about the two other axes.
# Thigh and calf rotors sit on the hip and thigh links, offset along y towards the trunk's
# midplane (+y on right legs, -y on left legs), like the thigh COM.
THIGH_ROTOR_INBOARD = 0.00015  # [m]
CALF_ROTOR_INBOARD = 0.03235  # [m]
# Gear ratios: 6.33 for the Go1 joint motors; the calf adds a 1.5:1 linkage, which is why its
# effort limit (35.55 N m) is 1.5 times the others' (23.7 N m).
GEAR_RATIO = {"hip": 6.33, "thigh": 6.33, "calf": 9.495}
LIMITS = {  # lower, upper [rad], effort [N m], velocity [rad/s]
    "hip": (-0.863, 0.863, 23.7, 30.1),
    "thigh": (-0.686, 4.501, 23.7, 30.1),
    "calf": (-2.818, -0.888, 35.55, 20.06),
}

TRUNK = dict(
    mass=5.204,
    com=(0.0223, 0.002, -0.0005),
    inertia=(0.0168128557, 0.063009565, 0.0716547275, -0.0002296769, -0.0002945293, -4.18731e-05),
)
# FR leg values; inertia as (ixx, iyy, izz, ixy, ixz, iyz).
HIP = dict(
    mass=0.591,
    com=(-0.005657, 0.008752, -0.000102),
    inertia=(0.000334008405, 0.000619101213, 0.00040057614, 1.0826066e-05, 1.290732e-06, -1.643194e-06),
)
THIGH = dict(
    mass=0.92,
    com=(-0.003342, 0.018054, -0.033451),
    inertia=(0.004431760472, 0.004485671726, 0.000740309489, -5.7496807e-05, -0.000218457134, -0.000572001265),
)
CALF = dict(
    mass=0.135862,
    com=(0.006197, 0.001408, -0.116695),
    inertia=(0.001088793059, 0.001100428748, 2.4787446e-05, -2.55679e-07, 7.117814e-06, 2.077264e-06),
)
FOOT = dict(mass=0.06, com=(0.0, 0.0, 0.0), inertia=(9.6e-06, 9.6e-06, 9.6e-06, 0.0, 0.0, 0.0))
IMU = dict(mass=0.001, com=(0.0, 0.0, 0.0), inertia=(1e-4, 1e-4, 1e-4, 0.0, 0.0, 0.0))
IMU_ORIGIN = (-0.01592, -0.06659, -0.00617)  # [m] in the trunk frame.

COLORS = {"trunk": "0.15 0.15 0.17 1", "leg": "0.75 0.75 0.78 1", "rotor": "0.25 0.25 0.28 1", "foot": "0.1 0.1 0.1 1"}


def _mirror(props: dict, *, left: bool, rear: bool) -> dict:
    """Mirrors FR inertial data: left legs flip y (COM y, Ixy, Iyz); rear hips flip x (COM x, Ixy, Ixz)."""
    x, y, z = props["com"]
    ixx, iyy, izz, ixy, ixz, iyz = props["inertia"]
    if left:
        y, ixy, iyz = -y, -ixy, -iyz
    if rear:
        x, ixy, ixz = -x, -ixy, -ixz
    return dict(mass=props["mass"], com=(x, y, z), inertia=(ixx, iyy, izz, ixy, ixz, iyz))


def _f(values) -> str:
    return " ".join(f"{v:.12g}" for v in values)


def _inertial(props: dict) -> str:
    ixx, iyy, izz, ixy, ixz, iyz = props["inertia"]
    return (
        f'    <inertial>\n      <origin xyz="{_f(props["com"])}" rpy="0 0 0"/>\n'
        f'      <mass value="{props["mass"]:.12g}"/>\n'
        f'      <inertia ixx="{ixx:.12g}" ixy="{ixy:.12g}" ixz="{ixz:.12g}" iyy="{iyy:.12g}" '
        f'iyz="{iyz:.12g}" izz="{izz:.12g}"/>\n    </inertial>\n'
    )


def _shape(tag: str, shape: str, xyz, rpy, color: str | None = None) -> str:
    material = f'      <material><color rgba="{color}"/></material>\n' if color else ""
    return (
        f'    <{tag}>\n      <origin xyz="{_f(xyz)}" rpy="{_f(rpy)}"/>\n'
        f"      <geometry>{shape}</geometry>\n{material}    </{tag}>\n"
    )


def _link(name: str, body: str) -> str:
    return f'  <link name="{name}">\n{body}  </link>\n'


def _joint(name, kind, parent, child, xyz, axis=None, limits=None) -> str:
    text = f'  <joint name="{name}" type="{kind}">\n    <origin xyz="{_f(xyz)}" rpy="0 0 0"/>\n'
    text += f'    <parent link="{parent}"/>\n    <child link="{child}"/>\n'
    if axis is not None:
        text += f'    <axis xyz="{_f(axis)}"/>\n'
    if limits is not None:
        lo, hi, effort, velocity = limits
        text += f'    <limit lower="{lo}" upper="{hi}" effort="{effort}" velocity="{velocity}"/>\n'
        text += '    <dynamics damping="0.01" friction="0"/>\n'
    return text + "  </joint>\n"


def _rotor_link(name: str, spin_axis: int) -> str:
    inertia = [ROTOR_I_OTHER] * 3
    inertia[spin_axis] = ROTOR_I_SPIN
    props = dict(mass=ROTOR_MASS, com=(0, 0, 0), inertia=(*inertia, 0.0, 0.0, 0.0))
    rpy = (0, 1.5707963267948966, 0) if spin_axis == 0 else (1.5707963267948966, 0, 0)
    visual = _shape("visual", '<cylinder radius="0.035" length="0.02"/>', (0, 0, 0), rpy, COLORS["rotor"])
    return _link(name, _inertial(props) + visual)


def _transmission(joint: str, kind: str) -> str:
    return (
        f'  <transmission name="{joint}_tran">\n'
        "    <type>transmission_interface/SimpleTransmission</type>\n"
        f'    <joint name="{joint}"><hardwareInterface>EffortJointInterface</hardwareInterface></joint>\n'
        f'    <actuator name="{joint.replace("_joint", "_motor")}">\n'
        f'      <drake:rotor_inertia value="{ROTOR_I_SPIN}"/>\n'
        f'      <drake:gear_ratio value="{GEAR_RATIO[kind]}"/>\n'
        "    </actuator>\n  </transmission>\n"
    )


def make_urdf() -> str:
    """Returns the Go1 URDF text."""
    out = ['<?xml version="1.0"?>\n', "<!-- Generated by models/go1/generate_go1_urdf.py; do not edit. -->\n"]
    out.append('<robot name="go1" xmlns:drake="http://drake.mit.edu">\n')
    trunk_body = _inertial(TRUNK)
    trunk_body += _shape("visual", '<box size="0.3762 0.0935 0.114"/>', (0, 0, 0), (0, 0, 0), COLORS["trunk"])
    trunk_body += _shape("visual", '<box size="0.03 0.06 0.04"/>', (0.2, 0, 0.0), (0, 0, 0), "0.1 0.5 0.9 1")
    trunk_body += _shape("collision", '<box size="0.3762 0.0935 0.114"/>', (0, 0, 0), (0, 0, 0))
    out.append(_link("trunk", trunk_body))
    out.append(_link("imu_link", _inertial(IMU)))
    out.append(_joint("imu_joint", "fixed", "trunk", "imu_link", IMU_ORIGIN))
    for leg in LEGS:
        left, rear = leg[1] == "L", leg[0] == "R"
        side = 1.0 if left else -1.0
        hx, hy = HIP_ORIGIN[leg]
        hip, thigh, calf, foot = (f"{leg}_{n}" for n in ("hip", "thigh", "calf", "foot"))
        hip_body = _inertial(_mirror(HIP, left=left, rear=rear))
        hip_body += _shape(
            "visual",
            '<cylinder radius="0.046" length="0.04"/>',
            (0, side * THIGH_OFFSET, 0),
            (1.5707963267948966, 0, 0),
            COLORS["leg"],
        )
        out.append(_link(hip, hip_body))
        out.append(_joint(f"{hip}_joint", "revolute", "trunk", hip, (hx, hy, 0), (1, 0, 0), LIMITS["hip"]))
        out.append(_rotor_link(f"{hip}_rotor", spin_axis=0))
        rotor_x = HIP_ROTOR_X if not rear else -HIP_ROTOR_X
        out.append(_joint(f"{hip}_rotor_joint", "fixed", "trunk", f"{hip}_rotor", (rotor_x, hy, 0)))
        thigh_body = _inertial(_mirror(THIGH, left=left, rear=False))
        thigh_body += _shape(
            "visual", '<box size="0.034 0.0245 0.213"/>', (0, 0, -LINK_LENGTH / 2), (0, 0, 0), COLORS["leg"]
        )
        thigh_body += _shape("collision", '<box size="0.034 0.0245 0.213"/>', (0, 0, -LINK_LENGTH / 2), (0, 0, 0))
        out.append(_link(thigh, thigh_body))
        out.append(
            _joint(f"{thigh}_joint", "revolute", hip, thigh, (0, side * THIGH_OFFSET, 0), (0, 1, 0), LIMITS["thigh"])
        )
        out.append(_rotor_link(f"{thigh}_rotor", spin_axis=1))
        out.append(_joint(f"{thigh}_rotor_joint", "fixed", hip, f"{thigh}_rotor", (0, -side * THIGH_ROTOR_INBOARD, 0)))
        # The reference description uses the FR calf's inertial values on every leg.
        calf_body = _inertial(CALF)
        calf_body += _shape(
            "visual", '<box size="0.016 0.016 0.213"/>', (0, 0, -LINK_LENGTH / 2), (0, 0, 0), COLORS["leg"]
        )
        calf_body += _shape("collision", '<box size="0.016 0.016 0.18"/>', (0, 0, -0.09), (0, 0, 0))
        out.append(_link(calf, calf_body))
        out.append(_joint(f"{calf}_joint", "revolute", thigh, calf, (0, 0, -LINK_LENGTH), (0, 1, 0), LIMITS["calf"]))
        out.append(_rotor_link(f"{calf}_rotor", spin_axis=1))
        out.append(_joint(f"{calf}_rotor_joint", "fixed", thigh, f"{calf}_rotor", (0, -side * CALF_ROTOR_INBOARD, 0)))
        foot_body = _inertial(FOOT)
        foot_body += _shape("visual", f'<sphere radius="{FOOT_RADIUS}"/>', (0, 0, 0), (0, 0, 0), COLORS["foot"])
        foot_body += _shape("collision", f'<sphere radius="{FOOT_RADIUS}"/>', (0, 0, 0), (0, 0, 0))
        out.append(_link(foot, foot_body))
        out.append(_joint(f"{leg}_foot_fixed", "fixed", calf, foot, (0, 0, -LINK_LENGTH)))
        for kind in ("hip", "thigh", "calf"):
            out.append(_transmission(f"{leg}_{kind}_joint", kind))
    out.append("</robot>\n")
    return "".join(out)


if __name__ == "__main__":
    path = Path(__file__).with_name("go1.urdf")
    path.write_text(make_urdf())
    print(f"wrote {path}")
