"""Settings of the whole-body controller, loaded as part of the Scenario (`whole_body:`).

Owned by the whole-body controller; the Scenario only holds an instance.
"""

import dataclasses
import math

STACKS = ("paper000", "paper003")
HQP_MODES = ("strict", "weighted")


@dataclasses.dataclass
class PdGainsConfig:
    """Task-space PD of Eq. 1: a = a_ref + kp (x_ref - x) + kd (v_ref - v)."""

    kp: float = 100.0  # stiffness [1/s^2]
    kd: float = 20.0  # damping [1/s]


@dataclasses.dataclass
class ContactsConfig:
    """The contact settings both whole-body controllers share (their fields, at the top level of
    `whole_body:` and `projected_impedance:`)."""

    # Friction coefficient used when the `friction` input is not connected [-].
    friction: float = 0.6
    # Use the friction pyramid inscribed in the cone (mu / sqrt 2), conservative [-].
    friction_pyramid_inscribed: bool = True
    # Minimum normal force of a fully active contact [N].
    min_normal_force: float = 5.0
    # Maximum normal force of a fully active contact [N].
    max_normal_force: float = 250.0
    # Time over which a contact's force bounds ramp in (touch-down) or out (lift-off) [s].
    contact_ramp_time: float = 0.3
    # Velocity damping of the held contacts' no-motion (their constraint) [1/s].
    contact_damping: float = 10.0


@dataclasses.dataclass
class WholeBodyControllerConfig(ContactsConfig):
    """Whole-body QP controller settings."""

    # Control period [s] (500 Hz default; 1 kHz must also work).
    period: float = 0.002
    # Task stack preset: "paper000" (2 levels + regularisation) or "paper003" (5 levels).
    stack: str = "paper000"
    # "strict": each level optimises in the optimal set of the levels above; "weighted": one QP.
    hqp_mode: str = "strict"
    # Weighted mode: weight of each level of the stack, top first [-]. Empty: 100^(L-1-k) for the
    # L levels of the stack (physics 1e6 ... regularisation 1 for paper000).
    level_weights: list[float] = dataclasses.field(default_factory=list)
    # paper003 only: also keep the capture point in the safety polygon in its first level.
    paper003_balance: bool = True

    # Fraction of the effort limits the QP may use; the rest is headroom for the joint PD [-].
    torque_limit_scale: float = 0.9
    # Horizon over which joint position/velocity limits become acceleration bounds [s].
    joint_limit_horizon: float = 0.05
    # Distance kept from the joint position limits [rad].
    joint_limit_margin: float = 0.02

    # Capture-point prediction horizon of the balance task [s].
    balance_horizon: float = 0.05
    # Include Jdot_com v in the capture-point prediction (exact, but more work every tick) [-].
    balance_com_bias: bool = False
    # Default safety polygon: the stance contacts' support polygon shrunk by this margin [m].
    safety_margin: float = 0.03

    # Trunk position tracking gains (Eq. 1).
    trunk_position: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(100.0, 20.0))
    # Trunk attitude tracking gains (Eq. 1).
    trunk_orientation: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(150.0, 25.0))
    # Pedipulation / swing foot position tracking gains (Eq. 1).
    foot_position: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(400.0, 40.0))
    # Calf roll and pitch tracking of the 5-D foot task (leg mode 3), in the foot's level.
    foot_orientation: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(200.0, 30.0))
    # Joint-space tracking gains of a leg driven by a joint reference (and of idle swing legs).
    leg_joints: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(200.0, 30.0))
    # Whole-robot posture regularisation gains (towards `nominal_leg_posture`).
    posture: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(20.0, 5.0))
    # Nominal (hip, thigh, calf) of every leg for posture regularisation and idle swing legs [rad].
    nominal_leg_posture: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.9, -1.8])
    # Weights inside the regularisation level: posture, contact forces, torques [-].
    posture_weight: float = 1e-2
    force_regularization_weight: float = 1e-4
    torque_weight: float = 1e-3

    # Joint PD gains of go1.command around the integrated reference [N m/rad], [N m s/rad].
    joint_kp: float = 8.0
    joint_kd: float = 0.4
    # The integrated reference is kept within this distance of the measured joints [rad].
    max_reference_deviation: float = 0.05
    # ... and its rate within this distance of the measured rates [rad/s].
    max_reference_rate_deviation: float = 0.5
    # Joint damping sent while holding the last good command after a failed QP [N m s/rad].
    failure_kd: float = 1.0


FORCE_ESTIMATES = ("impedance", "joint_torque")


@dataclasses.dataclass
class ProjectedImpedanceConfig(ContactsConfig):
    """Paper 002's controller: projected inverse dynamics, foot impedance, contact-force QP."""

    # Control period [s] (500 Hz default).
    period: float = 0.002
    # Stiffness of the lifted feet along world x, y, z [N/m] (Eq. 10, K_s).
    foot_stiffness: list[float] = dataclasses.field(default_factory=lambda: [600.0, 600.0, 600.0])
    # Damping of the lifted feet along world x, y, z [N s/m] (Eq. 10, D_s).
    foot_damping: list[float] = dataclasses.field(default_factory=lambda: [30.0, 30.0, 30.0])
    # Stiffness of the lifted calf's pitch and roll in the 5-D foot task [N m/rad].
    foot_orientation_stiffness: float = 20.0
    # Damping of the lifted calf's pitch and roll in the 5-D foot task [N m s/rad].
    foot_orientation_damping: float = 1.0
    # Joint stiffness of a lifted leg without a foot task, held at `nominal_leg_posture` [N m/rad].
    idle_leg_stiffness: float = 30.0
    # Joint damping of such a leg [N m s/rad].
    idle_leg_damping: float = 1.0
    # Trunk tracking in the feet's null space, gains per unit of its inertia [1/s^2], [1/s].
    trunk_position: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(100.0, 20.0))
    # Trunk attitude tracking in the feet's null space [1/s^2], [1/s].
    trunk_orientation: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(150.0, 25.0))
    # Trunk position before its attitude (two levels): when the feet leave the trunk fewer than
    # six free directions, it keeps to its path and yields attitude. False: one level of 6 rows.
    # On loaded prongs the attitude always comes first (a prong tip pins the position).
    torso_position_first: bool = True
    # Joint posture in the null space of the feet and the trunk [1/s^2], [1/s].
    posture: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(20.0, 5.0))
    # Nominal (hip, thigh, calf) of every leg for the posture and idle legs [rad].
    nominal_leg_posture: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.9, -1.8])
    # Relative SVD tolerance of the pseudo-inverses (contact Jacobian, inertias) [-].
    rank_tolerance: float = 1e-6

    # Fraction of the effort limits the contact QP may use [-].
    torque_limit_scale: float = 0.9
    # Contact QP weights: squared torques [1/(N m)^2] and squared distance of the forces from an
    # even share of the weight [1/N^2]. The share term keeps load on the feet when prongs are down
    # (torques alone would put it all on the prongs, which cost no torque, and leave a placed foot
    # at its minimum force).
    torque_weight: float = 1.0
    force_regularization_weight: float = 0.1

    # Low-pass time constant of the foot error acceleration in the force estimate (Eq. 11) [s].
    force_estimate_filter_time: float = 0.02

    # Joint PD gains of go1.command around the integrated reference [N m/rad], [N m s/rad]. Zero
    # by default: the torque alone is the law. A joint stiffness would add to the commanded foot
    # stiffness, and so would a damping towards the integrated rate: under a steady external force
    # the model keeps planning an acceleration it does not get, the integrated rate runs to its
    # clip, and kd times that clip pushes back (about 1 N at the foot with kd = 0.3).
    joint_kp: float = 0.0
    joint_kd: float = 0.0
    # The integrated reference is kept within this distance of the measured joints [rad].
    max_reference_deviation: float = 0.05
    # ... and its rate within this distance of the measured rates [rad/s].
    max_reference_rate_deviation: float = 0.5
    # Joint damping sent while holding the last good command after a failed QP [N m s/rad].
    failure_kd: float = 1.0

    def validate(self, where: str = "projected_impedance") -> list[str]:
        """Problems with the settings, each naming its field (empty when all is well)."""
        problems = []

        def need(condition: bool, field: str, problem: str) -> None:
            if not condition:
                problems.append(f"{where}.{field}: {problem}")

        for name in ("foot_stiffness", "foot_damping"):
            values = getattr(self, name)
            need(len(values) == 3, name, f"expected [x, y, z], got {values}")
        need(all(math.isfinite(k) and k > 0 for k in self.foot_stiffness), "foot_stiffness", "must be > 0 N/m")
        need(all(math.isfinite(d) and d >= 0 for d in self.foot_damping), "foot_damping", "must be >= 0 N s/m")
        positive = (
            "period",
            "foot_orientation_stiffness",
            "idle_leg_stiffness",
            "rank_tolerance",
            "friction",
            "max_normal_force",
            "contact_ramp_time",
            "torque_limit_scale",
            "torque_weight",
            "force_estimate_filter_time",
            "max_reference_deviation",
            "max_reference_rate_deviation",
        )
        for name in positive:
            value = getattr(self, name)
            need(math.isfinite(value) and value > 0, name, f"must be > 0, got {value}")
        non_negative = (
            "foot_orientation_damping",
            "idle_leg_damping",
            "min_normal_force",
            "contact_damping",
            "force_regularization_weight",
            "joint_kp",
            "joint_kd",
            "failure_kd",
        )
        for name in non_negative:
            value = getattr(self, name)
            need(math.isfinite(value) and value >= 0, name, f"must be >= 0, got {value}")
        need(self.torque_limit_scale <= 1.0, "torque_limit_scale", "must be at most 1")
        need(self.min_normal_force <= self.max_normal_force, "min_normal_force", "must not exceed max_normal_force")
        need(len(self.nominal_leg_posture) == 3, "nominal_leg_posture", "expected [hip, thigh, calf] in radians")
        for name in ("trunk_position", "trunk_orientation", "posture"):
            gains = getattr(self, name)
            need(gains.kp >= 0 and gains.kd >= 0, name, "kp and kd must be >= 0")
        return problems


@dataclasses.dataclass
class StandControllerConfig:
    """The joint-space PD that takes the Go1 from its initial pose to standing and holds it."""

    # Target joint pose, (hip, thigh, calf) applied to all legs [rad].
    target_leg_pose: list[float] = dataclasses.field(default_factory=lambda: [0.0, 0.9, -1.8])
    # Duration of the quintic blend from the measured pose to the target [s].
    duration: float = 1.5
    # Motor PD gains [N m/rad], [N m s/rad].
    kp: float = 60.0
    kd: float = 2.0
    # Control period [s].
    period: float = 0.002
