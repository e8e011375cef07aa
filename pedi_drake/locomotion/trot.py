"""The trot: diagonal pairs of legs swing in turn, every half period (FR with RL, then FL with RR).

A trot has two feet down at a time, on a line through the trunk: it balances by where it puts
its feet, not by keeping the centre of mass over a support. Each half period the trunk's reference
starts where the trunk is and moves on at the twist (the trunk's position at constant velocity,
its heading rest to rest over the half period), the pair that landed takes the load, and the
other pair swings. A swing foot lands at Raibert's point: its place under its hip at the middle
of its coming stance on the walking line extrapolated at the twist
(pedi_drake.locomotion.footholds), plus `velocity_gain` times the trunk's velocity error, which
steps the feet towards a trunk that runs ahead of its reference (or away from one that lags) and
so brings it back.

The twist changes by at most `acceleration` (and `yaw_acceleration`) per second: a trot starts and
stops over a few steps.
"""

import dataclasses

import numpy as np

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.locomotion.footholds import PlanarPose, foothold_W

TROT_PAIRS = (("FR", "RL"), ("FL", "RR"))


@dataclasses.dataclass(frozen=True)
class TrotTiming:
    """The trot's timing [s], step height [m] and the limits of its twist's change."""

    period: float = 0.5  # both pairs' swings
    ramp: float = 0.02  # a contact's load ramped out before lift-off (the mission's contact_ramp_time)
    step_height: float = 0.06  # [m] the swing's apex above the ground
    # [s] the foothold's shift per m/s of the trunk's velocity error (Raibert's feedback term; the
    # inverted pendulum's sqrt(h/g) is 0.17 s at the Go1's height, about twice this).
    velocity_gain: float = 0.1
    acceleration: float = 1.0  # [m/s^2] of the commanded speed
    yaw_acceleration: float = 2.0  # [rad/s^2] of the commanded yaw rate

    def __post_init__(self) -> None:
        for name in ("period", "ramp", "step_height", "acceleration", "yaw_acceleration"):
            if not getattr(self, name) > 0.0:
                raise PediError(f"trot timing: {name} must be > 0, got {getattr(self, name)!r}")
        if not 0.0 <= self.velocity_gain:
            raise PediError(f"trot timing: velocity_gain must be >= 0, got {self.velocity_gain!r}")
        if not self.ramp < 0.25 * self.period:
            raise PediError(f"trot timing: the ramp {self.ramp} s leaves no swing in a {self.period} s period")

    @property
    def half(self) -> float:
        """[s] one pair's swing and the other's stance."""
        return 0.5 * self.period

    @property
    def swing(self) -> float:
        """[s] a foot in the air: the half period less its unloading."""
        return self.half - self.ramp


def next_twist(current: np.ndarray, wanted: np.ndarray, dt: float, timing: TrotTiming) -> np.ndarray:
    """The twist `dt` [s] after `current`, towards `wanted`, within the timing's accelerations."""
    step = np.array([timing.acceleration, timing.acceleration, timing.yaw_acceleration]) * dt
    return np.asarray(current, float) + np.clip(np.asarray(wanted, float) - current, -step, step)


def trot_foothold_W(
    leg: str, line: PlanarPose, twist: np.ndarray, velocity_error_W: np.ndarray, timing: TrotTiming
) -> np.ndarray:
    """(2,) [m] where `leg` lands when it lifts now with the walking line at `line` and `twist`:
    its neutral point at mid-stance (1.5 half periods ahead) plus the velocity feedback."""
    neutral = foothold_W(leg, line, twist, 1.5 * timing.half)
    return neutral + timing.velocity_gain * np.asarray(velocity_error_W, float)[:2]


def pair_of(step: int) -> tuple[str, str]:
    """The legs that swing at half period `step` (0, 1, ...)."""
    return TROT_PAIRS[step % 2]


def leg_index(leg: str) -> int:
    return robot.LEG_NAMES.index(leg)
