"""The oracle of the compiled hierarchical QP (pedi_drake.control.compiled_hqp): the same algorithm
in numpy on Python lists of tasks, as readable as the maths in compiled_hqp's docstring.

Levels of `EqualityTask`s and `InequalityTask`s, solved in strict priority (`solve_hqp`) or as one
weighted QP (`solve_weighted`), each level QP by DAQP through its Python module; `row_table`
turns levels into the compiled solver's RowTable. tests/test_hqp.py holds this against brute
force, tests/test_compiled_hqp.py the compiled solver against this.
"""

import dataclasses
import functools
import math
import time

import daqp
import numpy as np
from scipy.linalg import lapack

from pedi_drake.control.compiled_hqp import HqpSettings, RowTable
from pedi_drake.exceptions import QpInfeasible
from pedi_drake.numerics import daqp_kernel

# DAQP treats bounds beyond this magnitude as infinite.
_INFINITY = 1e30
# DAQP exit flags: 1 optimal, 2 optimal with soft constraints relaxed.
_DAQP_OK = (1, 2)


@dataclasses.dataclass
class EqualityTask:
    """Rows A x = b of one task, minimised as weight * ||A x - b||^2 at its level."""

    name: str
    A: np.ndarray  # (m, n)
    b: np.ndarray  # (m,)
    weight: float = 1.0  # relative weight inside its level [-]


@dataclasses.dataclass
class InequalityTask:
    """Rows G x <= h of one task. Hard rows are constraints; soft rows minimise their violation."""

    name: str
    G: np.ndarray  # (m, n)
    h: np.ndarray  # (m,)
    hard: bool = True
    weight: float = 1.0  # weight of the squared violation when soft [-]


@dataclasses.dataclass
class Level:
    """One priority level: tasks solved together (weighted) within the optimum of the levels above."""

    name: str
    equalities: list[EqualityTask] = dataclasses.field(default_factory=list)
    inequalities: list[InequalityTask] = dataclasses.field(default_factory=list)


@dataclasses.dataclass
class HqpSolution:
    """Result of a hierarchical solve."""

    x: np.ndarray  # (n,) the solution
    equality_residuals: list[float]  # per level: sqrt(sum_i weight_i ||A_i x - b_i||^2)
    solve_time: float  # wall time of the solve [s]
    # Per level, blocks (G, h) of its inequality rows (hard and soft), kept for `inequality_violations`.
    level_inequalities: list[list[tuple[np.ndarray, np.ndarray]]] = dataclasses.field(default_factory=list, repr=False)

    @functools.cached_property
    def inequality_violations(self) -> list[float]:
        """Per level: the largest G x - h over its rows (<= 0 when met; -inf for a level without any).

        Computed on first use: the controller does not read it, and at 500 Hz it would cost more
        than a level's QP set-up."""
        return [
            max((float(np.max(G @ self.x - h)) for G, h in blocks if len(h)), default=-np.inf)
            for blocks in self.level_inequalities
        ]


def _stack_equalities(tasks: list[EqualityTask], n: int) -> tuple[np.ndarray, np.ndarray]:
    if not tasks:
        return np.zeros((0, n)), np.zeros(0)
    if all(t.weight == 1.0 for t in tasks):
        if len(tasks) == 1:
            return tasks[0].A, tasks[0].b
        return np.concatenate([t.A for t in tasks]), np.concatenate([t.b for t in tasks])
    # Filled in place: vstack of scaled copies costs twice as much at these sizes.
    m = sum(len(t.b) for t in tasks)
    A, b = np.empty((m, n)), np.empty(m)
    row = 0
    for t in tasks:
        scale = math.sqrt(t.weight)
        rows = slice(row, row + len(t.b))
        np.multiply(t.A, scale, out=A[rows])
        np.multiply(t.b, scale, out=b[rows])
        row = rows.stop
    return A, b


def _stack_inequalities(
    tasks: list[InequalityTask], n: int, with_weights: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(G, h, sqrt(weight) per row, or None without `with_weights`) of a list of inequality tasks."""
    if not tasks:
        return np.zeros((0, n)), _EMPTY, _EMPTY
    if len(tasks) == 1:
        t = tasks[0]
        return t.G, t.h, np.full(len(t.h), math.sqrt(t.weight)) if with_weights else None
    G = np.vstack([t.G for t in tasks])
    h = np.concatenate([t.h for t in tasks])
    if not with_weights:
        return G, h, None
    return G, h, np.concatenate([np.full(len(t.h), math.sqrt(t.weight)) for t in tasks])


_EMPTY = np.zeros(0)
_EMPTY.flags.writeable = False


def _meets(G: np.ndarray, h: np.ndarray, x: np.ndarray, tolerance: float) -> bool:
    """Whether G x <= h + tolerance on every row."""
    return len(h) == 0 or bool((G @ x - h).max() <= tolerance)


def _solve_level_qp(
    H: np.ndarray,
    f: np.ndarray,
    C: np.ndarray,
    upper: np.ndarray,
    level: str,
    eps_prox: float,
    eta_prox: float = daqp_kernel.QP_FIXED_POINT,
) -> np.ndarray:
    """min 0.5 y'Hy + f'y s.t. C y <= upper, by DAQP; raises QpInfeasible on failure.
    eta_prox: when DAQP's proximal iterations stop (daqp_kernel.QP_FIXED_POINT for a strict level,
    AUTOMATIC_FIXED_POINT for the weighted QP)."""
    if C.shape[0] == 0:
        return np.linalg.lstsq(H, -f, rcond=None)[0]
    lower = np.full(len(upper), -_INFINITY)
    # A positive eps_prox makes DAQP run proximal-point iterations, which solve the exact
    # (semi-definite) problem instead of a regularised one: strict priorities stay exact.
    y, _, exitflag, _ = daqp.solve(
        np.ascontiguousarray(H),
        np.ascontiguousarray(f),
        np.ascontiguousarray(C),
        np.ascontiguousarray(upper),
        lower,
        eps_prox=eps_prox,
        eta_prox=eta_prox,
    )
    if exitflag not in _DAQP_OK or not np.isfinite(y).all():
        raise QpInfeasible(f"HQP level {level!r}: DAQP exit flag {exitflag}")
    return np.asarray(y)


def _row_space_split(A: np.ndarray, tolerance: float) -> tuple[np.ndarray, np.ndarray, int, np.ndarray | None]:
    """(row-space basis Y (n, r), null-space basis N (n, n - r), rank r, R) of A (m, n).

    A QR of A^T gives both when A has full row rank (the usual case, and twice as fast as an
    SVD here); then A = R^T Y^T with R (r, r) upper triangular. Otherwise an SVD decides the rank
    and R is None.
    """
    m, n = A.shape
    if 0 < m <= n:
        # LAPACK directly (Householder QR, then the complete Q): a third of numpy.linalg.qr's
        # time at this size, where the Python wrapper dominates.
        qr, tau, _, info = lapack.dgeqrf(A.T)
        if info == 0:
            # Python floats: numpy's reductions cost microseconds each on m <= 30 numbers.
            diagonal = [abs(d) for d in qr.diagonal().tolist()]
            if min(diagonal) > tolerance * max(1.0, max(diagonal)):
                square = np.zeros((n, n), order="F")
                square[:, :m] = qr
                Q, _, info = lapack.dorgqr(square, tau)
                if info == 0:
                    # Below its diagonal qr holds the Householder vectors: masked, not np.triu
                    # (which costs four times as much at this size).
                    return Q[:, :m], Q[:, m:], m, qr[:m] * _upper_triangle_mask(m)
    elif m == 0:
        return np.zeros((n, 0)), np.eye(n), 0, np.zeros((0, 0))
    _, sigma, Vt = np.linalg.svd(A, full_matrices=True)
    rank = int(np.sum(sigma > tolerance * max(1.0, sigma[0] if len(sigma) else 0.0)))
    return Vt[:rank].T, Vt[rank:].T, rank, None


@functools.lru_cache(maxsize=64)
def _upper_triangle_mask(m: int) -> np.ndarray:
    """(m, m) ones on and above the diagonal, zeros below (read-only)."""
    mask = np.triu(np.ones((m, m)))
    mask.flags.writeable = False
    return mask


def _least_squares_step(A: np.ndarray, r: np.ndarray, tolerance: float):
    """(argmin ||A z - r|| of least norm, or None when A is numerically rank-deficient and tall;
    the `_row_space_split` of A when it was computed, else None)."""
    m, n = A.shape
    if m <= n:
        split = _row_space_split(A, tolerance)
        return _min_norm_least_squares(A, r, split), split
    # Tall: the normal equations by Cholesky, accepted only when well conditioned (the
    # regularisation level, whose posture, force and torque rows cover every variable).
    factor, z, info = lapack.dposv(A.T @ A, A.T @ r)
    if info != 0:
        return None, None
    diagonal = [abs(d) for d in factor.diagonal().tolist()]
    if min(diagonal) <= math.sqrt(tolerance) * max(diagonal):
        return None, None
    return z, None


def _min_norm_least_squares(A: np.ndarray, r: np.ndarray, split) -> np.ndarray:
    """argmin ||z|| among the minimisers of ||A z - r||, using a `_row_space_split` of A."""
    Y, _, rank, R = split
    if rank == 0:
        # Every row lies (within the rank tolerance) in the span of the levels above: any z gives
        # the same residual, and the least norm is z = 0 (lstsq would invert the rows' rounding
        # noise).
        return np.zeros(A.shape[1])
    if R is not None:
        # R^T w = r by forward substitution (R is upper triangular).
        w, info = lapack.dtrtrs(R, r, lower=0, trans=1)
        if info == 0:
            return Y @ w
        return Y @ np.linalg.solve(R.T, r)
    return np.linalg.lstsq(A, r, rcond=None)[0]


def solve_hqp(levels: list[Level], num_variables: int, settings: HqpSettings | None = None) -> HqpSolution:
    """Solves `levels` in strict priority order (level 0 first).

    Raises QpInfeasible when the hard inequalities of some level cannot be met together with
    those above it.
    """
    settings = settings or HqpSettings()
    start = time.perf_counter()
    n = num_variables
    x = np.zeros(n)
    Z = np.eye(n)
    # Inequalities carried down: hard ones and soft ones fixed at their optimal violation.
    G_all = np.zeros((0, n))
    h_all = np.zeros(0)
    stacked: list[tuple[np.ndarray, ...]] = []  # per level: A, b, hard G, h, soft G, h
    num_verified = 0  # leading rows of G_all that x is known to meet (a level solved with them)
    for index, level in enumerate(levels):
        A, b = _stack_equalities(level.equalities, n)
        Gh, hh, _ = _stack_inequalities([t for t in level.inequalities if t.hard], n, with_weights=False)
        Gs, hs, ws = _stack_inequalities([t for t in level.inequalities if not t.hard], n)
        stacked.append((A, b, Gh, hh, Gs, hs))
        if len(hh):
            G_all = Gh if not len(h_all) else np.vstack([G_all, Gh])
            h_all = hh if not len(h_all) else np.concatenate([h_all, hh])
        nz = Z.shape[1]
        ms = len(hs)
        if nz == 0 and ms == 0:
            continue
        if len(b) == 0 and ms == 0 and index + 1 < len(levels):
            # Only hard constraints: nothing to optimise here. The levels below solve within them
            # (and report infeasibility); a feasibility QP here would only move x inside them.
            continue
        Az = A @ Z
        rz = b - A @ x
        svd = None
        if len(h_all) == 0 and ms == 0:
            # No inequality anywhere yet: the exact minimum-norm least-squares step, from the same
            # SVD that gives the null space below.
            z = np.zeros(nz)
            if Az.shape[0]:
                svd = _row_space_split(Az, settings.rank_tolerance)
                z = _min_norm_least_squares(Az, rz, svd)
        else:
            mh = len(h_all)
            GZ = G_all @ Z
            upper = np.empty(mh + ms)
            upper[:mh] = h_all - G_all @ x
            # The current x solved the levels above, so it meets the rows they verified up to the
            # solver's tolerance; clipping at zero keeps z = 0 feasible instead of failing on a
            # 1e-7 residue.
            upper[:num_verified] = np.maximum(upper[:num_verified], 0.0)
            # The unconstrained step (least squares of the equalities; none: stay) is an optimum
            # of this level's QP whenever it meets every hard row and every soft row with zero
            # violation: the QP cannot do better. Then the solver is not needed (most controller
            # ticks, at every QP level).
            z, svd = (
                _least_squares_step(Az, rz, settings.rank_tolerance) if Az.shape[0] and nz else (np.zeros(nz), None)
            )
            if z is not None and not (
                _meets(GZ, upper[:mh], z, 0.0) and (ms == 0 or _meets(Gs @ Z, hs - Gs @ x, z, 0.0))
            ):
                z = None
        if z is None:
            # Variables y = [z; v], with the soft violations v of this level.
            H = np.zeros((nz + ms, nz + ms))
            H[:nz, :nz] = Az.T @ Az
            f = np.zeros(nz + ms)
            f[:nz] = -Az.T @ rz
            C = np.zeros((mh + ms, nz + ms))
            C[:mh, :nz] = GZ
            if ms:
                soft = np.arange(ms)
                H[nz + soft, nz + soft] = ws * ws
                C[mh:, :nz] = Gs @ Z
                C[mh + soft, nz + soft] = -1.0
                upper[mh:] = hs - Gs @ x
            if settings.regularization:
                H[np.diag_indices(nz + ms)] += settings.regularization
            z = _solve_level_qp(H, f, C, upper, level.name, settings.proximal_weight)[:nz]
        x = x + Z @ z
        num_verified = len(h_all)
        if ms:
            # The level's optimal violation becomes a bound for every level below.
            violation = np.maximum(Gs @ x - hs, 0.0)
            G_all = np.vstack([G_all, Gs])
            h_all = np.concatenate([h_all, hs + violation + settings.fix_tolerance])
        if Az.shape[0] and nz and index + 1 < len(levels):
            _, null_space, _, _ = svd or _row_space_split(Az, settings.rank_tolerance)
            Z = Z @ null_space
    solve_time = time.perf_counter() - start
    residuals = []
    for A, b, *_ in stacked:
        r = A @ x - b
        residuals.append(math.sqrt(float(r @ r)))
    inequalities = [[(Gh, hh), (Gs, hs)] for _, _, Gh, hh, Gs, hs in stacked]
    return HqpSolution(x, residuals, solve_time, inequalities)


def solve_weighted(
    levels: list[Level], num_variables: int, level_weights: list[float], settings: HqpSettings | None = None
) -> HqpSolution:
    """One QP: level k's equalities and soft inequalities weighted by level_weights[k]; hard rows kept hard."""
    settings = settings or HqpSettings()
    start = time.perf_counter()
    n = num_variables
    if len(level_weights) != len(levels):
        raise ValueError(f"{len(levels)} levels need as many weights, got {len(level_weights)}")
    H = settings.regularization * np.eye(n)
    f = np.zeros(n)
    hard_G, hard_h, soft_G, soft_h, soft_w = [], [], [], [], []
    for level, weight in zip(levels, level_weights, strict=True):
        A, b = _stack_equalities(level.equalities, n)
        H[:n, :n] += weight * A.T @ A
        f[:n] -= weight * A.T @ b
        for task in level.inequalities:
            if task.hard:
                hard_G.append(task.G)
                hard_h.append(task.h)
            else:
                soft_G.append(task.G)
                soft_h.append(task.h)
                soft_w.append(np.full(len(task.h), weight * task.weight))
    Gh = np.vstack(hard_G) if hard_G else np.zeros((0, n))
    hh = np.concatenate(hard_h) if hard_h else np.zeros(0)
    Gs = np.vstack(soft_G) if soft_G else np.zeros((0, n))
    hs = np.concatenate(soft_h) if soft_h else np.zeros(0)
    ms = len(hs)
    Hfull = np.zeros((n + ms, n + ms))
    Hfull[:n, :n] = H
    if ms:
        Hfull[n:, n:] = np.diag(np.concatenate(soft_w)) + settings.regularization * np.eye(ms)
    C = np.vstack([np.hstack([Gh, np.zeros((len(hh), ms))]), np.hstack([Gs, -np.eye(ms)])])
    upper = np.concatenate([hh, hs])
    y = _solve_level_qp(
        Hfull,
        np.concatenate([f, np.zeros(ms)]),
        C,
        upper,
        "weighted",
        settings.proximal_weight,
        daqp_kernel.AUTOMATIC_FIXED_POINT,
    )
    x = y[:n]
    residuals, inequalities = [], []
    for level in levels:
        A, b = _stack_equalities(level.equalities, n)
        residuals.append(float(np.linalg.norm(A @ x - b)) if len(b) else 0.0)
        inequalities.append([(t.G, t.h) for t in level.inequalities])
    return HqpSolution(x, residuals, time.perf_counter() - start, inequalities)


def row_table(levels: list[Level], n: int) -> RowTable:
    """The compiled HQP's RowTable of `levels`."""
    eq_A, eq_b, hard_G, hard_h, soft_G, soft_h, soft_w = [], [], [], [], [], [], []
    eq_start, hard_start, soft_start = [0], [0], [0]
    for level in levels:
        for t in level.equalities:
            scale = math.sqrt(t.weight)
            eq_A.append(np.asarray(t.A, float) * scale)
            eq_b.append(np.asarray(t.b, float) * scale)
        for t in level.inequalities:
            if t.hard:
                hard_G.append(np.asarray(t.G, float))
                hard_h.append(np.asarray(t.h, float))
        for t in level.inequalities:
            if not t.hard:
                soft_G.append(np.asarray(t.G, float))
                soft_h.append(np.asarray(t.h, float))
                soft_w.append(np.full(len(t.h), float(t.weight)))
        eq_start.append(eq_start[-1] + sum(len(t.b) for t in level.equalities))
        hard_start.append(hard_start[-1] + sum(len(t.h) for t in level.inequalities if t.hard))
        soft_start.append(soft_start[-1] + sum(len(t.h) for t in level.inequalities if not t.hard))

    def rows(blocks, width):
        return np.ascontiguousarray(np.vstack(blocks)) if blocks else np.zeros((0, width))

    def values(blocks):
        return np.concatenate(blocks) if blocks else np.zeros(0)

    index = np.int64
    return RowTable(
        n,
        rows(eq_A, n),
        values(eq_b),
        np.array(eq_start, index),
        rows(hard_G, n),
        values(hard_h),
        np.array(hard_start, index),
        rows(soft_G, n),
        values(soft_h),
        values(soft_w),
        np.array(soft_start, index),
    )
