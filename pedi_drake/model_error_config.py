"""Model error as scenario data: how the simulated Go1 differs from the Go1 the controllers model.

The controllers, the estimator and the IK use `pedi_drake.robot`'s Go1 (13.1 kg, motors that
apply exactly the commanded torque, rigid feet of radius robot.FOOT_RADIUS). A real Go1 differs:
it carries things, its motors are weaker than their rating and respond late, its joints lose
torque to friction, its rubber feet are larger and soft. `ModelErrorConfig` (the scenario's
`model_error:`) says by how much; the simulated station applies it to its own plant and motor
model only (`pedi_drake.station.model_error`): never to the controllers' model, the estimator or
the hardware path. Every default is no error.
"""

import dataclasses
import math

import numpy as np
from pydrake.multibody.plant import MultibodyPlantConfig

from pedi_drake import robot

# A motor at most this much stronger than its rating [-]: beyond it the law would clamp at
# torques the Go1's motors cannot reach.
MAX_MOTOR_STRENGTH = 1.5
# The longest command latency a scenario may ask for [s]: ten times the Go1's measured
# round trip, and far past where the controllers hold (their period is 2 ms).
MAX_COMMAND_LATENCY = 0.1
# Foot radii the plant accepts [m]: a foot much smaller or larger than the Go1's 2 cm is another robot.
FOOT_RADIUS_RANGE = (0.01, 0.04)
# Upper bounds of the joint losses [N m s/rad, N m]. The motor model applies them explicitly (from
# the state at the start of a step), stable while (damping + friction / band) * time_step stays well
# below twice the lightest joint's inertia (about 0.016 kg m^2 at the calf, rotor included): at
# 1 ms these bounds give at most 12 N m s/rad against a limit of about 30.
MAX_JOINT_DAMPING = 2.0
MAX_JOINT_FRICTION = 1.0


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
