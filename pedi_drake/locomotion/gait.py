"""The static walk's schedule: one swing leg at a time, the centre of mass swayed over the support.

A cycle is six slots: the centre of mass (CoM) shifts to one side with all four feet loaded, the
two legs of the other side swing one after the other, the CoM shifts to the other side, and the
first side's legs swing. For instance (Unitree leg names):

    shift left, swing RR, swing FR, shift right, swing RL, swing FL

Grouping the legs by side lets the CoM stay put sideways through two swings: the two triangles of
a side's swings overlap between the other side's feet and the middle, and the CoM stands there.
Which side swings first and whether a side's hind or front leg leads are chosen per cycle for the
twist commanded (pedi_drake.locomotion.static_walk.choose_cycle): the legs that step outwards,
away from the support, go first, so that no triangle is pinched by a foot that has stepped under
the trunk ("the trailing leg steps first" of the crawl, read for any direction of travel).

A swing slot is `ramp` of unloading (the foot still down, its force ramped away), `swing` in the
air, and `ramp` of loading after the touchdown. The trunk moves along the walking line through
every slot (rest to rest within a slot: a quasi-static gait), so the robot's mean speed is the
stride over the cycle's duration.
"""

import dataclasses
import math

import numpy as np

from pedi_drake.exceptions import PediError

SWING, SHIFT = "swing", "shift"
LEFT, RIGHT = 1.0, -1.0  # the side the CoM stands on, as the sign of its sideways offset


@dataclasses.dataclass(frozen=True)
class Slot:
    """One slot of the cycle: a leg's swing, or the CoM's shift to a side."""

    kind: str  # SWING or SHIFT
    leg: str = ""  # SWING: the leg in the air
    side: float = 0.0  # LEFT or RIGHT: where the CoM stands through the slot (after it, for a shift)


def _cycle(first_side: str, hind_first: bool) -> tuple[Slot, ...]:
    """The six slots with the legs of `first_side` ("R" or "L") swinging first, each side's hind
    leg before its front leg when `hind_first`."""
    second_side = "L" if first_side == "R" else "R"
    order = ("R", "F") if hind_first else ("F", "R")
    stand = {"R": LEFT, "L": RIGHT}  # the CoM stands opposite the swinging side
    slots = []
    for side in (first_side, second_side):
        slots.append(Slot(SHIFT, side=stand[side]))
        slots += [Slot(SWING, f"{end}{side}", stand[side]) for end in order]
    return tuple(slots)


# Every cycle a static walk may take; the first (right legs first, hind legs leading) is the
# forward walk's.
STATIC_WALK_CYCLES = tuple(_cycle(side, hind) for hind in (True, False) for side in ("R", "L"))
CYCLE_LENGTH = 6


@dataclasses.dataclass(frozen=True)
class StaticWalkTiming:
    """How long each part of a static walk's cycle lasts [s], and how far the CoM sways [m]."""

    swing: float = 0.3  # a foot in the air
    ramp: float = 0.06  # a contact's load ramped out before lift-off, or in after touchdown
    shift: float = 0.35  # the CoM crossing to the other side, on four feet
    # The CoM's sideways offset from the walking line while a side's legs swing [m]: about a third
    # of the stance's half width puts it well inside both triangles of that side.
    sway: float = 0.045
    step_height: float = 0.07  # [m] the swing's apex above the higher of lift-off and touchdown

    def __post_init__(self) -> None:
        for name in ("swing", "ramp", "shift", "sway", "step_height"):
            value = getattr(self, name)
            if not value > 0.0:
                raise PediError(f"static walk timing: {name} must be > 0, got {value!r}")

    def duration(self, slot: Slot) -> float:
        """[s] the slot's length."""
        return self.swing + 2.0 * self.ramp if slot.kind == SWING else self.shift

    @property
    def cycle(self) -> float:
        """[s] one cycle of the six slots."""
        return sum(self.duration(slot) for slot in STATIC_WALK_CYCLES[0])

    def stance(self) -> float:
        """[s] how long a foot is down (loaded or ramping) per cycle."""
        return self.cycle - self.swing

    def stride(self, speed: float) -> float:
        """[m] how far each foot moves per cycle at `speed` [m/s]."""
        return speed * self.cycle

    def slowed(self, factor: float) -> "StaticWalkTiming":
        """This timing with its swings and shifts `factor` times as long (the contact ramps, the
        controller's, and the sway and step height as they are)."""
        return dataclasses.replace(self, swing=factor * self.swing, shift=factor * self.shift)


# [-] the friction coefficient of the ground the static walk's timing was measured on (the
# walking benchmark's scenario, pedi_drake.benchmarks.walking).
NOMINAL_WALK_FRICTION = 0.8


def friction_slowdown(mu: float) -> float:
    """The factor s >= 1 by which a static walk on ground of friction coefficient `mu` [-] (the one
    the controllers are given) stretches its swings and shifts and divides its twist.

    Each slot moves the CoM rest to rest by a quintic: with durations s times as long and the twist
    1/s of it, the strides are the same and every acceleration the plan asks for is 1/s^2 of it,
    so the tangential force the feet need for it scales by mu / NOMINAL_WALK_FRICTION, as the
    friction the ground offers does (paper 002 crosses its mu = 0.2 bridge at a slower static walk).
    """
    return max(1.0, math.sqrt(NOMINAL_WALK_FRICTION / mu))


@dataclasses.dataclass(frozen=True)
class GaitLimits:
    """The largest twist a gait takes, per component: forward and sideways speed [m/s], yaw rate
    [rad/s] (each in either direction); a twist past one is refused, not clipped."""

    forward: float
    sideways: float
    yaw_rate: float
    # Whether the sideways speed and the yaw rate share one budget, |sideways| / sideways +
    # |yaw rate| / yaw_rate <= 1 (`turn_limit`). In the static walk a sideways step and a turn move
    # the same swing feet toward the trunk's centre line: each alone at its limit leaves them on
    # their own side at touchdown, both together put a front foot across it, under the other feet
    # (tests/test_static_walk_plan.py).
    sideways_turn_shared: bool = False

    def turn_limit(self, sideways: float) -> float:
        """The largest yaw rate [rad/s] at the sideways speed `sideways` [m/s]."""
        if not self.sideways_turn_shared:
            return self.yaw_rate
        return self.yaw_rate * max(0.0, 1.0 - abs(sideways) / self.sideways)

    def problem(self, twist) -> str | None:
        """Why `twist` (forward, sideways, yaw rate) is past these limits, or None."""
        limits = (self.forward, self.sideways, self.yaw_rate)
        for value, limit, what in zip(twist, limits, ("forward", "sideways", "yaw rate"), strict=True):
            if not abs(value) <= limit:
                return f"{what} {value} is beyond the gait's limit {limit}"
        turn = self.turn_limit(twist[1])
        if not abs(twist[2]) <= turn + 1e-12:
            return (
                f"yaw rate {twist[2]} with sideways speed {twist[1]} is beyond the gait's limit {turn:.3g} "
                f"(sideways speed and yaw rate share one budget: |sideways| / {self.sideways} + |yaw rate| / "
                f"{self.yaw_rate} <= 1)"
            )
        return None

    def held(self, twist) -> np.ndarray:
        """`twist` (forward, sideways, yaw rate) held to these limits: each component saturated,
        then the yaw rate to `turn_limit` of the sideways speed."""
        bounds = np.array([self.forward, self.sideways, self.yaw_rate])
        held = np.clip(np.asarray(twist, float), -bounds, bounds)
        turn = self.turn_limit(held[1])
        held[2] = float(np.clip(held[2], -turn, turn))
        return held


# The gaits a walk may take, and their limits. The static walk's come from its plan on paper
# (pedi_drake.locomotion.static_walk.support_margins): every twist within them keeps the CoM
# SUPPORT_MARGIN inside the support (some combinations a cycle slower), and the stride (0.48 m at the
# forward limit) within the legs' reach.
# The trot's forward limit is the fastest trot the walking benchmark holds on every seed on the
# HQP (pedi_drake.benchmarks.walking --trot-speeds); its sideways and yaw limits are not yet
# measured by a benchmark.
GAITS = {
    "static_walk": GaitLimits(forward=0.2, sideways=0.11, yaw_rate=0.3, sideways_turn_shared=True),
    "trot": GaitLimits(forward=0.8, sideways=0.2, yaw_rate=0.5),
}
