"""The support posture that maximises the SUF at a lifted foot's target (paper 003's SUF as the
objective of the pedipulation posture, chosen once per target before the leg is lifted).

Given the stance (the world positions of the feet that stay on the ground), the lifted leg and
its foot target(s), a posture is the trunk pose X_WB: origin (x, y, z) and attitude (roll,
pitch, yaw). At a posture every leg's joint angles follow from the closed-form leg IK (the stance
feet where they stand, the lifted foot at its target), so the robot's configuration, and with it
the Rejectable Force Polytope of the lifted foot (pedi_drake.suf.problem), is a function of the
six posture numbers. The objective is the smallest SUF over the targets (the foot visits each with
the same posture); a posture counts only where it is feasible:

  * IK reachability: every stance foot and every world target (and every point the foot must
    pass, `reach_only`) has a closed-form solution at least `joint_margin` inside every joint
    limit; a point given in the trunk frame (targets that move with the trunk, and the lift's
    working position `lift_B`, where leg_to_pedipulation takes the foot before any reach) has
    the same joint angles at every posture, so it only has to be within the limits (how close
    to them is the mission's choice, which no posture changes); a target stays clear of the
    trunk's box and above the floor; the working position is at least `lift_height` above the
    floor (a low, pitched trunk would put it into the ground);
  * balance: the centre of mass, projected on the ground, lies at least `com_margin` inside the
    stance feet's support polygon at every target (at rest the capture point is the CoM's
    projection; the controller keeps it in the polygon shrunk by its safety margin);
  * the controller's limits: the torques of the SUF model are the fraction of the effort limits
    the whole-body QP may use, and the posture stays in the box of `PostureLimits`.

`optimise_posture` is a bounded compass (pattern) search from the posture the mission would take
without the optimiser (`start`): deterministic, derivative-free (the SUF is only piecewise
smooth: its active constraint changes), and never worse than its start, which it evaluates
first. `grid_posture` evaluates a full grid, the brute-force reference of the tests.

SUF method: `affine` (paper 003's affine control law, an SOCP): conservative, and measured on
these posture cases at a few milliseconds a posture against seconds for `exact`
(`python -m pedi_drake.benchmarks.posture --methods`), with the same ranking of postures.
Everything here is plain Python and solver calls taking about a second per target: it must never
run inside a control tick (pedi_drake.mission.posture_planner runs it in a worker process).
"""

import dataclasses
import itertools
import math

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

from pedi_drake import robot
from pedi_drake.exceptions import PediError, SufError
from pedi_drake.ik.analytic import leg_ik_solutions
from pedi_drake.polygon import polygon_halfplanes
from pedi_drake.suf.methods import smallest_unrejectable_force
from pedi_drake.suf.problem import ContactPoint, RejectableForceProblem, build_problem

FRAMES = ("world", "trunk")
# The posture's coordinates, in the order of a posture vector.
COORDINATES = ("x", "y", "z", "roll", "pitch", "yaw")
# The whole-body controller's QP may use this fraction of the effort limits (control.config's
# torque_limit_scale): the SUF model gets no more torque than the controller would use.
CONTROLLER_TORQUE_SCALE = 0.9
# The ground's friction coefficient the SUF model assumes [-] (the scenarios' default is 0.8;
# lower is conservative).
DEFAULT_MU = 0.6


@dataclasses.dataclass(frozen=True)
class PostureLimits:
    """The box the optimiser searches and the feasibility margins."""

    # Largest trunk shift from the start posture along x and along y [m].
    shift: float = 0.06
    # Trunk origin height above the ground, lowest and highest [m].
    height: tuple[float, float] = (0.22, 0.30)
    # Largest |roll|, |pitch| [rad] (absolute), and |yaw| [rad] relative to the start's heading.
    roll: float = 0.2
    pitch: float = 0.2
    yaw: float = 0.2
    # Every IK solution the posture sets (stance feet, world points) stays this far inside every
    # joint limit [rad]; a trunk-frame point's does not depend on the posture (see the module
    # docstring).
    joint_margin: float = 0.05
    # The CoM's ground projection stays this far inside the stance feet's polygon [m].
    com_margin: float = 0.05
    # A target's foot centre stays this far from the trunk's box [m].
    trunk_clearance: float = 0.01
    # The foot centre at the lift's working position stays this high above the ground [m].
    lift_height: float = 0.05

    def problems(self) -> list[tuple[str, str]]:
        """(field, problem) for every invalid value; empty when valid."""
        found = []
        for field in ("shift", "roll", "pitch", "yaw", "joint_margin", "com_margin", "trunk_clearance", "lift_height"):
            value = getattr(self, field)
            if not (math.isfinite(value) and value >= 0):
                found.append((field, f"must be a finite number >= 0, got {value}"))
        low, high = self.height
        if not (math.isfinite(low) and math.isfinite(high) and 0 < low <= high):
            found.append(("height", f"expected [lowest, highest] with 0 < lowest <= highest [m], got {self.height}"))
        return found


@dataclasses.dataclass(frozen=True)
class PostureCase:
    """What the optimiser needs to know (plain tuples: it is sent to a worker process and hashed)."""

    # (leg, (x, y, z)) of every foot that stays on the ground, world [m].
    stance_W: tuple[tuple[str, tuple[float, float, float]], ...]
    # The leg whose foot is lifted and works.
    leg: str
    # Foot targets at which the SUF counts, in `frame` [m] ("trunk": the trunk at the posture).
    targets: tuple[tuple[float, float, float], ...]
    frame: str = "world"
    # Further points the foot must reach with the same posture (approach, via, press ends) [m].
    reach_only: tuple[tuple[float, float, float], ...] = ()
    # The lift's working position, trunk frame [m] (the foot goes there first), or None.
    lift_B: tuple[float, float, float] | None = None
    # Prongs on the trunk (their mass counts; they are not contacts here), or None.
    prongs_key: tuple | None = None
    mu: float = DEFAULT_MU

    def problems(self) -> list[tuple[str, str]]:
        """(field, problem) for every invalid value; empty when valid."""
        found = []
        legs = [leg for leg, _ in self.stance_W]
        if self.leg not in robot.LEG_NAMES:
            found.append(("leg", f"must be one of {robot.LEG_NAMES}, got {self.leg!r}"))
        if self.leg in legs or len(set(legs)) != len(legs) or len(legs) < 3:
            found.append(("stance_W", f"expected three or more distinct stance legs other than {self.leg}"))
        if self.frame not in FRAMES:
            found.append(("frame", f"must be one of {FRAMES}, got {self.frame!r}"))
        if not self.targets:
            found.append(("targets", "expected at least one target"))
        points = [p for _, p in self.stance_W] + list(self.targets) + list(self.reach_only)
        points += [] if self.lift_B is None else [self.lift_B]
        if any(len(p) != 3 or not all(math.isfinite(v) for v in p) for p in points):
            found.append(("targets", "every point must be three finite numbers [m]"))
        if not (math.isfinite(self.mu) and self.mu > 0):
            found.append(("mu", f"must be a finite number > 0, got {self.mu}"))
        return found


@dataclasses.dataclass(frozen=True)
class Posture:
    """A trunk pose: origin in the world [m] and roll, pitch, yaw [rad] (Drake's RollPitchYaw)."""

    p_WB: tuple[float, float, float]
    rpy: tuple[float, float, float]

    def vector(self) -> np.ndarray:
        return np.array([*self.p_WB, *self.rpy], float)

    @staticmethod
    def from_vector(v) -> "Posture":
        v = [float(x) for x in v]
        return Posture(tuple(v[0:3]), tuple(v[3:6]))

    def pose(self) -> RigidTransform:
        return RigidTransform(RollPitchYaw(*self.rpy), np.asarray(self.p_WB, float))


@dataclasses.dataclass(frozen=True)
class PostureEvaluation:
    """One posture's verdict."""

    posture: Posture
    feasible: bool
    suf: float  # smallest SUF over the targets [N]; 0 where infeasible
    suf_per_target: tuple[float, ...]  # [N]
    reason: str = ""  # why infeasible
    com_margin: float = math.nan  # smallest CoM distance inside the stance polygon [m]


@dataclasses.dataclass(frozen=True)
class PostureResult:
    """The optimiser's answer."""

    start: PostureEvaluation
    best: PostureEvaluation
    evaluations: int
    method: str
    # The start without the margins (joint limits, CoM inside the polygon): what the start posture
    # gives even where it breaks a margin, for comparison.
    start_reference: PostureEvaluation | None = None


def _joint_limit_distance(q: np.ndarray) -> float:
    """Smallest distance [rad] of (hip, thigh, calf) inside its limits (< 0 outside)."""
    return float(min(np.min(q - robot.Q_LOWER[0:3]), np.min(robot.Q_UPPER[0:3] - q)))


def leg_angles(leg: str, p_B: np.ndarray, joint_margin: float) -> np.ndarray | None:
    """The closed-form solution for the foot of `leg` at `p_B` (trunk frame) [rad] farthest inside
    the joint limits, if it is at least `joint_margin` inside them; else None."""
    try:
        solutions = leg_ik_solutions(leg, p_B)
    except PediError:
        return None
    if not solutions:
        return None
    best = max(solutions, key=_joint_limit_distance)
    return best if _joint_limit_distance(best) >= joint_margin else None


def polygon_margin(points_xy: np.ndarray, p_xy: np.ndarray) -> float:
    """Signed distance [m] of `p_xy` inside the convex polygon of `points_xy` (< 0 outside)."""
    return polygon_margin_and_normal(points_xy, p_xy)[0]


def polygon_margin_and_normal(points_xy: np.ndarray, p_xy: np.ndarray) -> tuple[float, np.ndarray]:
    """(signed distance [m] of `p_xy` inside the convex hull of `points_xy`, the inward unit
    normal of the nearest edge)."""
    N, d = polygon_halfplanes(np.asarray(points_xy, float), 0.0)
    distances = d - N @ np.asarray(p_xy, float)
    nearest = int(np.argmin(distances))
    return float(distances[nearest]), -N[nearest]


def _configurations(case: PostureCase, posture: Posture, limits: PostureLimits):
    """(the 12 joint angles [rad] with the lifted foot at each target, "") at `posture`, or
    (None, why a stance foot, the lift's working position or a point is out of reach)."""
    joint_margin = limits.joint_margin
    X_WB = posture.pose()
    X_BW = X_WB.inverse()
    q = robot.STANDING_Q.copy()
    for leg, p_W in case.stance_W:
        angles = leg_angles(leg, X_BW @ np.asarray(p_W, float), joint_margin)
        if angles is None:
            return None, f"stance foot {leg} out of reach"
        q[robot.leg_slice(leg)] = angles
    if case.lift_B is not None:
        p_B = np.asarray(case.lift_B, float)
        if (X_WB @ p_B)[2] < limits.lift_height:
            return None, "the lift's working position too close to the floor"
        if leg_angles(case.leg, p_B, 0.0) is None:
            return None, f"the lift's working position out of reach of {case.leg}"
    half = np.asarray(robot.TRUNK_HALF_EXTENTS) + robot.FOOT_RADIUS + limits.trunk_clearance
    # A point given in the trunk frame has the same joint angles at every posture: how close they
    # come to a limit is the mission's choice, which no posture changes; it only has to be within
    # the limits. The margin holds where the posture sets the angles (stance feet, world points).
    target_margin = joint_margin if case.frame == "world" else 0.0
    configurations = []
    for k, point in enumerate([*case.targets, *case.reach_only]):
        p = np.asarray(point, float)
        p_B, p_W = (X_BW @ p, p) if case.frame == "world" else (p, X_WB @ p)
        if p_W[2] < robot.FOOT_RADIUS:
            return None, f"point {k} below the floor"
        if np.all(np.abs(p_B) < half):
            return None, f"point {k} inside the trunk"
        angles = leg_angles(case.leg, p_B, target_margin)
        if angles is None:
            return None, f"point {k} out of reach of {case.leg}"
        if k < len(case.targets):
            q[robot.leg_slice(case.leg)] = angles
            configurations.append(q.copy())
    return configurations, ""


def _plant_positions(case: PostureCase, posture: Posture, q: np.ndarray):
    """(plant, its Context at the posture and joint angles `q`, the plant's positions)."""
    plant, plant_map = robot.make_go1_plant(case.prongs_key)
    context = plant.CreateDefaultContext()
    X_WB = posture.pose()
    q_plant = plant_map.full_positions(
        X_WB.rotation().ToQuaternion().wxyz(), X_WB.translation(), q, plant.num_positions()
    )
    plant.SetPositions(context, q_plant)
    return plant, context, q_plant


def balance_margin(case: PostureCase, posture: Posture, limits: PostureLimits) -> tuple[float, np.ndarray] | None:
    """(the smallest CoM distance inside the stance polygon over the targets [m], the inward
    normal of the edge it is nearest), or None when a point is out of reach at `posture`."""
    configurations, _ = _configurations(case, posture, limits)
    if configurations is None:
        return None
    stance_xy = np.array([p[:2] for _, p in case.stance_W], float)
    worst = (math.inf, np.zeros(2))
    for q in configurations:
        plant, context, _ = _plant_positions(case, posture, q)
        found = polygon_margin_and_normal(stance_xy, plant.CalcCenterOfMassPositionInWorld(context)[:2])
        worst = min(worst, found, key=lambda m: m[0])
    return worst


def posture_problems(
    case: PostureCase, posture: Posture, limits: PostureLimits = PostureLimits()
) -> tuple[list[RejectableForceProblem] | None, str, float]:
    """(the Rejectable Force Polytope problem of each target, "", the smallest CoM margin [m]) at
    `posture`, or (None, why the posture is infeasible, the CoM margin or NaN)."""
    configurations, reason = _configurations(case, posture, limits)
    if configurations is None:
        return None, reason, math.nan
    stance_xy = np.array([p[:2] for _, p in case.stance_W], float)
    contacts = [ContactPoint(leg, f"{leg}_foot", np.zeros(3)) for leg, _ in case.stance_W]
    effector = ContactPoint(case.leg, f"{case.leg}_foot", np.zeros(3))
    torque_limits = CONTROLLER_TORQUE_SCALE * robot.EFFORT_LIMIT
    problems, com_margin = [], math.inf
    for q in configurations:
        plant, context, q_plant = _plant_positions(case, posture, q)
        com_margin = min(com_margin, polygon_margin(stance_xy, plant.CalcCenterOfMassPositionInWorld(context)[:2]))
        if com_margin < limits.com_margin:
            return None, "centre of mass too close to the support polygon's edge", com_margin
        try:
            problems.append(build_problem(plant, q_plant, contacts, effector, mu=case.mu, torque_limits=torque_limits))
        except SufError as error:
            return None, f"SUF: {error}", com_margin
    return problems, "", com_margin


def evaluate_posture(
    case: PostureCase, posture: Posture, limits: PostureLimits = PostureLimits(), method: str = "affine"
) -> PostureEvaluation:
    """The smallest SUF over the case's targets at `posture`, or why the posture is infeasible."""
    problems, reason, com_margin = posture_problems(case, posture, limits)
    count = len(case.targets)
    if problems is None:
        return PostureEvaluation(posture, False, 0.0, (0.0,) * count, reason, com_margin)
    try:
        sufs = [smallest_unrejectable_force(problem, method).value for problem in problems]
    except SufError as error:
        return PostureEvaluation(posture, False, 0.0, (0.0,) * count, f"SUF: {error}", com_margin)
    return PostureEvaluation(posture, True, float(min(sufs)), tuple(sufs), "", com_margin)


def balanced_evaluation(
    case: PostureCase, start: Posture, limits: PostureLimits = PostureLimits(), method: str = "affine"
) -> PostureEvaluation:
    """`start` evaluated as a fixed lift would take it: its trunk first shifted (x, y, within the
    box of `limits` about it) until the centre of mass is `com_margin` inside the stance polygon."""
    lower, upper = posture_box(start, limits)
    return evaluate_posture(case, _onto_balance(case, start.vector(), limits, lower, upper), limits, method)


def posture_box(start: Posture, limits: PostureLimits) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) posture vectors of the search box around `start`."""
    x, y, _ = start.p_WB
    yaw = start.rpy[2]
    low, high = limits.height
    lower = np.array([x - limits.shift, y - limits.shift, low, -limits.roll, -limits.pitch, yaw - limits.yaw])
    upper = np.array([x + limits.shift, y + limits.shift, high, limits.roll, limits.pitch, yaw + limits.yaw])
    return lower, upper


# First step of the compass search per coordinate, halved `_HALVINGS` times: 2 cm to 1.25 mm,
# 0.08 rad to 5 mrad.
_FIRST_STEP = np.array([0.02, 0.02, 0.02, 0.08, 0.08, 0.08])
_HALVINGS = 4
# Points per coordinate of the coarse grid the search starts from (x, y, z; the attitude starts
# at the start's) [-], and how many of its best points the compass search refines.
_COARSE_POINTS = (7, 7, 3, 1, 1, 1)
_REFINED_SEEDS = 3
_TRANSLATION = (0, 1, 2)


# Shifts that move the centre of mass back inside the balance margin, at most this many [-].
_BALANCE_STEPS = 3


def _onto_balance(case: PostureCase, v: np.ndarray, limits: PostureLimits, lower, upper) -> Posture:
    """The posture `v`, its trunk shifted (x, y, within the box) until the centre of mass is
    `com_margin` inside the stance polygon if it was not: the search then slides along the
    balance boundary, where the SUF is often largest, instead of stalling at it."""
    v = np.asarray(v, float).copy()
    for _ in range(_BALANCE_STEPS):
        found = balance_margin(case, Posture.from_vector(v), limits)
        if found is None or found[0] >= limits.com_margin:
            break
        # The CoM moves with the trunk (the stance legs' mass a little less): aim 0.1 mm inside.
        v[0:2] = np.clip(v[0:2] + (limits.com_margin - found[0] + 1e-4) * found[1], lower[0:2], upper[0:2])
    return Posture.from_vector(v)


def _search_directions(free: list[int]) -> list[np.ndarray]:
    """Unit steps along every free coordinate and, within the translation, along the diagonals
    of every pair: the feasible set's edges (reach against balance) run diagonally in (x, y, z),
    where a search along the axes alone stalls."""
    directions = []
    for k in free:
        for sign in (1.0, -1.0):
            d = np.zeros(6)
            d[k] = sign
            directions.append(d)
    pairs = [(i, j) for i in _TRANSLATION for j in _TRANSLATION if i < j and i in free and j in free]
    for i, j in pairs:
        for si in (1.0, -1.0):
            for sj in (1.0, -1.0):
                d = np.zeros(6)
                d[i], d[j] = si, sj
                directions.append(d)
    return directions


def optimise_posture(
    case: PostureCase,
    start: Posture,
    limits: PostureLimits = PostureLimits(),
    method: str = "affine",
    *,
    fixed: tuple[str, ...] = (),
) -> PostureResult:
    """The feasible posture of largest SUF found in the box of `limits` around `start`
    (coordinates named in `fixed`, of COORDINATES, stay at the start's values).

    Every posture tried is first shifted back inside the balance margin if it left it
    (`_onto_balance`). First a coarse grid over the trunk's origin (`_COARSE_POINTS`, at the
    start's attitude), then a compass search from each of its best `_REFINED_SEEDS` points:
    each round tries a step along every search direction (`_search_directions`) and moves to the
    best improvement; without one, the steps halve (`_HALVINGS` times). The search runs on the
    trunk's x and y first, then on every free coordinate from the best point found. Feasible beats
    infeasible, then the larger SUF; the start is evaluated first, so the answer is never worse
    than the start. Raises SufError for an invalid case.
    """
    for field, problem in [*case.problems(), *limits.problems()]:
        raise SufError(f"posture case: {field}: {problem}")
    unknown = set(fixed) - set(COORDINATES)
    if unknown:
        raise SufError(f"fixed: unknown coordinates {sorted(unknown)}; choose from {COORDINATES}")
    lower, upper = posture_box(start, limits)
    for k, name in enumerate(COORDINATES):
        if name in fixed:
            lower[k] = upper[k] = start.vector()[k]
    free = [k for k, name in enumerate(COORDINATES) if name not in fixed]
    cache: dict[tuple, PostureEvaluation] = {}

    def evaluate(v: np.ndarray) -> PostureEvaluation:
        key = tuple(np.round(v, 9))
        if key not in cache:
            cache[key] = evaluate_posture(case, _onto_balance(case, v, limits, lower, upper), limits, method)
        return cache[key]

    def rank(evaluation: PostureEvaluation) -> tuple[bool, float]:
        return evaluation.feasible, evaluation.suf

    start_evaluation = evaluate_posture(case, start, limits, method)
    centre = np.clip(start.vector(), lower, upper)
    coarse = []
    for k in range(6):
        points = _COARSE_POINTS[k] if k in free else 1
        coarse.append(np.linspace(lower[k], upper[k], points) if points > 1 else [centre[k]])
    seeds = []
    for values in itertools.product(*coarse):
        found = evaluate(np.array(values))
        seeds.append((found.posture.vector(), found))
    seeds.sort(key=lambda seed: rank(seed[1]), reverse=True)

    def climb(v: np.ndarray, found: PostureEvaluation, directions: list[np.ndarray]) -> PostureEvaluation:
        step = _FIRST_STEP.copy()
        for _ in range(_HALVINGS + 1):
            while True:
                candidates = []
                for d in directions:
                    trial = np.clip(v + d * step, lower, upper)
                    if not np.array_equal(trial, v):
                        candidates.append(evaluate(trial))
                improving = [c for c in candidates if rank(c) > rank(found)]
                if not improving:
                    break
                found = max(improving, key=rank)
                v = found.posture.vector()
            step /= 2.0
        return found

    # The trunk's x and y first (where the feasible set is narrowest), from the best seeds; then
    # every free coordinate from the best of those.
    best = seeds[0][1]
    planar = _search_directions([k for k in free if k in (0, 1)])
    for v, found in seeds[:_REFINED_SEEDS]:
        found = climb(v, found, planar)
        if rank(found) > rank(best):
            best = found
    best = climb(best.posture.vector(), best, _search_directions(free))
    if rank(start_evaluation) > rank(best):
        best = start_evaluation
    reference = start_evaluation
    if not start_evaluation.feasible:
        bare = dataclasses.replace(limits, joint_margin=0.0, com_margin=-math.inf, trunk_clearance=0.0)
        reference = evaluate_posture(case, start, bare, method)
    return PostureResult(start_evaluation, best, len(cache), method, reference)


def grid_posture(
    case: PostureCase,
    start: Posture,
    axes: dict[str, np.ndarray],
    limits: PostureLimits = PostureLimits(),
    method: str = "affine",
) -> list[PostureEvaluation]:
    """Every posture of the grid: the start with the coordinates named in `axes` (of COORDINATES)
    set to each combination of their values (the brute-force reference)."""
    names = list(axes)
    indices = [COORDINATES.index(name) for name in names]
    results = []
    for values in (
        np.array(np.meshgrid(*[np.asarray(axes[n], float) for n in names], indexing="ij")).reshape(len(names), -1).T
    ):
        v = start.vector()
        v[indices] = values
        results.append(evaluate_posture(case, Posture.from_vector(v), limits, method))
    return results
