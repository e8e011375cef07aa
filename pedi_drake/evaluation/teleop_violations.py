"""Violations of the teleoperated foot's bounds, counted from a run's logs.

While a teleop_foot phase runs (pedi_drake.mission.teleop_foot), each mission update makes a
reference segment from where the foot reference is to that update's target, and each controller
tick (2 ms) samples it. The logs hold both (mission.leg_reference), the trunk pose each update saw
(base_state: a state output, logged before the updates of its instant, as the mission reads it),
the force estimate the force bound acted on (mission.operator_feedback) and go1.command.
Counted, each with a tolerance for rounding (ROUNDING, ROUNDING_LENGTH):

  * workspace: an update whose target (its segment's end) is outside the leg's workspace at the
    trunk pose that update saw: `workspace_margin` < 0 (the closed-form IK at least the phase's
    joint_margin inside every joint limit, the foot min_height above the ground, clear of the
    trunk);
  * speed: a controller tick over which the foot reference moved faster than the phase's
    max_speed, or whose reference velocity is faster;
  * force: an update whose estimated contact force exceeded the phase's max_force while its
    segment took the foot further into that contact (along minus the force);
  * nonfinite_command: a controller tick whose go1.command holds a value that is not finite (over
    the whole run).

`min_tick_margin_m` adds, for information, the smallest workspace margin of the foot reference at
any controller tick of the phases against the trunk estimate of that same tick: between updates
the trunk estimate moves on under a target made at the previous one.
"""

import numpy as np
from pydrake.math import RigidTransform

from pedi_drake import robot
from pedi_drake.control.references import LEG_BLOCK, LEG_MODE_FOOT
from pedi_drake.estimation.base_state import BaseState
from pedi_drake.mission import spec
from pedi_drake.mission.teleop_bounds import workspace_margin
from pedi_drake.run_logs import SignalLog

VIOLATIONS = ("workspace", "speed", "force", "nonfinite_command")
ROUNDING = 1e-9  # [-] relative
# [m] absolute: a target's round trip through the world frame and back moves it by about 1e-16 m.
ROUNDING_LENGTH = 1e-12


def teleop_phase_spec(mission: spec.MissionSpec, name: str) -> spec.TeleopFoot:
    """The teleop_foot phase `name` of `mission`: one of its phases, or one its `teleop:` block
    inserted (named `<block name>_<number>`, pedi_drake.mission.mode_switch)."""
    for phase in mission.phases:
        if phase.name == name and isinstance(phase, spec.TeleopFoot):
            return phase
    block = mission.teleop
    if block is not None and name.startswith(f"{block.name}_"):
        return block.foot_phase(name)
    raise KeyError(f"{mission.name}: no teleop_foot phase {name!r}")


def _index(times: np.ndarray, t: float) -> int:
    """The sample at `t` [s] (the log's grid holds every update time)."""
    i = int(np.clip(np.searchsorted(times, t - 1e-9), 0, len(times) - 1))
    if abs(times[i] - t) > 1e-6:
        raise ValueError(f"no log sample at t = {t:.6f} s (nearest {times[i]:.6f} s)")
    return i


def _pose(base: np.ndarray, i: int) -> RigidTransform:
    return BaseState.from_vector(base[:, i]).pose()


def phase_violations(
    logs: dict[str, SignalLog], phase: spec.TeleopFoot, t_start: float, t_end: float, mission_period: float
) -> tuple[dict[str, int], float]:
    """({violation: count} of one teleop_foot phase run from `t_start` to `t_end` [s] (without
    nonfinite_command, a whole-run count), the smallest per-tick workspace margin [m])."""
    legs, base, feedback = logs["mission.leg_reference"], logs["base_state"], logs["mission.operator_feedback"]
    times = legs.times
    k = robot.LEG_NAMES.index(phase.leg)
    block = legs.data[k * LEG_BLOCK : (k + 1) * LEG_BLOCK]
    counts = dict.fromkeys(VIOLATIONS[:3], 0)

    def margin(p_W: np.ndarray, X_WB: RigidTransform) -> float:
        return workspace_margin(phase.leg, X_WB.inverse() @ p_W, X_WB, phase.joint_margin, phase.min_height)

    # The mission's updates after the phase's first (which only starts it: a segment at rest).
    first = int(np.floor(t_start / mission_period + 0.5)) + 1
    # ... up to the one that ended it, or the last whose segment the log holds to its end.
    last = min(int(np.floor(t_end / mission_period + 0.5)), int(np.floor(times[-1] / mission_period + 1e-9)))
    for n in range(first, last):
        t = n * mission_period
        i, j = _index(times, t), _index(times, t + mission_period)
        if round(block[0, j]) != LEG_MODE_FOOT:
            continue
        start, target = block[1:4, i], block[1:4, j]
        if margin(target, _pose(base.data, i)) < -ROUNDING_LENGTH:
            counts["workspace"] += 1
        leg, force = feedback.data[0, j], feedback.data[1:4, j]
        magnitude = float(np.linalg.norm(force))
        if round(leg) == k and magnitude > phase.max_force * (1.0 + ROUNDING):
            into_contact = float((target - start) @ (-force / magnitude))
            counts["force"] += int(into_contact > ROUNDING_LENGTH)
    # Every controller tick the phase's segments cover.
    modes = np.round(block[0]).astype(int)
    ticks = np.flatnonzero((times > t_start + 1e-9) & (times <= t_end + 1e-9))
    # The first foot reference of the phase may follow a joint reference (the lift's): a mode
    # change, whose step is a switch's (pedi_drake.evaluation.reference_steps), not a speed.
    ticks = ticks[(ticks > 0) & (modes[ticks] == LEG_MODE_FOOT) & (modes[ticks - 1] == LEG_MODE_FOOT)]
    limit = phase.max_speed * (1.0 + ROUNDING)
    min_margin = np.inf
    for i in ticks:
        moved = float(np.linalg.norm(block[1:4, i] - block[1:4, i - 1]))
        too_fast = moved > limit * (times[i] - times[i - 1]) + ROUNDING_LENGTH
        too_fast |= float(np.linalg.norm(block[4:7, i])) > limit
        counts["speed"] += int(too_fast)
        min_margin = min(min_margin, margin(block[1:4, i], _pose(base.data, i)))
    return counts, float(min_margin)


def teleop_violations(
    logs: dict[str, SignalLog], mission: spec.MissionSpec, phases: list[dict], mission_period: float
) -> dict:
    """Violations over every teleop_foot phase that ran of `phases` (result.json's rows: name, kind,
    status, t_start, t_end; a phase still running ends at the last log sample), and of go1.command over
    the run: {violation: count, total, per_phase: [{phase, counts, min_tick_margin_m}]}."""
    end = float(logs["mission.leg_reference"].times[-1])
    totals = dict.fromkeys(VIOLATIONS, 0)
    per_phase = []
    for row in phases:
        if row["kind"] != "teleop_foot" or row["status"] == "skipped":
            continue
        phase = teleop_phase_spec(mission, row["name"])
        t_end = row["t_end"] if row["t_end"] is not None else end
        counts, min_margin = phase_violations(logs, phase, row["t_start"], t_end, mission_period)
        per_phase.append({"phase": row["name"], "counts": counts, "min_tick_margin_m": min_margin})
        for name, count in counts.items():
            totals[name] += count
    totals["nonfinite_command"] = int(np.count_nonzero(~np.isfinite(logs["go1.command"].data).all(axis=0)))
    return {**totals, "total": sum(totals.values()), "per_phase": per_phase}
