"""Reference inputs of the WholeBodyController: numeric vector ports with fixed layouts.

The Mission Manager (or a demo script) drives the controller through these vectors; every one
has a builder (`*_vector`) and a parser. An unconnected port means "stand in place": hold the
trunk pose seen at the first tick, all four feet in contact, no leg task, the default safety
polygon and the configured friction.

Layouts (world frame W, Unitree leg order FR, FL, RR, RL):

`body_reference` (19):
    [0:3] p_WB_ref [m]   [3:7] quaternion of R_WB_ref (w, x, y, z)   [7:10] v_WB_ref [m/s]
    [10:13] a_WB_ref [m/s^2]   [13:16] w_WB_ref [rad/s]   [16:19] alpha_WB_ref [rad/s^2]
`leg_reference` (40): per leg k (10 entries from 10 k):
    [0] mode: 0 none (the leg is a stance or idle leg), 1 foot position in W, 2 joint angles,
        3 foot pose in W (the 5-D task: foot position, and the calf's roll and pitch; yaw free)
    [1:4] position: foot p_WF_ref [m] (modes 1, 3) or (hip, thigh, calf) [rad] (mode 2)
    [4:7] velocity [m/s | rad/s]
    [7:10] acceleration [m/s^2 | rad/s^2] (modes 1, 2); mode 3: the rotation vector of the calf's
        reference orientation R_WC_ref [rad] (the foot pose is held: no acceleration reference)
    A leg with mode != 0 is a pedipulation leg; it should not be in the contact set.
`contact_set` (4 + number of prongs): 1 for a contact that should bear load (FR, FL, RR, RL,
    prong_0, ...), 0 otherwise. Changes are ramped over `contact_ramp_time`.
`safety_polygon` (6): [enabled, centre x [m], centre y [m], half size x [m], half size y [m], yaw [rad]];
    enabled = 0 selects the default: the support polygon of the loaded contacts shrunk by `safety_margin`.
`friction` (1): Coulomb coefficient of the ground [-].
"""

import dataclasses

import numpy as np
from pydrake.math import RotationMatrix

from pedi_drake import robot
from pedi_drake.vector3 import rotation_matrix_wxyz

BODY_REFERENCE_SIZE = 19
LEG_REFERENCE_SIZE = 40
LEG_BLOCK = 10
SAFETY_POLYGON_SIZE = 6
LEG_MODE_NONE, LEG_MODE_FOOT, LEG_MODE_JOINTS, LEG_MODE_FOOT_POSE = 0, 1, 2, 3


@dataclasses.dataclass
class BodyReference:
    """Trunk pose trajectory sample (world frame)."""

    p: np.ndarray  # [m]
    R: np.ndarray  # (3, 3)
    v: np.ndarray  # [m/s]
    a: np.ndarray  # [m/s^2]
    w: np.ndarray  # [rad/s]
    alpha: np.ndarray  # [rad/s^2]


def body_reference_vector(
    p_WB: np.ndarray,
    R_WB: RotationMatrix,
    v_WB: np.ndarray | None = None,
    a_WB: np.ndarray | None = None,
    w_WB: np.ndarray | None = None,
    alpha_WB: np.ndarray | None = None,
) -> np.ndarray:
    """The 19-vector of `body_reference` (velocities and accelerations default to zero)."""
    zero = np.zeros(3)
    parts = [p_WB, R_WB.ToQuaternion().wxyz()]
    parts += [zero if x is None else x for x in (v_WB, a_WB, w_WB, alpha_WB)]
    return np.concatenate([np.asarray(x, float) for x in parts])


def parse_body_reference(x: np.ndarray) -> BodyReference:
    R = rotation_matrix_wxyz(x[3:7])
    return BodyReference(x[0:3], R, x[7:10], x[10:13], x[13:16], x[16:19])


@dataclasses.dataclass
class LegReference:
    """One leg's task: mode and position/velocity/acceleration (units per mode)."""

    mode: int
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


def leg_reference_vector(
    entries: dict[str, tuple[int, np.ndarray, np.ndarray, np.ndarray]] | None = None,
) -> np.ndarray:
    """The 40-vector of `leg_reference` from {leg: (mode, position, velocity, acceleration)}."""
    x = np.zeros(LEG_REFERENCE_SIZE)
    for leg, (mode, p, v, a) in (entries or {}).items():
        k = robot.LEG_NAMES.index(leg) * LEG_BLOCK
        x[k] = mode
        x[k + 1 : k + 10] = np.concatenate([p, v, a])
    return x


def parse_leg_reference(x: np.ndarray) -> list[LegReference]:
    blocks = np.asarray(x, float).reshape(len(robot.LEG_NAMES), LEG_BLOCK)
    return [LegReference(round(b[0]), b[1:4], b[4:7], b[7:10]) for b in blocks]


def safety_polygon_vector(centre_xy=None, half_sizes=None, yaw: float = 0.0) -> np.ndarray:
    """The 6-vector of `safety_polygon`; no arguments selects the default (support polygon)."""
    if centre_xy is None:
        return np.zeros(SAFETY_POLYGON_SIZE)
    return np.array([1.0, centre_xy[0], centre_xy[1], half_sizes[0], half_sizes[1], yaw])


def contact_set_vector(
    feet: tuple[str, ...] = robot.LEG_NAMES, num_prongs: int = 0, prongs: bool = False
) -> np.ndarray:
    """The `contact_set` vector with the given feet loaded and the prongs on or off."""
    x = np.zeros(len(robot.LEG_NAMES) + num_prongs)
    for leg in feet:
        x[robot.LEG_NAMES.index(leg)] = 1.0
    if prongs:
        x[len(robot.LEG_NAMES) :] = 1.0
    return x


def validate_reference(name: str, x: np.ndarray) -> bool:
    """True when every entry is finite (non-finite references are rejected by the controller)."""
    return bool(np.all(np.isfinite(x)))
