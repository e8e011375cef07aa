"""DAQP called from compiled code: the solver of every QP and LP the controllers and the live SUF solve.

    minimise   0.5 y'H y + f'y      over y (n,)
    subject to lower <= C y <= upper    (m rows; a bound at or beyond +-INFINITE_BOUND is none)

DAQP (Arnström, Bemporad and Axehill, "A dual active-set solver for embedded quadratic
programming using recursive LDL^T updates", IEEE TAC 2022) is a dense dual active-set solver for
exactly the small dense problems of a whole-body controller: a few tens of variables, a hundred
rows, a handful active. Its C library is compiled into the `daqp` wheel's extension module, whose
symbols the module loader exports; `solve_qp` below calls its `daqp_quadprog` by symbol name
(registered with LLVM when this module is imported), so a numba kernel solves a QP without
returning to Python and without holding the interpreter's lock, and numba's disk cache keeps the
kernels (the call is resolved by name when a cached kernel is loaded, not baked in as an address).

Semi-definite Hessians (a level of the hierarchical QP: H = A'A of its least squares, often
singular; an LP: H = 0) are solved exactly, not regularised: a positive `eps_prox` [units of H]
makes DAQP run proximal-point outer iterations, which converge to a solution of the original
problem (its KKT conditions) rather than of a Tikhonov-regularised one.

Warm start: rows whose `sense` has the ACTIVE bit (and LOWER for a lower bound) start in the
working set; the solution's multipliers say which rows ended active (`active_rows`).

The three structs DAQP takes (DAQPProblem, DAQPSettings, DAQPResult) are laid out here in
int64/float64 arrays as the DAQP 0.11 series declares them (`pyproject.toml` pins that series).
Importing this module checks the layout against the library's own defaults
(`daqp_default_settings`) and refuses to load with a clear error if they do not match, rather than
pass a solver wrongly placed fields.
"""

import ctypes

import numpy as np

from pedi_drake.exceptions import PediError
from pedi_drake.runtime.jit import ENABLED, kernel

# DAQP's exit flags (constants.h). SOFT_OPTIMAL: optimal with soft constraints relaxed.
EXIT_OPTIMAL, EXIT_SOFT_OPTIMAL = 1, 2
EXIT_INFEASIBLE, EXIT_CYCLE, EXIT_UNBOUNDED, EXIT_ITERLIMIT = -1, -2, -3, -4
# Not DAQP's: an argument that is not a C-contiguous array of the solver's element type.
EXIT_BAD_ARRAY = -100
EXIT_NAMES = {
    EXIT_OPTIMAL: "optimal",
    EXIT_SOFT_OPTIMAL: "optimal with soft constraints relaxed",
    EXIT_INFEASIBLE: "infeasible",
    EXIT_CYCLE: "cycling",
    EXIT_UNBOUNDED: "unbounded",
    EXIT_ITERLIMIT: "iteration limit",
    EXIT_BAD_ARRAY: "an argument not C-contiguous",
}
# A bound at or beyond this magnitude is no bound (DAQP_INF).
INFINITE_BOUND = 1e30
# DAQP's eta_prox for a strict level's QP (semi-definite, eps_prox > 0): its proximal iterations
# stop when one moves no entry of y by more than eta_prox / eps_prox. The automatic value allows
# 0.1 at the controllers' eps_prox of 1e-5, enough for a level's optimum to move by solver tolerance
# from one tick to the next, which the integrated joint reference accumulates; at 1e-10 a level's
# optimal value is found to 1e-11 relative, at the same cost (both measured on the levels of
# hit_target_front).
QP_FIXED_POINT = 1e-10
# DAQP's automatic eta_prox: for LPs (which end on a vertex, reached exactly) and for the weighted
# mode's single QP, whose Hessian is definite but spans twelve decades (the weights), where a
# fixed-point test this tight would not be met within the iteration limit.
AUTOMATIC_FIXED_POINT = -1.0
# Bits of a row's `sense` (constants.h): in the starting working set, at its lower bound.
SENSE_ACTIVE, SENSE_LOWER = 1, 2

# DAQPSettings: five float64 tolerances, two int32 (cycle_tol, iter_limit), then float64 fields.
_SETTINGS_FLOATS = 16
_S_PRIMAL_TOL, _S_DUAL_TOL, _S_ZERO_TOL = 0, 1, 2
_S_ITERATION_INTS = 10  # int32 index of cycle_tol (byte 40); iter_limit follows
_S_FVAL_BOUND, _S_EPS_PROX, _S_ETA_PROX = 6, 7, 8
# DAQPProblem: n, m, ms (int32 at 0, 4, 8), pointers H, f, A, bupper, blower, sense,
# break_points (int64 words 2..8), nh and problem_type (int32 at 72, 76).
_PROBLEM_WORDS = 10
# DAQPResult: pointers x, lam (words 0, 1), fval, soft_slack (float64 words 2, 3), exitflag, iter,
# nodes (int32 at 32, 36, 40), solve_time, setup_time.
_RESULT_WORDS = 8
_R_EXITFLAG, _R_ITERATIONS = 8, 9  # int32 indices


def _library() -> ctypes.CDLL:
    """The loaded DAQP extension module, as a C library."""
    try:
        import daqp
    except ImportError as error:  # pragma: no cover - daqp is a dependency
        raise PediError("pedi_drake needs the 'daqp' package (pip install daqp)") from error
    return ctypes.CDLL(daqp.__file__)


def _check_layout(library: ctypes.CDLL) -> None:
    """Refuses a DAQP whose settings struct does not hold its documented defaults where this module
    reads and writes them (another series of the library)."""
    settings = np.zeros(_SETTINGS_FLOATS)
    library.daqp_default_settings(ctypes.c_void_p(settings.ctypes.data))
    integers = settings.view(np.int32)
    found = (
        settings[_S_PRIMAL_TOL],
        settings[_S_DUAL_TOL],
        integers[_S_ITERATION_INTS],
        integers[_S_ITERATION_INTS + 1],
        settings[_S_FVAL_BOUND],
    )
    if found != (1e-6, 1e-12, 10, 10000, 1e30):
        from importlib.metadata import version

        raise PediError(
            f"daqp {version('daqp')}: its settings struct is not laid out as pedi_drake.numerics.daqp_kernel "
            f"reads it (defaults read {found}); install the series pyproject.toml pins (daqp>=0.11,<0.12)"
        )


def _register_symbols() -> None:
    """Makes DAQP's entry points callable by name from compiled kernels."""
    import llvmlite.binding

    library = _library()
    _check_layout(library)
    for name in ("daqp_quadprog", "daqp_default_settings"):
        llvmlite.binding.add_symbol(name, ctypes.cast(getattr(library, name), ctypes.c_void_p).value)


if ENABLED:
    from numba.core import types

    _register_symbols()
    # Pointers pass as 64-bit integers (the same registers on x86-64 and aarch64).
    _daqp_quadprog = types.ExternalFunction("daqp_quadprog", types.void(types.intp, types.intp, types.intp))
    _daqp_default_settings = types.ExternalFunction("daqp_default_settings", types.void(types.intp))
else:  # interpreted kernels call the same C functions through ctypes
    _LIBRARY = _library()
    _check_layout(_LIBRARY)

    def _daqp_quadprog(result, problem, settings):
        _LIBRARY.daqp_quadprog(ctypes.c_void_p(result), ctypes.c_void_p(problem), ctypes.c_void_p(settings))

    def _daqp_default_settings(settings):
        _LIBRARY.daqp_default_settings(ctypes.c_void_p(settings))


@kernel
def solve_qp(H, f, C, upper, lower, sense, eps_prox, eta_prox, primal_tolerance, y, multipliers) -> int:
    """min 0.5 y'Hy + f'y s.t. lower <= C y <= upper by DAQP, into y (n,) and the rows' multipliers
    (m,; positive at an upper bound, negative at a lower one); returns DAQP's exit flag.

    H (n, n), C (m, n): C-contiguous float64; sense (m,) int32: 0, or SENSE_ACTIVE (| SENSE_LOWER)
    to start with the row in the working set. eps_prox > 0 [units of H]: proximal iterations
    (needed when H is singular); <= 0: DAQP's default (H positive definite). eta_prox: when the
    proximal iterations stop (QP_FIXED_POINT or AUTOMATIC_FIXED_POINT).
    primal_tolerance: the constraint violation accepted [units of the rows]; <= 0: DAQP's default.
    y and the multipliers are meaningful only with EXIT_OPTIMAL or EXIT_SOFT_OPTIMAL."""
    # DAQP reads raw memory: a strided view would be read as if it were packed.
    contiguous = (
        H.flags.c_contiguous
        and C.flags.c_contiguous
        and f.flags.c_contiguous
        and upper.flags.c_contiguous
        and lower.flags.c_contiguous
        and y.flags.c_contiguous
        and multipliers.flags.c_contiguous
        and sense.flags.c_contiguous
    )
    if not contiguous or sense.itemsize != 4:
        return EXIT_BAD_ARRAY
    settings = np.zeros(_SETTINGS_FLOATS)
    _daqp_default_settings(settings.ctypes.data)
    settings[_S_EPS_PROX] = eps_prox
    settings[_S_ETA_PROX] = eta_prox
    if primal_tolerance > 0.0:
        settings[_S_PRIMAL_TOL] = primal_tolerance
    problem = np.zeros(_PROBLEM_WORDS, dtype=np.int64)
    sizes = problem.view(np.int32)
    sizes[0] = H.shape[0]
    sizes[1] = C.shape[0]
    problem[2] = H.ctypes.data
    problem[3] = f.ctypes.data
    problem[4] = C.ctypes.data
    problem[5] = upper.ctypes.data
    problem[6] = lower.ctypes.data
    problem[7] = sense.ctypes.data
    result = np.zeros(_RESULT_WORDS, dtype=np.int64)
    result[0] = y.ctypes.data
    result[1] = multipliers.ctypes.data
    _daqp_quadprog(result.ctypes.data, problem.ctypes.data, settings.ctypes.data)
    return result.view(np.int32)[_R_EXITFLAG]


@kernel
def solved(exit_flag: int) -> bool:
    """Whether DAQP's exit flag means a solution."""
    return exit_flag == EXIT_OPTIMAL or exit_flag == EXIT_SOFT_OPTIMAL


@kernel
def active_rows(multipliers, active) -> int:
    """The rows with a nonzero multiplier into `active` (int64; as many as it holds); how many."""
    count = 0
    for i in range(multipliers.shape[0]):
        if multipliers[i] != 0.0 and count < active.shape[0]:
            active[count] = i
            count += 1
    return count
