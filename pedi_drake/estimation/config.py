"""Settings of the floating-base Kalman estimator, loaded as part of the Scenario (`kalman:`)."""

import dataclasses


@dataclasses.dataclass
class KalmanEstimatorConfig:
    """Noise model and contact logic of `pedi_drake.estimation.kalman_estimator`."""

    # Filter period [s] (the controller's, 500 Hz).
    period: float = 0.002
    # A foot counts as in contact when its sensor reads above this and the mission's contact
    # schedule (when connected) has it loaded. go1.foot_contact is a force [N] in simulation and
    # the raw sensor value on the Go1 (contact above about 200): raise it on hardware.
    foot_contact_threshold: float = 10.0
    # Accelerometer noise driving the velocity [m/s^2 / sqrt(Hz)] ...
    accelerometer_noise: float = 0.5
    # ... and a small random walk of the trunk position [m / sqrt(s)].
    position_process_noise: float = 0.005
    # Random walk of a foot in contact (rolling of the foot sphere) [m / sqrt(s)] ...
    stance_foot_process_noise: float = 0.002
    # ... and of a foot in the air, which the kinematics then carry along [m / sqrt(s)].
    swing_foot_process_noise: float = 1.0
    # Leg-kinematics foot position noise (encoders, link lengths) [m].
    foot_position_noise: float = 0.003
    # Noise of the trunk velocity seen through a stance foot that does not move [m/s].
    foot_velocity_noise: float = 0.05
    # With no foot loaded the trunk rests on the ground: its horizontal velocity is zero within this [m/s].
    resting_velocity_noise: float = 0.05
    # Flat ground at z = 0: feet in contact are at the foot radius. Removes height drift [-].
    ground_height_measurement: bool = True
    # Noise of that height measurement [m].
    ground_height_noise: float = 0.003
    # Feet that sink into the ground under load (rubber feet, carpet, soft soil): each stance foot's
    # centre sits at foot radius - c F above the ground, F its vertical load [N] (joint-torque
    # estimate), c the compliance [m/N] the filter estimates from how the loads differ between the
    # feet and change over time. Its prior mean [m/N] (0: rigid) ...
    foot_compliance_prior: float = 0.0
    # ... and standard deviation [m/N] (0: c stays at the prior). 5e-4 covers a rubber foot that
    # sinks 17 mm under a quarter of a Go1's weight (0.53 mm/N) at one sigma.
    foot_compliance_std: float = 5e-4
    # Random walk of c [m/N / sqrt(s)]: the ground changes under a walking robot.
    foot_compliance_process_noise: float = 2e-5
    # The sink s [m] every stance foot has whatever its load (a soft layer that bottoms out): the
    # centre sits at foot radius - s - c F. The feet's loads cannot tell it from a higher floor; it
    # is calibrated whenever something rigid rests on the ground (the trunk, the prong tips). Its
    # prior mean [m] ...
    foot_sink_prior: float = 0.0
    # ... standard deviation [m] (0: s stays at the prior) ...
    foot_sink_std: float = 0.01
    # ... and random walk [m / sqrt(s)].
    foot_sink_process_noise: float = 1e-4
    # Where the trunk starts in the world, x, y [m]; null takes the scenario's robot.initial_xy
    # (the height follows from the feet on the ground, the orientation from the IMU).
    initial_xy: list[float] | None = None

    def validate(self, where: str = "kalman") -> list[str]:
        """Problems with the settings, each naming its field (empty when all is well)."""
        problems = []
        for name in (
            "period",
            "accelerometer_noise",
            "position_process_noise",
            "stance_foot_process_noise",
            "swing_foot_process_noise",
            "foot_position_noise",
            "foot_velocity_noise",
            "resting_velocity_noise",
            "ground_height_noise",
        ):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and value > 0 and value < float("inf")):
                problems.append(f"{where}.{name}: must be a finite number > 0, got {value!r}")
        for name in (
            "foot_compliance_prior",
            "foot_compliance_std",
            "foot_compliance_process_noise",
            "foot_sink_prior",
            "foot_sink_std",
            "foot_sink_process_noise",
        ):
            value = getattr(self, name)
            if not (isinstance(value, int | float) and 0 <= value < float("inf")):
                problems.append(f"{where}.{name}: must be a finite number >= 0, got {value!r}")
        if self.initial_xy is not None and len(self.initial_xy) != 2:
            problems.append(f"{where}.initial_xy: expected [x, y] in metres, got {self.initial_xy!r}")
        return problems
