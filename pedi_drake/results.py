"""Run results: result.json (DESIGN.md section 5) computed from a finished run's logs."""

import json
import math
from pathlib import Path

import numpy as np

from pedi_drake import robot

FALL_HEIGHT = 0.07  # [m] trunk origin below this height: the trunk is on the ground.
FALL_TILT = math.radians(60.0)  # [rad] trunk roll or pitch beyond this: toppled.


def trunk_fell(plant_state_log: np.ndarray, plant_map: robot.Go1PlantMap, *, has_prongs: bool) -> bool:
    """True if the trunk dropped below FALL_HEIGHT (unless prongs hold it) or tilted past FALL_TILT.

    `plant_state_log` is (nx, N): plant state samples as columns.
    """
    q0 = plant_map.base_q_start
    return trunk_pose_fell(plant_state_log[q0 : q0 + 4], plant_state_log[q0 + 6], has_prongs=has_prongs)


def trunk_pose_fell(quaternion_wxyz: np.ndarray, height: np.ndarray, *, has_prongs: bool) -> bool:
    """`trunk_fell` from trunk quaternions (4, N) and heights (N,) [m] (e.g. the base-state estimate)."""
    w, x, y, z = quaternion_wxyz
    # Angle between the trunk's z axis and world z, from the quaternion.
    cos_tilt = 1.0 - 2.0 * (x**2 + y**2) / np.maximum(w**2 + x**2 + y**2 + z**2, 1e-12)
    tilted = bool(np.any(cos_tilt < math.cos(FALL_TILT)))
    # The run starts lying; only a drop after first standing counts.
    stood = np.nonzero(height > FALL_HEIGHT + 0.05)[0]
    dropped = bool(stood.size and np.any(height[stood[0] :] < FALL_HEIGHT)) and not has_prongs
    return tilted or dropped


def write_result(out_dir: Path, result: dict) -> Path:
    """Writes `result` as out_dir/result.json; non-finite numbers become null (valid JSON)."""

    def clean(value):
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items()}
        if isinstance(value, list | tuple):
            return [clean(v) for v in value]
        if isinstance(value, np.generic):
            value = value.item()
        if isinstance(value, float) and not math.isfinite(value):
            return None
        return value

    path = Path(out_dir) / "result.json"
    path.write_text(json.dumps(clean(result), indent=2, allow_nan=False) + "\n")
    return path
