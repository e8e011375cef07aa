"""The exact SUF, compiled and warm-started from the previous configuration's projection.

The same support-function (convex hull) method as `methods.suf_exact`: an inner polytope of
rejectable forces grows until an LP certifies every facet to `tol` [N], then Eq. 9. What differs
is how little each configuration costs when the one before it was close, as along a teleoperated
path where the robot moves a few millimetres per tick:

1. Equalities eliminated once. x = [F; lambda] meets A_eq x = b_eq exactly when x = x_0 + N z,
   N a basis of A_eq's null space (nz = 6 for three stance feet, 9 for four contacts), so every
   LP is over z with the inequality rows G z <= h (A_in's rows and a box |F_i| <= RAY_CAP, each
   scaled to a unit normal) and F = F_0 + N_F z. Row k of G is always the same constraint (a
   motor's torque limit, a contact's pyramid face), whatever N is, so a set of active rows means
   the same vertex from one configuration to the next.
2. LPs by DAQP called from compiled code (pedi_drake.numerics.daqp_kernel, H = 0: its
   proximal-point iterations end on an exact vertex), each started from an active set: max a . F from the
   active set of the facet's first vertex, which usually is already optimal or one step from it.
3. Warm start: the directions that produced the previous polytope's vertices, each with its
   vertex's active set. The first LPs re-find those vertices in the new configuration (one
   factorisation each when the active set is still optimal), the hull of the new points is
   built, and the certification LPs check its facets; only what changed costs pivots. Cold
   (no warm start, or a different number of contacts) it starts from the six axis rays as
   `suf_exact` does.
4. A budget of LPs (`max_lps`): a projection that would need more stops with status INCOMPLETE
   and its callers use the single-direction SUF (`ray_suf`) for that update; the budget makes
   the worst case a fixed amount of work, whatever the configuration did.
5. Resumable (`project_within`): the projection is a sequence of steps (a point found by a check
   or an LP, the first tetrahedron, a point joined to the hull, a facet checked or certified by
   an LP) whose whole state is in its arrays and a small `progress` array, so it can stop after
   any step and go on in a later call. Each call gets a budget of work counted in LPs (each kind
   of step charged its measured cost against an LP's, `*_WORK`), not in time: where it stops
   depends only on the problem and the budgets, so a caller that spreads a projection over its
   control ticks stays deterministic.

Everything from the rows on is one `pedi_drake.runtime.jit.kernel` call (nopython, nogil) per call of
`project_within`, so a caller in a control loop pays no Python per LP. `suf_exact_warm` is the Python entry point on a
RejectableForceProblem; pedi_drake.suf.live builds the rows from the robot's state in compiled
code too.
"""

import dataclasses
import math
import time

import numpy as np

from pedi_drake.exceptions import SufError
from pedi_drake.numerics import daqp_kernel
from pedi_drake.runtime.jit import kernel
from pedi_drake.suf import hull3d
from pedi_drake.suf.methods import Polytope, SufResult
from pedi_drake.suf.problem import RejectableForceProblem
from pedi_drake.suf.ray_program import RAY_CAP

# Status of a projection (and of pedi_drake.suf.live's results).
EXACT = 1  # every facet certified: the exact SUF
INCOMPLETE = 2  # the LP budget ran out first
INFEASIBLE = 3  # not even F = 0 is rejectable (the nominal motion is not feasible): SUF 0
FLAT = 4  # the rejectable forces do not span a 3-D polytope: SUF 0
NUMERICAL = 5  # an LP failed otherwise, or the arrays were too small
STATUS_NAMES = {
    EXACT: "exact",
    INCOMPLETE: "incomplete",
    INFEASIBLE: "infeasible",
    FLAT: "flat",
    NUMERICAL: "numerical failure",
}

# Certification tolerance of a facet [N], as `suf_exact`'s default.
TOLERANCE = 1e-3
# A point this far outside a facet's plane is outside the hull [N]: well below TOLERANCE, so a
# point an LP found beyond a facet by more than TOLERANCE is always added.
HULL_EPS = 1e-6
# Facets whose unit normals differ by less than this and offsets by less than HULL_EPS are one
# plane (coplanar triangles of one facet of the polytope): one LP certifies them all.
SAME_NORMAL = 1e-9
# Rank tolerance of the equality rows' singular values, relative to the largest [-].
RANK_TOLERANCE = 1e-10
# An inequality row whose coefficients vanish in z (norm below this) is a constant: satisfied
# or the problem is infeasible [units of the row].
ZERO_ROW = 1e-12
# A vertex recomputed from its active set may violate another row by this much and still count
# [N, the rows' unit]: rounding of a degenerate vertex (many rows through one point).
VERTEX_FEASIBILITY = 1e-7
# Multipliers above -this (relative to the gradient) prove a vertex optimal without an LP [-].
MULTIPLIER_TOLERANCE = 1e-9
# Points and face slots of the hull: the Go1's polytopes have 20 to 60 vertices.
POINT_CAP = 400
FACE_CAP = 2000
DEFAULT_MAX_LPS = 5000
# DAQP's proximal weight for the LPs (H = 0): any positive weight gives the same vertex.
_PROX_WEIGHT = 1e-5
# Constraint violation accepted at an LP's solution [N, the rows are unit normals].
_PRIMAL_TOLERANCE = 1e-9
_NO_BOUND = daqp_kernel.INFINITE_BOUND
# The part of a unit row outside the span of the rows before it below which it is dependent [-].
_INDEPENDENT_ROW = 1e-6


@kernel
def eliminate_equalities(A_eq, b_eq, A_in, b_in, ray_cap):
    """(G, h, N_F, F_0, feasible): the rows of the LPs in z (see the module docstring).

    G (m, nz) has unit rows (a zero row gets h = no bound), m = rows of A_in + 6 (the F box);
    feasible is False when the equalities have no solution or a constant row is violated.
    """
    nx = A_eq.shape[1]
    U, sigma, Vt = np.linalg.svd(A_eq)
    rank = 0
    for s in sigma:
        if s > RANK_TOLERANCE * sigma[0]:
            rank += 1
    nz = nx - rank
    # Minimum-norm particular solution x_0 = V S^-1 U' b_eq, then its residual.
    x0 = np.zeros(nx)
    for k in range(rank):
        coefficient = 0.0
        for i in range(A_eq.shape[0]):
            coefficient += U[i, k] * b_eq[i]
        coefficient /= sigma[k]
        for j in range(nx):
            x0[j] += coefficient * Vt[k, j]
    feasible = True
    scale = 1.0
    for i in range(A_eq.shape[0]):
        scale = max(scale, abs(b_eq[i]))
    for i in range(A_eq.shape[0]):
        residual = -b_eq[i]
        for j in range(nx):
            residual += A_eq[i, j] * x0[j]
        if abs(residual) > 1e-9 * scale:
            feasible = False
    N = np.ascontiguousarray(Vt[rank:].T)  # (nx, nz)
    m_in = A_in.shape[0]
    m = m_in + 6
    G = np.zeros((m, nz))
    h = np.zeros(m)
    for i in range(m_in):
        slack = b_in[i]
        for j in range(nx):
            slack -= A_in[i, j] * x0[j]
        for k in range(nz):
            value = 0.0
            for j in range(nx):
                value += A_in[i, j] * N[j, k]
            G[i, k] = value
        h[i] = slack
    N_F = np.ascontiguousarray(N[0:3])
    F0 = x0[0:3].copy()
    for axis in range(3):
        for sign_index in range(2):
            sign = 1.0 if sign_index == 0 else -1.0
            row = m_in + 2 * axis + sign_index
            for k in range(nz):
                G[row, k] = sign * N_F[axis, k]
            h[row] = ray_cap - sign * F0[axis]
    for i in range(m):
        norm = 0.0
        for k in range(nz):
            norm += G[i, k] * G[i, k]
        norm = math.sqrt(norm)
        if norm < ZERO_ROW:
            if h[i] < -1e-9:
                feasible = False
            for k in range(nz):
                G[i, k] = 0.0
            h[i] = _NO_BOUND
            continue
        for k in range(nz):
            G[i, k] /= norm
        h[i] /= norm
    return G, h, N_F, F0, feasible


@kernel
def _solve_lp(H, f, G, h, lower, sense, y, multipliers) -> int:
    """min f'y s.t. lower <= G y <= h (H = 0, its proximal term) by DAQP; its exit flag."""
    return daqp_kernel.solve_qp(
        H, f, G, h, lower, sense, _PROX_WEIGHT, daqp_kernel.AUTOMATIC_FIXED_POINT, _PRIMAL_TOLERANCE, y, multipliers
    )


@kernel
def _support(G, h, N_F, F0, a, start_active, num_start, active_out, F_out, lp):
    """max a . F over the RFP, DAQP started from the working set start_active[:num_start];
    (DAQP's exit flag, value, num_active), the maximiser in F_out and the rows with a nonzero
    multiplier (its active set) in active_out. `lp`: the scratch tuple of `_lp_scratch`."""
    H, f, y, multipliers, lower, sense = lp
    nz = G.shape[1]
    for k in range(nz):
        f[k] = -(N_F[0, k] * a[0] + N_F[1, k] * a[1] + N_F[2, k] * a[2])
    sense[:] = 0
    for k in range(num_start):
        sense[start_active[k]] = daqp_kernel.SENSE_ACTIVE
    exit_flag = _solve_lp(H, f, G, h, lower, sense, y, multipliers)
    if num_start > 0 and not daqp_kernel.solved(exit_flag):
        # A start whose rows are dependent in this configuration: solve cold.
        sense[:] = 0
        exit_flag = _solve_lp(H, f, G, h, lower, sense, y, multipliers)
    for i in range(3):
        value = F0[i]
        for k in range(nz):
            value += N_F[i, k] * y[k]
        F_out[i] = value
    q = 0
    if daqp_kernel.solved(exit_flag):
        q = _vertex_rows(G, h, y, active_out, daqp_kernel.active_rows(multipliers, active_out))
    return exit_flag, a[0] * F_out[0] + a[1] * F_out[1] + a[2] * F_out[2], q


@kernel
def _vertex_rows(G, h, y, rows, q) -> int:
    """Completes the rows[:q] of nonzero multiplier at the solution y with further rows tight there
    (within VERTEX_FEASIBILITY) and independent of those before, up to nz: at a degenerate
    vertex (more tight rows than nz, some with zero multipliers) the nz rows that determine it,
    which `_vertex` and `_optimal_at` need. Returns the number of rows."""
    nz = G.shape[1]
    # An orthonormal basis of the rows so far (modified Gram-Schmidt), one row per basis vector.
    basis = np.zeros((nz, nz))
    size = 0
    candidate = np.empty(nz)
    for i in range(G.shape[0] + q):
        if size == nz:
            break
        if i < q:
            row = rows[i]
        else:
            row = i - q
            if h[row] >= _NO_BOUND:
                continue
            slack = h[row]
            for k in range(nz):
                slack -= G[row, k] * y[k]
            if abs(slack) > VERTEX_FEASIBILITY:
                continue
        candidate[:] = G[row]
        for b in range(size):
            projection = 0.0
            for k in range(nz):
                projection += basis[b, k] * candidate[k]
            for k in range(nz):
                candidate[k] -= projection * basis[b, k]
        norm = math.sqrt(np.sum(candidate * candidate))
        if norm <= _INDEPENDENT_ROW:
            continue
        basis[size] = candidate / norm
        rows[size] = row
        size += 1
    return size


@kernel
def _lp_scratch(nz, m):
    """(H, f, y, multipliers, lower, sense) for LPs of nz variables and m rows (H = 0)."""
    return (
        np.zeros((nz, nz)),
        np.zeros(nz),
        np.zeros(nz),
        np.zeros(m),
        np.full(m, -daqp_kernel.INFINITE_BOUND),
        np.zeros(m, dtype=np.int32),
    )


@kernel
def _solve_square(A, b, x) -> bool:
    """x = A^-1 b for a small square A (Gaussian elimination with partial pivoting on copies);
    False when A is singular to rounding."""
    n = b.shape[0]
    M = A.copy()
    r = b.copy()
    scale = 0.0
    for i in range(n):
        for j in range(n):
            scale = max(scale, abs(M[i, j]))
    if not scale > 0.0:
        return False
    for col in range(n):
        pivot, best = col, abs(M[col, col])
        for row in range(col + 1, n):
            if abs(M[row, col]) > best:
                pivot, best = row, abs(M[row, col])
        if not best > 1e-12 * scale:
            return False
        if pivot != col:
            for j in range(n):
                M[col, j], M[pivot, j] = M[pivot, j], M[col, j]
            r[col], r[pivot] = r[pivot], r[col]
        for row in range(col + 1, n):
            factor = M[row, col] / M[col, col]
            if factor != 0.0:
                for j in range(col, n):
                    M[row, j] -= factor * M[col, j]
                r[row] -= factor * r[col]
    for row in range(n - 1, -1, -1):
        value = r[row]
        for j in range(row + 1, n):
            value -= M[row, j] * x[j]
        x[row] = value / M[row, row]
    return True


@kernel
def _vertex(G, h, N_F, F0, rows, F_out) -> bool:
    """The point where the nz rows `rows` of G z <= h are all tight, if it is feasible: F in F_out.
    A still-valid vertex of the previous configuration costs this one solve instead of an LP."""
    nz = G.shape[1]
    A = np.empty((nz, nz))
    b = np.empty(nz)
    for i in range(nz):
        for k in range(nz):
            A[i, k] = G[rows[i], k]
        b[i] = h[rows[i]]
    z = np.empty(nz)
    if not _solve_square(A, b, z):
        return False
    for i in range(G.shape[0]):
        if h[i] >= _NO_BOUND:
            continue
        value = -h[i]
        for k in range(nz):
            value += G[i, k] * z[k]
        if value > VERTEX_FEASIBILITY:
            return False
    for i in range(3):
        value = F0[i]
        for k in range(nz):
            value += N_F[i, k] * z[k]
        F_out[i] = value
    return True


@kernel
def _optimal_at(G, N_F, rows, a) -> bool:
    """Whether the vertex where the nz rows `rows` are tight maximises a . F: the gradient
    N_F' a is a non-negative combination of those rows (their multipliers, one solve)."""
    nz = G.shape[1]
    A = np.empty((nz, nz))
    c = np.empty(nz)
    size = 0.0
    for k in range(nz):
        c[k] = N_F[0, k] * a[0] + N_F[1, k] * a[1] + N_F[2, k] * a[2]
        size = max(size, abs(c[k]))
        for i in range(nz):
            A[k, i] = G[rows[i], k]
    multipliers = np.empty(nz)
    if not _solve_square(A, c, multipliers):
        return False
    for i in range(nz):
        if multipliers[i] < -MULTIPLIER_TOLERANCE * max(size, 1e-300):
            return False
    return True


_AXES = np.array(
    [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]
)


# The resumable projection's progress (an int64 array of PROGRESS_SIZE, `new_progress`): its stage,
# whether it fell back from the warm start to the axis rays, the next point (or facet) to look at,
# the points found, the LPs solved, the tetrahedron's corners, and the final status (0 until done).
_STAGE, _ATTEMPT, _NEXT, _NUM_POINTS, _LPS, _CORNERS, _FINAL = 0, 1, 2, 3, 4, 5, 9
PROGRESS_SIZE = 10
_POINTS, _TETRAHEDRON, _HULL, _CERTIFY = 0, 1, 2, 3
# The status of a call that spent its work budget before the projection was done: call again.
PENDING = -1
# What the projection's steps cost, in the work unit of `project_within`'s budget: one LP on the
# Go1's problems; a vertex's or a facet's check (a small solve) under a tenth of that; a point
# joined to the hull (or the first tetrahedron) under one [LP]. Measured with
# pedi_drake.benchmarks.live_suf_slices (each kind of step timed alone), and rounded up: they
# make a budget of work a budget of time, roughly.
LP_WORK = 1.0
CHECK_WORK = 0.1
INSERT_WORK = 0.2
TETRAHEDRON_WORK = 0.2


@kernel
def new_progress():
    """The progress of a projection not yet started (see `project_within`)."""
    return np.zeros(PROGRESS_SIZE, dtype=np.int64)


@kernel
def progress_lps(progress) -> int:
    """LPs the projection of `progress` has solved so far."""
    return progress[_LPS]


@kernel
def _finished(progress, status):
    progress[_FINAL] = status
    return status


@kernel
def project_within(
    G, h, N_F, F0, warm_directions, warm_active, warm_num_active, num_warm, tol, max_lps, hull, meta, progress, budget
):
    """Goes on with the projection recorded in `progress` (hull3d arrays in `hull`, warm-started
    from `num_warm` directions with their active sets) until it is done or this call's work
    reaches `budget` [LP, see LP_WORK]; (status, work done). The status is PENDING when the
    budget ran out first: a later call with the same arrays goes on where this one stopped, so
    any sequence of budgets ends on the same polytope, with the same LPs, as one call with an
    infinite budget (steps are never cut: a call that starts a step finishes it, so a call's work
    exceeds its budget by at most one step, an LP and a point joined to the hull). Once done, the
    status is the projection's (`progress_lps`: its LPs) and later calls do nothing.

    meta = (directions (point_cap, 3), active sets (point_cap, nz) int64, their sizes
    (point_cap,) int64): for every hull point, the LP direction that found it and its vertex's
    active set (what the next configuration's warm start reads).
    """
    points, faces, normals, offsets, alive, certified, counts = hull
    directions, actives, num_actives = meta
    if progress[_FINAL] != 0:
        return progress[_FINAL], 0.0
    nz, m = G.shape[1], G.shape[0]
    lp = _lp_scratch(nz, m)
    F = np.zeros(3)
    a = np.zeros(3)
    active = np.zeros(max(nz, 1), dtype=np.int64)
    corners = progress[_CORNERS:_FINAL]
    work = 0.0
    while True:
        if work >= budget:
            return PENDING, work
        stage = progress[_STAGE]
        warm = progress[_ATTEMPT] == 0 and num_warm >= 4
        if stage == _POINTS:
            # 1. Points: the warm directions from their active sets, or the six axis rays.
            k = progress[_NEXT]
            if k >= (num_warm if warm else 6):
                progress[_STAGE] = _TETRAHEDRON
                continue
            num_points = progress[_NUM_POINTS]
            if num_points >= points.shape[0]:
                return _finished(progress, NUMERICAL), work
            for i in range(3):
                a[i] = warm_directions[k, i] if warm else _AXES[k, i]
            start = warm_num_active[k] if warm else 0
            kept = False
            if warm and start == nz:
                work += CHECK_WORK
                kept = _vertex(G, h, N_F, F0, warm_active[k], F)
            if kept:
                q = nz  # the previous vertex is still one: no LP
                for j in range(nz):
                    active[j] = warm_active[k, j]
            else:
                status, _, q = _support(G, h, N_F, F0, a, warm_active[k] if warm else active, start, active, F, lp)
                progress[_LPS] += 1
                work += LP_WORK
                if status == daqp_kernel.EXIT_INFEASIBLE:
                    return _finished(progress, INFEASIBLE), work
                if not daqp_kernel.solved(status):
                    return _finished(progress, NUMERICAL), work
            for i in range(3):
                points[num_points, i] = F[i]
                directions[num_points, i] = a[i]
            for j in range(q):
                actives[num_points, j] = active[j]
            num_actives[num_points] = q
            progress[_NUM_POINTS] = num_points + 1
            progress[_NEXT] = k + 1
        elif stage == _TETRAHEDRON:
            work += TETRAHEDRON_WORK
            started = hull3d.start_tetrahedron(
                points, faces, normals, offsets, alive, certified, counts, progress[_NUM_POINTS], HULL_EPS, corners
            )
            if started == hull3d.FULL:
                return _finished(progress, NUMERICAL), work
            if started == hull3d.FLAT:
                if not warm:
                    return _finished(progress, FLAT), work
                # The warm points are flat here: start again from the axis rays.
                progress[_ATTEMPT], progress[_STAGE], progress[_NEXT], progress[_NUM_POINTS] = 1, _POINTS, 0, 0
                continue
            progress[_STAGE], progress[_NEXT] = _HULL, 0
        elif stage == _HULL:
            # Every other point joined to the tetrahedron.
            k = progress[_NEXT]
            if k >= progress[_NUM_POINTS]:
                progress[_STAGE], progress[_NEXT] = _CERTIFY, 0
                continue
            if not hull3d.is_corner(corners, k):
                work += INSERT_WORK
                if hull3d.insert_existing(points, faces, normals, offsets, alive, certified, counts, k, HULL_EPS) == (
                    hull3d.FULL
                ):
                    return _finished(progress, NUMERICAL), work
            progress[_NEXT] = k + 1
        else:
            # 2. Certify every facet, in slot order from the last point added; a facet an LP finds
            # a force beyond gains that force, and the facets are looked at from the first again.
            f = progress[_NEXT]
            while f < counts[1] and (alive[f] == 0 or certified[f] == 1):
                f += 1
            if f >= counts[1]:
                return _finished(progress, EXACT), work
            progress[_NEXT] = f
            work += CHECK_WORK
            normal_size = abs(normals[f, 0]) + abs(normals[f, 1]) + abs(normals[f, 2])
            if normal_size == 0.0:
                certified[f] = 1  # a zero-area triangle: its neighbours hold the plane
                continue
            for g in range(counts[1]):
                if g != f and alive[g] == 1 and certified[g] == 1 and abs(offsets[g] - offsets[f]) <= HULL_EPS:
                    difference = 0.0
                    for i in range(3):
                        difference = max(difference, abs(normals[g, i] - normals[f, i]))
                    if difference <= SAME_NORMAL:
                        certified[f] = 1
                        break
            if certified[f] == 1:
                continue
            for i in range(3):
                a[i] = normals[f, i]
            # A vertex of the face whose active set is optimal for its normal: the support value is
            # the face's own offset, certified by one solve.
            first = faces[f, 0]
            for e in range(3):
                vertex = faces[f, e]
                if num_actives[vertex] == nz:
                    first = vertex
                    if _optimal_at(G, N_F, actives[vertex], a):
                        certified[f] = 1
                        break
            if certified[f] == 1:
                continue
            if progress[_LPS] >= max_lps:
                return _finished(progress, INCOMPLETE), work
            status, value, q = _support(G, h, N_F, F0, a, actives[first], num_actives[first], active, F, lp)
            progress[_LPS] += 1
            work += LP_WORK
            if not daqp_kernel.solved(status):
                return _finished(progress, NUMERICAL), work
            if value > offsets[f] + tol:
                k = counts[0]
                inserted = hull3d.insert_point(points, faces, normals, offsets, alive, certified, counts, F, HULL_EPS)
                if inserted == hull3d.FULL:
                    return _finished(progress, NUMERICAL), work
                if inserted == hull3d.INSERTED:
                    work += INSERT_WORK
                    for i in range(3):
                        directions[k, i] = a[i]
                    for j in range(q):
                        actives[k, j] = active[j]
                    num_actives[k] = q
                    progress[_NEXT] = 0
                    continue
            certified[f] = 1  # certified, or within HULL_EPS of the hull: nothing to add


@kernel
def project(G, h, N_F, F0, warm_directions, warm_active, warm_num_active, num_warm, tol, max_lps, hull, meta):
    """The whole projection in one call (`project_within` with no budget); (status, LPs solved)."""
    progress = new_progress()
    status, _ = project_within(
        G, h, N_F, F0, warm_directions, warm_active, warm_num_active, num_warm, tol, max_lps, hull, meta, progress,
        math.inf,
    )  # fmt: skip
    return status, progress[_LPS]


@kernel
def vertex_warm_start(hull, meta, out_directions, out_active, out_num_active) -> int:
    """Copies the direction and active set of every hull vertex (a point of a live face) into the
    out arrays; the number of vertices (the next projection's `num_warm`)."""
    points, faces, normals, offsets, alive, certified, counts = hull
    directions, actives, num_actives = meta
    used = np.zeros(counts[0], dtype=np.bool_)
    for f in range(counts[1]):
        if alive[f] == 1:
            for e in range(3):
                used[faces[f, e]] = True
    n = 0
    for k in range(counts[0]):
        if used[k] and n < out_directions.shape[0]:
            for i in range(3):
                out_directions[n, i] = directions[k, i]
            q = num_actives[k]
            for j in range(min(q, out_active.shape[1])):
                out_active[n, j] = actives[k, j]
            out_num_active[n] = min(q, out_active.shape[1])
            n += 1
    return n


@kernel
def ray_suf(G, h, N_F, F0, d):
    """(status, f): the largest f >= 0 with f d rejectable, d (3,) a unit vector [N]: the
    single-direction SUF, one LP (the component of F across d eliminated as an equality)."""
    nz, m = G.shape[1], G.shape[0]
    # Two unit vectors across d.
    helper = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(d, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(d, e1)
    K = np.zeros((2, nz))
    r = np.zeros(2)
    for k in range(nz):
        K[0, k] = e1[0] * N_F[0, k] + e1[1] * N_F[1, k] + e1[2] * N_F[2, k]
        K[1, k] = e2[0] * N_F[0, k] + e2[1] * N_F[1, k] + e2[2] * N_F[2, k]
    r[0] = -(e1[0] * F0[0] + e1[1] * F0[1] + e1[2] * F0[2])
    r[1] = -(e2[0] * F0[0] + e2[1] * F0[1] + e2[2] * F0[2])
    U, sigma, Vt = np.linalg.svd(K)
    rank = 0
    for s in sigma:
        if s > RANK_TOLERANCE * max(sigma[0], 1e-300):
            rank += 1
    if rank < 2:
        return NUMERICAL, 0.0
    z0 = np.zeros(nz)
    for k in range(rank):
        coefficient = (U[0, k] * r[0] + U[1, k] * r[1]) / sigma[k]
        for j in range(nz):
            z0[j] += coefficient * Vt[k, j]
    M = np.ascontiguousarray(Vt[rank:].T)  # (nz, ny)
    ny = M.shape[1]
    C = np.ascontiguousarray(np.dot(G, M))
    u = h - np.dot(G, z0)
    for i in range(m):
        if h[i] >= _NO_BOUND:
            u[i] = _NO_BOUND
    gradient = np.dot(d, N_F)  # (nz,)
    f = -np.dot(gradient, M)
    y = np.zeros(ny)
    exit_flag = _solve_lp(
        np.zeros((ny, ny)), f, C, u, np.full(m, -daqp_kernel.INFINITE_BOUND), np.zeros(m, np.int32), y, np.zeros(m)
    )
    if exit_flag == daqp_kernel.EXIT_INFEASIBLE:
        return INFEASIBLE, 0.0
    if not daqp_kernel.solved(exit_flag):
        return NUMERICAL, 0.0
    z = z0 + np.dot(M, y)
    value = np.dot(d, F0 + np.dot(N_F, z))
    return EXACT, max(value, 0.0)


@dataclasses.dataclass(frozen=True)
class WarmStart:
    """What a projection hands the next one: the directions that found its vertices [-] and their
    vertices' active sets (rows of G), for problems with `num_rows` rows in `nz` variables."""

    directions: np.ndarray  # (k, 3)
    active: np.ndarray  # (k, nz) int64
    num_active: np.ndarray  # (k,) int64
    num_rows: int
    nz: int

    def fits(self, num_rows: int, nz: int) -> bool:
        return self.num_rows == num_rows and self.nz == nz


def new_projection_arrays(nz: int, point_cap: int = POINT_CAP, face_cap: int = FACE_CAP):
    """(hull, meta): empty arrays for `project` on problems of nz variables."""
    hull = hull3d.new_hull(point_cap, face_cap)
    meta = (np.zeros((point_cap, 3)), np.zeros((point_cap, max(nz, 1)), dtype=np.int64), np.zeros(point_cap, np.int64))
    return hull, meta


def polytope_of(hull) -> Polytope:
    """The hull's vertices and its distinct facet planes (coplanar triangles merged)."""
    points, faces, normals, offsets, alive, _, counts = hull
    live = np.flatnonzero(alive[: counts[1]] == 1)
    live = live[np.abs(normals[live]).sum(axis=1) > 0.0]
    planes = np.round(np.column_stack([normals[live], offsets[live]]), 9)
    _, first = np.unique(planes, axis=0, return_index=True)
    keep = live[np.sort(first)]
    vertices = points[np.unique(faces[live].ravel())]
    return Polytope(vertices.copy(), normals[keep].copy(), offsets[keep].copy())


def problem_rows(problem: RejectableForceProblem):
    """`eliminate_equalities` of a problem's rows (C-contiguous float arrays)."""
    return eliminate_equalities(
        np.ascontiguousarray(problem.A_eq, float),
        np.ascontiguousarray(problem.b_eq, float),
        np.ascontiguousarray(problem.A_in, float),
        np.ascontiguousarray(problem.b_in, float),
        RAY_CAP,
    )


def _warm_arrays(warm: WarmStart | None, num_rows: int, nz: int):
    if warm is None or not warm.fits(num_rows, nz):
        return np.zeros((1, 3)), np.zeros((1, max(nz, 1)), np.int64), np.zeros(1, np.int64), 0
    return warm.directions, warm.active, warm.num_active, len(warm.directions)


def suf_exact_warm(
    problem: RejectableForceProblem,
    warm: WarmStart | None = None,
    *,
    tol: float = TOLERANCE,
    max_lps: int = DEFAULT_MAX_LPS,
) -> tuple[SufResult, WarmStart]:
    """The exact SUF of `problem` (as `methods.suf_exact`), started from `warm` (the WarmStart of a
    nearby configuration's projection, or None); (result, the WarmStart for the next).

    Raises SufError as `suf_exact` does: the nominal motion infeasible, a flat polytope, or the
    projection not done within `max_lps` LPs.
    """
    start = time.perf_counter()
    G, h, N_F, F0, feasible = problem_rows(problem)
    if not feasible:
        raise SufError("the nominal motion is not feasible (the equality rows have no solution)")
    nz = G.shape[1]
    hull, meta = new_projection_arrays(nz)
    directions, active, num_active, num_warm = _warm_arrays(warm, len(h), nz)
    status, lps = project(G, h, N_F, F0, directions, active, num_active, num_warm, float(tol), int(max_lps), hull, meta)
    if status == INFEASIBLE:
        raise SufError("the nominal motion is not feasible (no torques and contact forces within the limits hold it)")
    if status == FLAT:
        raise SufError("the rejectable forces do not span a 3D polytope")
    if status == INCOMPLETE:
        raise SufError(f"exact projection did not converge within {max_lps} LPs (tol {tol} N)")
    if status != EXACT:
        raise SufError(f"exact projection: {STATUS_NAMES.get(status, status)}")
    value_direction = np.zeros(3)
    points, faces, normals, offsets, alive, _, counts = hull
    value = hull3d.smallest_offset(normals, offsets, alive, counts, value_direction)
    out = (np.zeros((POINT_CAP, 3)), np.zeros((POINT_CAP, max(nz, 1)), np.int64), np.zeros(POINT_CAP, np.int64))
    k = vertex_warm_start(hull, meta, *out)
    next_warm = WarmStart(out[0][:k].copy(), out[1][:k].copy(), out[2][:k].copy(), len(h), nz)
    result = SufResult(
        "exact", max(float(value), 0.0), value_direction, polytope_of(hull), time.perf_counter() - start, True, int(lps)
    )
    return result, next_warm


def warm_up() -> None:
    """Compiles the kernels of this module for the argument types its callers pass (or loads them
    from numba's cache): call it in a constructor, never inside a control tick."""
    # A point mass on one frictional contact, pushed by F: lambda + F = (0, 0, 1).
    A_eq = np.hstack([np.eye(3), np.eye(3)])
    pyramid = np.array([[0.0, 0.0, -1.0], [1.0, 0.0, -0.5], [-1.0, 0.0, -0.5], [0.0, 1.0, -0.5], [0.0, -1.0, -0.5]])
    A_in = np.hstack([np.zeros((5, 3)), pyramid])
    G, h, N_F, F0, _ = eliminate_equalities(A_eq, np.array([0.0, 0.0, 1.0]), A_in, np.zeros(5), RAY_CAP)
    nz = G.shape[1]
    hull, meta = new_projection_arrays(nz, 32, 128)
    no_warm = (np.zeros((1, 3)), np.zeros((1, nz), np.int64), np.zeros(1, np.int64))
    project(G, h, N_F, F0, *no_warm, 0, TOLERANCE, 100, hull, meta)
    out = (np.zeros((32, 3)), np.zeros((32, nz), np.int64), np.zeros(32, np.int64))
    vertex_warm_start(hull, meta, *out)
    ray_suf(G, h, N_F, F0, np.array([0.0, 0.0, -1.0]))
