"""The 4-edge friction pyramid of a point contact on flat ground, for every user of it.

A contact force lambda (world frame, z up) is admissible when lambda_z >= 0 and

    |lambda_x| <= m lambda_z,   |lambda_y| <= m lambda_z,   m = mu / sqrt(2) (inscribed) or mu.

The inscribed pyramid (the default everywhere) lies inside the Coulomb cone of radius mu: every
force it admits the contact can hold. The circumscribed one (m = mu) admits tangential forces up
to sqrt(2) mu lambda_z along the diagonals, which the contact cannot hold. Prong tips and feet
use the same pyramid; the SUF analysis of prong designs uses it too. The compiled controller
ticks write its faces into their constraint matrices with `write_pyramid_faces`.
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


@kernel
def write_pyramid_faces(G: np.ndarray, row: int, column: int, slope: float) -> None:
    """Writes the pyramid's four faces (rows r with r . lambda <= 0) into G[row:row + 4], for a
    force lambda at G's columns column, column + 1, column + 2 (x, y, z); the rest of the rows
    is left as it is."""
    for k in range(4):
        G[row + k, column + 2] = -slope
    G[row, column] = 1.0
    G[row + 1, column] = -1.0
    G[row + 2, column + 1] = 1.0
    G[row + 3, column + 1] = -1.0


def friction_pyramid_edges(mu: float, *, inscribed: bool = True) -> np.ndarray:
    """(4, 3): rows r with r . lambda <= 0, the pyramid's four faces (no unilateral row)."""
    faces = np.zeros((4, 3))
    write_pyramid_faces(faces, 0, 0, pyramid_slope(mu, inscribed))
    return faces


def friction_pyramid_rows(mu: float, *, inscribed: bool = True) -> np.ndarray:
    """(5, 3): rows r with r . lambda <= 0: lambda_z >= 0 then the four faces."""
    return np.vstack([[0.0, 0.0, -1.0], friction_pyramid_edges(mu, inscribed=inscribed)])
