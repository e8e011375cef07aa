"""Compiled numerical kernels: numba's nopython mode for the controller side's hot small-array maths.

At 500 Hz the estimator, the safety filter and the leg kinematics spend most of their time in the
Python and numpy call overhead of operations on 3- to 18-element arrays, not in arithmetic. A
`kernel` is plain Python written as loops over floats; with numba it is compiled to machine code
on first use (and cached on disk, so later processes load it in milliseconds). The same function
is the reference implementation: `kernel(f).py_func` is `f` itself, which the tests compare with
the compiled one on random inputs.

    PEDI_DRAKE_JIT=0    runs every kernel as plain Python (debugging; the same results, slower)

Without numba installed the kernels run as plain Python too. Systems that call kernels compile
them in their constructor (`warm_up`), never inside a control tick.

A kernel may call kernels (numba compiles them into it) and reads module constants as they were
when it was compiled. numba's cache notices a change of the kernel's own file only, so a kernel
takes what another file defines (model constants, geometry) as arguments, and after an edit of a
kernel that a kernel of another file calls (leg_odometry's, called by the estimator's) the cache
must be cleared (`find pedi_drake -name "*.nb[ci]" -delete`): the tests that compare a kernel
with its `.py_func` notice a stale one, as `.py_func` calls the fresh callee.
"""

import os

try:
    import numba
except ImportError:  # pragma: no cover - numba is a dependency; this keeps a broken install usable
    numba = None

ENABLED = numba is not None and os.environ.get("PEDI_DRAKE_JIT", "1") != "0"


def kernel(function):
    """`function` compiled by numba (nopython, cached, releases the GIL) when enabled, else itself.

    The returned object is called like `function`; `.py_func` is always the plain function.
    """
    if not ENABLED:
        function.py_func = function
        return function
    return numba.njit(cache=True, nogil=True)(function)
