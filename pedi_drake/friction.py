"""The 4-edge friction pyramid of a point contact, for every user of it.

A contact force lambda (world frame) on ground of unit normal n is admissible when n . lambda >= 0
and

    |t1 . lambda| <= m n . lambda,   |t2 . lambda| <= m n . lambda,   m = mu / sqrt(2) (inscribed) or mu,

with t1, t2 the tangents of `contact_tangents` (on flat ground, n = z: t1 = x, t2 = y, and the rows
are |lambda_x| <= m lambda_z, |lambda_y| <= m lambda_z).

The inscribed pyramid (the default everywhere) lies inside the Coulomb cone of radius mu: every
force it admits the contact can hold. The circumscribed one (m = mu) admits tangential forces up
to sqrt(2) mu lambda_z along the diagonals, which the contact cannot hold. Prong tips and feet
use the same pyramid; the SUF analysis of prong designs uses it too (on flat ground). The
compiled controller ticks write each contact's rows, about the normal of the terrain under it,
into their constraint matrices with `write_contact_force_rows`: on a 15 degree slope a pyramid
about the world's z would admit forces 15 degrees further downhill than the ground can hold.
"""

import math

import numpy as np

from pedi_drake.runtime.jit import kernel

# [-] the friction coefficients a controller may be given at run time, and a terrain patch may
# have: from wet ice to rubber on rough concrete.
FRICTION_RANGE = (0.05, 1.5)


@kernel
def pyramid_slope(mu: float, inscribed: bool = True) -> float:
    """m of |lambda_x|, |lambda_y| <= m lambda_z for friction coefficient `mu` [-]."""
    return mu / math.sqrt(2.0) if inscribed else mu


UP = np.array([0.0, 0.0, 1.0])  # the flat ground's normal


@kernel
def contact_tangents(normal: np.ndarray, t1: np.ndarray, t2: np.ndarray) -> None:
    """Writes the pyramid's edge directions for the unit ground normal `normal` (world): t1 the
    world x projected into the ground's plane (the world y's when the ground is nearly vertical
    to x), t2 = normal x t1. Flat ground (normal z) gives exactly x and y."""
    axis = 0 if abs(normal[0]) < 0.9 else 1
    norm2 = 0.0
    for k in range(3):
        t1[k] = (1.0 if k == axis else 0.0) - normal[axis] * normal[k]
        norm2 += t1[k] * t1[k]
    scale = 1.0 / math.sqrt(norm2)
    for k in range(3):
        t1[k] *= scale
    t2[0] = normal[1] * t1[2] - normal[2] * t1[1]
    t2[1] = normal[2] * t1[0] - normal[0] * t1[2]
    t2[2] = normal[0] * t1[1] - normal[1] * t1[0]


@kernel
def write_pyramid_faces(G: np.ndarray, row: int, column: int, slope: float, normal: np.ndarray) -> None:
    """Writes the pyramid's four faces about the unit ground normal `normal` (rows r with
    r . lambda <= 0) into G[row:row + 4], for a force lambda at G's columns column, column + 1,
    column + 2 (x, y, z); the rest of the rows is left as it is."""
    t1, t2 = np.empty(3), np.empty(3)
    contact_tangents(normal, t1, t2)
    for k in range(3):
        G[row, column + k] = t1[k] - slope * normal[k]
        G[row + 1, column + k] = -t1[k] - slope * normal[k]
        G[row + 2, column + k] = t2[k] - slope * normal[k]
        G[row + 3, column + k] = -t2[k] - slope * normal[k]


@kernel
def write_contact_force_rows(
    G: np.ndarray, h: np.ndarray, row: int, column: int, slope: float, normal: np.ndarray, low: float, high: float
) -> None:
    """Writes one contact's six rows of G lambda <= h into G[row:row + 6] and h[row:row + 6]: the
    normal force n . lambda between `low` and `high` [N], then the pyramid's four faces about the
    unit ground normal `normal` (`write_pyramid_faces`), for a force lambda at G's columns column
    to column + 2; the rest of the rows is left as it is."""
    for k in range(3):
        G[row, column + k] = -normal[k]
        G[row + 1, column + k] = normal[k]
    write_pyramid_faces(G, row + 2, column, slope, normal)
    h[row] = -low
    h[row + 1] = high
    for r in range(2, 6):
        h[row + r] = 0.0


def friction_pyramid_edges(mu: float, *, inscribed: bool = True, normal: np.ndarray = UP) -> np.ndarray:
    """(4, 3): rows r with r . lambda <= 0, the pyramid's four faces about the unit ground
    normal `normal` (no unilateral row)."""
    faces = np.zeros((4, 3))
    write_pyramid_faces(faces, 0, 0, pyramid_slope(mu, inscribed), np.asarray(normal, dtype=float))
    return faces


def friction_pyramid_rows(mu: float, *, inscribed: bool = True, normal: np.ndarray = UP) -> np.ndarray:
    """(5, 3): rows r with r . lambda <= 0: n . lambda >= 0 then the four faces."""
    normal = np.asarray(normal, dtype=float)
    return np.vstack([-normal, friction_pyramid_edges(mu, inscribed=inscribed, normal=normal)])
