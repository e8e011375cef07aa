"""The Go1 driver's safety layer: no command outside limits, NaN -> damping, watchdogs, E-stop."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.go1_command import pack_command, pd_torque, split_command
from pedi_drake.go1_driver.config import Go1SafetyConfig
from pedi_drake.go1_driver.safety import (
    INTERVENTION_INDEX,
    INTERVENTIONS,
    Go1SafetyFilter,
    SafetyLimits,
    bound_command,
    damping_command,
    robot_status_vector,
)

CONFIG = Go1SafetyConfig()
LIMITS = SafetyLimits.from_config(CONFIG)
PERIOD = CONFIG.period

# Anything a broken controller could emit: huge, tiny, infinite, NaN.
wild = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-100.0, max_value=100.0),
    st.sampled_from([0.0, -0.0, 1e308, -1e308, np.nan, np.inf, -np.inf]),
)
commands = hnp.arrays(np.float64, 60, elements=wild)
# Measured states, including joints outside their limits (a real encoder can read past them).
positions = hnp.arrays(np.float64, 12, elements=st.floats(min_value=-4.0, max_value=5.0))
rates = hnp.arrays(np.float64, 12, elements=st.floats(min_value=-40.0, max_value=40.0))


def assert_within_limits(command: np.ndarray, q: np.ndarray, qd: np.ndarray) -> None:
    assert np.all(np.isfinite(command))
    q_des, qd_des, kp, kd, tau_ff = split_command(command)
    assert np.all(q_des >= robot.HARDWARE_Q_LOWER) and np.all(q_des <= robot.HARDWARE_Q_UPPER)
    assert np.all(np.abs(qd_des) <= robot.VELOCITY_LIMIT)
    assert np.all(np.abs(tau_ff) <= robot.EFFORT_LIMIT)
    assert np.all(kp >= 0) and np.all(kp <= CONFIG.kp_max)
    assert np.all(kd >= 0) and np.all(kd <= CONFIG.kd_max)
    assert np.all(np.abs(pd_torque(command, q, qd)) <= robot.EFFORT_LIMIT)


class Harness:
    """A Go1SafetyFilter on its own, with a fake wall clock equal to the simulation time."""

    def __init__(self, config: Go1SafetyConfig = CONFIG):
        self.wall_offset = 0.0
        self.filter = Go1SafetyFilter(config, clock=lambda: self.context.get_time() + self.wall_offset)
        self.simulator = Simulator(self.filter)
        self.context = self.simulator.get_mutable_context()
        self.remote_estop = 0.0
        self.set_inputs(pack_command(robot.STANDING_Q, 0, 40, 1, 0), robot.STANDING_Q, np.zeros(12))
        self.status_time = 0.0
        self.filter.GetInputPort("estop").FixValue(self.context, [0.0])

    def set_inputs(self, command, q, qd) -> None:
        self.filter.GetInputPort("command").FixValue(self.context, command)
        self.q, self.qd = q, qd

    def step(self, n: int = 1, fresh_status: bool = True) -> np.ndarray:
        for _ in range(n):
            t = self.context.get_time()
            if fresh_status:
                self.status_time = t + self.wall_offset
            silence = [t + self.wall_offset - self.status_time] * 2
            status = robot_status_vector(self.q, self.qd, silence, self.remote_estop)
            self.filter.GetInputPort("robot_status").FixValue(self.context, status)
            self.simulator.AdvanceTo(t + PERIOD)
        return self.command()

    def command(self) -> np.ndarray:
        return self.filter.GetOutputPort("command").Eval(self.context)

    def count(self, name: str) -> int:
        return int(self.filter.GetOutputPort("status").Eval(self.context)[1 + INTERVENTION_INDEX[name]])

    def latched(self) -> str | None:
        code = int(self.filter.GetOutputPort("status").Eval(self.context)[0])
        return None if code == 0 else INTERVENTIONS[code - 1]


def is_damping(command: np.ndarray) -> bool:
    _, qd_des, kp, kd, tau_ff = split_command(command)
    return bool(np.all(kp == 0) and np.all(kd > 0) and np.all(tau_ff == 0) and np.all(qd_des == 0))


@settings(max_examples=400, deadline=None)
@given(command=commands, q=positions, qd=rates, previous=positions)
def test_bounded_command_never_leaves_limits(command, q, qd, previous):
    if not np.all(np.isfinite(command)):
        safe = damping_command(previous, qd, LIMITS, CONFIG.damping_kd)
        assert is_damping(safe)
    else:
        safe, _ = bound_command(command, q, qd, LIMITS, LIMITS.clip_position(previous))
    assert_within_limits(safe, q, qd)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(sequence=st.lists(st.tuples(commands, positions, rates), min_size=3, max_size=12))
def test_filter_never_publishes_outside_limits(sequence):
    harness = Harness()
    for command, q, qd in sequence:
        harness.set_inputs(command, q, qd)
        published = harness.step()
        assert_within_limits(published, q, qd)
        if not np.all(np.isfinite(command)):
            assert is_damping(published)


def test_nan_command_gives_damping_and_is_counted():
    harness = Harness()
    harness.step(10)
    command = pack_command(robot.STANDING_Q, 0, 40, 1, 0)
    command[5] = np.nan
    harness.set_inputs(command, robot.STANDING_Q, np.full(12, 0.3))
    published = harness.step()
    assert is_damping(published)
    assert harness.count("nonfinite_command") == 1
    # Not latched: a finite command is passed again on the next tick.
    harness.set_inputs(pack_command(robot.STANDING_Q, 0, 40, 1, 0), robot.STANDING_Q, np.zeros(12))
    published = harness.step()
    assert split_command(published)[2][0] == 40
    assert harness.latched() is None


def test_nan_measurement_gives_damping():
    harness = Harness()
    harness.step(3)
    q = robot.STANDING_Q.copy()
    q[0] = np.inf
    harness.set_inputs(pack_command(robot.STANDING_Q, 0, 40, 1, 0), q, np.zeros(12))
    assert is_damping(harness.step())
    assert harness.count("nonfinite_status") == 1


def test_targets_clamped_to_the_hardware_limits():
    q_des = robot.STANDING_Q.copy()
    q_des[2] = -0.1  # calf past the SDK's -0.837 and the URDF's -0.888
    safe, flags = bound_command(pack_command(q_des, 0, 0, 1, 0), robot.STANDING_Q, np.zeros(12), LIMITS)
    assert split_command(safe)[0][2] == pytest.approx(robot.HARDWARE_Q_UPPER[2])
    assert robot.HARDWARE_Q_UPPER[2] == -0.888
    assert flags == {"position_clamped"}


def test_gains_and_feedforward_clamped():
    command = pack_command(robot.STANDING_Q, 0, 1e4, -3, 1e3)
    safe, flags = bound_command(command, robot.STANDING_Q, np.zeros(12), LIMITS)
    _, _, kp, kd, tau_ff = split_command(safe)
    assert np.all(kp == CONFIG.kp_max) and np.all(kd == 0)
    np.testing.assert_allclose(tau_ff, robot.EFFORT_LIMIT, rtol=1e-8)
    assert {"gain_clamped", "feedforward_clamped"} <= flags


def test_pd_torque_bounded_by_moving_the_target_toward_the_measured_pose():
    q = robot.STANDING_Q.copy()
    q_des = q + 0.5  # 100 N m/rad * 0.5 rad = 50 N m, beyond every effort limit
    safe, flags = bound_command(pack_command(LIMITS.clip_position(q_des), 0, 100, 0, 0), q, np.zeros(12), LIMITS)
    tau = pd_torque(safe, q, np.zeros(12))
    assert "torque_bounded" in flags
    np.testing.assert_allclose(np.abs(tau), robot.EFFORT_LIMIT, rtol=1e-8)
    assert np.all(split_command(safe)[2] == 100)  # stiffness kept


def test_rate_limit_on_targets():
    previous = robot.STANDING_Q.copy()
    q_des = previous + 0.2
    safe, flags = bound_command(pack_command(q_des, 0, 5, 0, 0), previous, np.zeros(12), LIMITS, previous)
    step = np.abs(split_command(safe)[0] - previous)
    assert "rate_limited" in flags
    assert np.all(step <= CONFIG.max_target_rate * PERIOD + 1e-15)


def test_soft_start_begins_at_the_measured_pose():
    harness = Harness()
    q_measured = robot.LYING_Q.copy()
    harness.set_inputs(pack_command(robot.STANDING_Q, 0, 10, 1, 5.0), q_measured, np.zeros(12))
    first = harness.step()
    np.testing.assert_allclose(split_command(first)[0], LIMITS.clip_position(q_measured), atol=1e-12)
    np.testing.assert_allclose(split_command(first)[4], 0.0, atol=1e-12)
    n = int(round(CONFIG.soft_start_duration / PERIOD)) + 5
    last = harness.step(n)
    np.testing.assert_allclose(split_command(last)[0], robot.STANDING_Q, atol=1e-12)
    assert harness.count("soft_start") >= n - 10


def test_status_timeout_latches_damping():
    harness = Harness()
    harness.step(100)
    ticks = int(np.ceil(CONFIG.status_timeout / PERIOD))
    # Messages stop: still within the timeout for (ticks - 1) ticks, then damping.
    for _ in range(ticks - 1):
        assert not is_damping(harness.step(fresh_status=False))
    harness.step(2, fresh_status=False)
    assert is_damping(harness.command())
    assert harness.latched() == "status_timeout"
    # Status comes back: damping stays latched.
    assert is_damping(harness.step(20))
    assert harness.count("damping") >= 20


def test_controller_silence_latches_damping():
    harness = Harness()
    harness.step(int(CONFIG.warmup_duration / PERIOD) + 10)
    harness.wall_offset += CONFIG.command_timeout + 0.01  # the loop hung for 60 ms of wall time
    assert is_damping(harness.step())
    assert harness.latched() == "controller_silence"


def test_the_first_ticks_may_be_slow_but_not_hung():
    harness = Harness()
    harness.step(2)
    harness.wall_offset += CONFIG.command_timeout + 0.01  # one-time work of the first ticks
    assert not is_damping(harness.step(5))
    harness.wall_offset += CONFIG.warmup_command_timeout + 0.01  # a hang, even while warming up
    assert is_damping(harness.step())
    assert harness.latched() == "controller_silence"


def test_estop_port_latches_damping():
    harness = Harness()
    harness.step(10)
    harness.filter.GetInputPort("estop").FixValue(harness.context, [1.0])
    assert is_damping(harness.step())
    harness.filter.GetInputPort("estop").FixValue(harness.context, [0.0])
    assert is_damping(harness.step(10))
    assert harness.latched() == "estop_port"
    assert harness.count("estop_port") == 1


def test_remote_estop_latches_damping():
    harness = Harness()
    harness.step(10)
    assert not is_damping(harness.command())
    harness.remote_estop = 1.0
    assert is_damping(harness.step())
    assert harness.latched() == "estop_remote"


def test_damping_torque_within_limits_at_high_joint_rates():
    qd = np.full(12, 30.0)
    command = damping_command(robot.STANDING_Q, qd, LIMITS, kd=5.0)
    assert is_damping(command)
    assert np.all(np.abs(pd_torque(command, robot.STANDING_Q, qd)) <= robot.EFFORT_LIMIT)


def test_driver_report_names_the_latch_and_counts_every_intervention():
    from pedi_drake.go1_driver.safety import INTERVENTION_INDEX, INTERVENTIONS, driver_report

    status = np.zeros(1 + len(INTERVENTIONS))
    status[0] = 1 + INTERVENTION_INDEX["status_timeout"]
    status[1 + INTERVENTION_INDEX["status_timeout"]] = 1
    status[1 + INTERVENTION_INDEX["position_clamped"]] = 368
    report = driver_report(status, np.array([6292, 0, 6288, 2, 0, 0]))
    assert report["latched"] == "status_timeout"
    assert report["interventions"] == {"position_clamped": 368, "status_timeout": 1}
    assert report["messages"]["state_estimator_data"] == {"received": 6288, "dropped": 2}
    assert driver_report(np.zeros(1 + len(INTERVENTIONS)))["latched"] is None
