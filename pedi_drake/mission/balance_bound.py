"""The balance bound: a lifted foot never pushes harder than a margin of the live SUF in its push direction.

The Rejectable Force Polytope (paper 003) holds the forces F of the environment on the foot that
the stance can take without the robot tipping, slipping or exceeding a torque limit; its extent
along a direction d is the largest such force along d (the "SUF in direction d"; the SUF itself
is the smallest over all directions). The bound keeps the estimated force on the foot along d
below `margin` times that extent, d being the force's own direction:

  * `disturbance_direction`: d = the estimated force's direction once it stands out of the
    estimate's noise; before any contact, the direction a contact ahead of the commanded motion
    would push back along (against the motion); otherwise the previous d;
  * `balance_limit`: margin x the live SUF's extent along d (pedi_drake.suf.live reports it for
    the direction the mission asked about at its previous update; when that direction is more
    than `SAME_DIRECTION` away from d, margin x the SUF, the smallest extent of all);
  * `bound_balance`: the foot's velocity into the contact (against d) is slowed over the last
    `APPROACH` of the limit, stopped at the limit, and beyond it turned into a retreat
    proportional to the excess, so a foot held against a rigid wall settles at the limit.

Plain functions on arrays (the teleop_foot and press runners apply them every mission update).
"""

import math

import numpy as np

from pedi_drake.suf.live import LiveSufReading
from pedi_drake.suf.warm_projection import EXACT, FLAT, INCOMPLETE, INFEASIBLE, NUMERICAL

# An estimated foot force below this has no reliable direction [N] (the joint-torque estimate's
# noise standing still is about 1 N).
FORCE_NOISE = 3.0
# A requested direction within this angle of d counts as d [rad].
SAME_DIRECTION = math.radians(10.0)
# The approach band: over the last 20 % of the limit the speed into the contact falls to zero.
APPROACH = 0.2
# Retreat speed per newton beyond the limit [m/s/N]: 1 cm/s at 5 N over, well below the foot's
# speed bounds, and fast enough that the estimate's lag (one mission update) cannot run away.
RETREAT_GAIN = 0.002


def disturbance_direction(
    force_W: np.ndarray, velocity_W: np.ndarray, previous: np.ndarray | None
) -> np.ndarray | None:
    """The unit direction d of the environment's force on the foot (see the module docstring), or
    None with no estimate, no motion and no previous direction."""
    force_W = np.asarray(force_W, float)
    magnitude = float(np.linalg.norm(force_W))
    if magnitude > FORCE_NOISE:
        return force_W / magnitude
    speed = float(np.linalg.norm(velocity_W))
    if speed > 1e-9:
        return -np.asarray(velocity_W, float) / speed
    return None if previous is None else np.asarray(previous, float)


def balance_limit(suf: LiveSufReading | None, leg_index: int, direction: np.ndarray, margin: float) -> float | None:
    """margin x the live SUF along `direction` [N], or None when there is no live SUF of this leg
    yet (the bound then waits for one); 0 when the stance cannot take any force (the SUF is 0, or
    its computation failed: the foot may not push at all)."""
    if suf is None or suf.leg != leg_index:
        return None
    if suf.status == NUMERICAL:
        return 0.0
    if suf.status not in (EXACT, INCOMPLETE, INFEASIBLE, FLAT):
        return None
    alignment = float(np.dot(suf.request, direction))
    if alignment >= math.cos(SAME_DIRECTION) and math.isfinite(suf.reach):
        extent = suf.reach
    else:
        extent = suf.value if math.isfinite(suf.value) else 0.0
    return margin * max(extent, 0.0)


def bound_balance(
    velocity_W: np.ndarray, force_W: np.ndarray, direction: np.ndarray, limit: float, max_speed: float
) -> tuple[np.ndarray, bool]:
    """(velocity [m/s], whether the bound acted): `velocity_W` with its part against `direction`
    (into the contact) scaled down near `limit` [N] of the force along `direction`, removed at it
    and reversed beyond it (at most `max_speed` [m/s] of retreat)."""
    velocity_W = np.asarray(velocity_W, float)
    d = np.asarray(direction, float)
    along = float(np.dot(force_W, d))
    into = -float(velocity_W @ d)  # speed into the contact [m/s]
    if along >= limit:
        retreat = min(RETREAT_GAIN * (along - limit), max_speed)
        return velocity_W + (max(into, 0.0) + retreat) * d, True
    band = APPROACH * limit
    if into <= 0.0 or along <= limit - band:
        return velocity_W, False
    scale = (limit - along) / band if band > 0.0 else 0.0
    return velocity_W + (1.0 - scale) * into * d, True
