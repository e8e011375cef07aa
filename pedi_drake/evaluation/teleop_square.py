"""The teleoperated square: a scripted operator drives the lifted foot around a square path, and
the true foot is judged against it.

The operator (`square_stream`, on missions/operator/teleop_foot.yaml) asks for the teleoperated
foot from the start and keeps sending, at RATE, what a person with a joystick would: once the
foot is lifted (by APPROACH_START) it moves it APPROACH forward to where the square begins,
waits, then from SQUARE_START sends world-frame foot velocities of SPEED along +x, +z, -x and -z,
SIDE / SPEED each: a vertical square in front of the hip, inside the leg's workspace. Then it stops the foot
and asks for the autonomous mode, and the mission puts the leg back.

`square_errors` judges the true foot (ground truth, which the controller never reads) while the
square is driven (SQUARE_START to its end): its distance to the square path (the polyline through
the four corners, the first one where the true foot was when the square began) and its distance
to the point of the path the operator's command had reached at that time (the commanded motion
integrated: this one also counts the lag of the whole chain, from the operator input to the
motors); and how close the foot came to each corner.
"""

import numpy as np

from pedi_drake.operator.command import FRAME_WORLD, MODE_AUTONOMOUS, MODE_TELEOP
from pedi_drake.operator.message_stream import TimedMessage
from pedi_drake.operator.scripted_operator import ScriptStep, script_stream

MISSION = "operator/teleop_foot"
SIDE = 0.10  # [m]
SPEED = 0.10  # [m/s]: the mission's teleop max_speed, so the bound lets it through unchanged
RATE = 100.0  # [Hz] the operator's messages
# The square's edges in the world, in order (forward, up, back, down).
EDGES = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
# From the lift's working position (15 cm under the hip), forward to the square's first corner [m]:
# the square then lies 10 to 20 cm in front of the hip joint and 5 to 15 cm below it, at least
# 3 cm inside the workspace all round (closer in, its upper corners need the knee past its margin).
APPROACH = 0.10
# Diagram times [s]: the mission's teleop phase starts at about 4.8 s (stand up, shift, lift).
APPROACH_START = 5.5
SQUARE_START = 7.0
SQUARE_END = SQUARE_START + len(EDGES) * SIDE / SPEED
ASK_AUTONOMOUS = SQUARE_END + 0.7
STREAM_END = ASK_AUTONOMOUS + 0.5
# The run: the leg is put back and the robot lies down after the autonomous request.
SIMULATION_DURATION = STREAM_END + 6.0


def square_steps() -> list[ScriptStep]:
    """The operator's script (module docstring)."""
    teleop = dict(mode_request=MODE_TELEOP, frame=FRAME_WORLD)
    steps = [
        ScriptStep(0.0, **teleop),
        ScriptStep(APPROACH_START, tuple(SPEED * EDGES[0]), **teleop),
        ScriptStep(APPROACH_START + APPROACH / SPEED, **teleop),
    ]
    for k, edge in enumerate(EDGES):
        steps.append(ScriptStep(SQUARE_START + k * SIDE / SPEED, tuple(SPEED * edge), **teleop))
    steps.append(ScriptStep(SQUARE_END, **teleop))
    steps.append(ScriptStep(ASK_AUTONOMOUS, mode_request=MODE_AUTONOMOUS, frame=FRAME_WORLD))
    return steps


def square_stream(channel: str) -> list[TimedMessage]:
    """The square operator's messages on `channel`."""
    return script_stream(square_steps(), RATE, STREAM_END, channel)


def commanded_point(t: np.ndarray, corner: np.ndarray) -> np.ndarray:
    """(N, 3) where the operator's command had taken the foot at `t` [s] (N,) from `corner` [m]."""
    elapsed = np.clip(np.asarray(t, float) - SQUARE_START, 0.0, SQUARE_END - SQUARE_START)
    points = np.tile(corner, (len(elapsed), 1))
    duration = SIDE / SPEED
    for k, edge in enumerate(EDGES):
        points += np.outer(np.clip(elapsed - k * duration, 0.0, duration) * SPEED, edge)
    return points


def _distance_to_path(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(N,) distance of each point to the closed polyline through `corners` (4, 3) [m]."""
    best = np.full(len(points), np.inf)
    for a, b in zip(corners, np.roll(corners, -1, axis=0), strict=True):
        ab = b - a
        s = np.clip((points - a) @ ab / (ab @ ab), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points - (a + np.outer(s, ab)), axis=1))
    return best


def square_errors(times: np.ndarray, p_true_W: np.ndarray) -> dict:
    """The true foot `p_true_W` (N, 3) [m] at `times` (N,) [s] (diagram time) against the square:
    {path_max_m, path_rms_m, timed_max_m, timed_rms_m, corner_max_m, samples} (module docstring)."""
    times, p_true_W = np.asarray(times, float), np.asarray(p_true_W, float)
    corner = np.array([np.interp(SQUARE_START, times, p_true_W[:, k]) for k in range(3)])
    corners = corner + SIDE * np.cumsum(np.vstack([np.zeros(3), EDGES[:-1]]), axis=0)
    during = (times >= SQUARE_START) & (times <= SQUARE_END)
    t, p = times[during], p_true_W[during]
    path = _distance_to_path(p, corners)
    timed = np.linalg.norm(p - commanded_point(t, corner), axis=1)
    reached = [float(np.min(np.linalg.norm(p - c, axis=1))) for c in corners]
    return {
        "path_max_m": float(path.max()),
        "path_rms_m": float(np.sqrt(np.mean(path**2))),
        "timed_max_m": float(timed.max()),
        "timed_rms_m": float(np.sqrt(np.mean(timed**2))),
        "corner_max_m": max(reached),
        "samples": int(during.sum()),
        "corner_W": corner.tolist(),
    }
