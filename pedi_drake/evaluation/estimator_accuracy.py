"""How far a run's base-state estimate was from the simulated truth (evaluation only)."""

import numpy as np

from pedi_drake import robot
from pedi_drake.run_logs import SignalLog

# [m] true trunk height above which the robot counts as standing for the height error.
STANDING_TRUNK_HEIGHT = 0.2


def estimate_errors(
    base_state: SignalLog, plant_state: SignalLog, plant_map: robot.Go1PlantMap, num_positions: int
) -> dict:
    """Trunk position error (max, final) [m], velocity RMS error [m/s], orientation error (max)
    [deg] and, while standing (the true trunk above STANDING_TRUNK_HEIGHT), the trunk height error
    |z_estimated - z_true| (median, max; None if it never stood) [m] of the logged estimate against
    the logged plant state (`num_positions` q entries first)."""
    n = min(base_state.data.shape[1], plant_state.data.shape[1])
    estimate = base_state.data[:, :n].astype(float)
    truth = plant_state.data[:, :n].astype(float)
    q0 = plant_map.base_q_start
    v0 = num_positions + plant_map.base_v_start
    position_error = np.linalg.norm(estimate[4:7] - truth[q0 + 4 : q0 + 7], axis=0)
    velocity_error = np.linalg.norm(estimate[10:13] - truth[v0 + 3 : v0 + 6], axis=0)
    quaternion_est = estimate[0:4] / np.linalg.norm(estimate[0:4], axis=0)
    quaternion_true = truth[q0 : q0 + 4] / np.linalg.norm(truth[q0 : q0 + 4], axis=0)
    dot = np.clip(np.abs(np.sum(quaternion_est * quaternion_true, axis=0)), 0.0, 1.0)
    orientation_error = np.degrees(2.0 * np.arccos(dot))
    standing = truth[q0 + 6] > STANDING_TRUNK_HEIGHT
    height_error = np.abs(estimate[6] - truth[q0 + 6])[standing]
    return {
        "height_error_standing_median_m": float(np.median(height_error)) if height_error.size else None,
        "height_error_standing_max_m": float(np.max(height_error)) if height_error.size else None,
        "position_error_max_m": float(np.max(position_error)),
        "position_error_final_m": float(position_error[-1]),
        "velocity_rms_m_s": float(np.sqrt(np.mean(velocity_error**2))),
        "orientation_error_max_deg": float(np.max(orientation_error)),
    }
