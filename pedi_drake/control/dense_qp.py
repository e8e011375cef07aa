"""TEMPORARY stand-in (replaced by the compiled solver): DAQP through numba's object mode."""

import daqp
import numba
import numpy as np

from pedi_drake.jit import kernel

OPTIMAL = 1


def _daqp(H, f, C, u, eps_prox):
    y, _, exitflag, _ = daqp.solve(
        np.ascontiguousarray(H),
        np.ascontiguousarray(f),
        np.ascontiguousarray(C),
        np.ascontiguousarray(u),
        np.full(len(u), -1e30),
        eps_prox=eps_prox,
    )
    return np.asarray(y, float), (1 if exitflag in (1, 2) else 0)


@kernel
def solve(H, f, C, u, eps_prox, y):
    with numba.objmode(out="float64[:]", status="int64"):
        out, status = _daqp(H, f, C, u, eps_prox)
    y[:] = out
    return status
