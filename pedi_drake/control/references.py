"""Reference inputs of the WholeBodyController: numeric vector ports with fixed layouts.

The Mission Manager (or a demo script) drives the controller through these vectors; every one
has a builder (`*_vector`) and a parser. An unconnected port means "stand in place": hold the
trunk pose seen at the first tick, all four feet in contact, no leg task, the default safety
polygon and the configured friction.

Layouts (world frame W, Unitree leg order FR, FL, RR, RL):

`body_reference` (19):
    [0:3] p_WB_ref [m]   [3:7] quaternion of R_WB_ref (w, x, y, z)   [7:10] v_WB_ref [m/s]
    [10:13] a_WB_ref [m/s^2]   [13:16] w_WB_ref [rad/s]   [16:19] alpha_WB_ref [rad/s^2]
`leg_reference` (48): per leg k (12 entries from 12 k):
    [0] mode: 0 none (the leg is a stance or idle leg), 1 foot position in W, 2 joint angles,
        3 foot pose in W (the 5-D task: foot position, and the calf's roll and pitch; yaw free),
        4 shank pose in W (the 6-D task: foot position and the calf's full orientation)
    [1:4] position: foot p_WF_ref [m] (modes 1, 3, 4) or (hip, thigh, calf) [rad] (mode 2)
    [4:7] velocity [m/s | rad/s]
    [7:10] acceleration [m/s^2 | rad/s^2] (modes 1, 2); modes 3, 4: the rotation vector of the
        calf's reference orientation R_WC_ref [rad] (the pose is held: no acceleration reference)
    [10:12] the whole-body controller's foot task gains of modes 1, 3 and 4, stiffness kp [1/s^2]
        and damping kd [1/s] of Eq. 1; kp 0 (or kp not > 0, or kd < 0) selects its configured
        `foot_position` gains (paper 002's controller keeps its own `foot_stiffness`). A
        low stiffness makes the foot compliant: pressed against an object it pushes with about
        the leg's task-space inertia times kp times the distance to its reference.
    A leg with mode != 0 is a pedipulation leg; it should not be in the contact set.
`contact_set` (4 + number of prongs): 1 for a contact that should bear load (FR, FL, RR, RL,
    prong_0, ...), 0 otherwise. Changes are ramped over `contact_ramp_time`.
`safety_polygon` (4 + 2 SAFETY_POLYGON_MAX_VERTICES = 20): the convex polygon the capture point is
    kept in, expressed in its own frame P (paper 000: the Mission Manager sets its size, position
    and orientation at runtime):
    [0] n, the number of vertices: 0 selects the default (the support polygon of the loaded
        contacts shrunk by `safety_margin`), else 3 <= n <= SAFETY_POLYGON_MAX_VERTICES
    [1:3] origin of P in W, x, y [m]   [3] yaw of P in W [rad]
    [4:4+2n] the vertices (x, y) in P [m], counter-clockwise; the rest is zero.
    Vertices rather than a centre and half sizes: the three-foot stance's polygon is a triangle.
`friction` (1): Coulomb coefficient of the ground [-].
"""

import dataclasses

import numpy as np
from pydrake.math import RotationMatrix

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.vector3 import rotation_matrix_wxyz

BODY_REFERENCE_SIZE = 19
LEG_REFERENCE_SIZE = 48
LEG_BLOCK = 12
SAFETY_POLYGON_MAX_VERTICES = 8  # the four feet and up to four prong tips
SAFETY_POLYGON_SIZE = 4 + 2 * SAFETY_POLYGON_MAX_VERTICES
LEG_MODE_NONE, LEG_MODE_FOOT, LEG_MODE_JOINTS, LEG_MODE_FOOT_POSE, LEG_MODE_SHANK_POSE = 0, 1, 2, 3, 4
# The modes with calf-orientation rows, and how many rows each has (roll and pitch; all three axes).
CALF_ORIENTATION_ROWS = {LEG_MODE_FOOT_POSE: 2, LEG_MODE_SHANK_POSE: 3}


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
    """One leg's task: mode and position/velocity/acceleration (units per mode), and the foot
    task's gains (0: the controller's configured ones)."""

    mode: int
    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    foot_kp: float = 0.0  # [1/s^2]
    foot_kd: float = 0.0  # [1/s]


def leg_reference_vector(
    entries: dict[str, tuple[int, np.ndarray, np.ndarray, np.ndarray]] | None = None,
    foot_gains: dict[str, tuple[float, float]] | None = None,
) -> np.ndarray:
    """The 48-vector of `leg_reference` from {leg: (mode, position, velocity, acceleration)} and
    {leg: (kp [1/s^2], kd [1/s])} for the legs whose foot task runs at its own gains."""
    x = np.zeros(LEG_REFERENCE_SIZE)
    for leg, (mode, p, v, a) in (entries or {}).items():
        k = robot.LEG_NAMES.index(leg) * LEG_BLOCK
        x[k] = mode
        x[k + 1 : k + 10] = np.concatenate([p, v, a])
    for leg, (kp, kd) in (foot_gains or {}).items():
        k = robot.LEG_NAMES.index(leg) * LEG_BLOCK
        x[k + 10 : k + 12] = kp, kd
    return x


def parse_leg_reference(x: np.ndarray) -> list[LegReference]:
    blocks = np.asarray(x, float).reshape(len(robot.LEG_NAMES), LEG_BLOCK)
    return [LegReference(round(b[0]), b[1:4], b[4:7], b[7:10], b[10], b[11]) for b in blocks]


def _rotation_2d(yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s], [s, c]])


def safety_polygon_vector(vertices_P: np.ndarray | None = None, origin_xy=(0.0, 0.0), yaw: float = 0.0) -> np.ndarray:
    """The `safety_polygon` vector of `vertices_P` (n, 2) [m] in the frame at `origin_xy` [m], `yaw` [rad].

    No vertices (None or an empty array) selects the controller's default polygon.
    """
    x = np.zeros(SAFETY_POLYGON_SIZE)
    if vertices_P is None or len(vertices_P) == 0:
        return x
    vertices_P = np.asarray(vertices_P, float)
    n = len(vertices_P)
    if not 3 <= n <= SAFETY_POLYGON_MAX_VERTICES or vertices_P.shape != (n, 2):
        raise PediError(
            f"safety_polygon: 3 to {SAFETY_POLYGON_MAX_VERTICES} vertices (x, y), got shape {vertices_P.shape}"
        )
    x[0], x[1:3], x[3] = n, origin_xy, yaw
    x[4 : 4 + 2 * n] = vertices_P.ravel()
    return x


def safety_polygon_vertices_W(x: np.ndarray) -> np.ndarray | None:
    """The polygon's vertices (n, 2) in W [m]; None for the default; PediError for a bad count."""
    n = int(round(x[0]))
    if n == 0:
        return None
    if not 3 <= n <= SAFETY_POLYGON_MAX_VERTICES:
        raise PediError(f"safety_polygon: {n} vertices; expected 0 or 3 to {SAFETY_POLYGON_MAX_VERTICES}")
    vertices_P = np.asarray(x[4 : 4 + 2 * n], float).reshape(n, 2)
    return x[1:3] + vertices_P @ _rotation_2d(x[3]).T


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
