"""The hardware loop's busy wait (pedi_drake.go1_driver.pacing): its clock, its lock, its schedule."""

import os
import threading
import time

import pytest
from pydrake.systems.framework import EventStatus

from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.exceptions import ScenarioError
from pedi_drake.go1_driver.hardware_station import hardware_link
from pedi_drake.go1_driver.pacing import SpinPacedMonitor, loop_wait, monotonic_ns, spin_until, wait_problem
from pedi_drake.scenario import load_scenario

# A bus of this test process's own (nothing is sent on it: the diagrams are built, not run).
URL = f"udpm://239.255.76.67:{23000 + os.getpid() % 20000}?ttl=0"


def test_the_compiled_clock_is_time_monotonic():
    before = time.monotonic_ns()
    reading = spin_until(0)  # a deadline long past: returns the clock's first reading
    after = time.monotonic_ns()
    assert before <= reading <= after
    assert before <= monotonic_ns() <= time.monotonic_ns()


def test_spin_until_returns_at_its_deadline_not_before():
    deadline = time.monotonic_ns() + 3_000_000
    reading = spin_until(deadline)
    assert reading >= deadline
    assert time.monotonic_ns() >= deadline


def test_other_threads_run_python_while_the_loop_spins():
    """The spin holds no lock: with the interpreter's lock held, this thread could not run at all
    until the spinner's deadline, one second later."""
    spinner = threading.Thread(target=spin_until, args=(time.monotonic_ns() + 1_000_000_000,))
    spinner.start()
    time.sleep(0.05)  # the spinner is in its wait
    total = sum(range(100_000))  # Python bytecode: needs the interpreter's lock
    ran_while_spinning = spinner.is_alive()
    spinner.join()
    assert total == 4_999_950_000
    assert ran_while_spinning


class _Context:
    def __init__(self, t: float):
        self.t = t

    def get_time(self) -> float:
        return self.t


class _Link:
    busy_wait_cpu = 0.0


@pytest.mark.parametrize("rate", [1.0, 0.5])
def test_the_monitor_waits_for_the_wall_time_of_each_step(rate):
    calls = []

    def inner(context):
        calls.append(context.get_time())
        return EventStatus.Succeeded()

    link = _Link()
    monitor = SpinPacedMonitor(inner, rate, link)
    start = time.monotonic()
    monitor(_Context(0.0))  # Initialize's call anchors the schedule
    for k in range(1, 6):
        monitor(_Context(0.002 * k))
    elapsed = time.monotonic() - start
    assert calls == pytest.approx([0.002 * k for k in range(6)])
    assert elapsed >= 0.010 / rate  # never ahead of the schedule
    assert link.busy_wait_cpu > 0.0


def test_the_monitor_does_not_wait_once_the_run_ends():
    monitor = SpinPacedMonitor(lambda context: EventStatus.ReachedTermination(None, "mission over"), 1.0)
    monitor(_Context(0.0))
    start = time.monotonic()
    monitor(_Context(10.0))  # ten seconds ahead of the wall clock: a waiting monitor would spin for them
    assert time.monotonic() - start < 1.0


def test_a_rate_that_is_not_positive_is_refused():
    with pytest.raises(ValueError, match="realtime_rate"):
        SpinPacedMonitor(lambda context: EventStatus.Succeeded(), 0.0)


def test_the_wait_setting_is_checked_by_name():
    assert all(wait_problem(wait) is None for wait in ("auto", "sleep", "spin"))
    with pytest.raises(ScenarioError, match="go1_driver.wait.*'spinning'"):
        load_scenario(scenario_text="{go1_driver: {wait: spinning}}")


def test_auto_spins_only_where_nothing_else_needs_the_core():
    assert loop_wait("auto", realtime_priority=0, work_beside_loop=False) == "spin"
    # A real-time thread that never sleeps is throttled by the kernel; an operator's input or the
    # posture planner's worker needs the core a spinning loop would take.
    assert loop_wait("auto", realtime_priority=50, work_beside_loop=False) == "sleep"
    assert loop_wait("auto", realtime_priority=0, work_beside_loop=True) == "sleep"
    for wait in ("sleep", "spin"):  # a wait chosen by name is kept
        assert loop_wait(wait, realtime_priority=50, work_beside_loop=True) == wait


@pytest.mark.parametrize(
    ("settings", "expected"),
    [
        ("mission: hit_target_front", "spin"),
        ("mission: hit_target_front, go1_driver: {wait: sleep}", "sleep"),
        ("mission: hit_target_front, go1_driver: {realtime_priority: 50}", "sleep"),
        ("mission: operator/stand_with_teleop, operator: {source: lcm}", "sleep"),  # an operator's input
        ("mission: operator/stand_with_semi_autonomous", "sleep"),  # the posture planner's worker
    ],
)
def test_a_hardware_run_resolves_auto_to_the_wait_its_loop_does(settings, expected):
    scenario = load_scenario(scenario_text=f"{{{settings}, lcm_buses: {{go1: {{lcm_url: '{URL}'}}}}}}")
    assert scenario.go1_driver.wait == "auto" or "wait" in settings
    link = hardware_link(MakePedipulationDiagram(scenario, None, hardware=True).diagram)
    assert link.config.wait == expected
