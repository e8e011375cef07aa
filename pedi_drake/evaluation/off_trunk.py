"""Judging whether an object left the robot's back, by physics (the logged plant state).

The rule: an object is on the trunk while its centre of mass, in the trunk frame, lies over the
top face's footprint (the trunk's collision box, `robot.TRUNK_HALF_EXTENTS`) and between the top
face and ON_TRUNK_MAX_HEIGHT above it. An object whose centre of mass is outside the footprint
cannot rest on the top face (it tips off its edge); one below the face has slid down the trunk's
side or lies on the ground. The trunk's own motion (rolling, lying down) is in the rule, as it is
judged in the trunk frame at each sample. No controller or mission ever reads this.
"""

import dataclasses

import numpy as np

from pedi_drake import robot

# Highest centre of mass above the trunk's top face that still counts as resting on it [m]: well
# over a back object's own half height (a few centimetres), well under an object flung upwards.
ON_TRUNK_MAX_HEIGHT = 0.10


@dataclasses.dataclass(frozen=True)
class OffTrunkTrace:
    """An object's centre of mass over the run (N samples)."""

    times: np.ndarray  # (N,) [s]
    p_TopO: np.ndarray  # (N, 3) from the centre of the trunk's top face, trunk frame [m]
    p_WO: np.ndarray  # (N, 3) world frame [m]


def off_trunk_trace(plant, name: str, times: np.ndarray, states: np.ndarray) -> OffTrunkTrace:
    """The centre of mass of scene object `name` (a one-body model instance) relative to the trunk's
    top face at each logged plant state (`states` (nx, N) at `times`)."""
    (body_index,) = plant.GetBodyIndices(plant.GetModelInstanceByName(name))
    body = plant.get_body(body_index)
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME)
    context = plant.CreateDefaultContext()
    nq = plant.num_positions()
    top = np.array([0.0, 0.0, robot.TRUNK_HALF_EXTENTS[2]])
    p_TopO, p_WO = np.zeros((len(times), 3)), np.zeros((len(times), 3))
    for k in range(len(times)):
        plant.SetPositions(context, states[:nq, k])
        p_WO[k] = body.EvalPoseInWorld(context) @ body.CalcCenterOfMassInBodyFrame(context)
        p_TopO[k] = trunk.EvalPoseInWorld(context).inverse() @ p_WO[k] - top
    return OffTrunkTrace(np.asarray(times, float), p_TopO, p_WO)


def on_trunk(p_TopO: np.ndarray) -> np.ndarray:
    """(N,) whether the centre of mass at each row of `p_TopO` (N, 3) [m] is on the trunk (see the module)."""
    half_x, half_y, _ = robot.TRUNK_HALF_EXTENTS
    over = (np.abs(p_TopO[:, 0]) <= half_x) & (np.abs(p_TopO[:, 1]) <= half_y)
    return over & (p_TopO[:, 2] >= 0.0) & (p_TopO[:, 2] <= ON_TRUNK_MAX_HEIGHT)


def judge_off_trunk(name: str, trace: OffTrunkTrace) -> tuple[dict, str]:
    """result.json's row for the object `name`, and why it did not leave the trunk ("" when it did).

    `left_at_s`: the first sample after its last one on the trunk (None while it is still there).
    """
    on = on_trunk(trace.p_TopO)
    last_on = np.flatnonzero(on)
    stays = bool(on[-1])
    if stays:
        left_at = None
    elif last_on.size:
        left_at = float(trace.times[last_on[-1] + 1])
    else:
        left_at = float(trace.times[0])
    row = {
        "final_position_trunk_m": [float(v) for v in trace.p_TopO[-1]],
        "final_position_W_m": [float(v) for v in trace.p_WO[-1]],
        "on_trunk": stays,
        "left_at_s": left_at,
    }
    if not stays:
        return row, ""
    x, y, z = trace.p_TopO[-1]
    return row, (
        f"{name} is still on the trunk at the end: its centre of mass is {100 * z:.1f} cm above the top "
        f"face at ({100 * x:.1f}, {100 * y:.1f}) cm from its centre, inside the "
        f"{200 * robot.TRUNK_HALF_EXTENTS[0]:.1f} x {200 * robot.TRUNK_HALF_EXTENTS[1]:.1f} cm footprint"
    )
