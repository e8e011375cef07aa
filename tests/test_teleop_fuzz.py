"""The teleoperation floor, fuzz: a seeded stream of 10,000 foot commands at 1 kHz on an
in-process LCM bus (lock step), most of them broken (NaN and inf, values up to 1e308, stale,
replayed and future-stamped, unknown codes, truncated, foreign bytes; the valid ones often beyond
the workspace, the speed bound or into a wall), drives the lifted FR foot beside a rigid wall.
Floors: no tick where the foot reference leaves the workspace, moves faster than the speed bound
or further into a contact whose estimated force exceeds the force bound, no non-finite value in
go1.command; every broken message rejected and counted under its reason; the robot does not fall.

The same stream at real time over UDP: `python -m pedi_drake.benchmarks.teleop --scenarios fuzz`.
Run with -s to see the figures.
"""

import pytest

from pedi_drake.benchmarks.teleop import lock_step_run
from pedi_drake.evaluation import command_fuzz
from pedi_drake.evaluation.teleop_floors import floor_figures
from pedi_drake.operator.config import DEFAULT_FOOT_COMMAND_CHANNEL


@pytest.fixture(scope="module")
def fuzz_run():
    seed = command_fuzz.SEED  # printed: a failure can be replayed
    stream = command_fuzz.fuzz_stream(seed, command_fuzz.FUZZ_COUNT, DEFAULT_FOOT_COMMAND_CHANNEL)
    run = lock_step_run(command_fuzz.MISSION, stream.messages, stream.simulation_duration)
    figures = floor_figures(run.result, run.logs, run.truth, run.scenario, run.mission)
    print(
        f"\nfuzz seed {seed}: sent {stream.sent}\nexpected rejections {stream.expected}, taken {stream.taken}"
        f"\ninput counted {run.result['operator_messages']}\nteleop {run.result['teleop']}"
        f"\nviolations {figures['violations']}"
    )
    return stream, run, figures


def test_the_stream_has_every_kind_of_broken_message(fuzz_run):
    stream, _, _ = fuzz_run
    assert sum(n for kind, n in stream.sent.items() if kind != "heartbeat") == command_fuzz.FUZZ_COUNT
    assert set(command_fuzz.KINDS) <= set(stream.sent)


def test_no_bound_is_violated(fuzz_run):
    _, run, figures = fuzz_run
    assert figures["violations"]["total"] == 0, figures["violations"]
    # The bounds had work to do: the foot met the workspace's edge, the speed bound and the wall.
    (teleop,) = run.result["teleop"]
    assert all(teleop["bound_activations"][bound] > 0 for bound in ("workspace", "speed", "force"))


def test_every_broken_message_is_rejected_under_its_reason_and_the_rest_taken(fuzz_run):
    stream, run, _ = fuzz_run
    counted = run.result["operator_messages"]
    assert counted["rejected"] == stream.expected
    assert counted["received"] == stream.taken


def test_the_robot_does_not_fall_and_the_mission_succeeds(fuzz_run):
    _, run, figures = fuzz_run
    assert not figures["fell"]
    assert run.result["teleop"][0]["ended_by"] == "operator"
    assert run.result["success"], run.result["reason"]
