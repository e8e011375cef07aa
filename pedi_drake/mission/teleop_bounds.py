"""The bounds on a teleoperated foot: its leg's workspace, its speed and its contact force.

Plain functions on arrays (the TeleopFootRunner applies them every mission tick):

  * `workspace_margin`: how far a trunk-frame foot target is inside the workspace [m]: the leg's
    closed-form IK (pedi_drake.ik.analytic) has a solution at least `joint_margin` inside every
    joint limit, the foot centre is `min_height` above the ground and clear of the trunk's box.
    Continuous, positive inside, so its finite-difference gradient gives the boundary's normal.
  * `slide_in_workspace`: a step from an inside target towards another: the step's end when it
    is inside, otherwise the boundary point on the way there plus the rest of the step with its
    outward component removed (the target slides along the boundary and never leaves it).
  * `step_into_workspace`: from a target the workspace has moved away from (the trunk moved under
    it), the nearest point back inside along the boundary's normal, within a step length;
  * `bound_speed`, `bound_force`: the velocity clipped to a speed, and its component into a
    contact slowed as the contact's estimated force nears a limit, stopped at it, reversed beyond.
"""

import math

import numpy as np
from pydrake.math import RigidTransform

from pedi_drake import robot
from pedi_drake.ik.analytic import leg_ik_solutions
from pedi_drake.mission.balance_bound import bound_balance

# Joint-limit distances [rad] enter the margin as metres at this lever (a link length): only the
# sign and, near a boundary, the active term's gradient matter, not the scale between the terms.
JOINT_TO_METRES = 0.213
# Clearance of the foot sphere from the trunk's box [m].
TRUNK_CLEARANCE = 0.01
# Margin of a target with no IK solution at all (beyond the leg's reach) [m]: outside.
_BEYOND_REACH = -1.0
_GRADIENT_STEP = 1e-5  # [m]
# Halvings of a step to find the boundary: a 1 mm step (0.1 m/s for 10 ms) to 4 um.
_BISECTION_STEPS = 8
_MAX_SLIDES = 2  # boundary faces a step may slide along in one tick (two meet at an edge)
_LOWER = robot.Q_LOWER[0:3]
_UPPER = robot.Q_UPPER[0:3]


def _joint_limit_distance(q: np.ndarray) -> float:
    """Smallest distance of (hip, thigh, calf) [rad] to its limits, any 2 pi representation (< 0 outside)."""
    best = math.inf
    for j in range(3):
        distance = max(min(q[j] + k * 2 * math.pi - _LOWER[j], _UPPER[j] - q[j] - k * 2 * math.pi) for k in (-1, 0, 1))
        best = min(best, distance)
    return best


def workspace_margin(leg: str, p_B: np.ndarray, X_WB: RigidTransform, joint_margin: float, min_height: float) -> float:
    """How far the foot target `p_B` (trunk frame, trunk at X_WB) is inside the workspace [m] (< 0 outside)."""
    p_B = np.asarray(p_B, float)
    solutions = leg_ik_solutions(leg, p_B, respect_limits=False)
    if not solutions:
        return _BEYOND_REACH
    joints = JOINT_TO_METRES * (max(_joint_limit_distance(q) for q in solutions) - joint_margin)
    floor = float((X_WB @ p_B)[2]) - min_height
    half = np.asarray(robot.TRUNK_HALF_EXTENTS) + robot.FOOT_RADIUS + TRUNK_CLEARANCE
    excess = np.abs(p_B) - half
    trunk = float(np.linalg.norm(np.maximum(excess, 0.0))) if np.any(excess > 0) else float(np.max(excess))
    return min(joints, floor, trunk)


def _inward_normal(margin, p: np.ndarray) -> np.ndarray | None:
    """Unit gradient of `margin` at `p` (points into the workspace), None where it is not defined."""
    # Forward differences: each margin costs a closed-form IK, so three evaluations, not a Jacobian.
    here = margin(p)
    gradient = np.zeros(3)
    for k in range(3):
        step = np.zeros(3)
        step[k] = _GRADIENT_STEP
        ahead = margin(p + step)
        if ahead == _BEYOND_REACH or here == _BEYOND_REACH:
            return None
        gradient[k] = (ahead - here) / _GRADIENT_STEP
    norm = float(np.linalg.norm(gradient))
    return gradient / norm if norm > 0 else None


def _last_inside(margin, p: np.ndarray, direction: np.ndarray, inside: float, outside: float) -> float:
    """The boundary of {margin >= 0} along p + s * direction, bisected between a parameter s
    `inside` the set and one `outside` it: the last s found inside (never outside)."""
    for _ in range(_BISECTION_STEPS):
        middle = 0.5 * (inside + outside)
        if margin(p + middle * direction) >= 0.0:
            inside = middle
        else:
            outside = middle
    return inside


def slide_in_workspace(margin, p_from: np.ndarray, p_to: np.ndarray) -> tuple[np.ndarray, bool]:
    """(target, clipped): the step p_from -> p_to [m] kept in {margin >= 0}, sliding along its boundary.

    `margin`: p -> margin [m] (e.g. `workspace_margin` with the leg and pose bound); `p_from`
    must be inside. `clipped` is True when the step was changed.
    """
    p = np.asarray(p_from, float).copy()
    remaining = np.asarray(p_to, float) - p
    for _ in range(_MAX_SLIDES):
        if margin(p + remaining) >= 0.0:
            return p + remaining, not np.array_equal(p + remaining, p_to)
        inside = _last_inside(margin, p, remaining, 0.0, 1.0)
        p = p + inside * remaining
        remaining = (1.0 - inside) * remaining
        normal = _inward_normal(margin, p)
        if normal is None:
            break
        outward = min(float(remaining @ normal), 0.0)
        remaining = remaining - outward * normal
        if float(np.linalg.norm(remaining)) < 1e-9:
            break
    return p, True


def step_into_workspace(margin, p: np.ndarray, max_step: float) -> np.ndarray | None:
    """The point of {margin >= 0} nearest to `p` (outside) along the margin's gradient at `p`, at
    most `max_step` [m] away (to the bisection's resolution, on the inside); None when there is none
    that close, or no gradient (beyond the leg's reach)."""
    p = np.asarray(p, float)
    normal = _inward_normal(margin, p)
    if normal is None or margin(p + max_step * normal) < 0.0:
        return None
    return p + _last_inside(margin, p, normal, max_step, 0.0) * normal


def bound_speed(velocity: np.ndarray, max_speed: float) -> tuple[np.ndarray, bool]:
    """(velocity scaled to at most `max_speed` [m/s], whether it was changed). A velocity that is
    not finite (a command so large that its velocity overflowed) is no motion."""
    velocity = np.asarray(velocity, float)
    if not np.isfinite(velocity).all():
        return np.zeros_like(velocity), True
    largest = float(np.max(np.abs(velocity)))
    # The norm of the scaled vector: a huge finite command's square would overflow.
    speed = largest * float(np.linalg.norm(velocity / largest)) if largest > 0.0 else 0.0
    if speed <= max_speed:
        return velocity, False
    return velocity * (max_speed / speed), True


def bound_force(
    velocity: np.ndarray, force_W: np.ndarray, max_force: float, max_speed: float
) -> tuple[np.ndarray, bool]:
    """(velocity, limited): with the environment's force on the foot `force_W` [N] near
    `max_force`, the velocity's component against that force (further into the contact) slowed,
    removed at it and turned into a retreat beyond it (at most `max_speed` [m/s]), as the balance
    bound does (pedi_drake.mission.balance_bound.bound_balance). A foot only stopped at the bound
    overshoots it: the force keeps rising while the foot's tracking error closes."""
    magnitude = float(np.linalg.norm(force_W))
    if magnitude == 0.0:
        return np.asarray(velocity, float), False
    return bound_balance(velocity, force_W, np.asarray(force_W, float) / magnitude, max_force, max_speed)
