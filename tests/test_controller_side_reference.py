"""The controller side of a hardware run sends the recorded reference commands.

The fixture holds the first 4000 ticks (8 s: settling the trunk on the ground, standing up,
lifting FR and reaching) of hit_target_front replayed through the `--hardware` diagram: the
robot's status at every tick and the command sent for it, both float32 as on the wire. Regenerate
it only when a change of the commands is intended (say which in the commit):

    python -m pedi_drake.benchmarks.controller_latency --record-reference \
        tests/fixtures/controller_side_reference.npz

Speed work on the estimator, mission manager, IK, whole-body controller or driver must leave
every command within the solver's tolerance of the reference.
"""

from pathlib import Path

import numpy as np
import pytest

from pedi_drake.benchmarks.controller_latency import Replay

FIXTURE = Path(__file__).parent / "fixtures" / "controller_side_reference.npz"
# Per command field: the recorded commands are float32, so differences of a few float32 ulps are
# rounding; anything above these is a changed command [rad, rad/s, gain units, N m].
# Column blocks of the 60-vector go1.command (pedi_drake.go1_command).
FIELDS = {
    "q_des": slice(0, 12),
    "qd_des": slice(12, 24),
    "kp": slice(24, 36),
    "kd": slice(36, 48),
    "tau_ff": slice(48, 60),
}
TOLERANCE = {"q_des": 1e-5, "qd_des": 1e-4, "kp": 1e-4, "kd": 1e-5, "tau_ff": 1e-3}


@pytest.fixture(scope="module")
def replayed():
    reference = np.load(FIXTURE)
    status = reference["status"].astype(float)
    replay = Replay(str(reference["mission"]), float(reference["period"]), status)
    replay.run(len(status) - 1)
    return reference["commands"].astype(float), replay.sent_commands()


def test_replay_sends_one_command_per_tick(replayed):
    expected, sent = replayed
    assert sent.shape == expected.shape


@pytest.mark.parametrize("field", list(TOLERANCE))
def test_commands_equal_the_reference(replayed, field):
    expected, sent = replayed
    rows = FIELDS[field]
    error = np.abs(sent[:, rows] - expected[:, rows])
    worst = np.unravel_index(np.argmax(error), error.shape)
    assert error.max() <= TOLERANCE[field], (
        f"{field}: tick {worst[0]} joint {worst[1]} differs by {error.max():.3g} from the reference"
    )


def test_no_command_on_the_wire_leaves_a_motor_limp(replayed):
    # From the first command on, every joint has damping: the controller's gains from its first
    # tick, which the safety filter's soft start blends in from the measured pose.
    _, sent = replayed
    kd = sent[:, FIELDS["kd"]]
    assert kd.min() > 0.0, f"a command with kd = 0 at tick {np.argmin(kd.min(axis=1))}"
