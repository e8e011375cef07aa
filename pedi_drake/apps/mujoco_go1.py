"""The Go1 in MuJoCo behind the motor drivers: a second physics engine for the robot side of the wire.

`MujocoGo1(scenario)` builds the MuJoCo world of a scenario (models/go1/go1.xml, the scenario's
prongs welded to the trunk, its scene objects converted from their SDF by `mujoco_scene`, the
floor's friction) and steps it as a Go1 bridge does, with no LCM and no clock: lock-step tests
drive it directly, `pedi_drake.apps.mujoco_bridge` puts it on the wire at wall time.

- Initial state: the Drake station's (`pedi_drake.station.initial_state`: lying, level, at the
  scenario's x, y and yaw), raised so that the lowest MuJoCo foot sphere (radius 0.023 m, the
  project's 0.02 m) starts GROUND_CLEARANCE above the floor, then left to come to rest under the
  hold for SETTLE_TIME and put back at the scenario's x, y (`_settle`): the robot lies at rest
  where the scenario places it when the run begins.
- Motors: every physics step applies the wire's law tau = tau_ff + kp (q_des - q) + kd (qd_des -
  qd) from the last command, clamped to the effort limits, with q and qd read from the joint
  sensors at the start of the step (`mj_step1`, then the torques, then `mj_step2`). Before the
  first command it holds the joint angles of its first status with HOLD_KP, HOLD_KD, as
  `sim_bridge` does.
- Physics step PHYSICS_STEP = 1 ms, two steps per 500 Hz bridge tick: the motor drivers close
  their PD loop faster than the wire (the law is explicit here, and a stiff kd on the calf's
  small inertia, 0.01 kg m^2 of armature plus the link, stays well inside the explicit stability
  bound kd dt / I < 2 at 1 ms for any kd up to ~20 N m s/rad), the soft foot contact (30 ms time
  constant) is resolved with many steps, and the bridge keeps real time with both on one core.
- Status (`status_sample`, the layout of pedi_drake.apps.status_sample): joint q, qd from the
  joint sensors, tau_est the applied actuator torque, the IMU's frame quaternion (trunk in world,
  w x y z), gyro and accelerometer (specific force, trunk frame), and each foot's normal contact
  force [N] summed over its contacts, as the Drake station's go1.foot_contact. With the
  scenario's sensor_noise enabled, Gaussian noise of the same standard deviations is added.
- Truth (`truth_sample`): trunk position and quaternion, foot sphere centres, and the normal
  contact force between each scene object and each foot / the rest of the robot, in the layout
  of pedi_drake.station.scene_contact (`scene_contact_index`).
- Pushes (`Scenario.pushes`) are applied to the named body with `push_force_W`, as the station does.
"""

import dataclasses
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
from pydrake.math import RigidTransform

from pedi_drake import robot
from pedi_drake.apps.mujoco_scene import SceneBodies, add_scene
from pedi_drake.apps.status_sample import SAMPLE, SAMPLE_SIZE
from pedi_drake.exceptions import ConfigError
from pedi_drake.go1_command import COMMAND_SIZE, pack_command, pd_torque
from pedi_drake.go1_driver import constants as c
from pedi_drake.leg_kinematics import foot_position_B
from pedi_drake.prongs import ProngDesign
from pedi_drake.resources import models_dir
from pedi_drake.scenario import Scenario
from pedi_drake.station.disturbance import push_force_W
from pedi_drake.station.initial_state import GROUND_CLEARANCE, initial_joint_positions, initial_trunk_pose
from pedi_drake.station.scene_contact import ROBOT_CONTACT_SOURCES

PHYSICS_STEP = 0.001  # [s] (module docstring)
# The initial pose rests under the hold this long before the run starts [s] (MujocoGo1._settle).
SETTLE_TIME = 1.0
MJCF_PATH = models_dir() / "go1" / "go1.xml"
# Gains with which the robot holds its first measured pose until the first command [N m/rad], [N m s/rad];
# sim_bridge's HOLD_KP, HOLD_KD.
HOLD_KP = 60.0
HOLD_KD = 2.0
PRONG_ROD_RADIUS = 0.006  # [m] as robot.add_go1 draws and weighs it


def mujoco_foot_radius() -> float:
    """Radius of the MuJoCo foot spheres [m] (models/go1/go1.xml)."""
    model = mujoco.MjModel.from_xml_path(str(MJCF_PATH))
    return float(model.geom_size[model.geom(robot.FOOT_BODY_NAMES[0]).id, 0])


def mujoco_initial_trunk_pose(scenario: Scenario, foot_radius: float) -> RigidTransform:
    """The Drake station's initial trunk pose, raised until the lowest foot sphere of radius
    `foot_radius` [m] is GROUND_CLEARANCE above the ground (prongs, if any, stay where they rest)."""
    X_WB = initial_trunk_pose(scenario.robot)
    q = initial_joint_positions(scenario.robot)
    lowest = min(foot_position_B(leg, q[robot.leg_slice(leg)])[2] for leg in robot.LEG_NAMES)
    z_feet = X_WB.translation()[2] + lowest  # level trunk: the lowest foot centre's height
    raise_by = max(0.0, foot_radius + GROUND_CLEARANCE - z_feet)
    return RigidTransform(X_WB.rotation(), X_WB.translation() + [0.0, 0.0, raise_by])


def _add_prongs(trunk: ET.Element, design: ProngDesign) -> None:
    """The prongs of robot.add_go1 as bodies welded to the trunk: a rod (mass, inertia) and its tip sphere."""
    design.validate()
    length, mass = design.length, design.mass
    # Solid cylinder about its centre, shifted to the attachment point (robot._add_prongs).
    i_axis = 0.5 * mass * PRONG_ROD_RADIUS**2
    i_cross = mass * (3 * PRONG_ROD_RADIUS**2 + length**2) / 12.0
    for i, p_BA in enumerate(design.attachment_points):
        body = ET.SubElement(trunk, "body", name=f"prong_{i}", pos=" ".join(f"{float(v):.12g}" for v in p_BA))
        if mass > 0.0:
            inertia = f"{i_cross:.12g} {i_cross:.12g} {i_axis:.12g}"
            ET.SubElement(body, "inertial", pos=f"0 0 {-length / 2:.12g}", mass=f"{mass:.12g}", diaginertia=inertia)
        rod = {"type": "cylinder", "size": f"{PRONG_ROD_RADIUS} {length / 2:.12g}", "pos": f"0 0 {-length / 2:.12g}"}
        ET.SubElement(body, "geom", {"name": f"prong_{i}_rod", "class": "visual", "rgba": "0.9 0.5 0.1 1", **rod})
        tip = {"type": "sphere", "size": f"{design.tip_radius:.12g}", "pos": f"0 0 {-length:.12g}"}
        friction = f"{design.friction:.12g} 0.005 0.0001"
        ET.SubElement(
            body, "geom", {"name": f"prong_{i}_tip", "class": "collision", "priority": "1", "friction": friction, **tip}
        )


def world_mjcf(scenario: Scenario, foot_radius: float | None = None) -> tuple[str, list[SceneBodies]]:
    """The MJCF text of `scenario`'s world (robot variant, floor friction, scene) and its scene objects."""
    root = ET.parse(MJCF_PATH).getroot()
    worldbody = root.find("worldbody")
    floor = worldbody.find("geom[@name='floor']")
    floor.set("friction", f"{scenario.ground_friction:.12g} 0.005 0.0001")
    if scenario.robot.prongs is not None:
        _add_prongs(worldbody.find("body[@name='trunk']"), scenario.robot.prongs)
    X_WB0 = mujoco_initial_trunk_pose(scenario, foot_radius if foot_radius is not None else mujoco_foot_radius())
    scene = add_scene(root, scenario.scene, X_WB0, scenario.ground_friction)
    return ET.tostring(root, encoding="unicode"), scene


@dataclasses.dataclass(frozen=True)
class TruthSample:
    """The ground truth of one instant: trunk pose, feet and robot-object contact forces."""

    p_WB: np.ndarray  # (3,) [m]
    quaternion_WB: np.ndarray  # (4,) w, x, y, z
    p_WF: np.ndarray  # (4, 3) foot sphere centres FR, FL, RR, RL [m]
    scene_contact_forces: np.ndarray  # (num objects * 5,) [N], scene_contact's layout


class MujocoGo1:
    """The Go1 of `scenario` in MuJoCo, stepped by the bridge period with the wire's motor law.

    build (constructor), `reset`, `apply_command`, `tick` (one bridge period) or `step` (one physics
    step), `status_sample`, `truth_sample`. No clock, no LCM: see the module docstring.
    """

    def __init__(self, scenario: Scenario, *, physics_step: float = PHYSICS_STEP, period: float = c.BRIDGE_PERIOD):
        steps = period / physics_step
        if abs(steps - round(steps)) > 1e-9 or round(steps) < 1:
            raise ConfigError(f"physics step {physics_step} s does not divide the bridge period {period} s")
        self.scenario = scenario
        self.steps_per_tick = int(round(steps))
        self.period = period
        text, self.scene = world_mjcf(scenario)
        self.model = mujoco.MjModel.from_xml_string(text)
        self.model.opt.timestep = physics_step
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.scene_names = [obj.name for obj in self.scene]
        joints = [m.joint(name) for name in robot.JOINT_NAMES]
        self._qpos = np.array([m.jnt_qposadr[j.id] for j in joints])
        self._sensor = {name: self._sensor_slice(name) for name in ("imu_quat", "imu_gyro", "imu_acc")}
        self._q_sensors = np.concatenate([self._sensor_range(f"{n}_pos") for n in robot.JOINT_NAMES])
        self._qd_sensors = np.concatenate([self._sensor_range(f"{n}_vel") for n in robot.JOINT_NAMES])
        self._tau_sensors = np.concatenate([self._sensor_range(f"{n}_force") for n in robot.MOTOR_NAMES])
        self._actuators = np.array([m.actuator(name).id for name in robot.MOTOR_NAMES])
        self._effort = robot.EFFORT_LIMIT.copy()
        self._trunk = m.body(robot.TRUNK_BODY_NAME).id
        self._feet = np.array([m.body(name).id for name in robot.FOOT_BODY_NAMES])
        self._free = m.joint("floating_base")
        # Contact sources by geom: foot number (0-3) or "other" (4) for robot geoms; object number for scene geoms.
        robot_bodies = {self._trunk} | {b for b in range(m.nbody) if self._in_subtree(b, self._trunk)}
        self._geom_source = np.full(m.ngeom, -1)
        self._geom_object = np.full(m.ngeom, -1)
        scene_body = {m.body(name).id: k for k, obj in enumerate(self.scene) for name in obj.bodies}
        for g in range(m.ngeom):
            body = int(m.geom_bodyid[g])
            if body in robot_bodies:
                foot = np.flatnonzero(self._feet == body)
                self._geom_source[g] = foot[0] if foot.size else len(robot.LEG_NAMES)
            elif body in scene_body:
                self._geom_object[g] = scene_body[body]
        self._pushes = [(push, self._push_body(push, k)) for k, push in enumerate(scenario.pushes)]
        self._noise = scenario.sensor_noise
        self._rng = np.random.default_rng([scenario.random_seed, 7])
        self._force = np.zeros(6)
        self.reset()

    def _in_subtree(self, body: int, root: int) -> bool:
        while body != 0:
            if body == root:
                return True
            body = int(self.model.body_parentid[body])
        return False

    def _sensor_range(self, name: str) -> np.ndarray:
        sensor = self.model.sensor(name)
        return np.arange(sensor.adr[0], sensor.adr[0] + sensor.dim[0])

    def _sensor_slice(self, name: str) -> slice:
        sensor = self.model.sensor(name)
        return slice(int(sensor.adr[0]), int(sensor.adr[0] + sensor.dim[0]))

    def _push_body(self, push, k: int) -> int:
        names = [self.model.body(b).name for b in range(self.model.nbody)]
        matches = [b for b, name in enumerate(names) if name == push.body or name.endswith(f"/{push.body}")]
        if len(matches) != 1:
            raise ConfigError(f"pushes[{k}].body: {push.body!r}: {len(matches)} MuJoCo bodies have that name")
        return matches[0]

    def reset(self) -> None:
        """The initial state (module docstring); no command received, the hold pose not yet taken."""
        mujoco.mj_resetData(self.model, self.data)
        X_WB = mujoco_initial_trunk_pose(self.scenario, float(self.model.geom_size[self.model.geom("FR_foot").id, 0]))
        start = self._free.qposadr[0]
        self.data.qpos[start : start + 3] = X_WB.translation()
        self.data.qpos[start + 3 : start + 7] = X_WB.rotation().ToQuaternion().wxyz()
        self.data.qpos[self._qpos] = initial_joint_positions(self.scenario.robot)
        for obj in self.scene:
            for name, value in obj.initial_joint_positions.items():
                self.data.qpos[self.model.jnt_qposadr[self.model.joint(name).id]] = value
        mujoco.mj_forward(self.model, self.data)
        self.command: np.ndarray | None = None
        self._hold = pack_command(self.data.sensordata[self._q_sensors], 0.0, HOLD_KP, HOLD_KD, 0.0)
        self._settle()
        self._hold = pack_command(self.data.sensordata[self._q_sensors], 0.0, HOLD_KP, HOLD_KD, 0.0)
        self.ticks = 0

    def _settle(self) -> None:
        """Lets the initial pose come to rest under the hold for SETTLE_TIME, then puts the trunk
        back at the scenario's x, y, and the clock at 0. MuJoCo's soft feet sink under any load
        and a robot lying on the prongs' line rolls until its feet take it: that motion belongs
        to how the robot was put down, before the run, not to the run."""
        pushes, self._pushes = self._pushes, []
        for _ in range(int(round(SETTLE_TIME / self.model.opt.timestep))):
            self.step()
        self._pushes = pushes
        start = self._free.qposadr[0]
        self.data.qpos[start : start + 2] = self.scenario.robot.initial_xy
        self.data.time = 0.0
        mujoco.mj_forward(self.model, self.data)

    @property
    def time(self) -> float:
        """Simulated time [s]."""
        return float(self.data.time)

    def apply_command(self, command: np.ndarray | None) -> None:
        """The 60-vector go1.command (q_des, qd_des, kp, kd, tau_ff; Unitree order) the motors apply
        from the next step on, until the next one; None: hold the first measured pose."""
        if command is not None:
            command = np.asarray(command, dtype=float)
            if command.shape != (COMMAND_SIZE,) or not np.isfinite(command).all():
                raise ValueError(f"apply_command: expected {COMMAND_SIZE} finite values, got {command!r}")
        self.command = command

    def applied_command(self) -> np.ndarray:
        """The command the motors apply: the last one received, or the hold before the first."""
        return self.command if self.command is not None else self._hold

    def step(self) -> None:
        """One physics step: read the joint sensors, apply the motor law, integrate."""
        m, d = self.model, self.data
        mujoco.mj_step1(m, d)
        q, qd = d.sensordata[self._q_sensors], d.sensordata[self._qd_sensors]
        tau = np.clip(pd_torque(self.applied_command(), q, qd), -self._effort, self._effort)
        d.ctrl[self._actuators] = tau
        if self._pushes:
            d.qfrc_applied[:] = 0.0
            for push, body in self._pushes:
                point = d.xpos[body] + d.xmat[body].reshape(3, 3) @ np.asarray(push.point, float)
                mujoco.mj_applyFT(m, d, push_force_W(push, d.time), np.zeros(3), point, body, d.qfrc_applied)
        mujoco.mj_step2(m, d)

    def tick(self) -> None:
        """One bridge period of physics steps."""
        for _ in range(self.steps_per_tick):
            self.step()
        self.ticks += 1

    def _contact_normals(self) -> tuple[np.ndarray, np.ndarray]:
        """(foot normal forces (4,), scene contact forces (objects * 5,)) [N] of the current contacts."""
        m, d = self.model, self.data
        feet = np.zeros(len(robot.LEG_NAMES))
        sources = len(ROBOT_CONTACT_SOURCES)
        scene = np.zeros(len(self.scene) * sources)
        for i in range(d.ncon):
            contact = d.contact[i]
            g1, g2 = contact.geom1, contact.geom2
            s1, s2 = self._geom_source[g1], self._geom_source[g2]
            if s1 < 0 and s2 < 0:
                continue
            mujoco.mj_contactForce(m, d, i, self._force)
            normal = abs(self._force[0])
            for s in (s1, s2):
                if 0 <= s < len(feet):
                    feet[s] += normal
            source, obj = (s1, self._geom_object[g2]) if s1 >= 0 else (s2, self._geom_object[g1])
            if obj >= 0:
                scene[obj * sources + source] += normal
        return feet, scene

    def status_sample(self) -> np.ndarray:
        """The status of the last step in the layout of apps.status_sample (50,): q, qd, tau_est,
        imu (quaternion w x y z, gyro, accelerometer), foot normal forces."""
        s = self.data.sensordata
        sample = np.empty(SAMPLE_SIZE)
        sample[SAMPLE["go1.position_measured"]] = s[self._q_sensors]
        sample[SAMPLE["go1.velocity_measured"]] = s[self._qd_sensors]
        sample[SAMPLE["go1.torque_estimated"]] = s[self._tau_sensors]
        imu = SAMPLE["go1.imu"].start
        sample[imu : imu + 4] = s[self._sensor["imu_quat"]]
        sample[imu + 4 : imu + 7] = s[self._sensor["imu_gyro"]]
        sample[imu + 7 : imu + 10] = s[self._sensor["imu_acc"]]
        sample[SAMPLE["go1.foot_contact"]] = self._contact_normals()[0]
        if self._noise.enabled:
            self._add_noise(sample)
        return sample

    def _add_noise(self, sample: np.ndarray) -> None:
        noise, rng = self._noise, self._rng
        for name, sigma in (
            ("go1.position_measured", noise.joint_position),
            ("go1.velocity_measured", noise.joint_velocity),
            ("go1.torque_estimated", noise.joint_torque),
        ):
            sample[SAMPLE[name]] += rng.normal(0.0, sigma, 12)
        imu = SAMPLE["go1.imu"].start
        half = 0.5 * rng.normal(0.0, noise.orientation, 3)  # a small rotation in the trunk frame
        w, v = sample[imu], sample[imu + 1 : imu + 4].copy()
        sample[imu] = w - v @ half
        sample[imu + 1 : imu + 4] = w * half + v + np.cross(v, half)
        sample[imu : imu + 4] /= np.linalg.norm(sample[imu : imu + 4])
        sample[imu + 4 : imu + 7] += rng.normal(0.0, noise.gyro, 3)
        sample[imu + 7 : imu + 10] += rng.normal(0.0, noise.accelerometer, 3)
        feet = SAMPLE["go1.foot_contact"]
        sample[feet] = np.maximum(sample[feet] + rng.normal(0.0, noise.foot_force, 4), 0.0)

    def truth_sample(self) -> TruthSample:
        """The true trunk pose, feet and robot-object contact forces now."""
        d = self.data
        return TruthSample(
            p_WB=d.xpos[self._trunk].copy(),
            quaternion_WB=d.xquat[self._trunk].copy(),
            p_WF=d.xpos[self._feet].copy(),
            scene_contact_forces=self._contact_normals()[1],
        )

    def joint_positions(self) -> np.ndarray:
        """The true joint angles in Unitree order [rad]."""
        return self.data.qpos[self._qpos].copy()
