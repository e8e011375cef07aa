"""The Scenario: the single source of truth for a run, in simulation or on hardware.

Loaded from YAML with `load_scenario(filename=..., scenario_name=..., scenario_text=...)`, in the
manner of Drake's examples/hardware_sim: a file holds named scenarios; `scenario_text` is a YAML
mapping merged on top (for command-line overrides). Every value is checked on load and an
error names the file and the field.
"""

import dataclasses
import math
from pathlib import Path

from pydrake.common.yaml import yaml_load, yaml_load_typed
from pydrake.lcm import DrakeLcmParams
from pydrake.multibody.plant import MultibodyPlantConfig

from pedi_drake.config_validation import check_against_schema
from pedi_drake.control.config import (
    FORCE_ESTIMATES,
    ProjectedImpedanceConfig,
    StandControllerConfig,
    WholeBodyControllerConfig,
)
from pedi_drake.estimation.config import KalmanEstimatorConfig
from pedi_drake.exceptions import ProngDesignError, ScenarioError
from pedi_drake.go1_driver.config import Go1DriverConfig
from pedi_drake.go1_driver.constants import DEFAULT_GO1_LCM_URL, GO1_BUS_NAME
from pedi_drake.prongs import ProngDesign
from pedi_drake.resources import models_dir, scenarios_dir

SCENE_OBJECT_KINDS = ("door", "box", "target_panel", "back_object", "fixed_obstacle", "soft_obstacle")
INITIAL_POSES = ("lying", "standing")
ESTIMATORS = ("ground_truth", "kalman")
CONTROLLERS = ("stand_pd", "whole_body", "projected_impedance")
# The controllers that run missions (the same ports; see pedi_drake.control).
MISSION_CONTROLLERS = ("whole_body", "projected_impedance")


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
    # joints the kind expects (see pedi_drake/station/scene.py).
    model: str = ""


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
    # Simulated sensor noise.
    sensor_noise: SensorNoiseConfig = dataclasses.field(default_factory=SensorNoiseConfig)
    # Which controller drives the robot: "stand_pd", "whole_body" (the HQP of papers 000 / 003) or
    # "projected_impedance" (paper 002's projected inverse dynamics with foot impedance).
    controller: str = "stand_pd"
    # Settings of the stand controller.
    stand: StandControllerConfig = dataclasses.field(default_factory=StandControllerConfig)
    # Settings of the whole-body controller.
    whole_body: WholeBodyControllerConfig = dataclasses.field(default_factory=WholeBodyControllerConfig)
    # Settings of paper 002's projected-impedance controller.
    projected_impedance: ProjectedImpedanceConfig = dataclasses.field(default_factory=ProjectedImpedanceConfig)
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
    # Meshcat publish period for the live view and the HTML replay [s].
    visualization_period: float = 1.0 / 32.0

    def validate(self, where: str = "scenario", base_dir: Path | None = None) -> None:
        """Raises ScenarioError naming the field when a value is out of its allowed set or range.

        `base_dir` is the folder relative model paths are resolved from (the scenario file's).
        """

        def need(condition: bool, field: str, problem: str) -> None:
            if not condition:
                raise ScenarioError(f"{where}: {field}: {problem}")

        need(self.simulation_duration > 0, "simulation_duration", f"must be > 0 s, got {self.simulation_duration}")
        need(self.plant_config.time_step > 0, "plant_config.time_step", "must be > 0 (a discrete plant)")
        need(self.robot.initial_pose in INITIAL_POSES, "robot.initial_pose", f"must be one of {INITIAL_POSES}")
        need(len(self.robot.initial_xy) == 2, "robot.initial_xy", "expected [x, y] in metres")
        need(self.controller in CONTROLLERS, "controller", f"must be one of {CONTROLLERS}, got {self.controller!r}")
        need(self.estimator in ESTIMATORS, "estimator", f"must be one of {ESTIMATORS}, got {self.estimator!r}")
        need(self.ground_friction > 0, "ground_friction", "must be > 0")
        need(len(self.stand.target_leg_pose) == 3, "stand.target_leg_pose", "expected [hip, thigh, calf] in radians")
        need(self.stand.duration > 0 and self.stand.period > 0, "stand", "duration and period must be > 0")
        names = set()
        for i, obj in enumerate(self.scene):
            need(
                obj.kind in SCENE_OBJECT_KINDS,
                f"scene[{i}].kind",
                f"must be one of {SCENE_OBJECT_KINDS}, got {obj.kind!r}",
            )
            need(len(obj.position) == 3, f"scene[{i}].position", "expected [x, y, z] in metres")
            if obj.model:
                need(
                    resolve_model_path(obj.model, base_dir).exists(),
                    f"scene[{i}].model",
                    f"model file not found: {obj.model!r}",
                )
            name = obj.name or obj.kind
            need(name not in names, f"scene[{i}].name", f"duplicate object name {name!r}")
            names.add(name)
        if self.robot.prongs is not None:
            try:
                self.robot.prongs.validate(where="robot.prongs")
            except ProngDesignError as error:
                raise ScenarioError(f"{where}: {error}") from None
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
        for number_field in ("simulation_duration", "visualization_period", "ground_friction"):
            need(math.isfinite(getattr(self, number_field)), number_field, "must be finite")


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
    scenario = apply_scenario_text(scenario, scenario_text)
    _make_model_paths_absolute(scenario, filename.parent)
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
