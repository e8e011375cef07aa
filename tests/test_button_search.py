"""The operator that finds an E-stop button's cap by touch (pedi_drake.operator.button_search):
the cap's axis from two bumps, hand-worked, and the whole program against a cap it can only
feel, the foot following its commands exactly."""

import math

import numpy as np
import pytest

from pedi_drake.operator.button_search import BUMP_RADIUS, RISE, ButtonSearch, cap_axis
from pedi_drake.operator.command import FRAME_WORLD, MODE_AUTONOMOUS

PERIOD = 0.01  # [s] between two commands


def test_two_bumps_put_the_cap_at_the_crossing_beyond_them():
    # A cap 10 cm ahead and 1 cm to the left: a sweep along the start's line meets it where the
    # foot is BUMP_RADIUS from its axis, as does one 2 cm to the left.
    axis = np.array([0.10, 0.01])
    bumps = [np.array([axis[0] - math.sqrt(BUMP_RADIUS**2 - (axis[1] - y) ** 2), y]) for y in (0.0, 0.02)]
    np.testing.assert_allclose(cap_axis(*bumps), axis, atol=1e-12)
    assert cap_axis(np.zeros(2), np.array([0.0, 0.1])) is None


def _search(heading: float, cap_plane: np.ndarray, noise: float, seed: int):
    """The program's run against a cap at `cap_plane` (forward, left) [m] from the foot's start for
    a robot facing `heading`: the foot goes where it is told; at the sweep height it feels 6 N
    within BUMP_RADIUS of the cap's axis, over it from above 5 N, and `noise` [N] of estimate noise
    on each axis otherwise. Returns the foot's world positions while pressing and the last mode."""
    rng = np.random.default_rng(seed)
    program = ButtonSearch(heading)
    forward = np.array([math.cos(heading), math.sin(heading)])
    left = np.array([-math.sin(heading), math.cos(heading)])
    cap_W = cap_plane[0] * forward + cap_plane[1] * left
    foot, state, t = np.zeros(3), program.initial_state(), 0.0
    pressing, modes = [], []
    while t < 120.0:
        horizontal = float(np.linalg.norm(foot[:2] - cap_W))
        force = rng.normal(0.0, noise, 3)
        if abs(foot[2] - RISE) < 1e-3 and horizontal <= BUMP_RADIUS:
            force += np.array([-6.0, 0.0, 0.0])
        if foot[2] < RISE and horizontal < 0.02:
            force += np.array([0.0, 0.0, 5.0])
        step, state = program.command(state, t, force)
        if step is None:
            break
        assert step.frame == FRAME_WORLD
        modes.append(step.mode_request)
        if state.stage == "press":
            pressing.append(foot.copy())
        foot = foot + PERIOD * np.asarray(step.value)
        t += PERIOD
    return np.array(pressing), modes, t


@pytest.mark.parametrize(
    "heading, cap, seed",
    [(0.0, (0.137, 0.0), 0), (math.pi, (0.172, -0.05), 1), (math.pi, (0.102, 0.035), 2), (0.5, (0.12, 0.05), 3)],
)
def test_the_search_presses_on_the_caps_axis_and_hands_the_foot_back(heading, cap, seed):
    pressing, modes, t = _search(heading, np.array(cap), noise=0.8, seed=seed)
    forward = np.array([math.cos(heading), math.sin(heading)])
    left = np.array([-math.sin(heading), math.cos(heading)])
    cap_W = cap[0] * forward + cap[1] * left
    assert len(pressing) > 0, "it pressed"
    assert np.max(np.linalg.norm(pressing[:, :2] - cap_W, axis=1)) < 0.005
    assert modes[-1] == MODE_AUTONOMOUS and t < 90.0


def test_no_cap_within_reach_gives_the_foot_back_without_pressing():
    pressing, modes, _ = _search(0.0, np.array([0.30, 0.0]), noise=0.8, seed=4)
    assert len(pressing) == 0 and modes[-1] == MODE_AUTONOMOUS
