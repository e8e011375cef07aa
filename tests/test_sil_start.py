"""apps.sil's account of the loop's start and of the bridge's pace, on synthetic logs of the two processes."""

import numpy as np

from pedi_drake.apps.sil import bridge_pace, start_transient
from pedi_drake.run_logs import SignalLog

PERIOD = 0.002  # [s]


def _logs(q: np.ndarray, wall_start: float) -> dict[str, SignalLog]:
    """Controller logs: measured joints (12, N) every period, the wall clock of each tick."""
    times = PERIOD * np.arange(q.shape[1])
    return {
        "go1.position_measured": SignalLog(times, q),
        "wall_clock": SignalLog(times, (wall_start + times)[np.newaxis, :]),
    }


def _truth(wall: np.ndarray, z: np.ndarray) -> dict[str, np.ndarray]:
    p_WB = np.zeros((len(wall), 3))
    p_WB[:, 2] = z
    return {"wall_time": wall, "p_WB": p_WB}


def test_a_joint_jump_and_a_sinking_trunk_in_the_window_are_reported():
    q = np.zeros((12, 200))
    q[4, 3:] = -0.05  # FL thigh (Unitree order) steps by 50 mrad between ticks 2 and 3
    q[0, 120:] = 0.3  # after the 0.1 s window: not the start's
    wall = 100.0 + 0.01 * np.arange(-50, 50)
    z = np.where(wall < 100.02, 0.08, 0.075)  # sinks 5 mm 20 ms after the first tick
    start = start_transient(_logs(q, 100.0), _truth(wall, z), window=0.1)
    assert start["largest_joint_step_joint"] == "FL_thigh_joint"
    assert np.isclose(start["largest_joint_step_rad"], 0.05)
    assert np.isclose(start["largest_joint_step_t"], 3 * PERIOD)
    assert np.isclose(start["true_trunk_sink_m"], 0.005)
    assert start["true_trunk_height_bridge_start_m"] == 0.08
    assert start["true_trunk_height_loop_start_m"] == 0.08


def test_a_still_robot_has_a_quiet_start():
    q = np.full((12, 100), 0.7)
    wall = 5.0 + 0.01 * np.arange(100)
    start = start_transient(_logs(q, 5.0), _truth(wall, np.full(100, 0.3)), window=0.1)
    assert start["largest_joint_step_rad"] == 0.0
    assert start["true_trunk_sink_m"] == 0.0


def test_the_bridges_pace_counts_its_stops():
    wall = 100.0 + 0.01 * np.arange(300)
    wall[150:] += 0.055  # stopped for 55 ms, as the kernel's real-time throttling stops it
    wall[250:] += 0.015  # 25 ms between two samples: behind, but not two samples' worth more
    pace = bridge_pace({"wall_time": wall})
    assert pace["gaps"] == 2
    assert np.isclose(pace["longest_gap_ms"], 65.0)
    assert np.isclose(pace["median_spacing_ms"], 10.0)
    assert pace["sample_period_ms"] == 10.0


def test_the_bridges_pace_on_time_has_no_gaps():
    pace = bridge_pace({"wall_time": 100.0 + 0.01 * np.arange(100)})
    assert pace["gaps"] == 0
    assert np.isclose(pace["longest_gap_ms"], 10.0)
