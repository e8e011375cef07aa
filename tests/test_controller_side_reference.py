"""The controller side of a hardware run sends the recorded reference commands.

The fixture holds the first 4000 ticks (8 s: standing up, lifting FR and reaching) of
hit_target_front replayed through the `--hardware` diagram: the robot's status at every tick and
the command sent for it, both float32 as on the wire. Regenerate it only when a change of the
commands is intended:

    python -m pedi_drake.benchmarks.controller_latency --record-reference \
        tests/fixtures/controller_side_reference.npz

Speed work on the estimator, mission manager, IK, whole-body controller or driver must leave
every command within the solver's tolerance of the reference.

It was last recorded when the driver's safety filter and sender began to run after the
controller in the same tick, so the command computed in a tick is sent in it (before, two ticks
later): the commands are the recording before's two ticks earlier (4000 of its 4001; the two
damping commands the filter and the controller held at the start are gone), equal in kp and kd,
and in q_des within 0.64 mrad and tau_ff within 0.026 N m (a median of 0), where the filter now
bounds them against the status of their own tick. The recording before it was made when the
driver's status receiver began to latch in an unrestricted update,
so the estimator and the controller use the status of their own tick, a tick sooner than before
(from tick 1 on the commands differ: up to 0.1 rad in q_des over the open-loop ticks, where the
controller's joint reference runs against its bound around the measurement, a median of 6 mN m a
tick in tau_ff). The recording before it was made when the controllers began to hold damping
until their first tick
(go1_command.initial_command: the second command on the wire, tick 1, went from kp = kd = 0, a
limp motor, to kd = 1 N m s/rad; the other 4000 commands stayed within one float32 rounding of
the recording before, 1.5e-8 rad/s in qd_des, from the recorded status's own last bits). The
recording before it began when the hardware diagram began to initialise its state estimate from the
robot's first status (an intended change of the commands from the third tick on: before, the
mission's first update planned the stand-up from the estimator's unset output, a trunk at z = 0,
so the replayed stand-up differed by up to 0.1 rad in q_des and 2.8 N m in tau_ff). The
recording before that one began when reaches planned their joint targets from the trunk's
reference pose instead of its estimate. Both were made on the compiled whole-body tick, whose
level QPs are solved exactly (`pedi_drake.control.dense_qp`; tests/test_compiled_controller.py
and tests/test_dense_qp.py tie it to the Python reference and to DAQP at tight tolerances). An
older reference had been recorded with DAQP at the controller's settings, which stops within its tolerance: the
compiled tick's commands differed from it by at most 1.2e-7 rad (q_des), 7.4e-5 N m (tau_ff)
and 3.2e-4 rad/s (qd_des, which integrates the per-tick differences of the joint accelerations
over the 4000 open-loop ticks).
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
