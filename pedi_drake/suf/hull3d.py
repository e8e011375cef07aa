"""An incremental 3-D convex hull, compiled: the inner polytope of the exact SUF projection.

The support-function projection (pedi_drake.suf.warm_projection) adds one rejectable force at a
time to an inner polytope and asks an LP about each of its facets, so the hull is kept as a
triangle mesh that grows point by point (the classic incremental algorithm: the faces a new point
sees are removed and the horizon's edges are joined to it), never rebuilt.

The mesh lives in a `Hull` of fixed-size arrays (`new_hull`):

    points (point_cap, 3)           every point inserted so far [N] (vertices or not)
    faces (face_cap, 3) int64       a triangle's point indices, counter-clockwise seen from outside
    normals (face_cap, 3)           its unit outward normal a [-]
    offsets (face_cap,)             b = a . (any of its points) [N]: the face lies on a . F = b
    alive (face_cap,) int64         1 for faces of the current hull
    certified (face_cap,) int64     1 once the projection has checked the face's plane (set by
                                    the caller; a new face starts at 0)

A point is seen by a face when it lies more than `eps` [N] outside the face's plane; a point no
face sees is inside (to `eps`) and is not added. Nearly coplanar points therefore never make
slivers that point inwards: the hull may be non-convex by at most `eps` at an edge, far below
the projection's certification tolerance. Each face records its plane, so coplanar triangles of
one facet of the polytope share (a, b) to rounding.

All functions are `pedi_drake.runtime.jit.kernel`s (callable from compiled code); an insertion allocates
only its small scratch (the seen faces and the horizon).

Why not Qhull (scipy.spatial.ConvexHull, the maintained library): `python -m
pedi_drake.benchmarks.hull3d` (benchmarks/results/hull3d.json) times both on 32 seeded point sets
shaped like the projection's (10 to 60 vertices of force polytopes, polygonal facets), in CPU time
per call, medians over all sets in one run: Qhull builds a hull from scratch (`ConvexHull(points)`
against `project_within`'s build) about 4x slower, and adds one point (`add_points` on
`ConvexHull(..., incremental=True)`) about 24x slower; a compiled caller would also cross into
Python (an `objmode` block) and take the GIL, which the projection's kernel releases. Qhull
with that crossing is 2.1x (50 to 60 vertices) to 14x (10 to 12) slower to build and 24x to 32x
slower to add a point, beyond the 1.2x the project allows, so the hull stays here. The benchmark
checks that both give the same vertices, volume and facet planes, and
tests/test_hull3d_against_qhull.py holds the two to the same vertices and volume.
"""

import math

import numpy as np

from pedi_drake.runtime.jit import kernel

# Returns of `insert_point`.
INSERTED = 1
INSIDE = 0
FULL = -1  # no room left in the arrays
# Returns of `start_hull`.
STARTED = 1
FLAT = 0  # the points do not span a 3-D volume (to eps)


@kernel
def new_hull(point_cap: int, face_cap: int):
    """(points, faces, normals, offsets, alive, certified, counts): empty arrays for a hull of at
    most `point_cap` points and `face_cap` face slots; counts = [points used, face slots used]."""
    return (
        np.zeros((point_cap, 3)),
        np.zeros((face_cap, 3), dtype=np.int64),
        np.zeros((face_cap, 3)),
        np.zeros(face_cap),
        np.zeros(face_cap, dtype=np.int64),
        np.zeros(face_cap, dtype=np.int64),
        np.zeros(2, dtype=np.int64),
    )


@kernel
def _set_plane(points, faces, normals, offsets, f) -> bool:
    """The unit normal and offset of face f from its points; False for a degenerate triangle."""
    a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
    ux, uy, uz = points[b, 0] - points[a, 0], points[b, 1] - points[a, 1], points[b, 2] - points[a, 2]
    vx, vy, vz = points[c, 0] - points[a, 0], points[c, 1] - points[a, 1], points[c, 2] - points[a, 2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not norm > 0.0:
        return False
    normals[f, 0], normals[f, 1], normals[f, 2] = nx / norm, ny / norm, nz / norm
    # The offset from the triangle's centroid: the same to rounding for each of its points.
    cx = (points[a, 0] + points[b, 0] + points[c, 0]) / 3.0
    cy = (points[a, 1] + points[b, 1] + points[c, 1]) / 3.0
    cz = (points[a, 2] + points[b, 2] + points[c, 2]) / 3.0
    offsets[f] = normals[f, 0] * cx + normals[f, 1] * cy + normals[f, 2] * cz
    return True


@kernel
def _new_face(points, faces, normals, offsets, alive, certified, counts, a, b, c) -> int:
    """Face (a, b, c) in a free slot (a dead one first); its index, or -1 without room."""
    slot = -1
    for f in range(counts[1]):
        if alive[f] == 0:
            slot = f
            break
    if slot < 0:
        if counts[1] >= faces.shape[0]:
            return -1
        slot = counts[1]
        counts[1] += 1
    faces[slot, 0], faces[slot, 1], faces[slot, 2] = a, b, c
    alive[slot] = 1
    certified[slot] = 0
    if not _set_plane(points, faces, normals, offsets, slot):
        # A zero-area triangle (three points on a line): its plane is taken from its neighbours'
        # later; as a plane through the point with any normal it would cut the hull.
        normals[slot, 0], normals[slot, 1], normals[slot, 2] = 0.0, 0.0, 0.0
        offsets[slot] = math.inf
    return slot


@kernel
def _distance_to_line(points, i, j, k) -> float:
    """Distance of point k from the line through points i and j [N]."""
    ux, uy, uz = points[j, 0] - points[i, 0], points[j, 1] - points[i, 1], points[j, 2] - points[i, 2]
    wx, wy, wz = points[k, 0] - points[i, 0], points[k, 1] - points[i, 1], points[k, 2] - points[i, 2]
    cx, cy, cz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
    length = math.sqrt(ux * ux + uy * uy + uz * uz)
    if not length > 0.0:
        return 0.0
    return math.sqrt(cx * cx + cy * cy + cz * cz) / length


@kernel
def _signed_volume(points, i, j, k, m) -> float:
    """(p_j - p_i) x (p_k - p_i) . (p_m - p_i) / |(p_j - p_i) x (p_k - p_i)|: the signed distance
    of point m from the plane through i, j, k [N] (0 for a degenerate triangle)."""
    ux, uy, uz = points[j, 0] - points[i, 0], points[j, 1] - points[i, 1], points[j, 2] - points[i, 2]
    vx, vy, vz = points[k, 0] - points[i, 0], points[k, 1] - points[i, 1], points[k, 2] - points[i, 2]
    nx, ny, nz = uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx
    norm = math.sqrt(nx * nx + ny * ny + nz * nz)
    if not norm > 0.0:
        return 0.0
    wx, wy, wz = points[m, 0] - points[i, 0], points[m, 1] - points[i, 1], points[m, 2] - points[i, 2]
    return (nx * wx + ny * wy + nz * wz) / norm


@kernel
def start_hull(points, faces, normals, offsets, alive, certified, counts, num_points, eps) -> int:
    """The tetrahedron of the first `num_points` points (already in `points`) that spans the most,
    then every other of them inserted. STARTED, FLAT (no tetrahedron thicker than eps), or FULL."""
    corners = np.zeros(4, dtype=np.int64)
    started = start_tetrahedron(points, faces, normals, offsets, alive, certified, counts, num_points, eps, corners)
    if started != STARTED:
        return started
    for k in range(num_points):
        if not is_corner(corners, k):
            if insert_existing(points, faces, normals, offsets, alive, certified, counts, k, eps) == FULL:
                return FULL
    return STARTED


@kernel
def is_corner(corners, k) -> bool:
    """Whether point k is one of the tetrahedron's `corners` (4,)."""
    return k == corners[0] or k == corners[1] or k == corners[2] or k == corners[3]


@kernel
def start_tetrahedron(points, faces, normals, offsets, alive, certified, counts, num_points, eps, corners) -> int:
    """The first step of `start_hull`: the hull is the tetrahedron of the first `num_points` points
    that spans the most, its corners' indices written into `corners` (4,) int64; STARTED, FLAT or
    FULL. The other points are then joined one by one (`insert_existing`), in any number of calls."""
    counts[0] = num_points
    counts[1] = 0
    if num_points < 4:
        return FLAT
    # Two points far apart, a third far from their line, a fourth far from their plane.
    i = 0
    j, best = -1, -1.0
    for k in range(1, num_points):
        dx, dy, dz = points[k, 0] - points[i, 0], points[k, 1] - points[i, 1], points[k, 2] - points[i, 2]
        distance = dx * dx + dy * dy + dz * dz
        if distance > best:
            j, best = k, distance
    if not math.sqrt(best) > eps:
        return FLAT
    k3, best = -1, -1.0
    for k in range(num_points):
        distance = _distance_to_line(points, i, j, k)
        if distance > best:
            k3, best = k, distance
    if not best > eps:
        return FLAT
    k4, best = -1, -1.0
    for k in range(num_points):
        distance = abs(_signed_volume(points, i, j, k3, k))
        if distance > best:
            k4, best = k, distance
    if not best > eps:
        return FLAT
    # Orient (i, j, k3) so that k4 lies behind it (inside).
    if _signed_volume(points, i, j, k3, k4) > 0.0:
        j, k3 = k3, j
    for a, b, c in ((i, j, k3), (i, k4, j), (j, k4, k3), (k3, k4, i)):
        if _new_face(points, faces, normals, offsets, alive, certified, counts, a, b, c) < 0:
            return FULL
    corners[0], corners[1], corners[2], corners[3] = i, j, k3, k4
    return STARTED


@kernel
def insert_point(points, faces, normals, offsets, alive, certified, counts, p, eps) -> int:
    """Adds the point p (3,) [N] to the hull: INSERTED, INSIDE (no face sees it by more than eps;
    not stored) or FULL (no room; the hull is unchanged)."""
    k = counts[0]
    if k >= points.shape[0]:
        return FULL
    points[k, 0], points[k, 1], points[k, 2] = p[0], p[1], p[2]
    counts[0] = k + 1
    status = insert_existing(points, faces, normals, offsets, alive, certified, counts, k, eps)
    if status != INSERTED:
        counts[0] = k  # not a vertex: forget it
    return status


@kernel
def insert_existing(points, faces, normals, offsets, alive, certified, counts, k, eps) -> int:
    """Joins the stored point k to the hull (see `insert_point`)."""
    px, py, pz = points[k, 0], points[k, 1], points[k, 2]
    num_faces = counts[1]
    visible = np.zeros(num_faces, dtype=np.bool_)
    any_visible = False
    for f in range(num_faces):
        if alive[f] == 1:
            n = normals[f]
            if n[0] * px + n[1] * py + n[2] * pz - offsets[f] > eps:
                visible[f] = True
                any_visible = True
    if not any_visible:
        return INSIDE
    # The horizon: edges (a, b) of seen faces whose neighbour across (the face with edge b -> a)
    # is not seen, in the seen face's orientation.
    horizon = np.zeros((3 * num_faces, 2), dtype=np.int64)
    num_edges = 0
    for f in range(num_faces):
        if not visible[f]:
            continue
        for e in range(3):
            a, b = faces[f, e], faces[f, (e + 1) % 3]
            neighbour_seen = False
            for g in range(num_faces):
                if alive[g] == 1 and g != f:
                    for e2 in range(3):
                        if faces[g, e2] == b and faces[g, (e2 + 1) % 3] == a:
                            neighbour_seen = visible[g]
            if not neighbour_seen:
                horizon[num_edges, 0], horizon[num_edges, 1] = a, b
                num_edges += 1
    free = 0
    for f in range(num_faces):
        free += 1 - alive[f]
    free += faces.shape[0] - num_faces
    if free + sum_bool(visible) < num_edges:
        return FULL
    for f in range(num_faces):
        if visible[f]:
            alive[f] = 0
    for e in range(num_edges):
        _new_face(points, faces, normals, offsets, alive, certified, counts, horizon[e, 0], horizon[e, 1], k)
    return INSERTED


@kernel
def sum_bool(flags) -> int:
    total = 0
    for flag in flags:
        total += 1 if flag else 0
    return total


@kernel
def smallest_offset(normals, offsets, alive, counts, direction) -> float:
    """min b over the live faces (Eq. 9 on unit normals) [N], its normal written into direction (3,)."""
    best = math.inf
    for f in range(counts[1]):
        if alive[f] == 1 and offsets[f] < best:
            best = offsets[f]
            direction[0], direction[1], direction[2] = normals[f, 0], normals[f, 1], normals[f, 2]
    return best


@kernel
def ray_length(normals, offsets, alive, counts, d) -> float:
    """The largest f with f d inside the hull, d (3,) a unit vector [N] (inf if unbounded)."""
    best = math.inf
    for f in range(counts[1]):
        if alive[f] == 1:
            slope = normals[f, 0] * d[0] + normals[f, 1] * d[1] + normals[f, 2] * d[2]
            if slope > 1e-12:
                best = min(best, offsets[f] / slope)
    return best
