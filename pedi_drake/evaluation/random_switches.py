"""Random mode switches: a seeded operator takes a running mission out of its autonomous mode and
gives it back, again and again, at random times.

`switch_stream(seed, round_trips)` on missions/operator/stand_with_operator_modes.yaml (trunk moves
of half a second, so a request waits at most that long for a phase boundary): after the stand-up
the operator makes `round_trips` round trips, SEMI_ROUND_TRIPS of them semi-autonomous and the
rest teleoperated, in a random order, each two mode switches (there and back):

  * teleop: asks for the teleoperated foot; once the foot can be lifted (LIFT_TIME after the
    request) it moves it with random velocities (trunk frame, up to the speed bound, a new one every
    0.2 to 0.6 s); after a random hold (HOLD, from the request: sometimes before the lift is done,
    which drops the foot phase) it asks for the autonomous mode;
  * semi-autonomous: sends a foot target drawn within TARGET_SPREAD of a reachable point in front
    of the FR foot (world frame); the mission serves it (the optimal posture, then lift, reach and
    return at the default leg_duration, 1.5 s) and comes back on its own.

An interlude's request is not taken while another interlude runs, so the operator waits for the
previous one to end (the leg put back) before the next request, plus a random 0.8 to 1.8 s of
the autonomous mission. The operator sends its current command at RATE throughout.
"""

import dataclasses

import numpy as np

from pedi_drake.operator.command import (
    FRAME_TRUNK,
    FRAME_WORLD,
    KIND_POSITION,
    MODE_AUTONOMOUS,
    MODE_SEMI_AUTONOMOUS,
    MODE_TELEOP,
)
from pedi_drake.operator.message_stream import TimedMessage
from pedi_drake.operator.scripted_operator import ScriptStep, script_stream

MISSION = "operator/stand_with_operator_modes"
SEED = 4242  # of the tests and, unless told otherwise, the benchmark
ROUND_TRIPS = 10  # 20 switches
SEMI_ROUND_TRIPS = 2
RATE = 100.0  # [Hz]
FIRST_REQUEST = 2.5  # [s] after the mission's stand-up (2 s)
# From a teleop request: the next phase boundary (0.5 s at most), the trunk shift, the contact's
# release and the lift (the mission's teleop leg_duration, 0.6 s) are done within LIFT_TIME [s];
# putting the leg back takes at most PLACE_TIME [s] (placing, loading, re-centring the trunk).
LIFT_TIME = 2.6
PLACE_TIME = 2.4
# The autonomous request comes this long after the teleop request [s]: at least longer than a
# phase boundary's wait (an autonomous request before the teleop switch happened cancels it).
HOLD = (0.6, 4.0)
# A semi-autonomous target is served within SEMI_TIME [s] of its request: boundary, posture plan
# (2 s) and move (1.5 s), lift, reach and hold (the mission's leg_duration 1.5 s, hold 0.5 s),
# return and the trunk's way back (1.5 s).
SEMI_TIME = 13.5
GAP = (0.8, 1.8)  # [s] of the autonomous mission between interludes
TARGET_CENTRE_W = np.array([0.40, -0.13, 0.20])  # [m] in front of FR, the trunk at the origin
TARGET_SPREAD = 0.03  # [m]
MAX_SPEED = 0.1  # [m/s] the teleop speed bound of the mission
SETTLE = 1.0  # [s] after the last interlude's end, before the run ends


@dataclasses.dataclass
class SwitchStream:
    messages: list[TimedMessage]
    plan: list[dict]  # per round trip: {mode, request [s], autonomous [s] (teleop), target_W (semi)}
    end: float  # [s] diagram time of the last message

    @property
    def simulation_duration(self) -> float:
        return self.end + SETTLE


def switch_stream(seed: int, round_trips: int = ROUND_TRIPS, channel: str = "operator_foot_command") -> SwitchStream:
    """The random operator's messages (module docstring), drawn from `seed`."""
    rng = np.random.default_rng(seed)
    modes = ["semi"] * SEMI_ROUND_TRIPS + ["teleop"] * (round_trips - SEMI_ROUND_TRIPS)
    modes = [modes[k] for k in rng.permutation(len(modes))]
    steps = [ScriptStep(0.0, mode_request=MODE_AUTONOMOUS)]
    plan = []
    t = FIRST_REQUEST
    for mode in modes:
        if mode == "semi":
            target = TARGET_CENTRE_W + rng.uniform(-TARGET_SPREAD, TARGET_SPREAD, 3)
            steps.append(
                ScriptStep(t, tuple(target), mode_request=MODE_SEMI_AUTONOMOUS, frame=FRAME_WORLD, kind=KIND_POSITION)
            )
            plan.append({"mode": mode, "request": t, "target_W": target.tolist()})
            t += SEMI_TIME + rng.uniform(*GAP)
            continue
        steps.append(ScriptStep(t, mode_request=MODE_TELEOP))
        autonomous = t + rng.uniform(*HOLD)
        moving = t + LIFT_TIME
        while moving < autonomous:
            direction = rng.normal(size=3)
            velocity = rng.uniform(0.0, MAX_SPEED) * direction / np.linalg.norm(direction)
            steps.append(ScriptStep(moving, tuple(velocity), frame=FRAME_TRUNK))
            moving += rng.uniform(0.2, 0.6)
        steps.append(ScriptStep(autonomous, mode_request=MODE_AUTONOMOUS))
        plan.append({"mode": mode, "request": t, "autonomous": autonomous})
        t = max(t + LIFT_TIME, autonomous) + PLACE_TIME + rng.uniform(*GAP)
    end = t
    steps.append(ScriptStep(end, mode_request=MODE_AUTONOMOUS))
    return SwitchStream(script_stream(steps, RATE, end, channel), plan, end)
