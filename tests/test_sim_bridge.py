"""Software in the loop over real UDP multicast (ttl=0, this host only): the simulator bridge in a
second process, the driver here, an lcm-logger-format recorder in a third process on the wire."""

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

import pedi_drake
from pedi_drake.control.stand_controller import StandController
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.config import Go1DriverConfig, Go1SafetyConfig
from pedi_drake.go1_driver.hardware_station import MakeHardwareStation, go1_link
from pedi_drake.go1_driver.log import read_go1_log
from pedi_drake.go1_driver.safety import INTERVENTIONS
from pedi_drake.scenario import load_scenario
from pedi_drake.viz.log_plots import plot_go1_log

REPO = Path(pedi_drake.__file__).resolve().parents[1]
GROUP = "239.255.76.67"
# The Go1 group on a port of its own per test run, so parallel runs and a bridge the user has
# running on 7667 never hear each other; ttl=0 keeps every datagram on this host.
URL = f"udpm://{GROUP}:{20000 + os.getpid() % 20000}?ttl=0"


def _multicast_loops_back(url: str) -> bool:
    sender, receiver = DrakeLcm(url), DrakeLcm(url)
    received: list[bytes] = []
    receiver.Subscribe("pedi_drake_probe", received.append)
    for _ in range(5):
        sender.Publish("pedi_drake_probe", b"probe")
        receiver.HandleSubscriptions(50)
        if received:
            return True
    return False


def _ensure_multicast() -> None:
    try:
        if _multicast_loops_back(URL):
            return
    except RuntimeError:
        pass  # no route at all: DrakeLcm cannot even open the socket
    if os.geteuid() == 0:
        # What `.ci/run` does on a host without a multicast route: route the group via loopback.
        subprocess.run(["ip", "link", "set", "lo", "multicast", "on"], check=False)
        subprocess.run(["ip", "route", "replace", f"{GROUP}/32", "dev", "lo"], check=False)
        try:
            if _multicast_loops_back(URL):
                return
        except RuntimeError:
            pass
    pytest.skip(
        f"no multicast route for {GROUP} on this host (udpm with ttl=0 cannot loop back); as root run "
        f"`ip link set lo multicast on && ip route add {GROUP}/32 dev lo`"
    )


def _env() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO), env.get("PYTHONPATH", "")]))
    return env


def _start(args: list[str], ready_word: str, timeout: float = 60.0) -> subprocess.Popen:
    """Starts `python args` and waits until it prints `ready_word`."""
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
        raise AssertionError(f"{args[:2]} did not start: {''.join(lines)[-2000:]}")
    return process


def _stop(process: subprocess.Popen, sig=signal.SIGINT) -> None:
    if process.poll() is None:
        process.send_signal(sig)
        try:
            process.wait(10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait(5)


@pytest.fixture
def wire(tmp_path):
    """(start_bridge, log_path): the bridge starter and a recorder process logging the whole bus."""
    _ensure_multicast()
    processes: list[subprocess.Popen] = []
    log_path = tmp_path / "wire.lcmlog"
    record = ["-m", "pedi_drake.apps.go1_log", "record", "--out", str(log_path), "--lcm_url", URL]
    recorder = _start(record, "recording")
    processes.append(recorder)

    def start_bridge() -> subprocess.Popen:
        bridge = _start(["-m", "pedi_drake.apps.sim_bridge", "--lcm_url", URL], "running")
        processes.append(bridge)
        return bridge

    yield start_bridge, log_path, recorder
    # A link outlives its loop on purpose (its guard damps a silent loop until the process leaves):
    # close this test's links so that their guards stay off the next test's wire.
    while _LINKS:
        _LINKS.pop().close()
    for process in processes:
        if process.poll() is None:
            os.kill(process.pid, signal.SIGCONT)  # a test may have left the bridge stopped
        _stop(process)


_LINKS: list = []


def _driver(config: Go1DriverConfig | None = None):
    config = config if config is not None else Go1DriverConfig()
    scenario = load_scenario(scenario_text=f"{{lcm_buses: {{go1: {{lcm_url: '{URL}'}}}}}}")
    builder = DiagramBuilder()
    link = go1_link(config, scenario.lcm_buses)
    _LINKS.append(link)
    station = builder.AddNamedSystem("station", MakeHardwareStation(config, link))
    controller = builder.AddNamedSystem("controller", StandController(scenario.stand))
    builder.Connect(station.GetOutputPort("go1.position_measured"), controller.GetInputPort("position_measured"))
    builder.Connect(controller.GetOutputPort("command"), station.GetInputPort("go1.command"))
    for name in ("go1.position_measured", "driver.status", "driver.message_counts"):
        builder.ExportOutput(station.GetOutputPort(name), name)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.set_target_realtime_rate(1.0)
    return diagram, simulator


# For the round trip alone: watchdogs generous enough that a loaded machine (the bridge's
# simulation shares two cores with this process) never trips them; the next test measures them.
PATIENT = Go1DriverConfig(safety=Go1SafetyConfig(status_timeout=0.5, command_timeout=0.5))


def test_driver_stands_the_simulated_go1_up_over_udp_and_the_log_plots(wire, tmp_path):
    start_bridge, log_path, recorder = wire
    start_bridge()
    diagram, simulator = _driver(PATIENT)
    simulator.Initialize()
    simulator.AdvanceTo(3.0)
    context = simulator.get_context()
    q = diagram.GetOutputPort("go1.position_measured").Eval(context)
    np.testing.assert_allclose(q[1::3], 0.9, atol=0.06)
    np.testing.assert_allclose(q[2::3], -1.8, atol=0.06)
    assert diagram.GetOutputPort("driver.status").Eval(context)[0] == 0  # nothing latched
    counts = diagram.GetOutputPort("driver.message_counts").Eval(context)
    assert counts[0] >= 1000 and counts[1] == 0 and counts[3] == 0
    _stop(recorder)
    log = read_go1_log(log_path)
    assert len(log.channels[c.COMMAND_CHANNEL].messages) >= 1400
    assert len(log.channels[c.LEG_CONTROL_CHANNEL].messages) >= 1400
    assert not log.malformed
    # The bridge fills only what the real one fills: world-frame estimator fields stay zero.
    estimator = log.channels[c.STATE_ESTIMATOR_CHANNEL]
    for field in ("p", "vWorld", "vBody", "omegaWorld", "aWorld"):
        assert np.all(estimator.field(field) == 0), field
    assert np.all(np.abs(np.linalg.norm(estimator.field("quat"), axis=1) - 1) < 1e-6)
    paths = plot_go1_log(log, tmp_path / "plots")
    assert [p.name for p in paths] == ["joint_positions.png", "foot_forces.png"]
    assert all(p.stat().st_size > 10_000 for p in paths)


def test_damping_on_the_wire_within_50_ms_when_the_bridge_stops(wire):
    start_bridge, log_path, recorder = wire
    bridge = start_bridge()
    diagram, simulator = _driver()
    simulator.Initialize()
    stopper = threading.Timer(1.5, lambda: os.kill(bridge.pid, signal.SIGSTOP))
    stopper.start()
    simulator.AdvanceTo(2.0)
    stopper.join()
    status = diagram.GetOutputPort("driver.status").Eval(simulator.get_context())
    assert INTERVENTIONS[int(status[0]) - 1] == "status_timeout"
    os.kill(bridge.pid, signal.SIGCONT)
    _stop(recorder)

    log = read_go1_log(log_path)
    commands = log.channels[c.COMMAND_CHANNEL]
    kp = log.commands()[:, 24:36]
    # The first damping command after the soft start (the bridge's SIGSTOP at 1.5 s, or earlier if
    # the loaded machine starved the bridge for 40 ms: either way the status stopped).
    damping = np.flatnonzero(np.all(kp == 0, axis=1) & (commands.times > commands.times[0] + 0.1))
    assert damping.size > 0
    t_damping = commands.times[damping[0]]
    status_times = log.channels[c.LEG_CONTROL_CHANNEL].times
    t_last_status = status_times[status_times < t_damping].max()
    latency = t_damping - t_last_status
    print(f"watchdog: damping on the wire {1000 * latency:.1f} ms after the last status message")
    assert 0.040 <= latency < 0.050
    # Every command after that one is damping too (latched), and none before it was.
    assert np.all(kp[damping[0] :] == 0)
    assert np.all(np.any(kp[: damping[0]] > 0, axis=1)[commands.times[: damping[0]] > commands.times[0] + 0.1])


DRIVER_SCRIPT = """
import sys
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pedi_drake.control.stand_controller import StandController
from pedi_drake.go1_driver.hardware_station import MakeHardwareStation, go1_link
from pedi_drake.scenario import load_scenario
scenario = load_scenario(scenario_text="{lcm_buses: {go1: {lcm_url: '%s'}}}")
builder = DiagramBuilder()
station = builder.AddSystem(MakeHardwareStation(scenario.go1_driver, go1_link(scenario.go1_driver, scenario.lcm_buses)))
controller = builder.AddSystem(StandController(scenario.stand))
builder.Connect(station.GetOutputPort("go1.position_measured"), controller.GetInputPort("position_measured"))
builder.Connect(controller.GetOutputPort("command"), station.GetInputPort("go1.command"))
simulator = Simulator(builder.Build())
simulator.set_target_realtime_rate(1.0)
simulator.Initialize()
print("driving", flush=True)
simulator.AdvanceTo(30.0)
"""


def test_killed_controller_leaves_the_robot_on_its_last_targets(wire):
    """The bridge (like the real one) reuses the last command forever: after the controller process
    dies the legs stay servoed to stale targets, which is why the driver must command damping itself
    whenever it can (status loss, NaN, E-stop) instead of going silent."""
    start_bridge, log_path, recorder = wire
    start_bridge()
    driver = _start(["-c", DRIVER_SCRIPT % URL], "driving")
    time.sleep(1.8)  # mid stand-up: soft start done, the stand blend still moving
    driver.kill()
    driver.wait(5)
    time.sleep(1.5)
    _stop(recorder)

    log = read_go1_log(log_path)
    commands = log.commands()
    last = commands[-1]
    assert np.all(last[24:36] > 0)  # the last command was a stiff one
    t_kill = log.channels[c.COMMAND_CHANNEL].times[-1]
    status = log.channels[c.LEG_CONTROL_CHANNEL]
    after = status.times > t_kill + 0.5
    # The bridge kept publishing (at 500 Hz of its simulated time, which runs slower than the wall
    # clock on a loaded two-core machine) and kept servoing.
    assert np.count_nonzero(after) >= 100
    q_after = status.field("q")[after]
    # Stale targets are still tracked a half second and more after the controller died.
    np.testing.assert_allclose(q_after.mean(axis=0)[1::3], last[0:12][1::3], atol=0.05)
    np.testing.assert_allclose(q_after.mean(axis=0)[2::3], last[0:12][2::3], atol=0.08)
    assert np.all(q_after.std(axis=0) < 0.01)
