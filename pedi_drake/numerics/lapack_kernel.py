"""LAPACK's QR factorisations called from compiled code: the rank-revealing split of a level's rows.

numba's `np.linalg` has the QR without pivoting and only its economic Q; the hierarchical QP
needs the complete Q (the rows' null space) and, when rows come near rank deficiency, the QR with
column pivoting (dgeqp3), whose diagonal reveals the rank without an SVD
(`tests/test_compiled_hqp.py` holds the two to the same rank). This module calls the routines scipy ships
(`scipy.linalg.cython_lapack`: dgeqrf, dgeqp3, dorgqr) by symbol, as `daqp_kernel` calls DAQP, so
a kernel factors without returning to Python and numba's disk cache keeps the kernels.

`qr_of_transpose(A, pivot)` factors A^T (A is m x n, m <= n, C-contiguous, which LAPACK reads as
A^T in column-major order): A^T P = Q [R; 0], Q (n x n) orthogonal, R (m x m) upper triangular,
P the permutation `order` of A's rows (the identity without pivoting). Its first m columns span
A's row space; with pivoting the diagonal of R does not increase in magnitude, and a rank r shows
as the first r columns spanning the row space and the last n - r the null space.
"""

import ctypes

import numpy as np

from pedi_drake.runtime.jit import ENABLED, kernel

_ROUTINES = ("dgeqrf", "dgeqp3", "dorgqr")


def _address(name: str) -> int:
    from numba.extending import get_cython_function_address

    return get_cython_function_address("scipy.linalg.cython_lapack", name)


if ENABLED:
    import llvmlite.binding
    from numba.core import types

    for _name in _ROUTINES:
        # A name of the package's own: the process may hold other libraries' symbols of the same name.
        llvmlite.binding.add_symbol(f"pedi_drake_{_name}", _address(_name))
    # Fortran's calling convention: every argument by address (as a 64-bit integer here).
    _dgeqrf = types.ExternalFunction("pedi_drake_dgeqrf", types.void(*(types.intp,) * 8))
    _dgeqp3 = types.ExternalFunction("pedi_drake_dgeqp3", types.void(*(types.intp,) * 9))
    _dorgqr = types.ExternalFunction("pedi_drake_dorgqr", types.void(*(types.intp,) * 9))
else:  # interpreted kernels call the same routines through ctypes

    def _caller(name: str, arity: int):
        function = ctypes.CFUNCTYPE(None, *(ctypes.c_void_p,) * arity)(_address(name))
        return lambda *addresses: function(*(ctypes.c_void_p(a) for a in addresses))

    _dgeqrf = _caller("dgeqrf", 8)
    _dgeqp3 = _caller("dgeqp3", 9)
    _dorgqr = _caller("dorgqr", 9)


@kernel
def qr_of_transpose(A: np.ndarray, pivot: bool):
    """(ok, Q (n, n), R (m, m), order (m,)) of A^T P = Q [R; 0] for A (m, n), m <= n (see the module
    docstring); ok False when LAPACK reports a problem (then Q, R, order meaningless)."""
    m, n = A.shape
    factors = np.zeros((n, n))  # column-major n x n: row j of `factors` is column j
    factors[:m, :] = A
    tau = np.zeros(n)
    sizes = np.array([n, m, n, 0, 0], dtype=np.int32)  # M, N, LDA, INFO, N for dorgqr
    work_size = np.array([64 * n], dtype=np.int32)
    work = np.empty(64 * n)
    order_f = np.zeros(max(m, 1), dtype=np.int32)  # dgeqp3: 0 = a free column
    if pivot:
        _dgeqp3(
            sizes[0:].ctypes.data, sizes[1:].ctypes.data, factors.ctypes.data, sizes[2:].ctypes.data,
            order_f.ctypes.data, tau.ctypes.data, work.ctypes.data, work_size.ctypes.data, sizes[3:].ctypes.data,
        )  # fmt: skip
    else:
        _dgeqrf(
            sizes[0:].ctypes.data, sizes[1:].ctypes.data, factors.ctypes.data, sizes[2:].ctypes.data,
            tau.ctypes.data, work.ctypes.data, work_size.ctypes.data, sizes[3:].ctypes.data,
        )  # fmt: skip
    ok = sizes[3] == 0
    R = np.zeros((m, m))
    for j in range(m):
        for i in range(j + 1):
            R[i, j] = factors[j, i]
    order = np.empty(m, dtype=np.int64)
    for j in range(m):
        order[j] = order_f[j] - 1 if pivot else j
    # The complete Q from the m reflectors: dorgqr on the n x n array.
    sizes[4] = n
    reflectors = np.array([m], dtype=np.int32)
    _dorgqr(
        sizes[0:].ctypes.data, sizes[4:].ctypes.data, reflectors.ctypes.data, factors.ctypes.data,
        sizes[2:].ctypes.data, tau.ctypes.data, work.ctypes.data, work_size.ctypes.data, sizes[3:].ctypes.data,
    )  # fmt: skip
    ok = ok and sizes[3] == 0
    return ok, np.ascontiguousarray(factors.T), R, order
