"""The Smallest Unrejectable Force (paper 003, Sec. IV and Appendix): five ways to compute it.

The SUF is the radius of the largest ball centred at F = 0 inside the Rejectable Force Polytope:
with the RFP as {F : a_i . F <= b_i}, SUF = min_i b_i / |a_i| (Eq. 9), the worst force pointing
along that a_i.

* `exact`: the RFP projected exactly by the support-function (convex hull) method: start from the
  six axis rays, then for every facet of the current inner hull solve max a . F over the RFP; a
  facet whose support value exceeds its offset gains that vertex, until every facet is
  certified to a tolerance. Then Eq. 9.
* `single`: the largest rejectable force along one given direction (not conservative: it is an
  upper bound of the SUF).
* `fibonacci`: ray LPs along N directions of the Fibonacci sphere, the inner polytope of the
  points, Eq. 9 (conservative).
* `affine`: an affine control law dQ = dQ0 + V F over the null space N of W = [B J_c^T]; with the
  scaled gain U = rho V the robust constraints are second-order cones (Eqs. 10-11), conservative.
* `quadratic`: dQ_j = dQ0_j + V_j F + F^T W_j F; by the S-lemma each robust constraint becomes a
  4x4 linear matrix inequality (Appendix, Eqs. 12-14), conservative and at least as large as affine.
"""

import dataclasses
import time

import numpy as np
from pydrake.solvers import MathematicalProgram
from scipy.spatial import ConvexHull, QhullError

from pedi_drake.exceptions import SufError
from pedi_drake.suf.problem import RejectableForceProblem
from pedi_drake.suf.ray_program import RAY_CAP, RfpLinearProgram, make_solver

METHODS = ("exact", "single", "fibonacci", "affine", "quadratic")


@dataclasses.dataclass
class Polytope:
    """A 3D polytope in both representations: vertices (k, 3) [N] and A F <= b (unit rows of A)."""

    vertices: np.ndarray
    A: np.ndarray
    b: np.ndarray

    @staticmethod
    def from_points(points: np.ndarray) -> "Polytope":
        try:
            hull = ConvexHull(points)
        except (QhullError, ValueError) as error:
            raise SufError(f"the rejectable forces do not span a 3D polytope: {str(error).splitlines()[0]}") from None
        return Polytope(points[hull.vertices], hull.equations[:, :3], -hull.equations[:, 3])

    def contains(self, F: np.ndarray, tol: float = 1e-9) -> bool:
        return bool(np.all(self.A @ F <= self.b + tol))


@dataclasses.dataclass
class SufResult:
    """The SUF and how it was found."""

    method: str
    value: float  # [N]
    direction: np.ndarray  # unit vector of the worst (smallest unrejectable) force, world frame
    polytope: Polytope | None  # the RFP (exact) or its inner approximation (fibonacci)
    solve_time_s: float
    conservative: bool  # True when value never exceeds the exact SUF (all but `single`)
    num_programs: int = 0  # LPs / cone programs solved


def _suf_of(polytope: Polytope) -> tuple[float, np.ndarray]:
    """Eq. 9 on a polytope's halfspaces (unit normals): (min b_i, a_i of the minimiser)."""
    i = int(np.argmin(polytope.b))
    return max(float(polytope.b[i]), 0.0), polytope.A[i].copy()


def fibonacci_sphere(n: int) -> np.ndarray:
    """(n, 3) approximately uniform unit vectors (golden-angle spiral)."""
    if n < 4:
        raise SufError(f"fibonacci needs at least 4 directions, got {n}")
    k = np.arange(n) + 0.5
    z = 1.0 - 2.0 * k / n
    r = np.sqrt(1.0 - z * z)
    phi = np.pi * (3.0 - np.sqrt(5.0)) * k
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def suf_exact(problem: RejectableForceProblem, *, tol: float = 1e-3, solver: str = "clp", max_lps: int = 5000):
    """The exact RFP by the support-function method; `tol` [N] certifies each facet."""
    start = time.perf_counter()
    lp = RfpLinearProgram(problem, solver)
    points = [f * d for d in np.vstack([np.eye(3), -np.eye(3)]) for f in [lp.ray(d)]]
    num_lps = 6
    certified: set[tuple] = set()
    while True:
        polytope = Polytope.from_points(np.array(points))
        added = False
        for a, b in zip(polytope.A, polytope.b, strict=True):
            key = tuple(np.round(np.append(a, b), 9))
            if key in certified:
                continue
            value, F = lp.support(a)
            num_lps += 1
            if value > b + tol:
                points.append(F)
                added = True
            else:
                certified.add(key)
            if num_lps > max_lps:
                raise SufError(f"exact projection did not converge within {max_lps} LPs (tol {tol} N)")
        if not added:
            break
    value, direction = _suf_of(polytope)
    return SufResult("exact", value, direction, polytope, time.perf_counter() - start, True, num_lps)


def suf_single(problem: RejectableForceProblem, direction=(0.0, 0.0, -1.0), *, solver: str = "clp"):
    """The largest rejectable force along `direction` (default straight down) [N]; an upper bound."""
    start = time.perf_counter()
    d = np.asarray(direction, dtype=float)
    if d.shape != (3,) or not np.linalg.norm(d) > 0:
        raise SufError(f"direction: expected a non-zero 3-vector, got {direction!r}")
    d = d / np.linalg.norm(d)
    value = RfpLinearProgram(problem, solver).ray(d)
    return SufResult("single", value, d, None, time.perf_counter() - start, False, 1)


def suf_fibonacci(problem: RejectableForceProblem, num_directions: int = 1024, *, solver: str = "clp"):
    """Eq. 9 on the inner polytope of the ray points along `num_directions` Fibonacci directions."""
    start = time.perf_counter()
    lp = RfpLinearProgram(problem, solver)
    directions = fibonacci_sphere(num_directions)
    points = np.array([lp.ray(d) * d for d in directions])
    polytope = Polytope.from_points(points)
    value, direction = _suf_of(polytope)
    return SufResult("fibonacci", value, direction, polytope, time.perf_counter() - start, True, num_directions)


@dataclasses.dataclass(frozen=True)
class _ControlLawData:
    """Constraint rows on (F, dQ): g_i . F + h_i . dQ <= e_i, from y = W^+ (b - J_e^T F) + N dQ."""

    g: np.ndarray  # (m, 3)
    h: np.ndarray  # (m, n)
    e: np.ndarray  # (m,)


def _control_law_data(problem: RejectableForceProblem) -> _ControlLawData:
    W = problem.W
    U, sigma, Vt = np.linalg.svd(W)
    rank = int(np.sum(sigma > 1e-9 * sigma[0]))
    if rank < W.shape[0]:
        raise SufError(
            f"singular configuration: W = [B J_c^T] has rank {rank} < {W.shape[0]}, so the contacts and "
            "motors cannot produce every generalised force (add contacts, or move away from the singularity)"
        )
    W_pinv = Vt[:rank].T @ np.diag(1.0 / sigma[:rank]) @ U[:, :rank].T
    N = Vt[rank:].T
    G = problem.G_y
    return _ControlLawData(g=-(G @ W_pinv @ problem.Je_T), h=G @ N, e=problem.g_y - G @ W_pinv @ problem.b)


def _direction_of_tightest(data: _ControlLawData, rho: float, dQ0: np.ndarray, U: np.ndarray, P=None) -> np.ndarray:
    """The force direction of the constraint row with the least slack at the solution."""
    best, direction = np.inf, np.array([0.0, 0.0, -1.0])
    for g, h, e in zip(data.g, data.h, data.e, strict=True):
        c = rho * g + U.T @ h
        norm = np.linalg.norm(c)
        slack = e - h @ dQ0 - norm
        if norm > 1e-12 and slack < best:
            best, direction = slack, c / norm
    return direction


class _AffineProgram:
    """The affine-law SOCP for one problem structure (m rows, n null-space dimensions), built once;
    each solve only rewrites the cones' coefficients (building it costs as much as solving it)."""

    def __init__(self, m: int, n: int):
        self.m, self.n = m, n
        prog = MathematicalProgram()
        self.rho = prog.NewContinuousVariables(1, "rho")
        self.dQ0 = prog.NewContinuousVariables(n, "dQ0")
        self.U = prog.NewContinuousVariables(n, 3, "U")  # U = rho V
        self.variables = np.concatenate([self.rho, self.dQ0, self.U.ravel()])  # U[j, k] at 1 + n + 3 j + k
        zero = np.zeros((4, len(self.variables)))
        self.cones = [prog.AddLorentzConeConstraint(zero, np.zeros(4), self.variables) for _ in range(m)]
        prog.AddBoundingBoxConstraint(0.0, RAY_CAP, self.rho)
        prog.AddLinearCost([-1.0], self.rho)
        self.prog = prog

    def set_data(self, data: "_ControlLawData") -> None:
        n = self.n
        for i, cone in enumerate(self.cones):
            A = np.zeros((4, len(self.variables)))
            A[0, 1 : 1 + n] = -data.h[i]
            A[1:, 0] = data.g[i]
            for j in range(n):
                A[1:, 1 + n + 3 * j : 4 + n + 3 * j] = data.h[i, j] * np.eye(3)
            cone.evaluator().UpdateCoefficients(A, np.array([data.e[i], 0.0, 0.0, 0.0]))


_AFFINE_PROGRAMS: dict[tuple[int, int], _AffineProgram] = {}


def suf_affine(problem: RejectableForceProblem, *, solver: str = "clarabel") -> SufResult:
    """max rho s.t. |rho g_i + U^T h_i| <= e_i - h_i . dQ0 for every row i (an SOCP).

    The program of each problem structure is built once (module cache) and its coefficients
    replaced per call.
    """
    start = time.perf_counter()
    data = _control_law_data(problem)
    key = data.h.shape
    if key not in _AFFINE_PROGRAMS:
        _AFFINE_PROGRAMS[key] = _AffineProgram(*key)
    program = _AFFINE_PROGRAMS[key]
    program.set_data(data)
    result = make_solver(solver).Solve(program.prog)
    if not result.is_success():
        raise SufError(f"affine SOCP: {result.get_solution_result()} (is the nominal motion feasible?)")
    r = result.GetSolution(program.rho)[0]
    q0, Uv = result.GetSolution(program.dQ0), result.GetSolution(program.U)
    direction = _direction_of_tightest(data, r, q0, Uv)
    return SufResult("affine", max(float(r), 0.0), direction, None, time.perf_counter() - start, True, 1)


def suf_quadratic(problem: RejectableForceProblem, *, solver: str = "clarabel") -> SufResult:
    """max rho with a quadratic law; row i's robust constraint over |u| <= 1 (F = rho u) by the S-lemma:

        [[e_i - h_i . dQ0 - xi_i, -c_i^T / 2], [-c_i / 2, xi_i I - sum_j h_ij P_j]] >= 0,  xi_i >= 0,

    with c_i = rho g_i + U^T h_i, U = rho V and P_j = rho^2 W_j (an SDP of 4x4 blocks, written as
    numeric linear matrix inequalities F_0 + sum_k x_k F_k >= 0).
    """
    start = time.perf_counter()
    data = _control_law_data(problem)
    # Rows the control law cannot touch (h_i = 0: e.g. the end-effector leg's own torques) need no
    # matrix inequality: rho |g_i| <= e_i is a bound on rho.
    free = np.linalg.norm(data.h, axis=1) < 1e-12
    rho_max = RAY_CAP
    for g, e in zip(data.g[free], data.e[free], strict=True):
        if e < 0.0:
            raise SufError("quadratic SDP: the nominal motion is not feasible (a torque or friction row is violated)")
        norm = np.linalg.norm(g)
        rho_max = min(rho_max, e / norm) if norm > 1e-12 else rho_max
    full, data = data, _ControlLawData(data.g[~free], data.h[~free], data.e[~free])
    m, n = data.h.shape
    prog = MathematicalProgram()
    rho = prog.NewContinuousVariables(1, "rho")
    dQ0 = prog.NewContinuousVariables(n, "dQ0")
    U = prog.NewContinuousVariables(n, 3, "U")
    P = prog.NewContinuousVariables(n, 6, "P")  # upper triangles of the symmetric P_j
    xi = prog.NewContinuousVariables(m, "xi")
    prog.AddBoundingBoxConstraint(0.0, np.inf, xi)
    prog.AddBoundingBoxConstraint(0.0, rho_max, rho)
    shared = np.concatenate([rho, dQ0, U.ravel(), P.ravel()])
    upper = [(a, b) for a in range(3) for b in range(a, 3)]
    # The matrices multiplying the shared variables, less the row's coefficients.
    for i in range(m):
        g, h, e = data.g[i], data.h[i], data.e[i]
        F = [np.zeros((4, 4)) for _ in range(len(shared) + 2)]
        F[0][0, 0] = e
        F[1][0, 1:] = F[1][1:, 0] = -0.5 * g  # rho
        for j in range(n):
            F[2 + j][0, 0] = -h[j]  # dQ0_j
            for k in range(3):
                M = F[2 + n + 3 * j + k]  # U_jk enters c_k with h_j
                M[0, 1 + k] = M[1 + k, 0] = -0.5 * h[j]
            for t, (a, b) in enumerate(upper):
                M = F[2 + 4 * n + 6 * j + t]  # P_j[a, b] enters -sum_j h_j P_j
                M[1 + a, 1 + b] = M[1 + b, 1 + a] = -h[j]
        F[-1][0, 0] = -1.0  # xi_i
        F[-1][1:, 1:] = np.eye(3)
        prog.AddLinearMatrixInequalityConstraint(F, np.append(shared, xi[i]))
    prog.AddLinearCost([-1.0], rho)
    result = make_solver(solver).Solve(prog)
    if not result.is_success():
        raise SufError(f"quadratic SDP: {result.get_solution_result()} (is the nominal motion feasible?)")
    r, q0, Uv = result.GetSolution(rho)[0], result.GetSolution(dQ0), result.GetSolution(U)
    direction = _direction_of_tightest(full, r, q0, Uv)
    return SufResult("quadratic", max(float(r), 0.0), direction, None, time.perf_counter() - start, True, 1)


def smallest_unrejectable_force(problem: RejectableForceProblem, method: str = "exact", **options) -> SufResult:
    """The SUF of `problem` by `method` (one of METHODS); `options` go to that method's function."""
    functions = {
        "exact": suf_exact,
        "single": suf_single,
        "fibonacci": suf_fibonacci,
        "affine": suf_affine,
        "quadratic": suf_quadratic,
    }
    if method not in functions:
        raise SufError(f"method: must be one of {METHODS}, got {method!r}")
    return functions[method](problem, **options)
