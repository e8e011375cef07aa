"""The driver's link at real time, with the robot side in its own process (tests/go1_fake_robot.py):
status stamped while the loop is blocked, the guard, damping on every exit, a malformed flood."""

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import lcm
import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, EventStatus, LeafSystem

import pedi_drake
from pedi_drake.control.stand_controller import StandController
from pedi_drake.go1_command import split_command
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.config import Go1DriverConfig, Go1SafetyConfig
from pedi_drake.go1_driver.hardware_run import hardware_run
from pedi_drake.go1_driver.hardware_station import MakeHardwareStation
from pedi_drake.go1_driver.lcmtypes import leg_control_data_lcmt
from pedi_drake.go1_driver.link import (
    LEG_CONTROL_FIELDS,
    STATE_ESTIMATOR_FIELDS,
    FloatFields,
    Go1Link,
    Inbox,
    LoopTiming,
    loop_stalls,
)
from pedi_drake.go1_driver.pacing import SpinPacedMonitor
from pedi_drake.go1_driver.safety import driver_report
from pedi_drake.scenario import load_scenario

REPO = Path(pedi_drake.__file__).resolve().parents[1]
GROUP = "239.255.76.67"
# A port of this test run's own (see test_sim_bridge): ttl=0 keeps every datagram on this host.
URL = f"udpm://{GROUP}:{21000 + os.getpid() % 20000}?ttl=0"


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO), env.get("PYTHONPATH", "")]))
    return env


def _start(args: list[str], ready_word: str, timeout: float = 90.0) -> tuple[subprocess.Popen, list[str]]:
    process = subprocess.Popen(
        [sys.executable, *args], cwd=REPO, env=_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    lines: list[str] = []
    found = threading.Event()

    def read() -> None:
        for line in process.stdout:
            lines.append(line)
            if ready_word in line:
                found.set()

    threading.Thread(target=read, daemon=True).start()
    if not found.wait(timeout):
        process.kill()
        raise AssertionError(f"{args[:2]} did not print {ready_word!r}: {''.join(lines)[-2000:]}")
    return process, lines


class FakeRobot:
    """tests/go1_fake_robot.py in its own process; `stop()` returns what it recorded."""

    def __init__(self, tmp_path: Path, *extra: str):
        self.out = tmp_path / "fake_robot.npz"
        self.process, self.lines = _start(["tests/go1_fake_robot.py", URL, str(self.out), *extra], "publishing")

    def stop(self) -> dict:
        if self.process.poll() is None:
            os.kill(self.process.pid, signal.SIGCONT)
            self.process.send_signal(signal.SIGTERM)
            self.process.wait(20)
        with np.load(self.out) as archive:
            record = {key: archive[key] for key in archive.files}
        record["flooded"] = json.loads(str(record["flooded"]))
        return record


@pytest.fixture
def fake_robot(tmp_path):
    pytest.importorskip("lcm")
    robots: list[FakeRobot] = []

    def start(*extra: str) -> FakeRobot:
        robots.append(FakeRobot(tmp_path, *extra))
        return robots[-1]

    yield start
    for robot_process in robots:
        if robot_process.process.poll() is None:
            os.kill(robot_process.process.pid, signal.SIGCONT)
            robot_process.process.kill()


class Stall(LeafSystem):
    """At the first tick at or after `at` [s], blocks the loop for `duration` [s] of wall time.

    `busy`: spin in Python (holding the GIL between switch intervals, like a slow tick) instead of
    sleeping. While it blocks it samples the receipt stamp of leg_control_data every millisecond.
    """

    def __init__(self, link: Go1Link, at: float, duration: float, busy: bool):
        super().__init__()
        self._link, self._at, self._duration, self._busy = link, at, duration, busy
        self.samples: list[tuple[float, float]] = []  # (wall time, receipt stamp) [s]
        self.started: float | None = None
        self.DeclarePeriodicPublishEvent(c.BRIDGE_PERIOD, 0.0, self._tick)

    def _tick(self, context) -> EventStatus:
        if self.started is not None or context.get_time() < self._at:
            return EventStatus.Succeeded()
        self.started = time.monotonic()
        end = self.started + self._duration
        next_sample = self.started
        while (now := time.monotonic()) < end:
            if now >= next_sample:
                self.samples.append((now, self._link.leg_control.receipt_time))
                next_sample += 0.001
            if not self._busy:
                time.sleep(0.0005)
        return EventStatus.Succeeded()


def _driver(config: Go1DriverConfig, stall: dict | None = None):
    scenario = load_scenario()
    link = Go1Link.from_url(URL, config)
    builder = DiagramBuilder()
    station = builder.AddNamedSystem("station", MakeHardwareStation(config, link))
    controller = builder.AddNamedSystem("controller", StandController(scenario.stand))
    builder.Connect(station.GetOutputPort("go1.position_measured"), controller.GetInputPort("position_measured"))
    builder.Connect(controller.GetOutputPort("command"), station.GetInputPort("go1.command"))
    staller = builder.AddNamedSystem("stall", Stall(link, **stall)) if stall else None
    for name in ("driver.status", "driver.message_counts"):
        builder.ExportOutput(station.GetOutputPort(name), name)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.set_target_realtime_rate(1.0)
    return diagram, simulator, link, staller


def _report(diagram, simulator, link: Go1Link) -> dict:
    context = simulator.get_context()
    status = diagram.GetOutputPort("driver.status").Eval(context)
    report = driver_report(status, diagram.GetOutputPort("driver.message_counts").Eval(context))
    report.update(link.report())
    return report


def _is_damping(commands: np.ndarray) -> np.ndarray:
    """Per row of (n, 60) commands: kp 0, kd > 0, tau_ff 0."""
    _, _, kp, kd, tau_ff = split_command(commands.T)
    return np.all(kp == 0, axis=0) & np.all(kd > 0, axis=0) & np.all(tau_ff == 0, axis=0)


# These tests judge the link's logic, at the OS's normal scheduling (realtime_priority=0): a
# stalled loop that spins under SCHED_FIFO would starve the fake robot, a normal process, of a core.
# Watchdogs as shipped (40 ms status), and a loop silence limit longer than the stall so that only
# the robot-silence watchdog is under test.
PATIENT_LOOP = Go1DriverConfig(realtime_priority=0, safety=Go1SafetyConfig(status_timeout=0.04, command_timeout=0.5))


def test_status_is_stamped_while_a_tick_is_blocked_and_a_late_tick_does_not_look_like_robot_silence(
    fake_robot, tmp_path
):
    robot = fake_robot()
    diagram, simulator, link, stall = _driver(PATIENT_LOOP, {"at": 1.0, "duration": 0.15, "busy": True})
    with hardware_run(diagram, shutdown_damping_duration=0.05):
        simulator.Initialize()
        simulator.AdvanceTo(1.6)
    report = _report(diagram, simulator, link)
    robot.stop()
    # While the loop spun for 150 ms (almost four status timeouts), the receive thread kept
    # stamping, never falling behind by half the watchdog's timeout (it shares the GIL, so on a
    # loaded machine it gets its turn every few milliseconds, not at every message).
    samples = np.array(stall.samples)
    assert samples[-1, 0] - samples[0, 0] > 0.14
    stamps = np.unique(samples[:, 1])
    assert stamps.size > 10
    assert np.max(np.diff(np.concatenate([[stall.started], stamps, [samples[-1, 0]]]))) < 0.020
    # The link's thread read the socket while the loop was blocked (it wakes every 2 ms).
    assert report["loop"]["status_reads"]["thread"] >= 10
    # The late tick was seen as lateness of the loop, not as silence of the robot.
    assert report["latched"] is None, report
    assert report["guard"]["latched"] == "shutdown"
    assert report["loop"]["lateness_ms"]["max"] > 140.0
    assert report["loop"]["deadline_misses"] >= 1
    # The loop spun through the stall: reported as a stall in which it computed.
    stalls = report["loop"]["stalls"]
    assert stalls["computing"] >= 1
    longest = stalls["longest"][0]
    assert longest["gap_ms"] > 140.0 and longest["loop_cpu_ms"] > 0.5 * longest["gap_ms"]
    assert 1.0 <= longest["t"] < 1.2


def test_stalls_tell_a_loop_that_computed_from_one_that_waited():
    timing = LoopTiming()
    # Ticks of 2 ms; the publication at t = 0.010 comes 30 ms late after 25 ms of the loop's CPU,
    # the one at t = 0.020 20 ms late after 1 ms of it.
    departures = [0.002 * k for k in range(12)]
    cpu = [0.0003 * k for k in range(12)]
    departures[5:] = [d + 0.030 for d in departures[5:]]
    cpu[5:] = [x + 0.025 for x in cpu[5:]]
    departures[10:] = [d + 0.020 for d in departures[10:]]
    cpu[10:] = [x + 0.001 for x in cpu[10:]]
    for k, (wall, loop_cpu) in enumerate(zip(departures, cpu, strict=True)):
        timing.departures.append(wall)
        timing.offsets.append(wall - 0.002 * k)
        timing.times.append(0.002 * k)
        timing.loop_cpu.append(loop_cpu)
    stalls = loop_stalls(timing, 0.002)
    assert (stalls["count"], stalls["computing"], stalls["waiting"]) == (2, 1, 1)
    first, second = stalls["longest"]
    assert first["t"] == pytest.approx(0.010) and first["gap_ms"] == pytest.approx(32.0)
    assert first["loop_cpu_ms"] == pytest.approx(25.3)
    assert second["t"] == pytest.approx(0.020) and second["loop_cpu_ms"] == pytest.approx(1.3)


def test_robot_silence_still_trips_the_watchdog_within_its_timeout(fake_robot, tmp_path):
    robot = fake_robot("--silent_at", "1.5")
    diagram, simulator, link, _ = _driver(PATIENT_LOOP)
    with hardware_run(diagram, shutdown_damping_duration=0.05):
        simulator.Initialize()
        simulator.AdvanceTo(3.0)
    report = _report(diagram, simulator, link)
    record = robot.stop()
    assert report["latched"] == "status_timeout", report
    # Damping arrived at the robot 40 to 50 ms after its last status message (plus the receive
    # thread's look and one tick).
    t_last = record["status_sends"][-1]
    arrivals, damping = record["arrivals"], _is_damping(record["commands"])
    first_damping = arrivals[(arrivals > t_last) & damping][0]
    assert not np.any(damping[(arrivals > t_last - 0.5) & (arrivals < t_last)])
    assert 0.040 <= first_damping - t_last < 0.050 + 0.006


def test_the_guard_damps_a_hung_loop_within_command_timeout(fake_robot, tmp_path):
    config = Go1DriverConfig(realtime_priority=0, safety=Go1SafetyConfig(status_timeout=0.5, command_timeout=0.05))
    robot = fake_robot()
    diagram, simulator, link, stall = _driver(config, {"at": 1.2, "duration": 0.3, "busy": False})
    with hardware_run(diagram, shutdown_damping_duration=0.05):
        simulator.Initialize()
        simulator.AdvanceTo(1.8)
    report = _report(diagram, simulator, link)
    record = robot.stop()
    arrivals, damping = record["arrivals"], _is_damping(record["commands"])
    before = arrivals < stall.started
    assert not damping[before][-1]  # the loop was commanding stiffly when it hung
    t_last = arrivals[before][-1]
    first_damping = arrivals[~before & damping][0]
    # The robot held the stale command for command_timeout and one look of the receive thread,
    # then got damping while the loop was still hung, and damping only from then on.
    assert 0.050 <= first_damping - t_last < 0.050 + 0.008
    assert first_damping < stall.started + 0.3
    assert np.all(damping[arrivals >= first_damping])
    assert report["latched"] == "controller_silence"


def test_a_loop_that_spins_for_its_periods_keeps_time_and_counts_its_waiting_apart(fake_robot, tmp_path):
    robot = fake_robot()
    diagram, simulator, link, _ = _driver(Go1DriverConfig(realtime_priority=0, wait="spin"))
    with hardware_run(diagram, shutdown_damping_duration=0.05):
        simulator.set_target_realtime_rate(0.0)
        simulator.set_monitor(SpinPacedMonitor(lambda context: EventStatus.Succeeded(), 1.0, link))
        simulator.Initialize()
        start = time.monotonic()
        simulator.AdvanceTo(1.0)
        wall = time.monotonic() - start
    report = _report(diagram, simulator, link)
    robot.stop()
    assert wall >= 0.998  # paced to the wall clock, not run as fast as it can
    assert report["latched"] is None
    loop = report["loop"]
    assert loop["wait"] == "spin"
    assert loop["command_interdeparture_ms"]["median"] == pytest.approx(2.0, abs=0.2)
    # On time, the loop reads the status at every tick and the link's thread hardly ever (only
    # before the first tick, and in a tick late by over 1.5 periods): it stays off Python's lock.
    reads = loop["status_reads"]
    assert reads["loop"] >= loop["ticks"] and reads["thread"] < 0.1 * loop["ticks"], reads
    # Most of each period went to the wait, and the report keeps it apart from the loop's work.
    assert 0.5 < loop["busy_wait_cpu_s"] < wall
    assert link._timing.loop_cpu[-1] - link._timing.loop_cpu[0] < 0.5


def test_a_flood_of_malformed_messages_is_counted_by_channel_and_reason_and_latches_nothing(fake_robot, tmp_path):
    robot = fake_robot("--flood_at", "1.0", "--flood_duration", "1.0", "--flood_rate", "500")
    diagram, simulator, link, _ = _driver(Go1DriverConfig(realtime_priority=0))
    with hardware_run(diagram, shutdown_damping_duration=0.05):
        simulator.Initialize()
        simulator.AdvanceTo(3.0)
    report = _report(diagram, simulator, link)
    record = robot.stop()
    # The robot side's own status gaps (it floods from the same loop): on a loaded machine it may
    # itself fall silent, and then the watchdog is right to trip; otherwise nothing may latch.
    sends = record["status_sends"]
    robot_silent = np.max(np.diff(sends)) > Go1DriverConfig().safety.status_timeout
    assert report["latched"] == ("status_timeout" if robot_silent else None), report
    flooded = record["flooded"]
    assert sum(sum(kinds.values()) for kinds in flooded.values()) >= 3 * 3 * 400
    for channel in (c.LEG_CONTROL_CHANNEL, c.STATE_ESTIMATOR_CHANNEL):
        assert report["messages"][channel]["rejected"] == flooded[channel], channel
    # rc_command's floats (the sticks) are not used: only the switches, which cannot be NaN.
    remote = report["messages"][c.RC_COMMAND_CHANNEL]
    assert remote["rejected"] == {k: n for k, n in flooded[c.RC_COMMAND_CHANNEL].items() if k != "nonfinite"}
    assert remote["received"] == flooded[c.RC_COMMAND_CHANNEL]["nonfinite"]


def test_a_malformed_message_costs_microseconds():
    inbox = Inbox(c.LEG_CONTROL_CHANNEL, leg_control_data_lcmt, lambda m: np.asarray(m.q))
    good = leg_control_data_lcmt().encode()
    wrong_fingerprint = bytes([good[0] ^ 0xFF]) + good[1:]
    cases = {"wrong_size": good[:100], "wrong_fingerprint": wrong_fingerprint}
    for reason, data in cases.items():
        start = time.perf_counter()
        for _ in range(2000):
            inbox.handle(data)
        per_message = (time.perf_counter() - start) / 2000
        assert per_message < 20e-6, (reason, per_message)
    assert inbox.counts()["rejected"] == {"wrong_size": 2000, "wrong_fingerprint": 2000}


@pytest.mark.parametrize(
    ("channel", "fields"),
    [(c.LEG_CONTROL_CHANNEL, LEG_CONTROL_FIELDS), (c.STATE_ESTIMATOR_CHANNEL, STATE_ESTIMATOR_FIELDS)],
)
def test_status_values_read_from_the_bytes_are_the_decoded_fields(channel, fields):
    lcm_type = c.CHANNEL_TYPES[channel]
    read = FloatFields(lcm_type, fields)
    rng = np.random.default_rng(0)
    for _ in range(200):
        message = lcm_type()
        for name, dims in zip(lcm_type.__slots__, lcm_type.__dimensions__, strict=True):
            if dims:
                setattr(message, name, list(rng.normal(size=dims[0]) * 10.0 ** rng.integers(-8, 8)))
            else:
                setattr(message, name, int(rng.integers(0, 2**40)))
        data = message.encode()
        decoded = lcm_type.decode(data)
        expected = np.concatenate([np.asarray(getattr(decoded, name), float) for name in fields])
        assert np.array_equal(read(data), expected)


HARDWARE_RUN = [
    "run_sim.py",
    "--hardware",
    "--mission",
    "hit_target_front",
    "--scenario_text",
    f"{{lcm_buses: {{go1: {{lcm_url: '{URL}'}}}}}}",
]
RAISE_IN_THE_LOOP = """
import sys
from pedi_drake.control.whole_body_controller import WholeBodyController
original = WholeBodyController._update
def failing(self, context, *args):
    if context.get_time() > 2.5:
        raise RuntimeError("injected failure inside the loop")
    return original(self, context, *args)
WholeBodyController._update = failing
sys.argv = %r
import runpy
runpy.run_path("run_sim.py", run_name="__main__")
"""


@pytest.mark.parametrize("exit_path", ["end", "sigint", "sigterm", "exception"])
def test_every_exit_of_a_hardware_run_leaves_damping_on_the_wire(fake_robot, tmp_path, exit_path):
    robot = fake_robot()
    out = ["--out", str(tmp_path / "run")]
    if exit_path == "exception":
        args = ["-c", RAISE_IN_THE_LOOP % (HARDWARE_RUN + out + ["--duration", "6"])]
    else:
        args = HARDWARE_RUN + out + ["--duration", "3" if exit_path == "end" else "8"]
    process, lines = _start(args, "t =   2.0 s")
    if exit_path in ("sigint", "sigterm"):
        process.send_signal(signal.SIGINT if exit_path == "sigint" else signal.SIGTERM)
    process.wait(60)
    record = robot.stop()
    arrivals, damping = record["arrivals"], _is_damping(record["commands"])
    assert np.count_nonzero(~damping) > 100, "".join(lines)  # the loop ran and commanded
    assert damping[-1], "".join(lines)
    # The last stiff command was followed by damping, repeated for the shutdown duration.
    tail = arrivals[np.flatnonzero(~damping)[-1] + 1 :]
    assert tail.size >= 50 and tail[-1] - tail[0] >= 0.25, "".join(lines)


def test_a_link_keeps_what_it_published_only_when_asked_and_wakes_no_receiver():
    bus = lcm.LCM("memq://")
    link = Go1Link(bus, Go1DriverConfig(), url="memq://", threaded=False)
    command = np.concatenate([np.full(12, 0.1), np.zeros(12), np.full(12, 20.0), np.full(12, 0.5), np.zeros(12)])
    assert link.publish_command(command, 0.002)
    assert link.sent_messages is None
    link.keep_sent_messages()
    assert link.publish_command(command, 0.004)
    assert link.publish_command(2 * command, 0.006)
    decode = c.CHANNEL_TYPES[c.COMMAND_CHANNEL].decode
    kept = [c.message_to_command(decode(data)) for data in link.sent_messages]
    np.testing.assert_array_equal(kept, [command, 2 * command])
    assert [decode(data).timestamp_us for data in link.sent_messages] == [4000, 6000]
    # Kept by the link, not by a subscriber: nothing waits on the bus to be handled.
    assert bus.handle_timeout(0) == 0
