"""Judging a box lift by physics: how high the box's bottom rose, and for how long the feet held it.

Read from the logged plant state and the true contact forces (simulation ground truth); no
controller or mission ever sees these. The box counts as lifted while every corner of its
collision box is at least `BoxLift.height` above the ground and each holding foot touches
something with at least `BoxLift.contact_force` (the lifted feet touch nothing but the box).
"""

import dataclasses

import numpy as np
from pydrake.geometry import Box
from pydrake.math import RigidTransform
from pydrake.multibody.plant import MultibodyPlant

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.mission.spec import BoxLift

# The box counts as on the ground while its bottom is below this [m]: contact penetration and a
# slight tilt on a corner stay under it.
ON_GROUND_HEIGHT = 0.005


@dataclasses.dataclass(frozen=True)
class BoxLiftTrace:
    """The box and the holding feet over the run (N samples)."""

    times: np.ndarray  # (N,) [s]
    bottom_height: np.ndarray  # (N,) lowest corner of the box above the ground [m]
    foot_forces: np.ndarray  # (N, number of holding feet) true contact force magnitude [N]
    foot_positions: np.ndarray  # (N, number of holding feet, 3) true foot centres [m]


def box_corners_B(plant: MultibodyPlant, inspector, body) -> np.ndarray:
    """The 8 corners (8, 3) of `body`'s collision box in its body frame [m]."""
    for geometry in plant.GetCollisionGeometriesForBody(body):
        shape = inspector.GetShape(geometry)
        if isinstance(shape, Box):
            X_BG = RigidTransform(inspector.GetPoseInFrame(geometry))
            half = np.array([shape.width(), shape.depth(), shape.height()]) / 2
            signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
            return np.array([X_BG @ (s * half) for s in signs])
    raise PediError(f"box lift: body {body.name()!r} has no box collision geometry")


def box_lift_trace(
    plant: MultibodyPlant,
    inspector,
    check: BoxLift,
    times: np.ndarray,
    states: np.ndarray,
    foot_force_times: np.ndarray,
    foot_forces_W: np.ndarray,
) -> BoxLiftTrace:
    """The box's bottom height and the holding feet's forces and positions at each logged state.

    `states` (nx, N): the logged plant state at `times`; `foot_forces_W` (12, M): the logged true
    contact force on each foot (FR, FL, RR, RL x world xyz) at `foot_force_times`.
    """
    if not plant.HasModelInstanceNamed(check.box):
        raise PediError(f"box lift: the scene has no object named {check.box!r}")
    box = plant.GetBodyByName(check.box, plant.GetModelInstanceByName(check.box))
    corners_B = box_corners_B(plant, inspector, box)
    feet = [plant.GetBodyByName(robot.FOOT_BODY_NAMES[robot.LEG_NAMES.index(leg)]) for leg in check.feet]
    context = plant.CreateDefaultContext()
    nq = plant.num_positions()
    bottom = np.zeros(len(times))
    positions = np.zeros((len(times), len(feet), 3))
    for k in range(len(times)):
        plant.SetPositions(context, states[:nq, k])
        X_WB = box.EvalPoseInWorld(context)
        bottom[k] = np.min((X_WB.rotation().matrix() @ corners_B.T)[2]) + X_WB.translation()[2]
        for i, foot in enumerate(feet):
            positions[k, i] = foot.EvalPoseInWorld(context).translation()
    forces = np.zeros((len(times), len(feet)))
    for i, leg in enumerate(check.feet):
        j = robot.LEG_NAMES.index(leg)
        magnitude = np.linalg.norm(foot_forces_W[3 * j : 3 * j + 3], axis=0)
        forces[:, i] = np.interp(times, foot_force_times, magnitude)
    return BoxLiftTrace(np.asarray(times, float), bottom, forces, positions)


def _longest_run(times: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """(duration [s], start time [s]) of the longest stretch of consecutive samples where `mask` holds."""
    best, best_start, start = 0.0, float("nan"), None
    for k, ok in enumerate(mask):
        if ok and start is None:
            start = k
        if start is not None and (not ok or k == len(mask) - 1):
            end = k if ok else k - 1
            if times[end] - times[start] > best:
                best, best_start = float(times[end] - times[start]), float(times[start])
            start = None
    return best, best_start


def judge_box_lift(trace: BoxLiftTrace, check: BoxLift, phases: list[dict]) -> tuple[dict, str]:
    """result.json's `box_lift` row, and why the lift failed ("" when it met the check).

    Lifted: the bottom at least `check.height` above the ground while every holding foot presses
    with at least `check.contact_force`, for at least `check.hold` without a break. Dropped: the box
    back on the ground after it was lifted and before the phase `check.until_phase` started.
    """
    held = (trace.bottom_height >= check.height) & np.all(trace.foot_forces >= check.contact_force, axis=1)
    held_for, held_from = _longest_run(trace.times, held)
    t_until = next((row["t_start"] for row in phases if row["name"] == check.until_phase), None)
    lifted = np.flatnonzero(held)
    dropped_at = None
    if lifted.size:
        after = np.arange(len(trace.times)) > lifted[0]
        before = trace.times < (t_until if t_until is not None else np.inf)
        down = np.flatnonzero(after & before & (trace.bottom_height < ON_GROUND_HEIGHT))
        dropped_at = float(trace.times[down[0]]) if down.size else None
    window = held if lifted.size else np.zeros_like(held)
    row = {
        "box": check.box,
        "feet": list(check.feet),
        "max_bottom_height_m": float(np.max(trace.bottom_height)),
        "held_s": held_for,
        "held_from_s": held_from if held_for > 0 else None,
        "required_height_m": check.height,
        "required_hold_s": check.hold,
        "mean_foot_force_held_n": (
            [float(v) for v in trace.foot_forces[window].mean(axis=0)] if np.any(window) else None
        ),
        "dropped_at_s": dropped_at,
        "final_bottom_height_m": float(trace.bottom_height[-1]),
    }
    problems = []
    if held_for < check.hold:
        problems.append(
            f"box lift: the box's bottom was {100 * check.height:.0f} cm or more above the ground, held by "
            f"{'+'.join(check.feet)}, for {held_for:.2f} s at most (need {check.hold:.1f} s; highest "
            f"{100 * row['max_bottom_height_m']:.1f} cm)"
        )
    if dropped_at is not None:
        problems.append(
            f"box lift: the box fell back to the ground at t = {dropped_at:.2f} s, before {check.until_phase}"
        )
    return row, "; ".join(problems)
