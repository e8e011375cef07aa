"""The stance's safety polygon: the support polygon of the loaded contacts, shrunk, in the
controller's `safety_polygon` layout.

The Mission Manager sends it to the whole-body controller at every update (100 Hz), from the
estimated trunk pose and the measured joints, inside the control loop's tick at real time, so it
is one compiled call (`pedi_drake.runtime.jit`) rather than pydrake poses and small numpy steps, whose
per-call overhead would dominate: the feet from the legs' kinematics,
the prong tips from the trunk pose, the hull shrunk by the margin (`polygon.shrink_kernel`), the
frame at the shrunk polygon's vertex centroid turned to the trunk's heading.
"""

import math

import numpy as np

from pedi_drake.control.references import SAFETY_POLYGON_MAX_VERTICES, SAFETY_POLYGON_SIZE
from pedi_drake.estimation.leg_odometry import foot_kinematics_kernel, leg_offsets
from pedi_drake.exceptions import PediError
from pedi_drake.polygon import shrink_kernel
from pedi_drake.runtime.jit import kernel
from pedi_drake.vector3 import rotation_matrix_kernel

_NO_TIPS = np.zeros((0, 3))


@kernel
def stance_polygon_kernel(
    quaternion_wxyz: np.ndarray,
    p_WB: np.ndarray,
    q: np.ndarray,
    offsets: np.ndarray,
    contacts: np.ndarray,
    tips_B: np.ndarray,
    margin: float,
    out: np.ndarray,
) -> int:
    """The safety polygon of the loaded contacts into `out` (SAFETY_POLYGON_SIZE,), zeros (the
    controller's default) when fewer than three supports or nothing after the shrink is left.

    The trunk at `quaternion_wxyz` (normalised here), `p_WB` [m]; joints `q` (12,) [rad] with the
    legs' `offsets` (leg_odometry.leg_offsets); `contacts` (4 feet, then one per prong tip; loaded
    above 0.5); prong tip centres `tips_B` (n, 3) [m], trunk frame; `margin` [m]. Returns the
    number of vertices (0 for the default); a count over SAFETY_POLYGON_MAX_VERTICES leaves `out`
    zero, for the caller to refuse."""
    R = rotation_matrix_kernel(quaternion_wxyz)
    feet_B, _ = foot_kinematics_kernel(q, offsets)
    num_tips = tips_B.shape[0]
    points = np.empty((4 + num_tips, 2))
    count = 0
    for i in range(4 + num_tips):
        if contacts[i] <= 0.5:
            continue
        point = feet_B[i] if i < 4 else tips_B[i - 4]
        for axis in range(2):
            points[count, axis] = p_WB[axis] + R[axis, 0] * point[0] + R[axis, 1] * point[1] + R[axis, 2] * point[2]
        count += 1
    for k in range(out.shape[0]):
        out[k] = 0.0
    if count < 3:
        return 0
    vertices = np.empty((count * count + 1, 2))
    num_vertices = shrink_kernel(points[:count], margin, vertices)
    if num_vertices < 3 or num_vertices > SAFETY_POLYGON_MAX_VERTICES:
        return num_vertices if num_vertices >= 3 else 0
    origin_x, origin_y = 0.0, 0.0
    for k in range(num_vertices):
        origin_x += vertices[k, 0]
        origin_y += vertices[k, 1]
    origin_x /= num_vertices
    origin_y /= num_vertices
    yaw = math.atan2(R[1, 0], R[0, 0])
    c, s = math.cos(yaw), math.sin(yaw)
    out[0] = num_vertices
    out[1], out[2], out[3] = origin_x, origin_y, yaw
    for k in range(num_vertices):
        dx, dy = vertices[k, 0] - origin_x, vertices[k, 1] - origin_y
        # R_PW (v - origin): the vertex in the frame turned to the trunk's heading.
        out[4 + 2 * k] = c * dx + s * dy
        out[5 + 2 * k] = -s * dx + c * dy
    return num_vertices


def prong_tips_B(prongs) -> np.ndarray:
    """The prong tip centres (n, 3) [m] in the trunk frame, none without prongs (a ProngDesign or None)."""
    return _NO_TIPS if prongs is None else np.ascontiguousarray(prongs.tip_positions_B(), dtype=float)


def stance_safety_polygon(
    quaternion_wxyz: np.ndarray,
    p_WB: np.ndarray,
    q: np.ndarray,
    contacts: np.ndarray,
    tips_B: np.ndarray,
    margin: float,
) -> np.ndarray:
    """The controller's `safety_polygon` vector for the loaded contacts (three feet: a triangle).

    Their support polygon (prong tips `tips_B` included, see `prong_tips_B`) shrunk by `margin`
    [m], in a frame at the shrunk polygon's vertex centroid turned to the trunk's heading, from the
    trunk pose estimate (`quaternion_wxyz`, `p_WB` [m]) and the joints `q` [rad]. With fewer than
    three supports, or nothing left after the shrink, the controller's default (zeros).
    """
    contacts = np.asarray(contacts, dtype=float)
    if contacts.shape != (4 + len(tips_B),):
        # The kernel reads one contact flag per foot and prong tip, unchecked.
        raise PediError(f"stance_safety_polygon: {4 + len(tips_B)} contact flags expected, got shape {contacts.shape}")
    out = np.empty(SAFETY_POLYGON_SIZE)
    count = stance_polygon_kernel(quaternion_wxyz, p_WB, q, leg_offsets(), contacts, tips_B, float(margin), out)
    if count > SAFETY_POLYGON_MAX_VERTICES:
        raise PediError(f"safety_polygon: {count} vertices; at most {SAFETY_POLYGON_MAX_VERTICES}")
    return out
