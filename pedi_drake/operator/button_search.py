"""ButtonSearch: an operator program that finds an E-stop button's cap by touch and presses it.

An operator at a haptic device who cannot see exactly where the foot is against the button (the
robot walked 8 m to it, and its idea of where it stands is off by centimetres) finds it as people
do in the dark: sweep the foot forward at the height of the cap's rim until it bumps into it, do
it again a little to the side, and from how far each sweep went tell where the cap's axis is;
then lift over it, move onto it and press down. Only the haptic feedback's force is read (the
estimated force on the foot, bias removed: pedi_drake.operator.feedback), and only its size: its
direction, from a joint-torque estimate, is too rough to aim by. The foot moves by velocity
commands in the world frame; the robot's heading (which way it faces) is what the operator sees.

Each bump puts the cap's axis on a circle of radius BUMP_RADIUS (the foot's radius and the cap's,
at the sweep height) about where the foot was when it felt the bump; two bumps PROBE_SHIFT apart
sideways put it at the circles' crossing beyond them. The stages, from the robot's offer of the
foot (its teleop_foot phase has begun; the foot where leg_to_pedipulation holds it, the cap
expected 13.7 cm ahead of it and its top 1 cm above it):

  rise      up RISE, to the sweep height: the foot's sphere meets the cap's rim and clears the
            control box under it
  shift     sideways to the sweep's line
  sweep     forward (slowly beyond APPROACH), until the force exceeds CONTACT_FORCE for
            CONTACT_SAMPLES feedback messages in a row (a bump), or the sweep has gone
            SWEEP_LENGTH (then back and sweep again SWEEP_SHIFT to the left, then to the
            right), or, probing, PROBE_BEYOND past the
            first bump or PROBE_REACH from the start (a miss: the cap is on the other side;
            probe there)
  back      back BACK_OFF from the bump (or to the start)
  lift      up LIFT, over the cap's top
  over      onto the cap's axis
  press     down at PRESS_SPEED for PRESS_TIME (the compliant foot stops on the plunger's spring
            while its reference goes on: it pushes harder, under the phase's force bound)
  hold      still, HOLD
  release   up RELEASE
  home      back over the start (the commanded displacement undone), then down to it
  done      asks for the autonomous mode: the mission puts the leg back on the ground

A program gives the command for its state at a time (`command`), returning its next state: the
state is a value, so a LeafSystem can keep it in its Context (pedi_drake.operator.scripted_operator).
"""

import dataclasses
import math

import numpy as np

from pedi_drake.operator.command import FRAME_WORLD, MODE_AUTONOMOUS, MODE_NONE, MODE_TELEOP
from pedi_drake.operator.scripted_operator import ScriptStep

# [m] the sweep height above the start: the foot's centre 14.5 cm up, 0.5 cm over the cap's top
# and its bottom 1.5 cm over the control box.
RISE = 0.015
# [m] forward from the start before a sweep gives up: the cap's rim is met about 10 cm ahead; the
# leg reaches its workspace's edge about 16 cm ahead, where its stretched joints read as a push.
SWEEP_LENGTH = 0.145
SWEEP_SHIFT = 0.03  # [m] sideways between sweeps: the foot finds the cap within 4 cm of its line
SWEEP_OFFSETS = (0.0, 1.0, -1.0)  # the sweeps' lines, in SWEEP_SHIFT to the left of the start's
PROBE_SHIFT = 0.02  # [m] sideways from the first bump's line to the second's
PROBE_BEYOND = 0.03  # [m] a probe that passes the first bump by this much missed ...
PROBE_REACH = 0.155  # [m] ... or goes this far forward from the start (short of the workspace's edge)
# [m] between the foot's centre and the cap's axis, horizontally, when they touch at the sweep
# height: the cap's radius (2 cm) and the foot sphere's section 0.5 cm above its centre (1.94 cm).
BUMP_RADIUS = 0.0394
CONTACT_FORCE = 4.0  # [N] above the estimate's noise and the swept foot's own inertia
CONTACT_SAMPLES = 3  # feedback messages in a row over CONTACT_FORCE
BACK_OFF = 0.02  # [m]
LIFT = 0.035  # [m] the foot's bottom 1.5 cm over the cap's top
PRESS_SPEED = 0.02  # [m/s]
PRESS_TIME = 4.5  # [s]: the foot meets the cap after about 1 s, its reference 7 cm into it at the end
HOLD = 1.0  # [s]
RELEASE = 0.08  # [m]
SPEED = 0.03  # [m/s] of the moves without contact (at twice that: back, over, home, lift)
# [m/s] of the sweeps beyond APPROACH, where the cap may be: the cap is rigid sideways, and in trial
# runs a bump at 1.5 cm/s struck it with about 20 N for a moment (its force bound is 15 N), at
# 0.8 cm/s with about 10 N.
SWEEP_SPEED = 0.008
APPROACH = 0.055  # [m] of each sweep at SPEED: the cap's rim is not expected within 6 cm of the start
AUTONOMOUS = 0.5  # [s] the autonomous request is held this long, then the program ends
ARRIVED = 0.002  # [m] a move to a point is over this close to it


@dataclasses.dataclass(frozen=True)
class SearchState:
    """Where a ButtonSearch is: its stage and since when [s], the sweep line's index, the
    feedback messages over CONTACT_FORCE in a row, the bumps felt ((forward, left) [m] from the
    start, each), the point the stage moves to ((forward, left) [m]; the cap's axis once found),
    the commanded displacement from the start (world [m]) and the previous command's time [s]."""

    stage: str = "rise"
    since: float = 0.0
    sweep: int = 0
    heard: int = 0
    bumps: tuple = ()
    goal: tuple = (0.0, 0.0)
    then: tuple = (0.0, 0.0)  # the next sweep's start, reached sideways once `back` is over
    moved: tuple = (0.0, 0.0, 0.0)
    last: float = 0.0


def cap_axis(first: np.ndarray, second: np.ndarray, radius: float = BUMP_RADIUS) -> np.ndarray | None:
    """(forward, left) [m] of the cap's axis from two bumps felt at `first` and `second` (forward,
    left) [m]: the crossing of the circles of `radius` about them that lies further forward; None
    when they do not cross (the bumps are more than 2 radii apart)."""
    first, second = np.asarray(first, float), np.asarray(second, float)
    between = second - first
    distance = float(np.linalg.norm(between))
    if distance == 0.0 or distance > 2.0 * radius:
        return None
    middle = 0.5 * (first + second)
    across = math.sqrt(radius**2 - (0.5 * distance) ** 2)
    normal = np.array([-between[1], between[0]]) / distance
    a, b = middle + across * normal, middle - across * normal
    return a if a[0] >= b[0] else b


class ButtonSearch:
    """The program of the module docstring for a robot facing `heading` [rad] (world yaw)."""

    def __init__(self, heading: float):
        self.forward = np.array([math.cos(heading), math.sin(heading), 0.0])
        self.left = np.array([-math.sin(heading), math.cos(heading), 0.0])

    @staticmethod
    def initial_state() -> SearchState:
        return SearchState()

    def command(
        self, state: SearchState, t: float, force_W: np.ndarray | None
    ) -> tuple[ScriptStep | None, SearchState]:
        """The command at `t` [s] from the offer, with the latest feedback force `force_W` (3,) [N]
        (None: none yet), and the state after it; None once the program is over."""
        moved = np.asarray(state.moved) + self._velocity(state) * max(t - state.last, 0.0)
        state = self._advance(dataclasses.replace(state, moved=tuple(moved), last=t), t, force_W)
        if state.stage == "over_and_out":
            return None, state
        mode = {"rise": MODE_TELEOP, "done": MODE_AUTONOMOUS}.get(state.stage, MODE_NONE)
        velocity = tuple(float(v) for v in self._velocity(state))
        return ScriptStep(t, velocity, mode_request=mode, frame=FRAME_WORLD), state

    def _plane(self, state: SearchState) -> np.ndarray:
        """(forward, left) [m]: the foot's commanded displacement from the start in the plane."""
        moved = np.asarray(state.moved)
        return np.array([moved @ self.forward, moved @ self.left])

    def _towards(self, state: SearchState, speed: float) -> np.ndarray:
        """The velocity [m/s], world, that moves the foot in the plane toward `state.goal`."""
        error = np.asarray(state.goal) - self._plane(state)
        norm = float(np.linalg.norm(error))
        if norm < ARRIVED:
            return np.zeros(3)
        direction = error / norm
        return min(speed, norm / 0.05) * (direction[0] * self.forward + direction[1] * self.left)

    def _velocity(self, state: SearchState) -> np.ndarray:
        """The foot velocity [m/s], world, of `state`'s stage."""
        up = np.array([0.0, 0.0, 1.0])
        stage = state.stage
        if stage in ("shift", "back", "over", "home"):
            return self._towards(state, 2.0 * SPEED)
        return {
            "rise": SPEED * up,
            "sweep": (SPEED if self._plane(state)[0] < APPROACH else SWEEP_SPEED) * self.forward,
            "lift": 2.0 * SPEED * up,
            "press": -PRESS_SPEED * up,
            "release": 2.0 * SPEED * up,
            "down": -2.0 * SPEED * up,
        }.get(stage, np.zeros(3))

    def _advance(self, state: SearchState, t: float, force_W: np.ndarray | None) -> SearchState:
        """The state after the stage's end test at `t`."""
        elapsed = t - state.since
        plane = self._plane(state)
        moved = np.asarray(state.moved)
        arrived = float(np.linalg.norm(np.asarray(state.goal) - plane)) < ARRIVED

        def to(stage: str, **changes) -> SearchState:
            return dataclasses.replace(state, stage=stage, since=t, heard=0, **changes)

        def line(index: int) -> tuple:
            return (0.0, SWEEP_SHIFT * SWEEP_OFFSETS[index])

        stage = state.stage
        if stage == "rise" and moved[2] >= RISE:
            return to("shift", goal=line(0))
        if stage == "shift" and arrived:
            return to("sweep")
        if stage == "sweep":
            felt = force_W is not None and float(np.linalg.norm(force_W)) > CONTACT_FORCE
            heard = state.heard + 1 if felt else 0
            if heard >= CONTACT_SAMPLES:
                bumps = (*state.bumps, tuple(plane))
                # Straight back first, then sideways: a foot moved sideways along the cap's rim
                # strikes it.
                back = (plane[0] - BACK_OFF, plane[1])
                if len(bumps) == 2:
                    axis = cap_axis(*bumps)
                    if axis is not None:
                        return to("back", bumps=bumps, goal=back, then=back, sweep=-1)
                    bumps = bumps[1:]  # too far apart to be the same cap's: start over from this one
                return to("back", bumps=bumps, goal=back, then=(back[0], plane[1] + PROBE_SHIFT))
            if state.bumps and plane[0] > min(state.bumps[0][0] + PROBE_BEYOND, PROBE_REACH):
                # The probe missed: the cap lies on the first bump's other side.
                first = state.bumps[0]
                back = (first[0] - BACK_OFF, plane[1])
                return to("back", goal=back, then=(back[0], first[1] - PROBE_SHIFT))
            if not state.bumps and plane[0] >= SWEEP_LENGTH:
                if state.sweep + 1 >= len(SWEEP_OFFSETS):
                    return to("release")  # nothing found: the foot goes home
                following = line(state.sweep + 1)
                return to("back", goal=(0.0, plane[1]), then=following, sweep=state.sweep + 1)
            return dataclasses.replace(state, heard=heard)
        if stage == "back" and arrived:
            if state.sweep == -1:  # both bumps felt: over the cap
                return to("lift", goal=tuple(cap_axis(*state.bumps)))
            return to("shift", goal=state.then)
        if stage == "lift" and elapsed >= LIFT / (2.0 * SPEED):
            return to("over")
        if stage == "over" and arrived:
            return to("press")
        timed = {"press": PRESS_TIME, "hold": HOLD, "release": RELEASE / (2.0 * SPEED), "done": AUTONOMOUS}
        following = {"press": "hold", "hold": "release", "release": "home", "done": "over_and_out"}
        if stage in timed and elapsed >= timed[stage]:
            return to(following[stage], goal=(0.0, 0.0))
        if stage == "home" and arrived:
            return to("down")
        if stage == "down" and moved[2] <= 0.0:
            return to("done")
        return state
