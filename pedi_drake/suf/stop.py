"""Where a walk should stop before a leg works: the stance whose SUF at the coming targets is largest.

A walk that ends in pedipulation fixes the stance the leg then works from: how far the targets
are from the hips and the support triangle's edges, and so the foot's Smallest Unrejectable Force
(paper 003) at every posture the trunk can take there. Stopping at a fixed offset from the first
target (`fixed`, the trunk's planar pose the mission names) takes whatever SUF that stance gives;
`choose_stop` plans the approach and the manipulation together instead.

A candidate stop is the trunk's planar pose (x, y, yaw) in the world. The walk ends with every foot
under its hip (`StopCase.feet_B`), so a stop fixes the three stance feet; the robot stands at its
walking height and, lifting the leg, shifts its trunk over the three until the centre of mass is
`PostureLimits.com_margin` inside them (`pedi_drake.suf.posture.balanced_evaluation`). The stop's
score is that posture's SUF at the targets, where every target (and every point the foot passes)
is reachable within the joint margins and the stance balances; feasible beats infeasible, then
the larger SUF. The search: the fixed stop first (the answer is never worse), a coarse grid over
the box of `StopLimits` about it, then a compass search from the grid's best, its steps halving.

The lift that follows chooses its own optimal posture at the stance the walk really reached
(`pedi_drake.mission.posture_planner`): the stop's score is the posture a fixed lift takes, one
affine SUF per candidate (its cost: `python -m pedi_drake.benchmarks.posture --methods`), where an
optimised posture per candidate would be a whole optimisation each. A search evaluates about 150
stops (`evaluations` in benchmarks/results/walk_to.json): plain Python and solver calls, never
inside a control tick (the posture planner's worker runs it).
"""

import dataclasses
import itertools
import math

import numpy as np

from pedi_drake import robot
from pedi_drake.exceptions import SufError
from pedi_drake.suf.posture import (
    DEFAULT_MU,
    Posture,
    PostureCase,
    PostureEvaluation,
    PostureLimits,
    balanced_evaluation,
)

# The coarse grid's points per coordinate of the stop (x, y, yaw), spanning the search box.
_COARSE_POINTS = (5, 5, 5)
# The compass search's first step per coordinate [m, m, rad], halved this many times.
_FIRST_STEP = np.array([0.02, 0.02, 0.06])
_HALVINGS = 2


@dataclasses.dataclass(frozen=True)
class StopLimits:
    """The box about the fixed stop the search covers."""

    shift: float = 0.10  # largest move of the stop along the world's x and y [m]
    turn: float = 0.3  # largest turn of the stop's heading [rad]

    def problems(self) -> list[tuple[str, str]]:
        """(field, problem) for every invalid value; empty when valid."""
        return [
            (field, f"must be a finite number >= 0, got {value}")
            for field, value in (("shift", self.shift), ("turn", self.turn))
            if not (math.isfinite(value) and value >= 0.0)
        ]


@dataclasses.dataclass(frozen=True)
class StopCase:
    """What the stop is chosen for (plain tuples: it is sent to a worker process and hashed)."""

    # The leg that works from the stop, and its foot targets in the world [m].
    leg: str
    targets: tuple[tuple[float, float, float], ...]
    # Further points the foot must reach from the same stance (approach, via points) [m].
    reach_only: tuple[tuple[float, float, float], ...] = ()
    # The lift's working position, trunk frame [m], or None.
    lift_B: tuple[float, float, float] | None = None
    # Each foot's x, y under its hip, trunk frame, in robot.LEG_NAMES order [m]: where the walk
    # leaves the feet.
    feet_B: tuple[tuple[float, float], ...] = ()
    height: float = 0.28  # the trunk origin's height above the ground while standing [m]
    ground: float = 0.0  # the ground's height under the stance [m]
    prongs_key: tuple | None = None
    mu: float = DEFAULT_MU

    def posture_case(self, stop: tuple[float, float, float]) -> tuple[PostureCase, Posture]:
        """(the posture case of the stance the walk leaves at `stop` (x, y [m], yaw [rad]), the
        trunk standing there)."""
        x, y, yaw = stop
        c, s = math.cos(yaw), math.sin(yaw)
        z = self.ground + robot.FOOT_RADIUS
        stance = tuple(
            (leg, (x + c * fx - s * fy, y + s * fx + c * fy, z))
            for leg, (fx, fy) in zip(robot.LEG_NAMES, self.feet_B, strict=True)
            if leg != self.leg
        )
        case = PostureCase(
            stance_W=stance,
            leg=self.leg,
            targets=self.targets,
            reach_only=self.reach_only,
            lift_B=self.lift_B,
            prongs_key=self.prongs_key,
            mu=self.mu,
        )
        return case, Posture((x, y, self.ground + self.height), (0.0, 0.0, yaw))


@dataclasses.dataclass(frozen=True)
class StopEvaluation:
    """One stop's verdict: the stop (x, y [m], yaw [rad]) and its posture's evaluation."""

    stop: tuple[float, float, float]
    posture: PostureEvaluation

    @property
    def rank(self) -> tuple[bool, float]:
        return self.posture.feasible, self.posture.suf


@dataclasses.dataclass(frozen=True)
class StopResult:
    """The search's answer: the fixed stop's evaluation, the best found, stops evaluated."""

    fixed: StopEvaluation
    best: StopEvaluation
    evaluations: int


def evaluate_stop(case: StopCase, stop, limits: PostureLimits | None = None) -> StopEvaluation:
    """The stop (x, y [m], yaw [rad]) scored by the balanced posture it leaves (module docstring);
    `limits`: the posture's margins (None: PostureLimits' defaults)."""
    stop = tuple(float(v) for v in stop)
    posture_case, standing = case.posture_case(stop)
    return StopEvaluation(stop, balanced_evaluation(posture_case, standing, limits or PostureLimits()))


def choose_stop(
    case: StopCase,
    fixed: tuple[float, float, float],
    limits: StopLimits = StopLimits(),
    posture_limits: PostureLimits | None = None,
) -> StopResult:
    """The stop of largest SUF in the box of `limits` about the `fixed` stop (x, y [m], yaw
    [rad]); see the module docstring. Raises SufError for an invalid case."""
    for field, problem in limits.problems():
        raise SufError(f"stop limits: {field}: {problem}")
    if len(case.feet_B) != len(robot.LEG_NAMES) or case.leg not in robot.LEG_NAMES or not case.targets:
        raise SufError(f"stop case: expected the leg, its targets and {len(robot.LEG_NAMES)} feet_B")
    centre = np.asarray(fixed, float)
    half = np.array([limits.shift, limits.shift, limits.turn])
    lower, upper = centre - half, centre + half
    cache: dict[tuple, StopEvaluation] = {}

    def evaluate(v: np.ndarray) -> StopEvaluation:
        key = tuple(np.round(v, 9))
        if key not in cache:
            cache[key] = evaluate_stop(case, v, posture_limits)
        return cache[key]

    fixed_evaluation = evaluate(centre)
    best = fixed_evaluation
    axes = [np.linspace(lower[k], upper[k], _COARSE_POINTS[k]) for k in range(3)]
    for values in itertools.product(*axes):
        found = evaluate(np.array(values))
        if found.rank > best.rank:
            best = found
    v, step = np.asarray(best.stop, float), _FIRST_STEP.copy()
    directions = [sign * np.eye(3)[k] for k in range(3) for sign in (1.0, -1.0)]
    for _ in range(_HALVINGS + 1):
        while True:
            trials = [evaluate(np.clip(v + d * step, lower, upper)) for d in directions]
            improving = [trial for trial in trials if trial.rank > best.rank]
            if not improving:
                break
            best = max(improving, key=lambda trial: trial.rank)
            v = np.asarray(best.stop, float)
        step = step / 2.0
    return StopResult(fixed_evaluation, best, len(cache))


@dataclasses.dataclass(frozen=True)
class StopRequest:
    """One stop to choose, for the posture planner's worker (a value: hashed, sent to it)."""

    case: StopCase
    fixed: tuple[float, float, float]
    limits: StopLimits = StopLimits()

    def solve(self) -> StopResult:
        return choose_stop(self.case, self.fixed, self.limits)

    def __deepcopy__(self, memo) -> "StopRequest":
        return self  # a value
