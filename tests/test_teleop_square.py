"""The teleoperation floor, square: a scripted operator on an in-process LCM bus (lock step) drives
the lifted FR foot around a 10 cm square at 0.1 m/s (world-frame velocities, as a joystick would
send them); the true foot (the plant, read only here) stays within 1 cm of the square while it is
driven, no bound of the teleoperated foot is violated, and the robot does not fall.

The same scenario at real time over UDP, the robot side in its own process: `python -m
pedi_drake.benchmarks.teleop --scenarios square`. Run with -s to see the figures.
"""

import pytest

from pedi_drake.benchmarks.teleop import lock_step_run
from pedi_drake.evaluation import teleop_square
from pedi_drake.evaluation.teleop_floors import floor_figures
from pedi_drake.operator.config import DEFAULT_FOOT_COMMAND_CHANNEL

MAX_ERROR = 0.01  # [m] the floor


@pytest.fixture(scope="module")
def square_run():
    stream = teleop_square.square_stream(DEFAULT_FOOT_COMMAND_CHANNEL)
    run = lock_step_run(teleop_square.MISSION, stream, teleop_square.SIMULATION_DURATION)
    errors = teleop_square.square_errors(run.truth.times, run.truth.foot("FR"))
    figures = floor_figures(run.result, run.logs, run.truth, run.scenario, run.mission)
    print(f"\nsquare: {errors}\nteleop: {run.result['teleop']}\nviolations: {figures['violations']}")
    return run, errors, figures


def test_the_true_foot_stays_within_1cm_of_the_square(square_run):
    _, errors, _ = square_run
    assert errors["samples"] > 0.9 * (teleop_square.SQUARE_END - teleop_square.SQUARE_START) / 0.01
    assert errors["path_max_m"] < MAX_ERROR
    # Where the command had taken the foot at that moment, lag and all.
    assert errors["timed_max_m"] < MAX_ERROR
    assert errors["corner_max_m"] < MAX_ERROR  # it went all the way round


def test_the_operator_ends_the_teleop_and_the_mission_succeeds(square_run):
    run, _, _ = square_run
    (teleop,) = run.result["teleop"]
    assert teleop["ended_by"] == "operator"
    # The square's speed is the bound's: let through unchanged, and nowhere near the workspace's edge.
    assert teleop["bound_activations"]["speed"] == 0 and teleop["bound_activations"]["workspace"] == 0
    assert run.result["success"], run.result["reason"]


def test_no_bound_is_violated_and_the_robot_does_not_fall(square_run):
    _, _, figures = square_run
    assert figures["violations"]["total"] == 0
    assert not figures["fell"]
