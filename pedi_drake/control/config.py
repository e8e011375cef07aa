"""Settings of the whole-body controller, loaded as part of the Scenario (`whole_body:`).

Owned by the whole-body controller; the Scenario only holds an instance.
"""

import dataclasses

STACKS = ("paper000", "paper003")
HQP_MODES = ("strict", "weighted")
QP_BACKENDS = ("daqp", "osqp")


@dataclasses.dataclass
class PdGainsConfig:
    """Task-space PD of Eq. 1: a = a_ref + kp (x_ref - x) + kd (v_ref - v)."""

    kp: float = 100.0  # stiffness [1/s^2]
    kd: float = 20.0  # damping [1/s]


@dataclasses.dataclass
class WholeBodyControllerConfig:
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
    # QP backend: "daqp" (dense active set, called directly) or "osqp" (MathematicalProgram, baseline).
    qp_backend: str = "daqp"
    # paper003 only: also keep the capture point in the safety polygon in its first level.
    paper003_balance: bool = True

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
    # Velocity damping of the contact no-motion rows [1/s].
    contact_damping: float = 10.0

    # Fraction of the effort limits the QP may use; the rest is headroom for the joint PD [-].
    torque_limit_scale: float = 0.9
    # Horizon over which joint position/velocity limits become acceleration bounds [s].
    joint_limit_horizon: float = 0.05
    # Distance kept from the joint position limits [rad].
    joint_limit_margin: float = 0.02

    # Capture-point prediction horizon of the balance task [s].
    balance_horizon: float = 0.05
    # Include Jdot_com v in the capture-point prediction (exact, ~70 us a tick more) [-].
    balance_com_bias: bool = False
    # Default safety polygon: the stance contacts' support polygon shrunk by this margin [m].
    safety_margin: float = 0.03

    # Trunk position tracking gains (Eq. 1).
    trunk_position: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(100.0, 20.0))
    # Trunk attitude tracking gains (Eq. 1).
    trunk_orientation: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(150.0, 25.0))
    # Pedipulation / swing foot position tracking gains (Eq. 1).
    foot_position: PdGainsConfig = dataclasses.field(default_factory=lambda: PdGainsConfig(400.0, 40.0))
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
