"""How smooth a run's controller hand-overs were (pedi_drake.control.controller_switch), from its logs.

The switch logs `controller.switch` = [active controller code, the HQP's weight, switches so far]
at every control tick, beside the command that reached the motors (`go1.command`) and, in
simulation, the torque the motors applied (`sim.motor_torque`). A hand-over is the stretch from a
change of the active controller until the weight has settled (plus one tick). Over the hand-overs
and, for comparison, over every other tick:

  * the largest step of a joint target (q_des) from one tick to the next [rad], against the Go1
    safety filter's rate limit (max_target_rate x period): the floor is that no hand-over steps
    beyond it;
  * the largest step of a motor's applied torque from one tick to the next [N m].
"""

import numpy as np

from pedi_drake.run_logs import SignalLog

_ACTIVE, _WEIGHT, _SWITCHES = 0, 1, 2


def _steps(times: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(times of the later sample, largest |change| over the rows) of consecutive samples, from
    the second change on: the first is the controller's first command replacing the initial value."""
    if values.shape[1] < 3:
        return np.zeros(0), np.zeros(0)
    return times[2:], np.max(np.abs(np.diff(values, axis=1)), axis=0)[1:]


def hand_over_windows(switch: SignalLog, period: float) -> list[tuple[float, float]]:
    """[(start, end)] [s] of each hand-over: from the tick the active controller changed until the
    weight stopped moving, one period more on each side."""
    times, active, weight = switch.times, switch.data[_ACTIVE], switch.data[_WEIGHT]
    windows = []
    changes = np.flatnonzero(np.diff(active) != 0) + 1
    for k in changes:
        end = k
        while end + 1 < len(weight) and weight[end + 1] != weight[end]:
            end += 1
        windows.append((float(times[k]) - period, float(times[end]) + period))
    return windows


def switch_summary(
    switch: SignalLog,
    command: SignalLog,
    period: float,
    max_target_rate: float,
    motor_torque: SignalLog | None = None,
) -> dict:
    """result.json's `controller_switches` (module docstring): `switches`, `switch_times_s`,
    `max_target_step_rad` (in hand-overs), `max_target_step_elsewhere_rad`, `target_step_limit_rad`,
    and with `motor_torque` `max_torque_step_nm` / `max_torque_step_elsewhere_nm`."""
    windows = hand_over_windows(switch, period)

    def split(times: np.ndarray, steps: np.ndarray) -> tuple[float, float]:
        inside = np.zeros(times.shape, bool)
        for start, end in windows:
            inside |= (times >= start) & (times <= end)
        return float(np.max(steps[inside], initial=0.0)), float(np.max(steps[~inside], initial=0.0))

    target_in, target_out = split(*_steps(command.times, command.data[0:12]))
    summary = {
        "switches": int(switch.data[_SWITCHES, -1]) if switch.data.shape[1] else 0,
        "switch_times_s": [round(start + period, 6) for start, _ in windows],
        "max_target_step_rad": target_in,
        "max_target_step_elsewhere_rad": target_out,
        "target_step_limit_rad": max_target_rate * period,
    }
    if motor_torque is not None:
        torque_in, torque_out = split(*_steps(motor_torque.times, motor_torque.data))
        summary.update(max_torque_step_nm=torque_in, max_torque_step_elsewhere_nm=torque_out)
    return summary


def switch_problem(summary: dict) -> str:
    """Why the hand-overs fail their floor ("" when none stepped a joint target beyond the limit)."""
    if summary["max_target_step_rad"] <= summary["target_step_limit_rad"] + 1e-9:
        return ""
    return (
        f"a controller hand-over moved a joint target {summary['max_target_step_rad']:.4f} rad in one tick, over "
        f"the safety filter's rate limit of {summary['target_step_limit_rad']:.4f} rad"
    )
