"""Real-time scheduling of a wall-clock loop: every thread raised and restored, or refused and said."""

import os
import resource
import threading

import pytest

from pedi_drake.exceptions import ScenarioError
from pedi_drake.runtime.realtime_priority import priority_problem, realtime_priority, rt_throttling
from pedi_drake.scenario import load_scenario

# CAP_SYS_NICE's bit in /proc/self/status's CapEff.
CAP_SYS_NICE = 23
PRIORITY = 10


def _may_raise_priority(priority: int) -> bool:
    """Whether this process may use SCHED_FIFO at `priority` (the capability, or the rlimit)."""
    with open("/proc/self/status") as status:
        effective = next(int(line.split()[1], 16) for line in status if line.startswith("CapEff:"))
    soft_limit, _ = resource.getrlimit(resource.RLIMIT_RTPRIO)
    return bool(effective >> CAP_SYS_NICE & 1) or soft_limit == resource.RLIM_INFINITY or soft_limit >= priority


def _policies() -> dict[int, tuple[int, int]]:
    """{thread id: (policy, priority)} of the process's threads that are still alive when asked:
    a thread listed in /proc can end before its policy is read (the test's own waiting thread,
    released just before, or a library's worker)."""
    policies = {}
    for tid in os.listdir("/proc/self/task"):
        try:
            policies[int(tid)] = (os.sched_getscheduler(int(tid)), os.sched_getparam(int(tid)).sched_priority)
        except ProcessLookupError:
            continue
    return policies


@pytest.mark.parametrize("value", [-1, 100, 2.5, "50", True, None])
def test_a_priority_out_of_range_or_not_an_integer_is_refused(value):
    assert "integer from 0" in priority_problem(value)
    with pytest.raises(ValueError, match="loop: realtime_priority"):
        with realtime_priority(value, who="loop"):
            pass


def test_a_bad_priority_in_a_scenario_names_the_field():
    with pytest.raises(ScenarioError, match=r"go1_driver\.realtime_priority: must be an integer from 0"):
        load_scenario(scenario_text="{go1_driver: {realtime_priority: 120}}")
    assert load_scenario(scenario_text="{go1_driver: {realtime_priority: 0}}").go1_driver.realtime_priority == 0


def test_the_bridges_own_priority_is_checked_and_defaults_to_normal_scheduling():
    with pytest.raises(ScenarioError, match=r"go1_driver\.bridge\.realtime_priority: must be an integer from 0"):
        load_scenario(scenario_text="{go1_driver: {bridge: {realtime_priority: -1}}}")
    scenario = load_scenario(scenario_text="{go1_driver: {realtime_priority: 50}}")
    assert scenario.go1_driver.bridge.realtime_priority == 0


def test_rt_throttling_reads_the_kernels_share(tmp_path):
    (tmp_path / "sched_rt_period_us").write_text("1000000\n")
    (tmp_path / "sched_rt_runtime_us").write_text("950000\n")
    assert rt_throttling(tmp_path) == pytest.approx(0.95)
    (tmp_path / "sched_rt_runtime_us").write_text("-1\n")  # throttling off
    assert rt_throttling(tmp_path) is None
    assert rt_throttling(tmp_path / "missing") is None


def test_priority_zero_leaves_scheduling_alone():
    before = _policies()
    with realtime_priority(0, who="loop") as granted:
        assert granted == "normal scheduling"
        assert _policies() == before


def test_every_thread_is_raised_and_restored_or_the_refusal_is_reported():
    release = threading.Event()
    started_before = threading.Thread(target=release.wait, daemon=True)
    started_before.start()
    before = _policies()
    try:
        with realtime_priority(PRIORITY, who="loop") as granted:
            inside = _policies()
            born_inside = {}
            thread = threading.Thread(target=lambda: born_inside.update(_policies()), daemon=True)
            thread.start()
            thread.join()
    finally:
        release.set()
    if _may_raise_priority(PRIORITY):
        assert granted == f"SCHED_FIFO {PRIORITY}"
        # The thread started before the block is raised too, and a thread started inside inherits.
        assert started_before.native_id in inside
        assert all(policy == (os.SCHED_FIFO, PRIORITY) for policy in inside.values()), inside
        assert all(policy == (os.SCHED_FIFO, PRIORITY) for policy in born_inside.values()), born_inside
    else:
        assert granted.startswith("refused: ")
        assert "ulimit -r" in granted
        assert inside == before
    after = _policies()
    assert {tid: after[tid] for tid in before if tid in after} == {tid: before[tid] for tid in before if tid in after}
