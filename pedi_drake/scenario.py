"""The Scenario: the single source of truth for a run, in simulation or on hardware.

Loaded from YAML with `load_scenario(filename=..., scenario_name=..., scenario_text=...)`, in the
manner of Drake's examples/hardware_sim: a file holds named scenarios; `scenario_text` is a YAML
mapping merged on top (for command-line overrides). Every value is checked on load and an
error names the file and the field.
"""

import copy
import dataclasses
import functools
import math
import re
from pathlib import Path

from pydrake.common.yaml import yaml_load, yaml_load_typed
from pydrake.lcm import DrakeLcmParams
from pydrake.multibody.plant import MultibodyPlantConfig

from pedi_drake.config_validation import check_against_schema
from pedi_drake.control.config import (
    FORCE_ESTIMATES,
    HQP_MODES,
    STACKS,
    ProjectedImpedanceConfig,
    StandControllerConfig,
    WholeBodyControllerConfig,
)
from pedi_drake.control.controller_switch import ControllerSwitchConfig
from pedi_drake.control.trunk_load_compensation import TrunkLoadCompensationConfig
from pedi_drake.estimation.config import KalmanEstimatorConfig
from pedi_drake.exceptions import ProngDesignError, ScenarioError
from pedi_drake.go1_driver.config import Go1DriverConfig
from pedi_drake.go1_driver.constants import DEFAULT_GO1_LCM_URL, GO1_BUS_NAME
from pedi_drake.go1_driver.pacing import wait_problem
from pedi_drake.model_error_config import ModelErrorConfig
from pedi_drake.operator.command import CONTROLLER_NAMES
from pedi_drake.operator.config import OperatorConfig
from pedi_drake.prongs import ProngDesign
from pedi_drake.resources import models_dir, scenarios_dir
from pedi_drake.runtime.realtime_priority import priority_problem
from pedi_drake.suf.live_config import LiveSufConfig
from pedi_drake.terrain import TERRAIN_KINDS, terrain_problems

SCENE_OBJECT_KINDS = (
    "door",
    "box",
    "target_panel",
    "back_object",
    "fixed_obstacle",
    "soft_obstacle",
    "mobile_obstacle",
    "mobile_soft_obstacle",
    "hand",
    "estop_button",
    *TERRAIN_KINDS,
)
INITIAL_POSES = ("lying", "standing")
ESTIMATORS = ("ground_truth", "kalman")
CONTROLLERS = ("stand_pd", "whole_body", "projected_impedance")
# The controllers that run missions (the same ports; see pedi_drake.control).
MISSION_CONTROLLERS = ("whole_body", "projected_impedance")
# MultibodyPlantConfig's allowed strings (Drake rejects others only when the plant is built).
CONTACT_MODELS = ("point", "hydroelastic", "hydroelastic_with_fallback")
DISCRETE_CONTACT_APPROXIMATIONS = ("", "tamsi", "sap", "similar", "lagged")
# numpy's generators take seeds in [0, 2^32) for the sensor noise streams.
MAX_RANDOM_SEED = 2**32 - 1
# LCM URLs this package can open: UDP multicast (host:port, optional ?ttl=N) or in-process.
_UDPM_URL = re.compile(r"^udpm://(\d{1,3})\.(\d{1,3})\.(\d{1,3})\.(\d{1,3}):(\d{1,5})(\?ttl=\d+)?$")


def lcm_url_is_valid(url: str) -> bool:
    """Whether `url` is a UDP multicast LCM URL (group 224-239.x.x.x, port 1-65535) or memq://."""
    if url == "memq://":
        return True
    match = _UDPM_URL.match(url)
    if match is None:
        return False
    octets, port = [int(g) for g in match.groups()[:4]], int(match.group(5))
    return 224 <= octets[0] <= 239 and all(o <= 255 for o in octets) and 1 <= port <= 65535


def _default_plant_config() -> MultibodyPlantConfig:
    # SAP with point contact: stable at 1 ms for stiff foot contacts, and what paper-style
    # point-contact models of feet and prong tips assume.
    return MultibodyPlantConfig(
        time_step=0.001,
        contact_model="point",
        discrete_contact_approximation="sap",
        penetration_allowance=0.0005,
    )


@dataclasses.dataclass
class RobotConfig:
    """The Go1 variant and where it starts."""

    # Prongs on the trunk; null for the plain Go1.
    prongs: ProngDesign | None = None
    # Initial joint pose: "lying" (crouched on the floor) or "standing".
    initial_pose: str = "lying"
    # Initial trunk position x, y in the world [m]; the height follows from the pose.
    initial_xy: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0])
    # Initial trunk yaw about world z [rad].
    initial_yaw: float = 0.0


@dataclasses.dataclass
class SceneObject:
    """One object of the scene, placed in the world."""

    # One of SCENE_OBJECT_KINDS.
    kind: str = "box"
    # Model instance name; defaults to the kind (must be unique in a scene).
    name: str = ""
    # Position of the object's placement frame in the world [m] (see models/scenes/*.sdf).
    position: list[float] = dataclasses.field(default_factory=lambda: [0.6, 0.0, 0.0])
    # Rotation about world z [rad].
    yaw: float = 0.0
    # Door only: initial opening angle [rad] (0 = closed).
    initial_angle: float = 0.0
    # Optional model file replacing the kind's shipped model: a `package://pedi_drake/...` URL or a
    # path (relative paths are taken from the scenario file's folder). It must have the bodies and
    # joints the kind expects (see pedi_drake/station/scene.py). Terrain takes none.
    model: str = ""
    # Terrain only (slope, platform, friction_patch; pedi_drake.terrain): its extents [m], a
    # slope's angle [deg], and its friction coefficient [-] (0: the ground's).
    size: list[float] = dataclasses.field(default_factory=list)
    angle: float = 0.0
    friction: float = 0.0

    @property
    def instance_name(self) -> str:
        """The object's model instance name in the plant: its name, or its kind when unnamed."""
        return self.name or self.kind


@dataclasses.dataclass
class Push:
    """A push on a body of the simulated world: ramps up, holds, ramps down (a disturbance).

    Applied in the simulated station only (never on hardware, never seen by a controller), and
    logged as `sim.push_force`.
    """

    # Force at full strength [N] (>= 0).
    force: float = 0.0
    # Name of the pushed body (unique in the plant: a Go1 link or a scene object's body).
    body: str = "trunk"
    # Where the force acts, in the body's frame [m].
    point: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])
    # Direction of the force in the world (a unit vector) [-].
    direction: list[float] = dataclasses.field(default_factory=lambda: [1.0, 0.0, 0.0])
    # Simulated time the ramp up begins [s].
    start: float = 0.0
    # Time to ramp from zero to full force, and from full force back to zero [s] (0: a step).
    ramp: float = 0.0
    # Time at full force, between the two ramps [s].
    duration: float = 1.0

    def end(self) -> float:
        """Simulated time the push has ramped back to zero [s]."""
        return self.start + 2 * self.ramp + self.duration

    def problems(self) -> list[tuple[str, str]]:
        """(field, problem) for every invalid value; empty when the push is valid."""
        found = []
        for name in ("force", "start", "ramp", "duration"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                found.append((name, f"must be a finite number >= 0, got {value}"))
        if not self.body:
            found.append(("body", "must name a body of the plant (default trunk)"))
        if len(self.point) != 3:
            found.append(("point", f"expected [x, y, z] in metres (body frame), got {self.point}"))
        if len(self.direction) != 3:
            found.append(("direction", f"expected a unit [x, y, z] vector (world), got {self.direction}"))
        # 1e-3: a direction written to four digits, such as [0.7071, 0.7071, 0], is unit enough.
        elif abs(math.sqrt(sum(v * v for v in self.direction)) - 1.0) > 1e-3:
            found.append(("direction", f"must be a unit vector (world), got {self.direction}"))
        return found


@dataclasses.dataclass
class SensorNoiseConfig:
    """Gaussian noise of the simulated sensors (standard deviations); off unless enabled."""

    enabled: bool = False
    joint_position: float = 0.0005  # [rad]
    joint_velocity: float = 0.01  # [rad/s]
    joint_torque: float = 0.1  # [N m]
    gyro: float = 0.005  # [rad/s]
    accelerometer: float = 0.05  # [m/s^2]
    orientation: float = 0.002  # [rad] about a random axis
    foot_force: float = 1.0  # [N]


@dataclasses.dataclass
class Scenario:
    """Everything a run needs; one file drives both simulation and hardware."""

    # Seed of every random draw in the run (sensor noise, disturbances).
    random_seed: int = 0
    # Simulated duration [s].
    simulation_duration: float = 4.0
    # MultibodyPlant settings (time step, contact model).
    plant_config: MultibodyPlantConfig = dataclasses.field(default_factory=_default_plant_config)
    # The robot variant and its initial state.
    robot: RobotConfig = dataclasses.field(default_factory=RobotConfig)
    # Objects in the scene, besides the flat ground.
    scene: list[SceneObject] = dataclasses.field(default_factory=list)
    # Coulomb friction of the ground [-].
    ground_friction: float = 0.8
    # Pushes on the simulated world (disturbances; simulation only), in any order.
    pushes: list[Push] = dataclasses.field(default_factory=list)
    # Simulated sensor noise.
    sensor_noise: SensorNoiseConfig = dataclasses.field(default_factory=SensorNoiseConfig)
    # How the simulated Go1 differs from the controllers' model (payload, motor strength and
    # latency, joint losses, foot size and softness; simulation only, default none; see
    # pedi_drake.station.model_error for each field's unit and range).
    model_error: ModelErrorConfig = dataclasses.field(default_factory=ModelErrorConfig)
    # Which controller drives the robot: "stand_pd", "whole_body" (the HQP of papers 000 / 003) or
    # "projected_impedance" (paper 002's projected inverse dynamics with foot impedance).
    controller: str = "stand_pd"
    # Settings of the stand controller.
    stand: StandControllerConfig = dataclasses.field(default_factory=StandControllerConfig)
    # Settings of the whole-body controller.
    whole_body: WholeBodyControllerConfig = dataclasses.field(default_factory=WholeBodyControllerConfig)
    # Settings of paper 002's projected-impedance controller.
    projected_impedance: ProjectedImpedanceConfig = dataclasses.field(default_factory=ProjectedImpedanceConfig)
    # Both whole-body controllers in the run, switched by the mission or the operator
    # (pedi_drake.control.controller_switch); `controller` is the one driving at the start.
    controller_switch: ControllerSwitchConfig = dataclasses.field(default_factory=ControllerSwitchConfig)
    # Integral action on the trunk's tracking under a mission: learns the load the controllers'
    # model does not know (payload, weak motors, joint friction); see
    # pedi_drake.control.trunk_load_compensation.
    trunk_load_compensation: TrunkLoadCompensationConfig = dataclasses.field(
        default_factory=TrunkLoadCompensationConfig
    )
    # The foot force estimate of press phases (a mission file may set its own): "joint_torque"
    # (quasi-static, from the estimated joint torques; any controller) or "impedance" (Eq. 11 of
    # paper 002, from the foot's impedance error; controller: projected_impedance only).
    force_estimate: str = "joint_torque"
    # The mission to run (a name in missions/ or a YAML path); empty for none.
    mission: str = ""
    # Floating-base estimate used by controllers: "kalman" (IMU + leg kinematics, simulation and
    # hardware) or "ground_truth" (the simulated plant's state, for debugging only).
    estimator: str = "kalman"
    # Settings of the Kalman estimator.
    kalman: KalmanEstimatorConfig = dataclasses.field(default_factory=KalmanEstimatorConfig)
    # LCM buses by name; the Go1 driver and the simulator bridge use the bus "go1".
    lcm_buses: dict[str, DrakeLcmParams] = dataclasses.field(
        default_factory=lambda: {GO1_BUS_NAME: DrakeLcmParams(lcm_url=DEFAULT_GO1_LCM_URL)}
    )
    # The Go1 LCM driver (controller side: safety bounds, watchdogs, soft start) and the
    # simulator bridge (robot side: latency, drops).
    go1_driver: Go1DriverConfig = dataclasses.field(default_factory=Go1DriverConfig)
    # The operator's input: none, an LCM channel of foot commands, or the Go1 remote (see
    # pedi_drake.operator); its E-stop damps the motors, its commands drive teleop_foot phases.
    operator: OperatorConfig = dataclasses.field(default_factory=OperatorConfig)
    # The live SUF of a mission's lifted-leg stances (pedi_drake.suf.live_suf_system).
    live_suf: LiveSufConfig = dataclasses.field(default_factory=LiveSufConfig)
    # Meshcat publish period for the live view and the HTML replay [s].
    visualization_period: float = 1.0 / 32.0

    def validate(self, where: str = "scenario", base_dir: Path | None = None) -> None:
        """Raises ScenarioError naming the field when a value is out of its allowed set or range.

        `base_dir` is the folder relative model paths are resolved from (the scenario file's).
        """

        def need(condition: bool, field: str, problem: str) -> None:
            if not condition:
                raise ScenarioError(f"{where}: {field}: {problem}")

        for number_field in ("simulation_duration", "visualization_period", "ground_friction"):
            need(math.isfinite(getattr(self, number_field)), number_field, "must be finite")
        need(self.simulation_duration > 0, "simulation_duration", f"must be > 0 s, got {self.simulation_duration}")
        need(
            0 <= self.random_seed <= MAX_RANDOM_SEED,
            "random_seed",
            f"must be an integer in [0, {MAX_RANDOM_SEED}], got {self.random_seed}",
        )
        need(self.plant_config.time_step > 0, "plant_config.time_step", "must be > 0 (a discrete plant)")
        need(
            self.plant_config.contact_model in CONTACT_MODELS,
            "plant_config.contact_model",
            f"must be one of {CONTACT_MODELS}, got {self.plant_config.contact_model!r}",
        )
        need(
            self.plant_config.discrete_contact_approximation in DISCRETE_CONTACT_APPROXIMATIONS,
            "plant_config.discrete_contact_approximation",
            f"must be one of {DISCRETE_CONTACT_APPROXIMATIONS}, got "
            f"{self.plant_config.discrete_contact_approximation!r}",
        )
        need(
            self.visualization_period > 0,
            "visualization_period",
            f"must be > 0 s, got {self.visualization_period}",
        )
        for noise_field in dataclasses.fields(SensorNoiseConfig):
            value = getattr(self.sensor_noise, noise_field.name)
            if noise_field.name != "enabled":
                need(
                    math.isfinite(value) and value >= 0,
                    f"sensor_noise.{noise_field.name}",
                    f"a standard deviation: must be >= 0, got {value}",
                )
        for field, value, allowed in (
            ("whole_body.stack", self.whole_body.stack, STACKS),
            ("whole_body.hqp_mode", self.whole_body.hqp_mode, HQP_MODES),
        ):
            need(value in allowed, field, f"must be one of {allowed}, got {value!r}")
        need(self.whole_body.period > 0, "whole_body.period", f"must be > 0 s, got {self.whole_body.period}")
        need(
            not self.mission or self.controller in MISSION_CONTROLLERS,
            "controller",
            f"the mission {self.mission!r} runs under one of {MISSION_CONTROLLERS}, got {self.controller!r}",
        )
        for bus, params in self.lcm_buses.items():
            need(
                lcm_url_is_valid(params.lcm_url),
                f"lcm_buses[{bus!r}].lcm_url",
                f"expected 'udpm://GROUP:PORT' (a multicast group 224-239.x.x.x, optionally '?ttl=N') or 'memq://', "
                f"got {params.lcm_url!r}",
            )
        need(self.robot.initial_pose in INITIAL_POSES, "robot.initial_pose", f"must be one of {INITIAL_POSES}")
        need(len(self.robot.initial_xy) == 2, "robot.initial_xy", "expected [x, y] in metres")
        need(self.controller in CONTROLLERS, "controller", f"must be one of {CONTROLLERS}, got {self.controller!r}")
        need(self.estimator in ESTIMATORS, "estimator", f"must be one of {ESTIMATORS}, got {self.estimator!r}")
        need(self.ground_friction > 0, "ground_friction", "must be > 0")
        need(len(self.stand.target_leg_pose) == 3, "stand.target_leg_pose", "expected [hip, thigh, calf] in radians")
        need(self.stand.duration > 0 and self.stand.period > 0, "stand", "duration and period must be > 0")
        for problem in scene_problems(self.scene, base_dir):
            raise ScenarioError(f"{where}: {problem}")
        for i, push in enumerate(self.pushes):
            for field, problem in push.problems():
                need(False, f"pushes[{i}].{field}", problem)
        for field, problem in self.controller_switch.problems():
            need(False, f"controller_switch.{field}", problem)
        if self.controller_switch.enabled:
            need(
                self.controller in CONTROLLER_NAMES.values(),
                "controller",
                f"controller_switch runs both {tuple(CONTROLLER_NAMES.values())}: the one driving at the start must "
                f"be one of them, got {self.controller!r}",
            )
            need(
                self.force_estimate != "impedance",
                "force_estimate",
                "'impedance' (Eq. 11) holds only while paper 002's controller drives the motors: with "
                "controller_switch use joint_torque",
            )
            need(
                self.whole_body.period == self.projected_impedance.period,
                "projected_impedance.period",
                f"both controllers tick together: must equal whole_body.period {self.whole_body.period}, "
                f"got {self.projected_impedance.period}",
            )
        for field, problem in self.trunk_load_compensation.problems():
            need(False, f"trunk_load_compensation.{field}", problem)
        for field, problem in self.model_error.problems(self.plant_config):
            need(False, f"model_error.{field}", problem)
        if self.robot.prongs is not None:
            try:
                self.robot.prongs.validate(where="robot.prongs")
            except ProngDesignError as error:
                raise ScenarioError(f"{where}: {error}") from None
        # One control period: the estimator, the controller and the driver tick together (the
        # estimator integrates over its period and the driver's rate limit and watchdogs count it).
        if self.controller == "whole_body":
            periods = {
                "whole_body.period": self.whole_body.period,
                "kalman.period": self.kalman.period,
                "go1_driver.safety.period": self.go1_driver.safety.period,
            }
            need(
                len(set(periods.values())) == 1,
                "whole_body.period",
                f"the control period must be the same everywhere, got {periods}",
            )
        for field, priority in (
            ("go1_driver.realtime_priority", self.go1_driver.realtime_priority),
            ("go1_driver.bridge.realtime_priority", self.go1_driver.bridge.realtime_priority),
        ):
            problem = priority_problem(priority)
            need(problem is None, field, problem or "")
        problem = wait_problem(self.go1_driver.wait)
        need(problem is None, "go1_driver.wait", problem or "")
        for problem in self.kalman.validate(where="kalman"):
            raise ScenarioError(f"{where}: {problem}")
        need(
            self.force_estimate in FORCE_ESTIMATES,
            "force_estimate",
            f"must be one of {FORCE_ESTIMATES}, got {self.force_estimate!r}",
        )
        need(
            self.force_estimate != "impedance" or self.controller == "projected_impedance",
            "force_estimate",
            "'impedance' needs controller: projected_impedance (its Eq. 11 estimate)",
        )
        for problem in self.projected_impedance.validate(where="projected_impedance"):
            raise ScenarioError(f"{where}: {problem}")
        for field, problem in self.operator.problems(self.lcm_buses):
            need(False, f"operator.{field}", problem)
        for field, problem in self.live_suf.problems():
            need(False, f"live_suf.{field}", problem)


def scene_problems(scene: list[SceneObject], base_dir: Path | None, field: str = "scene") -> list[str]:
    """What is wrong with the objects of `scene` ("<field>[i].<name>: <problem>"), model files included.

    `base_dir` is the folder relative model paths are resolved from (the file's that lists them).
    """
    problems, names = [], set()
    for i, obj in enumerate(scene):
        where = f"{field}[{i}]"
        if obj.kind not in SCENE_OBJECT_KINDS:
            problems.append(f"{where}.kind: must be one of {SCENE_OBJECT_KINDS}, got {obj.kind!r}")
        if len(obj.position) != 3:
            problems.append(f"{where}.position: expected [x, y, z] in metres, got {obj.position}")
        if not all(math.isfinite(v) for v in [*obj.position, obj.yaw, obj.initial_angle]):
            problems.append(f"{where}: position, yaw and initial_angle must be finite")
        problems.extend(terrain_problems(obj, where))
        if obj.model and obj.kind not in TERRAIN_KINDS and not resolve_model_path(obj.model, base_dir).is_file():
            searched = "models/" if obj.model.startswith("package://") else (base_dir or Path.cwd())
            problems.append(f"{where}.model: model file not found: {obj.model!r} (looked in {searched})")
        name = obj.instance_name
        if name in names:
            problems.append(f"{where}.name: duplicate object name {name!r} (give each object a unique name)")
        names.add(name)
    return problems


def resolve_model_path(model: str, base_dir: Path | None = None) -> Path:
    """The file behind a scene object's `model` (a package://pedi_drake/ URL or a path)."""
    prefix = "package://pedi_drake/"
    if model.startswith(prefix):
        return models_dir() / model[len(prefix) :]
    path = Path(model)
    if not path.is_absolute() and base_dir is not None:
        path = base_dir / path
    return path


def default_scenario_file() -> Path:
    """The shipped scenarios file."""
    return scenarios_dir() / "default.yaml"


def load_scenario(
    *, filename: str | Path | None = None, scenario_name: str = "default", scenario_text: str = "{}"
) -> Scenario:
    """Loads `scenario_name` from `filename` (default: the shipped file), then applies `scenario_text`.

    Raises ScenarioError naming the file and field on any problem.
    """
    filename = Path(filename) if filename is not None else default_scenario_file()
    if not filename.exists():
        raise ScenarioError(f"{filename}: scenario file not found")
    stat = filename.stat()
    scenario = copy.deepcopy(
        _load_scenario_file(filename, filename.resolve(), scenario_name, stat.st_mtime_ns, stat.st_size)
    )
    scenario = apply_scenario_text(scenario, scenario_text)
    _make_model_paths_absolute(scenario, filename.parent)
    return scenario


# A study validates one scenario per task from the same file: parsed once per version of the file
# (Drake's YAML reader is pure Python), keyed by its modification time and size.
@functools.lru_cache(maxsize=32)
def _load_scenario_file(filename: Path, resolved: Path, scenario_name: str, mtime_ns: int, size: int) -> Scenario:
    """`scenario_name` of `filename` (named so in errors; `resolved`, its modification time and
    size key the cache), checked and validated (`load_scenario`); shared, not to be changed:
    `load_scenario` hands out copies."""
    try:
        raw = yaml_load(filename=str(filename))
    except Exception as error:  # Drake's YAML parser raises RuntimeError with the line.
        raise ScenarioError(f"{filename}: not valid YAML: {error}") from None
    if not isinstance(raw, dict) or scenario_name not in raw:
        available = ", ".join(sorted(raw)) if isinstance(raw, dict) else "none"
        raise ScenarioError(f"{filename}: no scenario named {scenario_name!r}; available: {available}")
    where = f"{filename} [{scenario_name}]"
    check_against_schema(raw[scenario_name], Scenario, "", where, ScenarioError)
    try:
        scenario = yaml_load_typed(schema=Scenario, filename=str(filename), child_name=scenario_name)
    except Exception as error:
        raise ScenarioError(f"{where}: {error}") from None
    scenario.validate(where=where, base_dir=filename.parent)
    return scenario


def _make_model_paths_absolute(scenario: Scenario, base_dir: Path) -> None:
    for obj in scenario.scene:
        if obj.model and not obj.model.startswith("package://"):
            obj.model = str(resolve_model_path(obj.model, base_dir).resolve())


def apply_scenario_text(scenario: Scenario, scenario_text: str) -> Scenario:
    """Merges the YAML mapping `scenario_text` onto `scenario` (the --scenario_text override)."""
    if not scenario_text or scenario_text.strip() in ("", "{}"):
        return scenario
    try:
        raw = yaml_load(data=scenario_text)
    except Exception as error:
        raise ScenarioError(f"--scenario_text: not valid YAML: {error}") from None
    check_against_schema(raw, Scenario, "", "--scenario_text", ScenarioError)
    try:
        merged = yaml_load_typed(schema=Scenario, data=scenario_text, defaults=scenario)
    except Exception as error:
        raise ScenarioError(f"--scenario_text: {error}") from None
    merged.validate(where="--scenario_text")
    return merged
