"""Small 3-vector helpers for code that runs every control tick.

numpy's general routines pay for their generality on 3-vectors: `np.cross` costs about 12 us a
call (axis handling), the scalar form below about 1 us. The sensors and the estimator call it a
few times every tick, at 500-1000 Hz.
"""

import numpy as np


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b for two 3-vectors (same result as np.cross)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])
