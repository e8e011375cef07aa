"""Joint-limit-constrained FABRIK with the compensation phase (paper 000, Sec. III-A, Alg. 1).

One Go1 leg is a fixed-base chain from the hip: hip joint H (abduction, axis e0), thigh joint T
(0.08 m lateral offset along the thigh axis), calf joint C, foot F. Each iteration runs:

1. Forward reaching (foot to base), as in FABRIK: the foot is put on the target t and the calf
   joint on the segment towards its previous position, at the calf length: C' = t + L2 u(C - t).
   The pass stops there: the thigh joint's position depends on the hip angle alone, so the
   backward pass places it from the hip.
2. Backward reaching (base to foot), projecting each joint onto the constraint plane of the
   joint before it and saturating every joint increment at the joint limits:
   - hip: the lateral offset makes the chain non-planar. The thigh and calf move in the leg
     plane, which stays at the lateral offset from the hip and parallel to the hip axis, so the
     hip angle is found in the hip abduction joint's plane (normal e0): the target projected on
     it must lie on the leg plane, i.e. on a tangent from the target to the circle that the
     thigh joint traces. Of the two tangents, the one within limits nearest the current hip
     angle is used.
   - thigh: C' is projected onto the leg plane (the thigh joint's constraint plane) and the
     thigh turned towards it;
   - calf: the target is projected onto the calf joint's plane and the calf turned towards it.
3. Compensation (Algorithm 1), foot to base over calf, thigh, hip: project the foot and the
   target onto the joint's plane (relative to the joint), take the rotation between them about
   the joint axis, skip it below 1e-4 rad, saturate, and update the downstream joints. The
   sweep is repeated (at most `_COMPENSATION_SWEEPS` times) until every rotation is skipped.

The iteration stops within the tolerance, at `max_iterations`, or when an iteration no longer
changes the error (a stall). A stall is the failure the paper reports ("the forward phase
positioned the elbow in a location that, upon projection, returned it to its previous iteration
point"). Here it happens when the target is near the hip's height and the hip chose the tangent
whose leg plane puts the target out of the thigh's range, so on a stall the solver switches to
the other tangent (and back on a second stall); if it is still stuck, which happens only from
starts far from the goal (about 1 in 10^4 random starts), it restarts once from the standing
pose. The best configuration seen is returned; it is always within the limits.

Every joint plane here is spanned by two of the leg's basis vectors (see `analytic.LegChain`),
so the projection matrix of Algorithm 1 reduces to taking two coordinates, written as a complex
number w = z + i x (sagittal joints) or v = y + i z (hip); the angle-axis rotation between two
projected vectors is then the phase of w_target * conj(w_foot), a signed angle about the joint
axis (the re-projection of rho on k_j). Plain float and complex arithmetic keeps a solve
cheap in CPython, where numpy's per-call overhead on 3-vectors would dominate.
"""

import cmath
import dataclasses
import functools
import math

import numpy as np

from pedi_drake import robot
from pedi_drake.exceptions import PediError
from pedi_drake.ik.analytic import LegChain, leg_chain

_PI = math.pi
_TWO_PI = 2.0 * math.pi
_MIN_ROTATION = 1e-4  # [rad] Algorithm 1, line 6: smaller compensation rotations are skipped.
_MIN_PROGRESS = 1e-8  # [m] an iteration that changes the error by less than this has stalled.
_MAX_BRANCH_SWITCHES = 2  # stalls after which the hip tangent is switched before giving up
DEFAULT_MAX_ITERATIONS = 50
# Compensation sweeps per iteration. One sweep (Algorithm 1) is a cyclic-coordinate step and
# converges linearly (x0.05-0.2 per sweep at the knee), so stopping at the first iterate under a
# 1 mm tolerance left a mean error near 0.28 mm. Repeating the sweep, until its rotations fall
# under the skip threshold, costs little and brings the mean near 0.1 mm and the mean
# iteration count at 1 cm from 1.4 to 1.0 (python -m pedi_drake.benchmarks.ik).
_COMPENSATION_SWEEPS = 8


@dataclasses.dataclass(frozen=True)
class LegIkResult:
    """The outcome of one leg IK solve."""

    q: np.ndarray  # (3,) hip, thigh, calf [rad], always within the joint limits
    success: bool  # error <= tol
    error: float  # final foot-centre-to-target distance [m]; inf for a non-finite target
    iterations: int  # full FABRIK iterations (forward, backward, compensation) performed
    # Compensation sweeps (Algorithm 1) over all iterations: one per iteration in the paper's
    # algorithm, here repeated within an iteration until they settle (at least one each).
    compensation_sweeps: int = 0


def extended_leg_q(leg: str) -> np.ndarray:
    """The paper's start: the leg as extended as its calf limit allows, foot under the thigh joint.

    The straight leg (calf 0) is outside the Go1's calf range [-2.818, -0.888] rad, so the calf
    sits at its upper limit and the thigh at half its magnitude (hip, thigh, calf) [rad].
    """
    c = leg_chain(leg)
    calf = c.q_upper[2]
    return np.array([0.0, -0.5 * calf, calf])


def _wrap(angle: float) -> float:
    """`angle` wrapped into [-pi, pi) [rad]."""
    return (angle + _PI) % _TWO_PI - _PI


def _saturate(q: float, q_goal: float, lower: float, upper: float) -> float:
    """Moves a revolute joint from `q` towards the angle `q_goal` (any 2 pi representation).

    Takes the shortest increment; if that crosses a limit but the goal has a representation
    within [lower, upper] (the thigh's range exceeds pi), goes the other way round; otherwise
    saturates at the limit nearer in angle to the goal [rad].
    """
    goal = q + _wrap(q_goal - q)
    if lower <= goal <= upper:
        return goal
    other = goal - _TWO_PI if goal > upper else goal + _TWO_PI
    if lower <= other <= upper:
        return other
    return lower if abs(_wrap(goal - lower)) < abs(_wrap(goal - upper)) else upper


@dataclasses.dataclass(frozen=True)
class _Chain:
    """Per-leg constants of the iteration, as plain floats."""

    base: LegChain
    lat: float
    lat_sq: float
    w_HT: complex
    w_TC: complex
    w_CF: complex
    calf_length: float  # |w_CF| [m]
    phase_TC: float  # direction of the thigh link at zero thigh angle [rad]
    phase_CF: float  # direction of the calf link at zero calf angle [rad]
    lower: tuple[float, float, float]
    upper: tuple[float, float, float]
    restart_q: tuple[float, float, float]  # the standing pose of the leg [rad]


@functools.lru_cache(maxsize=4)
def _chain(leg: str) -> _Chain:
    c = leg_chain(leg)
    return _Chain(
        base=c,
        lat=c.lateral,
        lat_sq=c.lateral**2,
        w_HT=c.w_HT,
        w_TC=c.w_TC,
        w_CF=c.w_CF,
        calf_length=abs(c.w_CF),
        phase_TC=cmath.phase(c.w_TC),
        phase_CF=cmath.phase(c.w_CF),
        lower=c.q_lower,
        upper=c.q_upper,
        restart_q=tuple(float(v) for v in robot.STANDING_Q[robot.leg_slice(leg)]),
    )


def _hip_from_plane(ch: _Chain, q0: float, tv: complex, branch: int) -> float:
    """Backward reaching at the hip: the hip angle whose leg plane holds the projected target.

    `tv` is the target projected on the hip joint's plane (y + i z) [m]. The leg plane is at
    the lateral offset from the hip axis, so the target's coordinate inside it is +-z_plane;
    `branch` +1 or -1 forces that sign, 0 takes the solution within limits nearest `q0` [rad].
    """
    z_plane = math.sqrt(max(tv.real * tv.real + tv.imag * tv.imag - ch.lat_sq, 0.0))
    phase_t = math.atan2(tv.imag, tv.real)
    lo, hi = ch.lower[0], ch.upper[0]
    if branch:
        return _saturate(q0, phase_t - math.atan2(branch * z_plane, ch.lat), lo, hi)
    best, best_key = q0, None
    for z in (z_plane, -z_plane):
        goal = q0 + _wrap(phase_t - math.atan2(z, ch.lat) - q0)
        q = _saturate(q0, goal, lo, hi)
        # Prefer a goal within limits, then the smaller move.
        key = (q != goal, abs(goal - q0))
        if best_key is None or key < best_key:
            best, best_key = q, key
    return best


def _iterate(ch: _Chain, tx: float, ty: float, tz: float, q0: float, q1: float, q2: float, branch: int):
    """One FABRIK iteration; returns the new (q0, q1, q2) [rad] and the compensation sweeps it made."""
    lat, w_HT, w_TC = ch.lat, ch.w_HT, ch.w_TC
    lo, hi = ch.lower, ch.upper
    tv = complex(ty, tz)

    # 1. Forward reaching: foot on the target, calf joint at the calf length towards its old place.
    e1 = cmath.exp(1j * q1)
    w_C = w_HT + e1 * w_TC
    v_C = cmath.exp(1j * q0) * complex(lat, w_C.real)
    dx, dy, dz = w_C.imag - tx, v_C.real - ty, v_C.imag - tz
    n = math.sqrt(dx * dx + dy * dy + dz * dz)
    if n > 1e-12:
        s = ch.calf_length / n
        cx, cy, cz = tx + dx * s, ty + dy * s, tz + dz * s
    else:  # target on the calf joint: keep the joint where it is.
        cx, cy, cz = w_C.imag, v_C.real, v_C.imag

    # 2. Backward reaching with plane projections and saturation.
    q0 = _hip_from_plane(ch, q0, tv, branch)
    r0_inv = cmath.exp(-1j * q0)
    vc = r0_inv * complex(cy, cz)  # C' in the hip frame: (lateral, z)
    u = complex(vc.imag, cx) - w_HT  # C' projected on the leg plane, from the thigh joint
    q1 = _saturate(q1, cmath.phase(u) - ch.phase_TC, lo[1], hi[1])
    e1 = cmath.exp(1j * q1)
    w_C = w_HT + e1 * w_TC
    vt = r0_inv * tv
    w_t = complex(vt.imag, tx)  # target projected on the leg plane
    q2 = _saturate(q2, cmath.phase(w_t - w_C) - ch.phase_CF - q1, lo[2], hi[2])

    # 3. Compensation phase (Algorithm 1), from the foot towards the base.
    sweeps = 0
    for _ in range(_COMPENSATION_SWEEPS):
        q0, q1, q2, rotated = _compensate(ch, w_t, tv, q0, q1, q2)
        sweeps += 1
        if not rotated:
            break
    return q0, q1, q2, sweeps


def _compensate(ch: _Chain, w_t: complex, tv: complex, q0: float, q1: float, q2: float):
    """One compensation sweep (Algorithm 1) over calf, thigh, hip; returns (q0, q1, q2, rotated).

    `w_t` is the target projected on the leg plane, `tv` on the hip joint's plane [m].
    `rotated` is False when every rotation was below the skip threshold of Algorithm 1.
    """
    lo, hi = ch.lower, ch.upper
    e1 = cmath.exp(1j * q1)
    w_C = ch.w_HT + e1 * ch.w_TC
    w_F = w_C + e1 * cmath.exp(1j * q2) * ch.w_CF
    rotated = False
    rho = cmath.phase((w_t - w_C) * (w_F - w_C).conjugate())  # calf
    if abs(rho) > _MIN_ROTATION:
        q2 = _saturate(q2, q2 + rho, lo[2], hi[2])
        w_F = w_C + e1 * cmath.exp(1j * q2) * ch.w_CF
        rotated = True
    rho = cmath.phase((w_t - ch.w_HT) * (w_F - ch.w_HT).conjugate())  # thigh
    if abs(rho) > _MIN_ROTATION:
        q1 = _saturate(q1, q1 + rho, lo[1], hi[1])
        w_F = ch.w_HT + cmath.exp(1j * q1) * (ch.w_TC + cmath.exp(1j * q2) * ch.w_CF)
        rotated = True
    v_F = cmath.exp(1j * q0) * complex(ch.lat, w_F.real)
    rho = cmath.phase(tv * v_F.conjugate())  # hip
    if abs(rho) > _MIN_ROTATION:
        q0 = _saturate(q0, q0 + rho, lo[0], hi[0])
        rotated = True
    return q0, q1, q2, rotated


def _foot_error(ch: _Chain, tx: float, ty: float, tz: float, q0: float, q1: float, q2: float) -> float:
    """Foot-centre-to-target distance [m]."""
    w_F = ch.w_HT + cmath.exp(1j * q1) * (ch.w_TC + cmath.exp(1j * q2) * ch.w_CF)
    v_F = cmath.exp(1j * q0) * complex(ch.lat, w_F.real)
    dx, dy, dz = w_F.imag - tx, v_F.real - ty, v_F.imag - tz
    return math.sqrt(dx * dx + dy * dy + dz * dz)


def solve_leg_ik(
    leg: str,
    p_target_B: np.ndarray,
    q_init: np.ndarray | None = None,
    *,
    tol: float = 1e-3,
    max_iterations: int = DEFAULT_MAX_ITERATIONS,
) -> LegIkResult:
    """Joint angles (hip, thigh, calf) [rad] of `leg` placing its foot centre at `p_target_B`.

    Args:
        leg: FR, FL, RR or RL.
        p_target_B: foot-centre target in the trunk frame [m], shape (3,).
        q_init: the leg's start angles (hip, thigh, calf) [rad]; the standing pose if None.
            Angles outside the limits are clipped onto them first.
        tol: success threshold on the foot-to-target distance [m].
        max_iterations: iteration budget.

    Returns:
        LegIkResult; `q` is always within the joint limits. An unreachable target gives the
        closest configuration found and success=False. A non-finite target (NaN, inf) gives
        success=False, error=inf, iterations=0 and q = the clipped start angles.

    Raises:
        PediError: unknown leg, or a target / q_init of the wrong shape or a non-finite q_init.
    """
    robot.leg_slice(leg)  # validates the leg name
    ch = _chain(leg)
    lo, hi = ch.lower, ch.upper
    if q_init is None:
        q_init = robot.STANDING_Q[robot.leg_slice(leg)]
    q_start = np.asarray(q_init, dtype=float)
    p = np.asarray(p_target_B, dtype=float)
    if q_start.shape != (3,) or not np.all(np.isfinite(q_start)):
        raise PediError(f"{leg}: q_init must be 3 finite angles [rad], got {q_init!r}")
    if p.shape != (3,):
        raise PediError(f"{leg}: p_target_B must have shape (3,), got {p.shape}")
    q0, q1, q2 = (min(max(float(q_start[k]), lo[k]), hi[k]) for k in range(3))
    if not (math.isfinite(p[0]) and math.isfinite(p[1]) and math.isfinite(p[2])):
        return LegIkResult(q=np.array([q0, q1, q2]), success=False, error=math.inf, iterations=0)

    tx, ty, tz = ch.base.to_local(p)
    error = _foot_error(ch, tx, ty, tz, q0, q1, q2)
    best = (error, q0, q1, q2)
    branch, switches, just_switched = 0, 0, False
    restarted = (q0, q1, q2) == ch.restart_q  # a restart from the start itself would repeat it
    iterations = sweeps = 0
    while error > tol and iterations < max_iterations:
        iterations += 1
        q0, q1, q2, made = _iterate(ch, tx, ty, tz, q0, q1, q2, branch)
        sweeps += made
        previous = error
        error = _foot_error(ch, tx, ty, tz, q0, q1, q2)
        if error < best[0]:
            best = (error, q0, q1, q2)
        if just_switched:  # the first iteration on the other tangent may move away first
            just_switched = False
        elif error > tol and abs(previous - error) < _MIN_PROGRESS:
            # Stalled: the iteration returned to where it was (an iteration that moves away,
            # e.g. the first one from a poor start, is not a stall; `best` keeps the best).
            if switches == _MAX_BRANCH_SWITCHES:
                if restarted:
                    break
                # Still stuck (the compensation phase can hold the hip in a local minimum when
                # the start is far from the goal): restart once from the standing pose.
                q0, q1, q2 = ch.restart_q
                branch, switches, just_switched, restarted = 0, 0, True, True
                continue
            # Switch the leg plane to the other side of the target (see module doc); the
            # target's z in the current leg plane tells which tangent is in use. A second
            # stall switches back.
            if branch == 0:
                branch = -1 if (cmath.exp(-1j * q0) * complex(ty, tz)).imag > 0.0 else 1
            else:
                branch = -branch
            switches += 1
            just_switched = True
    error, q0, q1, q2 = best
    return LegIkResult(
        q=np.array([q0, q1, q2]), success=error <= tol, error=error, iterations=iterations, compensation_sweeps=sweeps
    )
