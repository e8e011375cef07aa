"""Judging a push of a scene object by one foot, by physics (the logged plant state).

The push happened when the object's root body moved at least the check's distance on the floor
from the pushing phase's start to the end of the check's `until` phase (the pushing phase itself
by default: a struck object may slide on after the foot has stopped); it was made from a firm
stance when every foot on the ground at the phase's start stayed within the check's slide of
where it was over the pushing phase. No controller or mission ever reads this.
"""

import numpy as np

from pedi_drake import robot
from pedi_drake.evaluation.mission_results import FOOT_ON_GROUND, foot_positions_W
from pedi_drake.mission.spec import ObjectPush
from pedi_drake.station.scene import root_body

# Samples of the phase the stance feet are checked at: enough to see a slide of millimetres.
STANCE_SAMPLES = 200


def judge_object_push(
    plant, check: ObjectPush, phases: list[dict], times: np.ndarray, states: np.ndarray
) -> tuple[dict, str]:
    """result.json's row for `check` and why the push did not happen ("" when it did), from the
    logged plant `states` (nx, N) at `times` and the run's phase table."""
    phase = next((row for row in phases if row["name"] == check.phase), None)
    if phase is None or phase["t_end"] is None:
        return {"object": check.object, "phase": check.phase}, f"{check.object} was not pushed: {check.phase} never ran"
    until_name = check.until or check.phase
    until = next((row for row in phases if row["name"] == until_name), None)
    if until is None or until["t_end"] is None:
        return {"object": check.object, "phase": check.phase}, f"{check.object}: {until_name} never ended"
    first = int(np.searchsorted(times, phase["t_start"]))
    last = int(np.clip(np.searchsorted(times, phase["t_end"]), first, len(times) - 1))
    settled = int(np.clip(np.searchsorted(times, until["t_end"]), last, len(times) - 1))
    body = root_body(plant, plant.GetModelInstanceByName(check.object))
    context = plant.CreateDefaultContext()
    nq = plant.num_positions()

    def p_WO(k: int) -> np.ndarray:
        plant.SetPositions(context, states[:nq, k])
        return body.EvalPoseInWorld(context).translation()

    moved = float(np.linalg.norm((p_WO(settled) - p_WO(first))[:2]))
    indices = np.unique(np.linspace(first, last, STANCE_SAMPLES).astype(int))
    feet_W = foot_positions_W(plant, states, indices)
    stance = feet_W[0, :, 2] < robot.FOOT_RADIUS + FOOT_ON_GROUND
    slides = np.max(np.linalg.norm(feet_W[:, :, :2] - feet_W[:1, :, :2], axis=-1), axis=0)
    stance_slides = {leg: float(slides[i]) for i, leg in enumerate(robot.LEG_NAMES) if stance[i]}
    row = {
        "object": check.object,
        "phase": check.phase,
        "until": until_name,
        "moved_m": moved,
        "required_m": check.distance,
        "stance_feet_slide_m": stance_slides,
    }
    problems = []
    if moved < check.distance:
        problems.append(
            f"{check.object} moved {100 * moved:.1f} cm from {check.phase} to the end of {until_name}, "
            f"{100 * check.distance:.1f} cm needed"
        )
    slid = {leg: slide for leg, slide in stance_slides.items() if slide > check.stance_slide}
    if slid:
        worst = max(slid, key=slid.get)
        problems.append(
            f"the {worst} stance foot slid {1000 * slid[worst]:.1f} mm in {check.phase} "
            f"(at most {1000 * check.stance_slide:.1f} mm)"
        )
    return row, "; ".join(problems)
