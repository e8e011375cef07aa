"""Judging an E-stop button press by physics: the plunger went in past its trip travel, and the foot
never pushed harder than the teleoperated foot's force bound.

Read from the logged plant state (the plunger's joint position, `sim.plant_state`) and the true
normal contact forces between the robot and the scene objects (`sim.scene_contact_forces`); no
controller or mission ever sees them. The press (pedi_drake.mission.spec.ButtonPress) happened
when, during its phase, the plunger was in at least ESTOP_BUTTON_TRIP_TRAVEL; it was gentle when
the largest normal force between the foot and the button over the whole run stayed at or under
the phase's `max_force` (the bound the teleoperated foot applies to its force estimate).

The forces are those of the logged samples (the log's period, 2 ms, every other plant step): an
impact shorter than a step between two samples is not seen.
"""

import numpy as np

from pedi_drake.evaluation.touches import phase_window
from pedi_drake.mission.spec import ButtonPress
from pedi_drake.station.scene import ESTOP_BUTTON_JOINT, ESTOP_BUTTON_TRIP_TRAVEL
from pedi_drake.station.scene_contact import scene_contact_index


def plunger_travel(plant, button: str, states: np.ndarray) -> np.ndarray:
    """(N,) how far the plunger of the button `button` (a model instance) is in [m] at each logged
    plant state (`states` (nx, N))."""
    joint = plant.GetJointByName(ESTOP_BUTTON_JOINT, plant.GetModelInstanceByName(button))
    return np.asarray(states[joint.position_start()], float)


def judge_button_press(
    check: ButtonPress,
    force_bound: float,
    phases: list[dict],
    travel_times: np.ndarray,
    travel: np.ndarray,
    scene_names: list[str],
    force_times: np.ndarray,
    forces: np.ndarray,
) -> tuple[dict, str]:
    """result.json's `button_press` row, and why the press failed ("" when it succeeded).

    `travel` (N,) [m] at `travel_times` [s] (see `plunger_travel`); `forces` (len(scene_names) * 5, M)
    [N] at `force_times` [s]: the logged `sim.scene_contact_forces`; `force_bound` [N]: the phase's
    max_force.
    """
    travel_times, force_times = np.asarray(travel_times), np.asarray(force_times)
    t_last = float(travel_times[-1]) if travel_times.size else 0.0
    window = phase_window(phases, check.phase, t_last)
    inside = (
        np.zeros(travel_times.shape, bool)
        if window is None
        else (travel_times >= window[0]) & (travel_times <= window[1])
    )
    tripped = inside & (travel >= ESTOP_BUTTON_TRIP_TRAVEL)
    pressed = bool(np.any(tripped))
    pressed_at = float(travel_times[np.argmax(tripped)]) if pressed else None
    force = np.asarray(forces[scene_contact_index(check.button, check.leg, scene_names)], float)
    peak = float(np.max(force, initial=0.0))
    at_press = float(np.interp(pressed_at, force_times, force)) if pressed and force_times.size else None
    row = {
        "button": check.button,
        "leg": check.leg,
        "phase": check.phase,
        "pressed": pressed,
        "pressed_at_s": pressed_at,
        "max_travel_m": float(np.max(travel[inside], initial=0.0)),
        "trip_travel_m": ESTOP_BUTTON_TRIP_TRAVEL,
        "max_force_n": peak,
        "max_force_at_s": float(force_times[np.argmax(force)]) if peak > 0 else None,
        "force_at_press_n": at_press,
        "force_bound_n": force_bound,
        "gentle": peak <= force_bound,
    }
    problems = []
    if window is None:
        problems.append(f"{check.phase}: never ran, so the {check.leg} foot did not press {check.button}")
    elif not pressed:
        problems.append(
            f"{check.phase}: the {check.leg} foot did not press {check.button} (plunger in at most "
            f"{1000 * row['max_travel_m']:.1f} mm, it trips at {1000 * ESTOP_BUTTON_TRIP_TRAVEL:.1f} mm)"
        )
    if not row["gentle"]:
        problems.append(
            f"the {check.leg} foot pushed on {check.button} with up to {peak:.1f} N "
            f"at t = {row['max_force_at_s']:.3f} s, over the force bound of {force_bound:.1f} N (phase {check.phase})"
        )
    return row, "; ".join(problems)
