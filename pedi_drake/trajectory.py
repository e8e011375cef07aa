"""Quintic reference segments (paper 000, Eq. 2): rest-to-rest, zero velocity and acceleration at both ends.

A segment goes from a start value to an end value over a duration T [s], starting at time
t0 [s]. Its time law is the minimum-jerk quintic s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 with
tau = (t - t0) / T, whose first and second derivatives vanish at tau = 0 and tau = 1, so

    x(t) = x0 + (x1 - x0) s(tau)

is exactly Eq. 2 with a0 = x0, a1 = a2 = 0 and a3..a5 fixed by the end conditions. Before t0
the segment holds x0, after t0 + T it holds x1 (velocity and acceleration zero).

Orientations are interpolated on SO(3) along the geodesic: R(t) = R0 exp(s(tau) theta [k]x) with
theta k the axis-angle of R0^T R1, so the angular velocity is parallel to the fixed axis R0 k.

Every trajectory is also a flat float array, its `packed` form (layouts beside the PACKED_*
kinds), and the compiled kernels `sample_vector_into` and `sample_rotation_into` sample that
form: the classes' `sample` calls them, and so does a control tick that samples references
without the classes (pedi_drake.mission.reference_table). One implementation of each formula,
with no Python object made per sample in the tick.
"""

import dataclasses
import functools
import math

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RotationMatrix

from pedi_drake.exceptions import PediError
from pedi_drake.runtime.jit import kernel

# Kinds of packed trajectories (the first entry of every `packed` array) and their layouts:
# QUINTIC  [kind, m, n, m x (t0, duration, start (n), end (n))]: rest-to-rest quintics, one after
#          the other (a QuinticSegment is m = 1); the first whose end is after t is sampled, or
#          the last.
# RAMP     [kind, n, t0, duration, start (n), velocity (n)]
# CIRCLE   [kind, t0, duration, laps, phase, radius, start (3)]
# GEODESIC [kind, t0, duration, angle, R_start (9, row-major), R_end (9), axis in the start frame
#          (3), axis in W (3), quaternion of R_start (4, w x y z), of R_end (4)]
# PIVOT    [kind, pivot (3), lever at the start in the rotating frame (3), the GEODESIC packed]
PACKED_QUINTIC, PACKED_RAMP, PACKED_CIRCLE, PACKED_GEODESIC, PACKED_PIVOT = 0, 1, 2, 3, 4
GEODESIC_PACKED_SIZE = 36


@kernel
def _min_jerk(tau: float) -> tuple[float, float, float]:
    if tau <= 0.0:
        return 0.0, 0.0, 0.0
    if tau >= 1.0:
        return 1.0, 0.0, 0.0
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    ds = 30.0 * tau**2 * (1.0 - tau) ** 2
    dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * tau**2)
    return s, ds, dds


def min_jerk(tau: float) -> tuple[float, float, float]:
    """The minimum-jerk blend (paper 000, Eq. 2, rest to rest) at normalised time `tau`, clamped to [0, 1].

    Returns (s, ds/dtau, d2s/dtau2) of s = 10 tau^3 - 15 tau^4 + 6 tau^5: zero slope and
    curvature at both ends. (The kernels' blend, run interpreted: callers in a control tick
    outside a kernel need no compiled code.)
    """
    return _min_jerk.py_func(tau)


@kernel
def _quintic_time_law(t: float, t0: float, duration: float) -> tuple[float, float, float]:
    s, ds, dds = _min_jerk((t - t0) / duration)
    return s, ds / duration, dds / duration**2


def quintic_time_law(t: float, t0: float, duration: float) -> tuple[float, float, float]:
    """(s, ds/dt [1/s], d2s/dt2 [1/s^2]) of the rest-to-rest quintic at time `t` [s]."""
    if not duration > 0.0:
        raise PediError(f"quintic duration must be > 0 s, got {duration!r}")
    return _quintic_time_law.py_func(t, t0, duration)


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
    return smooth_start_kernel.py_func(t, t0, ramp)


@kernel
def smooth_start_kernel(t: float, t0: float, ramp: float) -> tuple[float, float, float]:
    """`smooth_start_time_law` without the check of `ramp` (> 0: the caller's to ensure)."""
    tau = (t - t0) / ramp
    if tau <= 0.0:
        return 0.0, 0.0, 0.0
    if tau >= 1.0:
        return t - t0 - 0.5 * ramp, 1.0, 0.0
    speed, ds, _ = _min_jerk(tau)
    # The blend's integral: tau^4 (2.5 - 3 tau + tau^2), 0.5 at tau = 1.
    return ramp * tau**4 * (2.5 - 3.0 * tau + tau**2), speed, ds / ramp


def quintic_coefficients(x0: float, x1: float, duration: float) -> np.ndarray:
    """Coefficients a0..a5 of Eq. 2 for a rest-to-rest move from x0 to x1 in `duration` [s]."""
    d = x1 - x0
    T = duration
    return np.array([x0, 0.0, 0.0, 10.0 * d / T**3, -15.0 * d / T**4, 6.0 * d / T**5])


# Sampling kernels of the packed forms ---------------------------------------------------------


@kernel
def _sample_quintic_segment(packed, base, n, t, p, v, a) -> None:
    """The quintic whose (t0, duration, start (n), end (n)) begin at packed[base], at `t` [s]."""
    start, end = base + 2, base + 2 + n
    s, ds, dds = _quintic_time_law(t, packed[base], packed[base + 1])
    if s == 0.0 or s == 1.0:
        # At rest at either end: exactly the end value (start + 1 * delta may round off it).
        rest = start if s == 0.0 else end
        for i in range(n):
            p[i] = packed[rest + i]
            v[i] = 0.0
            a[i] = 0.0
        return
    for i in range(n):
        delta = packed[end + i] - packed[start + i]
        p[i] = packed[start + i] + s * delta
        v[i] = ds * delta
        a[i] = dds * delta


@kernel
def _quaternion_of(R, q) -> None:
    """q (w, x, y, z), w >= 0, of the rotation matrix R: Drake's RotationMatrix::ToQuaternion
    (the branch on the largest of the trace and the diagonal keeps it accurate near pi)."""
    trace = R[0, 0] + R[1, 1] + R[2, 2]
    if trace >= R[0, 0] and trace >= R[1, 1] and trace >= R[2, 2]:
        w, x, y, z = 1.0 + trace, R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    elif R[0, 0] >= R[1, 1] and R[0, 0] >= R[2, 2]:
        w, x, y, z = R[2, 1] - R[1, 2], 1.0 - (trace - 2.0 * R[0, 0]), R[0, 1] + R[1, 0], R[0, 2] + R[2, 0]
    elif R[1, 1] >= R[2, 2]:
        w, x, y, z = R[0, 2] - R[2, 0], R[0, 1] + R[1, 0], 1.0 - (trace - 2.0 * R[1, 1]), R[1, 2] + R[2, 1]
    else:
        w, x, y, z = R[1, 0] - R[0, 1], R[0, 2] + R[2, 0], R[1, 2] + R[2, 1], 1.0 - (trace - 2.0 * R[2, 2])
    scale = (-1.0 if w < 0.0 else 1.0) / math.sqrt(x * x + y * y + z * z + w * w)
    q[0], q[1], q[2], q[3] = w * scale, x * scale, y * scale, z * scale


@kernel
def sample_rotation_into(packed, t, R, q, w, alpha) -> None:
    """Samples a GEODESIC packed array at `t` [s] into R (3, 3) = R_WB, its quaternion q (4,),
    the angular velocity w (3,) [rad/s] and acceleration alpha (3,) [rad/s^2], both in W."""
    s, ds, dds = _quintic_time_law(t, packed[1], packed[2])
    if s == 0.0 or s == 1.0:
        # At rest: the end rotation itself, and its quaternion as Drake computed it when packed.
        matrix, quaternion = (4, 28) if s == 0.0 else (13, 32)
        for i in range(3):
            for j in range(3):
                R[i, j] = packed[matrix + 3 * i + j]
            w[i] = 0.0
            alpha[i] = 0.0
        for i in range(4):
            q[i] = packed[quaternion + i]
        return
    angle = packed[3]
    # R_rel = exp(s angle [k]x), as Eigen's AngleAxis::toRotationMatrix; then R = R_start R_rel.
    kx, ky, kz = packed[22], packed[23], packed[24]
    theta = s * angle
    sine, cosine = math.sin(theta), math.cos(theta)
    sx, sy, sz = sine * kx, sine * ky, sine * kz
    cx, cy, cz = (1.0 - cosine) * kx, (1.0 - cosine) * ky, (1.0 - cosine) * kz
    r00, r11, r22 = cx * kx + cosine, cy * ky + cosine, cz * kz + cosine
    r01, r10 = cx * ky - sz, cx * ky + sz
    r02, r20 = cx * kz + sy, cx * kz - sy
    r12, r21 = cy * kz - sx, cy * kz + sx
    for i in range(3):
        a0, a1, a2 = packed[4 + 3 * i], packed[5 + 3 * i], packed[6 + 3 * i]
        R[i, 0] = a0 * r00 + a1 * r10 + a2 * r20
        R[i, 1] = a0 * r01 + a1 * r11 + a2 * r21
        R[i, 2] = a0 * r02 + a1 * r12 + a2 * r22
    _quaternion_of(R, q)
    rate, rate_dot = ds * angle, dds * angle
    for i in range(3):
        w[i] = rate * packed[25 + i]
        alpha[i] = rate_dot * packed[25 + i]


@kernel
def sample_vector_into(packed, t, p, v, a) -> None:
    """Samples a packed QUINTIC, RAMP, CIRCLE or PIVOT trajectory at `t` [s] into p, v, a
    (its value, first and second time derivatives; units of the trajectory)."""
    kind = packed[0]
    if kind == PACKED_QUINTIC:
        m, n = int(packed[1]), int(packed[2])
        for k in range(m):
            base = 3 + k * (2 + 2 * n)
            if t < packed[base] + packed[base + 1] or k == m - 1:
                _sample_quintic_segment(packed, base, n, t, p, v, a)
                return
    elif kind == PACKED_RAMP:
        n, t0, duration = int(packed[1]), packed[2], packed[3]
        elapsed = min(max(t - t0, 0.0), duration)
        moving = t0 <= t < t0 + duration
        for i in range(n):
            velocity = packed[4 + n + i]
            p[i] = packed[4 + i] + elapsed * velocity
            v[i] = velocity if moving else 0.0
            a[i] = 0.0
    elif kind == PACKED_CIRCLE:
        s, ds, dds = _quintic_time_law(t, packed[1], packed[2])
        laps, phase, radius = packed[3], packed[4], packed[5]
        sweep = 2.0 * np.pi * laps
        angle, rate, rate_dot = phase + sweep * s, sweep * ds, sweep * dds
        c, si = math.cos(angle), math.sin(angle)
        p[0] = packed[6] - radius * math.cos(phase) + radius * c
        p[1] = packed[7] - radius * math.sin(phase) + radius * si
        p[2] = packed[8] - radius * 0.0 + radius * 0.0
        v[0], v[1], v[2] = radius * rate * -si, radius * rate * c, radius * rate * 0.0
        centripetal = radius * rate**2
        a[0] = radius * rate_dot * -si - centripetal * c
        a[1] = radius * rate_dot * c - centripetal * si
        a[2] = radius * rate_dot * 0.0 - centripetal * 0.0
    else:  # PACKED_PIVOT: a point turning with the rotation about the pivot
        R, q, w, alpha = np.empty((3, 3)), np.empty(4), np.empty(3), np.empty(3)
        sample_rotation_into(packed[7:], t, R, q, w, alpha)
        r = np.empty(3)
        for i in range(3):
            r[i] = R[i, 0] * packed[4] + R[i, 1] * packed[5] + R[i, 2] * packed[6]
            p[i] = packed[1 + i] + r[i]
        wr = np.array([w[1] * r[2] - w[2] * r[1], w[2] * r[0] - w[0] * r[2], w[0] * r[1] - w[1] * r[0]])
        v[0], v[1], v[2] = wr[0], wr[1], wr[2]
        a[0] = (alpha[1] * r[2] - alpha[2] * r[1]) + (w[1] * wr[2] - w[2] * wr[1])
        a[1] = (alpha[2] * r[0] - alpha[0] * r[2]) + (w[2] * wr[0] - w[0] * wr[2])
        a[2] = (alpha[0] * r[1] - alpha[1] * r[0]) + (w[0] * wr[1] - w[1] * wr[0])


def _read_only(x) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    x.flags.writeable = False
    return x


def _sampled(packed: np.ndarray, t: float, shape: tuple) -> "TrajectorySample":
    """The TrajectorySample of a packed vector trajectory (values of `shape`) at `t` [s]."""
    n = int(np.prod(shape))
    p, v, a = np.empty(n), np.empty(n), np.empty(n)
    sample_vector_into(packed, float(t), p, v, a)
    return TrajectorySample(p.reshape(shape), v.reshape(shape), a.reshape(shape))


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
        return _sampled(self.packed, t, self.start.shape)

    @functools.cached_property
    def packed(self) -> np.ndarray:
        """The QUINTIC packed form (one segment; see PACKED_QUINTIC)."""
        n = self.start.size
        return _read_only([PACKED_QUINTIC, 1, n, self.t0, self.duration, *self.start.ravel(), *self.end.ravel()])


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
    def packed(self) -> np.ndarray:
        """The GEODESIC packed form (see PACKED_GEODESIC)."""
        axis, angle, axis_W = self._axis_angle
        ends = [R.matrix().ravel() for R in (self.start, self.end)]
        quaternions = [R.ToQuaternion().wxyz() for R in (self.start, self.end)]
        return _read_only(
            [
                PACKED_GEODESIC,
                self.t0,
                self.duration,
                angle,
                *ends[0],
                *ends[1],
                *axis,
                *axis_W,
                *quaternions[0],
                *quaternions[1],
            ]
        )

    def sample(self, t: float) -> OrientationSample:
        """Orientation, angular velocity and acceleration (in the world frame) at time `t` [s]."""
        R, q, w, alpha = np.empty((3, 3)), np.empty(4), np.empty(3), np.empty(3)
        sample_rotation_into(self.packed, float(t), R, q, w, alpha)
        return OrientationSample(RotationMatrix(R), w, alpha, q)


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
        return _sampled(self.packed, t, self.segments[0].start.shape)

    @functools.cached_property
    def packed(self) -> np.ndarray:
        """The QUINTIC packed form (see PACKED_QUINTIC)."""
        parts = [[s.t0, s.duration, *s.start.ravel(), *s.end.ravel()] for s in self.segments]
        return _read_only([PACKED_QUINTIC, len(self.segments), self.segments[0].start.size, *sum(parts, [])])


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
        return _sampled(self.packed, t, (3,))

    @functools.cached_property
    def packed(self) -> np.ndarray:
        """The CIRCLE packed form (see PACKED_CIRCLE)."""
        start = np.asarray(self.start, float)
        return _read_only([PACKED_CIRCLE, self.t0, self.duration, self.laps, self.phase, self.radius, *start])


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
        """Position [m], velocity w x r [m/s] and acceleration alpha x r + w x (w x r) [m/s^2] at `t` [s]."""
        return _sampled(self.packed, t, (3,))

    @functools.cached_property
    def packed(self) -> np.ndarray:
        """The PIVOT packed form (see PACKED_PIVOT)."""
        pivot = np.asarray(self.pivot, float)
        lever_0 = self.orientation.start.inverse().multiply(np.asarray(self.start, float) - pivot)
        return _read_only([PACKED_PIVOT, *pivot, *lever_0, *self.orientation.packed])


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
        """Position [m], velocity [m/s] (zero outside the interval) and acceleration (zero) at `t` [s]."""
        return _sampled(self.packed, t, self.start.shape)

    @functools.cached_property
    def packed(self) -> np.ndarray:
        """The RAMP packed form (see PACKED_RAMP)."""
        n = self.start.size
        return _read_only([PACKED_RAMP, n, self.t0, self.duration, *self.start.ravel(), *self.velocity.ravel()])
