"""Mode switching, the short version of its floor: a seeded operator on an in-process LCM bus
(lock step) makes 6 mode switches at random times during an autonomous mission (teleoperated foot
and semi-autonomous targets, and back); every switch is made, the robot does not fall, and no
reference or command steps beyond the rate limits between two controller ticks
(pedi_drake.evaluation.reference_steps: the trunk and a lifted foot 1 mm, a foot where its leg
changes mode 1 cm, joint targets the driver's 8 rad/s).

The floor itself, 20 switches, at real time over UDP: `python -m pedi_drake.benchmarks.teleop
--scenarios switches`. Run with -s to see the figures.
"""

import pytest

from pedi_drake.benchmarks.teleop import lock_step_run
from pedi_drake.evaluation import random_switches
from pedi_drake.evaluation.teleop_floors import floor_figures
from pedi_drake.operator.config import DEFAULT_FOOT_COMMAND_CHANNEL

# Both kinds of round trip (the stream has SEMI_ROUND_TRIPS semi-autonomous ones, then teleop
# ones): 6 switches.
ROUND_TRIPS = 3


@pytest.fixture(scope="module")
def switched_run():
    seed = random_switches.SEED  # printed: a failure names the switch times that caused it
    stream = random_switches.switch_stream(seed, ROUND_TRIPS, DEFAULT_FOOT_COMMAND_CHANNEL)
    run = lock_step_run(random_switches.MISSION, stream.messages, stream.simulation_duration)
    figures = floor_figures(run.result, run.logs, run.truth, run.scenario, run.mission)
    switches = [(round(s["time"], 2), s["from"], s["to"], s["reason"]) for s in run.result["mode_switches"]]
    print(f"\nseed {seed}: plan {stream.plan}\nswitches {switches}\nrate limits {figures['rate_limits']}")
    return stream, run, figures


def test_every_switch_is_made_there_and_back(switched_run):
    _, run, _ = switched_run
    switches = run.result["mode_switches"]
    assert len(switches) == 2 * ROUND_TRIPS
    assert [s["to"] for s in switches[1::2]] == ["autonomous"] * ROUND_TRIPS
    assert {s["to"] for s in switches[0::2]} == {"teleop", "semi_autonomous"}


def test_no_step_beyond_the_rate_limits(switched_run):
    _, _, figures = switched_run
    assert all(row["within"] for row in figures["rate_limits"].values()), figures["rate_limits"]


def test_the_robot_does_not_fall_and_no_phase_fails(switched_run):
    _, run, figures = switched_run
    assert not figures["fell"]
    assert figures["violations"]["total"] == 0
    assert not [row for row in run.result["phases"] if row["status"] == "failed"]
