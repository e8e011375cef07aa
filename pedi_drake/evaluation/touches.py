"""Judging touches by physics: did a foot press on a scene object, not only come close to it.

Read from `sim.scene_contact_forces` (pedi_drake.station.scene_contact), the true normal contact
forces between the robot and each scene object; no controller or mission ever sees them. A touch
(`pedi_drake.mission.spec.Touch`) happened when the largest normal force between the foot and
the object during its phase reached the touch's `force`.
"""

import numpy as np

from pedi_drake.mission.spec import Touch
from pedi_drake.station.scene_contact import scene_contact_index


def phase_window(phases: list[dict], name: str, t_last: float) -> tuple[float, float] | None:
    """(start, end) [s] of the phase `name` in result.json's `phases` (an unfinished phase ends at
    `t_last`); None if it never started."""
    row = next((row for row in phases if row["name"] == name), None)
    if row is None or row["t_start"] is None:
        return None
    return row["t_start"], row["t_end"] if row["t_end"] is not None else t_last


def judge_touches(
    touches: list[Touch], scene_names: list[str], phases: list[dict], times: np.ndarray, forces: np.ndarray
) -> tuple[list[dict], str]:
    """result.json's `touches` rows, and why a touch did not happen ("" when all did).

    `times` (N,) [s] and `forces` (len(scene_names) * 5, N) [N]: the logged `sim.scene_contact_forces`;
    `scene_names`: the scene's object names in the station's order.
    """
    rows, problems = [], []
    times = np.asarray(times)
    for touch in touches:
        window = phase_window(phases, touch.phase, float(times[-1]) if times.size else 0.0)
        force = forces[scene_contact_index(touch.object, touch.leg, scene_names)]
        inside = np.zeros(times.shape, bool) if window is None else (times >= window[0]) & (times <= window[1])
        peak = float(np.max(force[inside], initial=0.0))
        at = float(times[inside][np.argmax(force[inside])]) if peak > 0 else None
        touched = peak >= touch.force
        rows.append(
            {
                "object": touch.object,
                "leg": touch.leg,
                "phase": touch.phase,
                "max_normal_force_n": peak,
                "max_force_at_s": at,
                "required_force_n": touch.force,
                "touched": touched,
            }
        )
        if window is None:
            problems.append(f"{touch.phase}: never ran, so the {touch.leg} foot did not touch {touch.object}")
        elif not touched:
            problems.append(
                f"{touch.phase}: the {touch.leg} foot did not touch {touch.object} (largest normal contact "
                f"force {peak:.2f} N, need {touch.force:.1f} N)"
            )
    return rows, "; ".join(problems)
