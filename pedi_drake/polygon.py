"""Convex polygons in the ground plane: hulls, half-planes, shrinking. One copy for every user.

The whole-body controller keeps its capture point in a polygon (N p <= d), the Mission Manager
sends it the support polygon of the loaded contacts shrunk by a margin, and the evaluation
measures how far inside a point stayed. The maths is written once, as compiled kernels (the
controller's compiled tick calls them, the manager's update calls them every 10 ms), with thin
Python functions on top:

* `convex_hull_ccw(points)`: Andrew's monotone chain, counter-clockwise, collinear points dropped
  (a turn of at most 1e-12 m^2 is not a turn);
* `polygon_halfplanes(points, margin)`: (N, d) with unit outward normals, N p <= d, for the hull
  shrunk by `margin` [m] (every edge moved inwards; edges shorter than 1e-12 m are skipped);
* `shrink_polygon(points, margin)`: the vertices of that shrunk polygon: every pair of edge lines
  intersected (Cramer's rule; parallel pairs skipped), the corners inside all half-planes
  (1e-9 m) kept, their hull. Empty (0, 2) when fewer than three corners are left.
"""

import math

import numpy as np

from pedi_drake.runtime.jit import kernel


@kernel
def hull_kernel(points: np.ndarray, hull: np.ndarray) -> int:
    """The convex hull of points (k, 2) [m], counter-clockwise, into hull (>= 2 k + 1, 2); its size."""
    k = points.shape[0]
    # Lexicographic sort (x, then y) of the indices, by insertion: a handful of points.
    order = np.arange(k)
    for i in range(1, k):
        j = i
        while j > 0:
            a, b = order[j - 1], order[j]
            if points[a, 0] > points[b, 0] or (points[a, 0] == points[b, 0] and points[a, 1] > points[b, 1]):
                order[j - 1], order[j] = b, a
                j -= 1
            else:
                break
    if k <= 2:
        for i in range(k):
            hull[i, 0] = points[order[i], 0]
            hull[i, 1] = points[order[i], 1]
        return k
    count = 0
    chain = np.empty((k, 2))
    for upper in range(2):  # the lower chain, then the upper one, each without its last point
        length = 0
        for step in range(k):
            index = order[step] if upper == 0 else order[k - 1 - step]
            px, py = points[index, 0], points[index, 1]
            while length >= 2:
                ax, ay = chain[length - 2, 0], chain[length - 2, 1]
                bx, by = chain[length - 1, 0], chain[length - 1, 1]
                if (bx - ax) * (py - ay) - (by - ay) * (px - ax) > 1e-12:
                    break
                length -= 1
            chain[length, 0] = px
            chain[length, 1] = py
            length += 1
        for i in range(length - 1):
            hull[count, 0] = chain[i, 0]
            hull[count, 1] = chain[i, 1]
            count += 1
    return count


@kernel
def halfplanes_kernel(points: np.ndarray, margin: float, N: np.ndarray, d: np.ndarray) -> int:
    """N p <= d (rows written into N (>= 2 k + 1, 2), d) of the hull of points (k, 2) [m] shrunk by
    `margin` [m]; returns the number of rows."""
    hull = np.empty((2 * points.shape[0] + 1, 2))
    count = hull_kernel(points, hull)
    rows = 0
    for i in range(count):
        ax, ay = hull[i, 0], hull[i, 1]
        j = i + 1 if i + 1 < count else 0
        bx, by = hull[j, 0], hull[j, 1]
        nx, ny = by - ay, ax - bx  # outward for a counter-clockwise ring
        length = math.hypot(nx, ny)
        if length < 1e-12:
            continue  # coincident points: no edge
        nx, ny = nx / length, ny / length
        N[rows, 0] = nx
        N[rows, 1] = ny
        d[rows] = nx * ax + ny * ay - margin
        rows += 1
    return rows


@kernel
def shrink_kernel(points: np.ndarray, margin: float, vertices: np.ndarray) -> int:
    """The hull of points (k, 2) [m] shrunk by `margin` [m]: its vertices, counter-clockwise, into
    vertices (>= k^2 + 1, 2); their number (0 when fewer than three are left)."""
    k = points.shape[0]
    N = np.empty((2 * k + 1, 2))
    d = np.empty(2 * k + 1)
    rows = halfplanes_kernel(points, margin, N, d)
    corners = np.empty((rows * rows + 1, 2))
    count = 0
    for i in range(rows):
        for j in range(i + 1, rows):
            det = N[i, 0] * N[j, 1] - N[i, 1] * N[j, 0]
            if abs(det) < 1e-12:
                continue  # parallel edges
            cx = (d[i] * N[j, 1] - d[j] * N[i, 1]) / det
            cy = (N[i, 0] * d[j] - N[j, 0] * d[i]) / det
            inside = True
            for r in range(rows):
                if N[r, 0] * cx + N[r, 1] * cy > d[r] + 1e-9:
                    inside = False
                    break
            if inside:
                corners[count, 0] = cx
                corners[count, 1] = cy
                count += 1
    if count < 3:
        return 0
    return hull_kernel(corners[:count], vertices)


def _points(points_xy) -> np.ndarray:
    return np.ascontiguousarray(np.asarray(points_xy, dtype=float).reshape(-1, 2))


def convex_hull_ccw(points_xy: np.ndarray) -> np.ndarray:
    """Vertices (k, 2) of the convex hull of `points_xy` [m], counter-clockwise."""
    points = _points(points_xy)
    hull = np.empty((2 * len(points) + 1, 2))
    return hull[: hull_kernel(points, hull)].copy()


def polygon_halfplanes(vertices_xy: np.ndarray, margin: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(N, d) with N p <= d: the convex hull of `vertices_xy` (k >= 3, [m]) shrunk by `margin` [m]."""
    points = _points(vertices_xy)
    N, d = np.empty((2 * len(points) + 1, 2)), np.empty(2 * len(points) + 1)
    rows = halfplanes_kernel(points, float(margin), N, d)
    return N[:rows].copy(), d[:rows].copy()


def shrink_polygon(points_xy: np.ndarray, margin: float) -> np.ndarray:
    """Vertices (k, 2), counter-clockwise, of the convex hull of `points_xy` [m] shrunk by `margin` [m].

    Every edge moves inwards by `margin`; the result is the intersection of those half-planes
    (an edge shorter than the shrink drops out). Empty (0, 2) when nothing is left.
    """
    points = _points(points_xy)
    vertices = np.empty((len(points) ** 2 + 1, 2))
    return vertices[: shrink_kernel(points, float(margin), vertices)].copy()
