"""Switching between the autonomous mission and the teleoperated foot at runtime.

The guarantee: a switch never makes a reference jump. The operator's request for the teleop mode
waits for a safe point, and the teleop sequence is made of the ordinary phases, each of which
starts its trajectory segments where the references are:

  * safe points: a phase boundary (the previous phase ended, the next has not started), or at
    once while the teleop leg is already lifted and every reference is at rest (a held foot);
    in both cases only while the robot stands and, if the leg is on the ground, the other three
    feet carry it (`safe_point`);
  * the sequence (`teleop_sequence`): the leg on the ground is lifted (leg_to_pedipulation: the
    trunk shifts over the other feet first), follows the operator (teleop_foot with the mission
    file's `teleop:` bounds) and is put back (leg_to_support: the trunk re-centres over four
    feet); a leg the mission had lifted is instead brought back to where it was (a reach);
  * afterwards the interrupted phase restarts from the current state (its `start` plans from
    the measured robot and the current references).

The operator's request for the autonomous mode ends the teleop_foot phase (or drops it if it has
not started yet); operator silence ends it too, after the foot has held. Each switch is recorded
as a ModeSwitch.
"""

import numpy as np

from pedi_drake import robot
from pedi_drake.mission import spec
from pedi_drake.mission.progress import SUCCEEDED, MissionProgress, References
from pedi_drake.mission.robot_view import RobotView

AUTONOMOUS, TELEOP = "autonomous", "teleop"
# Reference speeds below this count as at rest [m/s, rad/s] (a quintic's end is exactly 0).
REST_SPEED = 1e-3
# A trunk above this with no stand_up or lie_down run yet counts as standing (the scenario's
# initial pose) [m]: the standing height is 0.28 m, lying under control 0.13 m.
STANDING_MIN_HEIGHT = 0.2
# The reach that brings a foot the mission had lifted back to where teleop found it.
RETURN_TOLERANCE = 0.01  # [m]
RETURN_DURATION = 1.0  # [s]
RETURN_TIMEOUT = 6.0  # [s]
# Time the inserted lift and placing may take beyond their joint motions (trunk shift, contact
# ramps, touch-down, re-centring) before they fail [s].
LEG_TIMEOUT = 4.0


def references_at_rest(refs: References, t: float) -> bool:
    """Whether the body and every lifted leg's reference is still at `t` [s] and nothing presses."""
    if refs.press is not None:
        return False
    if np.linalg.norm(refs.body_position.sample(t).velocity) > REST_SPEED:
        return False
    if np.linalg.norm(refs.body_orientation.sample(t).angular_velocity) > REST_SPEED:
        return False
    return all(np.linalg.norm(leg.trajectory.sample(t).velocity) <= REST_SPEED for leg in refs.legs.values())


def standing(progress: MissionProgress, trunk_height: float) -> bool:
    """Whether the robot stands: the last posture phase that succeeded stood it up (with none,
    the estimated trunk height [m] says)."""
    for record in reversed(progress.records):
        if record.kind in ("stand_up", "lie_down", "leave_prongs") and record.status == SUCCEEDED:
            return record.kind != "lie_down"
    return trunk_height > STANDING_MIN_HEIGHT


def _other_feet_loaded(refs: References, leg: str) -> bool:
    k = robot.LEG_NAMES.index(leg)
    return all(refs.contacts[j] > 0.5 for j in range(4) if j != k)


def safe_point(progress: MissionProgress, view: RobotView, block: spec.TeleopMode) -> str | None:
    """Why the teleop sequence may start now ("phase boundary", "foot held"), or None if not."""
    refs = progress.references
    if progress.interlude or not standing(progress, float(view.base.p_WB[2])):
        return None
    lifted = block.leg in refs.legs
    if not lifted and not _other_feet_loaded(refs, block.leg):
        return None  # another foot is off the ground: lifting this one would leave two
    if not progress.started:
        return "phase boundary"
    if lifted and (progress.ik is None or progress.ik.done) and references_at_rest(refs, view.time):
        return "foot held"
    return None


def teleop_sequence(block: spec.TeleopMode, lifted: bool, p_foot_W: np.ndarray, number: int) -> list[spec.PhaseBase]:
    """The phases of the `number`-th teleop switch: lift (unless `lifted`), teleop, then put the
    leg back, or with `lifted` bring the foot back to `p_foot_W` [m] (world)."""
    name = f"{block.name}_{number}"
    foot = block.foot_phase(name)
    if lifted:
        back = spec.Reach(
            name=f"{name}_return",
            leg=block.leg,
            target=[float(v) for v in p_foot_W],
            frame="world",
            tolerance=RETURN_TOLERANCE,
            duration=RETURN_DURATION,
            hold=0.0,
            timeout=RETURN_TIMEOUT,
        )
        return [foot, back]
    leg, duration = block.leg, block.leg_duration
    lift = spec.LegToPedipulation(
        name=f"{name}_lift",
        leg=leg,
        working_depth=block.working_depth,
        duration=duration,
        timeout=LEG_TIMEOUT + duration,
    )
    place = spec.LegToSupport(name=f"{name}_place", leg=leg, duration=duration, timeout=LEG_TIMEOUT + 1.6 * duration)
    return [lift, foot, place]
