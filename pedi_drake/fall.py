"""When the Go1 has fallen: one rule for the mission manager (online, on the state estimate),
the run's judge (after the run, on ground truth in simulation) and the benchmarks.

The trunk has fallen when it tilts past FALL_TILT (the angle between its z axis and world z),
or, once the robot has stood, when the trunk origin drops below FALL_HEIGHT while the trunk is
not meant to rest on prongs (a Go1 with prongs may lean its trunk on them by design).
"""

import math

import numpy as np

FALL_HEIGHT = 0.07  # [m] trunk origin below this: the trunk is on the ground
FALL_TILT = math.radians(50.0)  # [rad] trunk z axis this far from world z: toppled
# A trunk origin above this height has stood up; a run starts lying (trunk at about 0.1 m) [m].
STOOD_HEIGHT = FALL_HEIGHT + 0.05


def _cos_tilt(w, x, y, z, maximum=np.maximum):
    return 1.0 - 2.0 * (x * x + y * y) / maximum(w * w + x * x + y * y + z * z, 1e-12)


def cos_tilt(quaternion_wxyz: np.ndarray) -> np.ndarray:
    """cos of the angle between the trunk's z axis and world z, from quaternions (4,) or (4, N)."""
    return _cos_tilt(*quaternion_wxyz)


def trunk_has_fallen(quaternion_wxyz, height, *, has_stood, resting_on_prongs) -> np.ndarray | bool:
    """The fall rule for one sample or, with arrays (4, N), (N,) and (N,) flags, for each sample.

    quaternion_wxyz: trunk orientation in world; height: trunk origin z [m]; has_stood: the robot
    has stood up before this sample; resting_on_prongs: the trunk may touch the ground by design.
    """
    quaternion = np.asarray(quaternion_wxyz, dtype=float)
    if quaternion.ndim == 1 and np.ndim(height) == 0:
        # One sample (the mission manager's, at every update): the same arithmetic on floats,
        # without numpy's cost per call on scalars (tens of microseconds an update).
        tilted = _cos_tilt(*quaternion.tolist(), maximum=max) < math.cos(FALL_TILT)
        return tilted or (bool(has_stood) and float(height) < FALL_HEIGHT and not resting_on_prongs)
    tilted = cos_tilt(quaternion) < math.cos(FALL_TILT)
    dropped = np.logical_and(
        np.logical_and(has_stood, np.asarray(height) < FALL_HEIGHT), np.logical_not(resting_on_prongs)
    )
    return np.logical_or(tilted, dropped)


def fell_during(quaternion_wxyz: np.ndarray, height: np.ndarray, *, has_prongs: bool) -> bool:
    """Whether the fall rule held at any sample of a logged run: quaternions (4, N), heights (N,) [m].

    The robot has stood from the first sample above STOOD_HEIGHT on; with prongs the trunk may rest
    on them throughout.
    """
    return first_fallen_sample(quaternion_wxyz, height, has_prongs=has_prongs) is not None


def first_fallen_sample(quaternion_wxyz: np.ndarray, height: np.ndarray, *, has_prongs: bool) -> int | None:
    """The index of the first sample at which the fall rule held (see `fell_during`), or None."""
    height = np.asarray(height, dtype=float)
    has_stood = np.maximum.accumulate(height > STOOD_HEIGHT) if height.size else height.astype(bool)
    fallen = np.atleast_1d(trunk_has_fallen(quaternion_wxyz, height, has_stood=has_stood, resting_on_prongs=has_prongs))
    return int(np.argmax(fallen)) if np.any(fallen) else None
