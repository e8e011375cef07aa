"""Where a walking robot's feet go: the walking line's planar pose, and each swing's foothold.

The walking line is the planar pose (x, y, yaw) in the world the trunk would have walking at the
commanded twist without swaying; a twist (forward and sideways speed in the walking line's own
frame [m/s], yaw rate [rad/s]) held for a time moves it along an arc.

The foothold rule is Raibert's neutral point for a quasi-static gait: a swing foot lands where its
nominal stance position (under its hip, `NOMINAL_FEET_B`) will be at the middle of its coming
stance, the walking line extrapolated at the current twist. A foot so placed passes under its hip
half-way through its stance, so the feet spread evenly about the hips and every support polygon
keeps its width, whatever the speed within the gait's limits. The static walk needs no capture
point term (its CoM is never outside the support); the trot's footholds add one.
"""

import dataclasses
import math

import numpy as np

from pedi_drake import robot
from pedi_drake.leg_kinematics import leg_geometry
from pedi_drake.polygon import polygon_halfplanes


def _nominal_feet_B() -> np.ndarray:
    """(4, 2) each foot's x, y under its hip in the trunk frame [m] (the hip offset outwards)."""
    return np.array([(leg_geometry(leg).p_BH + leg_geometry(leg).p_HT)[:2] for leg in robot.LEG_NAMES])


NOMINAL_FEET_B = _nominal_feet_B()


@dataclasses.dataclass(frozen=True)
class PlanarPose:
    """A pose in the world's x-y plane: position [m] and yaw [rad]."""

    x: float
    y: float
    yaw: float

    @property
    def xy(self) -> np.ndarray:
        return np.array([self.x, self.y])

    def rotation(self) -> np.ndarray:
        """(2, 2) the planar rotation by yaw."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([[c, -s], [s, c]])

    def to_world(self, p: np.ndarray) -> np.ndarray:
        """A point (2,) given in this pose's frame, in the world [m]."""
        return self.xy + self.rotation() @ np.asarray(p, float)

    def moved(self, twist: np.ndarray, duration: float) -> "PlanarPose":
        """The pose after holding `twist` (forward [m/s], sideways [m/s], yaw rate [rad/s], in the
        pose's own frame) for `duration` [s]: exact on the arc it drives."""
        vx, vy, wz = (float(v) for v in twist)
        angle = wz * duration
        if abs(angle) < 1e-9:
            local = np.array([vx, vy]) * duration
        else:
            # The displacement integrated in the rotating frame: R(yaw + w t) v over [0, T].
            s, c = math.sin(angle), math.cos(angle)
            local = np.array([vx * s - vy * (1.0 - c), vx * (1.0 - c) + vy * s]) / wz
        x, y = self.to_world(local)
        return PlanarPose(float(x), float(y), self.yaw + angle)


def stance_pose(feet_xy: np.ndarray, legs: list[int]) -> PlanarPose:
    """The planar pose that puts the feet `legs` (indices in Unitree order; at least two) nearest,
    in least squares, to their places under the hips (`NOMINAL_FEET_B`), given their world
    positions `feet_xy` (len(legs), 2) [m]: the trunk's frame of a robot standing square on them,
    whatever the trunk does above them (2-D Kabsch)."""
    nominal = NOMINAL_FEET_B[legs]
    feet = np.asarray(feet_xy, float)
    nominal_mean, feet_mean = nominal.mean(axis=0), feet.mean(axis=0)
    a, b = nominal - nominal_mean, feet - feet_mean
    yaw = math.atan2(float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])), float(np.sum(a * b)))
    c, s = math.cos(yaw), math.sin(yaw)
    origin = feet_mean - np.array([[c, -s], [s, c]]) @ nominal_mean
    return PlanarPose(float(origin[0]), float(origin[1]), yaw)


def foothold_W(leg: str, line: PlanarPose, twist: np.ndarray, time_to_mid_stance: float) -> np.ndarray:
    """The neutral foothold (x, y) [m] in the world of `leg`: its nominal stance position in the
    walking line `time_to_mid_stance` [s] ahead at `twist`."""
    ahead = line.moved(twist, time_to_mid_stance)
    return ahead.to_world(NOMINAL_FEET_B[robot.LEG_NAMES.index(leg)])


def support_margin(points: np.ndarray, p: np.ndarray) -> float:
    """The distance [m] of the point `p` (2,) inside the convex hull of `points` (k >= 3, 2):
    > 0 inside, < 0 outside (then the distance past the nearest edge's line)."""
    N, d = polygon_halfplanes(points)
    return float(np.min(d - N @ np.asarray(p, float)))
