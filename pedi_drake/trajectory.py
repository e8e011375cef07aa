"""Quintic reference segments (paper 000, Eq. 2): rest-to-rest, zero velocity and acceleration at both ends.

A segment goes from a start value to an end value over a duration T [s], starting at time
t0 [s]. Its time law is the minimum-jerk quintic s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 with
tau = (t - t0) / T, whose first and second derivatives vanish at tau = 0 and tau = 1, so

    x(t) = x0 + (x1 - x0) s(tau)

is exactly Eq. 2 with a0 = x0, a1 = a2 = 0 and a3..a5 fixed by the end conditions. Before t0
the segment holds x0, after t0 + T it holds x1 (velocity and acceleration zero).

Orientations are interpolated on SO(3) along the geodesic: R(t) = R0 exp(s(tau) theta [k]x) with
theta k the axis-angle of R0^T R1, so the angular velocity is parallel to the fixed axis R0 k.
"""

import dataclasses
import functools

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RotationMatrix

from pedi_drake.exceptions import PediError


def min_jerk(tau: float) -> tuple[float, float, float]:
    """The minimum-jerk blend (paper 000, Eq. 2, rest to rest) at normalised time `tau`, clamped to [0, 1].

    Returns (s, ds/dtau, d2s/dtau2) of s = 10 tau^3 - 15 tau^4 + 6 tau^5: zero slope and
    curvature at both ends.
    """
    if tau <= 0.0:
        return 0.0, 0.0, 0.0
    if tau >= 1.0:
        return 1.0, 0.0, 0.0
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    ds = 30.0 * tau**2 * (1.0 - tau) ** 2
    dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * tau**2)
    return s, ds, dds


def quintic_time_law(t: float, t0: float, duration: float) -> tuple[float, float, float]:
    """(s, ds/dt [1/s], d2s/dt2 [1/s^2]) of the rest-to-rest quintic at time `t` [s]."""
    if not duration > 0.0:
        raise PediError(f"quintic duration must be > 0 s, got {duration!r}")
    s, ds, dds = min_jerk((t - t0) / duration)
    return s, ds / duration, dds / duration**2


def smooth_start_time_law(t: float, t0: float, ramp: float) -> tuple[float, float, float]:
    """(s [s], ds/dt [-], d2s/dt2 [1/s]) of a motion that starts at rest at `t0` [s] and reaches
    unit speed over `ramp` [s], then keeps it: its speed follows the minimum-jerk blend, so its
    acceleration starts and ends at zero and is continuous. Distance = speed * s.

    A reference that jumps to its speed in one tick asks for an infinite acceleration: a foot
    impedance reads the lag it causes as an external force, and so does the torque that
    accelerates the leg.
    """
    if not ramp > 0.0:
        raise PediError(f"speed ramp must be > 0 s, got {ramp!r}")
    tau = (t - t0) / ramp
    if tau <= 0.0:
        return 0.0, 0.0, 0.0
    if tau >= 1.0:
        return t - t0 - 0.5 * ramp, 1.0, 0.0
    speed, ds, _ = min_jerk(tau)
    # The blend's integral: tau^4 (2.5 - 3 tau + tau^2), 0.5 at tau = 1.
    return ramp * tau**4 * (2.5 - 3.0 * tau + tau**2), speed, ds / ramp


def quintic_coefficients(x0: float, x1: float, duration: float) -> np.ndarray:
    """Coefficients a0..a5 of Eq. 2 for a rest-to-rest move from x0 to x1 in `duration` [s]."""
    d = x1 - x0
    T = duration
    return np.array([x0, 0.0, 0.0, 10.0 * d / T**3, -15.0 * d / T**4, 6.0 * d / T**5])


@dataclasses.dataclass(frozen=True)
class TrajectorySample:
    """Reference at one instant: value, first and second time derivatives (units of the segment)."""

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


@dataclasses.dataclass(frozen=True)
class QuinticSegment:
    """Rest-to-rest quintic between two vectors (scalars, positions [m] or joint angles [rad]).

    Sampled values have the units of `start`; velocities per second, accelerations per second^2.
    """

    start: np.ndarray
    end: np.ndarray
    t0: float  # start time [s]
    duration: float  # [s], > 0

    def __post_init__(self) -> None:
        start = np.atleast_1d(np.asarray(self.start, dtype=float))
        end = np.atleast_1d(np.asarray(self.end, dtype=float))
        if start.shape != end.shape:
            raise PediError(f"quintic start {start.shape} and end {end.shape} differ in shape")
        if not (np.all(np.isfinite(start)) and np.all(np.isfinite(end))):
            raise PediError("quintic start and end must be finite")
        if not (np.isfinite(self.duration) and self.duration > 0.0):
            raise PediError(f"quintic duration must be a finite number > 0 s, got {self.duration!r}")
        # Private read-only copies: a segment is a value (see __deepcopy__).
        for name, value in (("start", start), ("end", end)):
            value = value.copy()
            value.flags.writeable = False
            object.__setattr__(self, name, value)

    def __deepcopy__(self, memo) -> "QuinticSegment":
        # Immutable: Drake clones the mission state (which holds segments) several times a tick.
        return self

    @property
    def t_end(self) -> float:
        """Time at which the segment arrives [s]."""
        return self.t0 + self.duration

    def sample(self, t: float) -> TrajectorySample:
        """Position, velocity and acceleration at time `t` [s]."""
        s, ds, dds = quintic_time_law(t, self.t0, self.duration)
        if s == 0.0 or s == 1.0:
            return self._at_rest[int(s)]
        delta = self.end - self.start
        return TrajectorySample(self.start + s * delta, ds * delta, dds * delta)

    @functools.cached_property
    def _at_rest(self) -> tuple[TrajectorySample, TrajectorySample]:
        """The samples before the start and after the end (read-only arrays, made once)."""
        zero = np.zeros_like(self.start)
        zero.flags.writeable = False
        return TrajectorySample(self.start, zero, zero), TrajectorySample(self.end, zero, zero)


@dataclasses.dataclass(frozen=True)
class OrientationSample:
    """Orientation reference: R_WB, angular velocity and acceleration expressed in W [rad/s, rad/s^2]."""

    rotation: RotationMatrix
    angular_velocity: np.ndarray
    angular_acceleration: np.ndarray
    # The rotation's quaternion (w, x, y, z), when already known.
    wxyz: np.ndarray | None = None

    def quaternion_wxyz(self) -> np.ndarray:
        """The rotation's quaternion (w, x, y, z), w >= 0."""
        return self.wxyz if self.wxyz is not None else self.rotation.ToQuaternion().wxyz()


@dataclasses.dataclass(frozen=True)
class QuinticOrientationSegment:
    """Rest-to-rest geodesic move on SO(3) from R_start to R_end with the quintic time law."""

    start: RotationMatrix
    end: RotationMatrix
    t0: float  # [s]
    duration: float  # [s], > 0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.duration) and self.duration > 0.0):
            raise PediError(f"quintic duration must be a finite number > 0 s, got {self.duration!r}")

    def __deepcopy__(self, memo) -> "QuinticOrientationSegment":
        return self  # immutable (RotationMatrix values and floats)

    @property
    def t_end(self) -> float:
        return self.t0 + self.duration

    @functools.cached_property
    def _axis_angle(self) -> tuple[np.ndarray, float, np.ndarray]:
        """(axis k in the start frame, angle [rad], axis in world) of R_start^T R_end (computed once)."""
        # Relative rotation expressed in the start frame: R_end = R_start * R_rel.
        rel = AngleAxis(self.start.inverse().multiply(self.end).ToQuaternion())
        axis = np.asarray(rel.axis())
        return axis, float(rel.angle()), self.start.multiply(axis)

    @functools.cached_property
    def _at_rest(self) -> tuple[OrientationSample, OrientationSample]:
        """The samples before the start and after the end (made once)."""
        zero = np.zeros(3)
        zero.flags.writeable = False
        return tuple(OrientationSample(R, zero, zero, R.ToQuaternion().wxyz()) for R in (self.start, self.end))

    def sample(self, t: float) -> OrientationSample:
        """Orientation, angular velocity and acceleration (in the world frame) at time `t` [s]."""
        axis, angle, axis_W = self._axis_angle
        s, ds, dds = quintic_time_law(t, self.t0, self.duration)
        if s == 0.0 or s == 1.0:
            # At rest at either end (most samples: the phases hold a pose far longer than they move).
            return self._at_rest[int(s)]
        rotation = self.start.multiply(RotationMatrix(AngleAxis(s * angle, axis)))
        return OrientationSample(rotation, ds * angle * axis_W, dds * angle * axis_W)


@dataclasses.dataclass(frozen=True)
class PiecewiseQuintic:
    """Consecutive vector quintic segments through waypoints; holds the last waypoint afterwards."""

    segments: tuple[QuinticSegment, ...]

    def __deepcopy__(self, memo) -> "PiecewiseQuintic":
        return self  # immutable: a tuple of immutable segments

    @staticmethod
    def through(waypoints: np.ndarray, t0: float, durations: list[float]) -> "PiecewiseQuintic":
        """Rest-to-rest segments from waypoints[0] through waypoints[k] with the given durations [s]."""
        waypoints = np.asarray(waypoints, dtype=float)
        if len(waypoints) != len(durations) + 1:
            raise PediError(f"{len(waypoints)} waypoints need {len(waypoints) - 1} durations, got {len(durations)}")
        segments, t = [], t0
        for k, duration in enumerate(durations):
            segments.append(QuinticSegment(waypoints[k], waypoints[k + 1], t, duration))
            t += duration
        return PiecewiseQuintic(tuple(segments))

    def sample(self, t: float) -> TrajectorySample:
        """Sample of the segment active at `t` [s] (the first before it starts, the last after)."""
        for segment in self.segments:
            if t < segment.t_end:
                return segment.sample(t)
        return self.segments[-1].sample(t)


@dataclasses.dataclass(frozen=True)
class CircularPath:
    """A closed circle in the world x-y plane through `start`, rest to rest.

    The centre is `start - radius * (cos phase, sin phase, 0)`; the angle runs from `phase` by
    2 pi `laps` along the quintic time law over `duration`, so the path starts and ends at `start`
    at rest and peaks at 1.875 times the mean speed (2 pi radius laps / duration).
    """

    start: np.ndarray  # [m]
    radius: float  # [m]
    t0: float  # [s]
    duration: float  # [s]
    laps: int = 1
    phase: float = 0.0  # angle of `start` seen from the centre [rad]

    def __deepcopy__(self, memo) -> "CircularPath":
        return self  # immutable

    @property
    def t_end(self) -> float:
        return self.t0 + self.duration

    @property
    def centre(self) -> np.ndarray:
        return np.asarray(self.start, float) - self.radius * np.array([np.cos(self.phase), np.sin(self.phase), 0.0])

    def sample(self, t: float) -> TrajectorySample:
        """Position [m], velocity [m/s] and acceleration [m/s^2] at `t` [s]."""
        s, ds, dds = quintic_time_law(t, self.t0, self.duration)
        sweep = 2.0 * np.pi * self.laps
        angle, rate, rate_dot = self.phase + sweep * s, sweep * ds, sweep * dds
        c, si = np.cos(angle), np.sin(angle)
        r = self.radius
        position = self.centre + r * np.array([c, si, 0.0])
        velocity = r * rate * np.array([-si, c, 0.0])
        acceleration = r * rate_dot * np.array([-si, c, 0.0]) - r * rate**2 * np.array([c, si, 0.0])
        return TrajectorySample(position, velocity, acceleration)


@dataclasses.dataclass(frozen=True)
class PivotedPosition:
    """The position of a point rigidly attached to a body that turns about a fixed `pivot` along
    `orientation` (a QuinticOrientationSegment from R0): p(t) = c + R(t) R0^T (p0 - c).

    Velocity w x r and acceleration alpha x r + w x (w x r), with r = p - c; so a trunk reference
    made of this and `orientation` turns the trunk about the pivot (a loaded prong tip, say)."""

    orientation: "QuinticOrientationSegment"
    pivot: np.ndarray  # c [m]
    start: np.ndarray  # p0 [m]

    def __deepcopy__(self, memo) -> "PivotedPosition":
        return self  # immutable

    @property
    def t_end(self) -> float:
        return self.orientation.t_end

    def sample(self, t: float) -> TrajectorySample:
        o = self.orientation.sample(t)
        lever_0 = self.orientation.start.inverse().multiply(np.asarray(self.start, float) - self.pivot)
        r = o.rotation.multiply(lever_0)
        w, alpha = o.angular_velocity, o.angular_acceleration
        return TrajectorySample(self.pivot + r, np.cross(w, r), np.cross(alpha, r) + np.cross(w, np.cross(w, r)))


@dataclasses.dataclass(frozen=True)
class RampSegment:
    """Constant velocity for one interval, then rest: p(t) = start + velocity clip(t - t0, 0, T).

    A teleoperated foot's reference for one control interval of length T [s]: the next interval's
    segment starts where this one ends, so the position never jumps (its velocity is the bounded
    command of each interval; the acceleration is zero, as the command holds no more)."""

    start: np.ndarray  # [m]
    velocity: np.ndarray  # [m/s]
    t0: float  # [s]
    duration: float  # T [s], > 0

    def __post_init__(self) -> None:
        for name in ("start", "velocity"):
            value = np.asarray(getattr(self, name), dtype=float).copy()
            if not np.all(np.isfinite(value)):
                raise PediError(f"ramp {name} must be finite, got {value}")
            value.flags.writeable = False
            object.__setattr__(self, name, value)
        if not (np.isfinite(self.duration) and self.duration > 0.0):
            raise PediError(f"ramp duration must be a finite number > 0 s, got {self.duration!r}")

    def __deepcopy__(self, memo) -> "RampSegment":
        return self  # immutable

    @property
    def t_end(self) -> float:
        return self.t0 + self.duration

    @property
    def end(self) -> np.ndarray:
        """Where the segment comes to rest [m]."""
        return self.start + self.duration * self.velocity

    def sample(self, t: float) -> TrajectorySample:
        elapsed = min(max(t - self.t0, 0.0), self.duration)
        moving = self.t0 <= t < self.t_end
        velocity = self.velocity if moving else np.zeros_like(self.velocity)
        return TrajectorySample(self.start + elapsed * self.velocity, velocity, np.zeros_like(self.velocity))
