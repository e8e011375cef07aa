"""The static walk's plan, one slot at a time (pedi_drake.locomotion.gait has the cycle).

A slot's plan says where the walking line (pedi_drake.locomotion.footholds) will be at the slot's
end, where the centre of mass (CoM) goes over the slot (a straight line in the ground plane, rest
to rest), and, for a swing, where the foot lands. The walk phase plans each slot as it starts, at
the twist commanded then, so a twist that changes (a stick, a goal coming near) takes effect at
the next slot.

`support_margins` replays plans on paper: the CoM's distance inside the support polygon of the
loaded feet through every slot, the property the gait is built for.
"""

import dataclasses

import numpy as np

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.locomotion.footholds import NOMINAL_FEET_B, PlanarPose, foothold_W, support_margin
from pedi_drake.locomotion.gait import STATIC_WALK_CYCLES, SWING, Slot, StaticWalkTiming
from pedi_drake.numerics.daqp_kernel import AUTOMATIC_FIXED_POINT, solve_qp, solved
from pedi_drake.polygon import polygon_halfplanes


@dataclasses.dataclass(frozen=True)
class SlotPlan:
    """What one slot of the static walk does."""

    slot: Slot
    t0: float  # [s] the slot's start
    duration: float  # [s]
    line_start: PlanarPose  # the walking line at the slot's start
    line_end: PlanarPose  # ... and at its end
    com_start_xy: np.ndarray  # (2,) the CoM's target at the slot's start, world [m]
    com_end_xy: np.ndarray  # (2,) ... at its end
    foothold_xy: np.ndarray | None  # (2,) SWING: where the foot lands, world [m]

    def __deepcopy__(self, memo) -> "SlotPlan":
        return self  # a value

    @property
    def t_end(self) -> float:
        return self.t0 + self.duration


# [m] how far from its place under its hip a foot may land, horizontally: the stance's half stride
# at the forward limit (0.21 m) and a margin, inside the leg's reach at the walking height.
FOOTHOLD_REACH = 0.23
# [m] how far inside the support the plan keeps the CoM: beyond the controllers' own margin for
# the capture point (`safety_margin`, 3 cm), so their balance task has nothing to correct.
SUPPORT_MARGIN = 0.04


def _support(feet_xy: np.ndarray, lifted: str) -> np.ndarray:
    return np.array([feet_xy[k] for k, leg in enumerate(robot.LEG_NAMES) if leg != lifted])


def closest_point_inside(N: np.ndarray, d: np.ndarray, p: np.ndarray) -> np.ndarray | None:
    """The point (2,) of {x: N x <= d} nearest `p` [m]; None if the set is empty."""
    y, multipliers = np.zeros(2), np.zeros(len(d))
    exit_flag = solve_qp(
        np.eye(2),
        -np.asarray(p, float),
        np.ascontiguousarray(N),
        np.ascontiguousarray(d),
        np.full(len(d), -1e30),
        np.zeros(len(d), dtype=np.int32),
        0.0,
        AUTOMATIC_FIXED_POINT,
        0.0,
        y,
        multipliers,
    )
    return y if solved(exit_flag) else None


def plan_slot(
    cycle: tuple[Slot, ...],
    index: int,
    t0: float,
    line: PlanarPose,
    com_xy: np.ndarray,
    feet_xy: np.ndarray,
    twist: np.ndarray,
    timing: StaticWalkTiming,
    margin: float = SUPPORT_MARGIN,
) -> SlotPlan:
    """The plan of slot `index` of `cycle` starting at `t0` [s] with the walking line at `line`,
    the CoM at `com_xy` [m], the feet at `feet_xy` (4, 2) [m], at `twist` (forward [m/s], sideways
    [m/s], yaw rate [rad/s]), the CoM kept `margin` [m] inside the supports.

    The CoM ends the slot where the support of this slot and that of the next overlap (both shrunk
    by `margin`), at the point of that overlap nearest its place on the walking line swayed
    to the side of the next swing: it moves in a straight line within this slot's support, and
    the next slot can start at once. Raises PediError if the supports do not overlap (a foothold too far).
    """
    slot = cycle[index]
    duration = timing.duration(slot)
    line_end = line.moved(twist, duration)
    feet_after = np.array(feet_xy, float)
    foothold = None
    if slot.kind == SWING:
        to_mid_stance = timing.ramp + timing.swing + 0.5 * timing.stance()
        foothold = foothold_W(slot.leg, line, twist, to_mid_stance)
        under_hip = line_end.to_world(NOMINAL_FEET_B[robot.LEG_NAMES.index(slot.leg)])
        if np.linalg.norm(foothold - under_hip) > FOOTHOLD_REACH:
            raise PediError(f"static walk: {slot.leg}'s foothold is beyond {FOOTHOLD_REACH} m of its hip at touchdown")
        feet_after[robot.LEG_NAMES.index(slot.leg)] = foothold
    next_slot = cycle[(index + 1) % len(cycle)]
    N_now, d_now = polygon_halfplanes(_support(feet_xy, slot.leg), margin)
    N_next, d_next = polygon_halfplanes(_support(feet_after, next_slot.leg), margin)
    swayed = line_end.to_world(np.array([0.0, next_slot.side * timing.sway]))
    com_end = closest_point_inside(np.vstack([N_now, N_next]), np.concatenate([d_now, d_next]), swayed)
    if com_end is None:
        raise PediError(
            f"static walk: no CoM position keeps {margin} m inside the supports of {slot} and the next slot"
        )
    return SlotPlan(
        slot=slot,
        t0=t0,
        duration=duration,
        line_start=line,
        line_end=line_end,
        com_start_xy=np.asarray(com_xy, float),
        com_end_xy=com_end,
        foothold_xy=foothold,
    )


def plan_cycle(
    cycle: tuple[Slot, ...], t0: float, line: PlanarPose, com_xy: np.ndarray, feet_xy: np.ndarray, twist, timing
) -> list[SlotPlan]:
    """The plans of every slot of `cycle` from `t0` [s] at a constant `twist` (see plan_slot);
    PediError if one has no CoM position."""
    plans, feet = [], np.array(feet_xy, float)
    for index in range(len(cycle)):
        plan = plan_slot(cycle, index, t0, line, com_xy, feet, twist, timing)
        if plan.foothold_xy is not None:
            feet[robot.LEG_NAMES.index(plan.slot.leg)] = plan.foothold_xy
        plans.append(plan)
        t0, line, com_xy = plan.t_end, plan.line_end, plan.com_end_xy
    return plans


# The shares of the commanded twist a cycle tries, largest first, when the full twist has no plan:
# some combinations within the limits (fast sideways while turning the same way) move a front foot
# too far for one cycle; the walk slows for that cycle rather than fail.
TWIST_SCALES = (1.0, 0.75, 0.5, 0.25, 0.0)


def choose_cycle(
    line: PlanarPose, com_xy: np.ndarray, feet_xy: np.ndarray, twist, timing: StaticWalkTiming
) -> tuple[tuple[Slot, ...], float] | None:
    """The cycle of STATIC_WALK_CYCLES for the next cycle at `twist`, and the share of the twist it
    walks at: the largest of TWIST_SCALES for which some cycle has a CoM position in every slot,
    and among those cycles the one keeping the CoM nearest its swayed places on the walking line
    (summed over the slots' ends). None if no cycle has one even at rest."""
    for scale in TWIST_SCALES:
        scaled = scale * np.asarray(twist, float)
        best, best_cost = None, np.inf
        for cycle in STATIC_WALK_CYCLES:
            try:
                plans = plan_cycle(cycle, 0.0, line, com_xy, feet_xy, scaled, timing)
            except PediError:
                continue
            places = [
                plan.line_end.to_world(np.array([0.0, _side_after(cycle, k) * timing.sway]))
                for k, plan in enumerate(plans)
            ]
            cost = sum(np.linalg.norm(plan.com_end_xy - place) for plan, place in zip(plans, places, strict=True))
            if cost < best_cost:
                best, best_cost = cycle, cost
        if best is not None:
            return best, scale
    return None


def replan_slot(
    cycle: tuple[Slot, ...],
    index: int,
    t0: float,
    line: PlanarPose,
    com_xy: np.ndarray,
    feet_xy: np.ndarray,
    twist,
    timing: StaticWalkTiming,
) -> tuple[SlotPlan, float]:
    """Slot `index` of a cycle under way, planned from where the feet really landed: at the largest
    of TWIST_SCALES that has a plan, the CoM SUPPORT_MARGIN inside; failing that (feet that landed
    a few centimetres off their footholds), at rest with half the margin, still beyond what the
    controllers' capture point task needs. Returns the plan and the twist's share; PediError if
    even that has none."""
    for margin in (SUPPORT_MARGIN, 0.5 * SUPPORT_MARGIN):
        for scale in TWIST_SCALES if margin == SUPPORT_MARGIN else (0.0,):
            try:
                plan = plan_slot(
                    cycle, index, t0, line, com_xy, feet_xy, scale * np.asarray(twist, float), timing, margin
                )
            except PediError:
                continue
            return plan, scale
    return plan_slot(cycle, index, t0, line, com_xy, feet_xy, np.zeros(3), timing, 0.5 * SUPPORT_MARGIN), 0.0


def _side_after(cycle: tuple[Slot, ...], index: int) -> float:
    return cycle[(index + 1) % len(cycle)].side


def support_margins(
    feet_xy: np.ndarray, line: PlanarPose, twist: np.ndarray, timing: StaticWalkTiming, cycles: int, samples: int = 20
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Replays `cycles` cycles on paper from feet at `feet_xy` (4, 2) [m] and the CoM on `line`
    (not swayed), each cycle chosen as the walk chooses it: per slot, the smallest distance [m] of
    the CoM inside the polygon of the feet down through the slot (the swing leg's excluded); the
    share of the twist each cycle walked at (TWIST_SCALES); and the feet at the end (4, 2) [m].
    PediError if a cycle has no plan."""
    feet = np.array(feet_xy, float)
    com = line.xy
    margins, scales = [], []
    for _ in range(cycles):
        chosen = choose_cycle(line, com, feet, twist, timing)
        if chosen is None:
            raise PediError(f"static walk: no cycle keeps the CoM inside the support at twist {list(twist)}")
        cycle, scale = chosen
        scales.append(scale)
        for plan in plan_cycle(cycle, 0.0, line, com, feet, scale * np.asarray(twist, float), timing):
            support = _support(feet, plan.slot.leg)
            # The CoM moves in a straight line between its targets (a rest-to-rest quintic).
            path = [com + s * (plan.com_end_xy - com) for s in np.linspace(0.0, 1.0, samples)]
            margins.append(min(support_margin(support, p) for p in path))
            if plan.foothold_xy is not None:
                feet[robot.LEG_NAMES.index(plan.slot.leg)] = plan.foothold_xy
            line, com = plan.line_end, plan.com_end_xy
    return np.array(margins), np.array(scales), feet
