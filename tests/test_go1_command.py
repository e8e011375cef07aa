"""The go1.command layout and the command a controller holds when it cannot compute one."""

import numpy as np

from pedi_drake import robot
from pedi_drake.go1_command import held_command, initial_command, pack_command, split_command


def test_held_command_keeps_the_last_targets_zeroes_rates_and_damps_at_least_kd_min():
    last = pack_command(robot.STANDING_Q, 0.3, 8.0, 0.4, 2.0)
    q_des, qd_des, kp, kd, tau = split_command(held_command(last, robot.LYING_Q, kd_min=1.0))
    np.testing.assert_array_equal(q_des, robot.STANDING_Q)
    assert np.all(qd_des == 0.0) and np.all(kp == 8.0) and np.all(kd == 1.0) and np.all(tau == 2.0)


def test_held_command_before_any_command_holds_the_measured_joints_and_is_never_nan():
    q_des, _, kp, kd, tau = split_command(held_command(np.zeros(60), robot.LYING_Q, kd_min=1.0))
    np.testing.assert_array_equal(q_des, robot.LYING_Q)
    assert np.all(kp == 0.0) and np.all(kd == 1.0) and np.all(tau == 0.0)
    torque_only = pack_command(0.0, 0.0, 0.0, 0.0, np.full(12, np.nan))
    assert np.all(np.isfinite(held_command(torque_only, robot.LYING_Q, kd_min=1.0)))


def test_a_controller_holds_damping_until_its_first_tick():
    command = initial_command(kd=1.0)
    _, _, kp, kd, tau_ff = split_command(command)
    np.testing.assert_array_equal(kp, 0.0)
    np.testing.assert_array_equal(tau_ff, 0.0)
    np.testing.assert_array_equal(kd, 1.0)
    # held_command reads it as "no good command yet": the measured joints become the targets.
    q = np.linspace(-1.0, 1.0, 12)
    np.testing.assert_array_equal(held_command(command, q, kd_min=0.5)[0:12], q)
