"""The Go1 LCM driver, in process: one shared DrakeLcm("memq://") between it and the simulator bridge."""

import dataclasses
import time

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, LeafSystem
from pydrake.systems.primitives import ConstantVectorSource

from pedi_drake import robot
from pedi_drake.apps.sim_bridge import MakeSimBridgeDiagram
from pedi_drake.control.stand_controller import StandController
from pedi_drake.exceptions import LcmTimeout
from pedi_drake.go1_command import pack_command, split_command
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.config import Go1DriverConfig, Go1SafetyConfig
from pedi_drake.go1_driver.hardware_station import MakeHardwareStation
from pedi_drake.go1_driver.lcmtypes import leg_control_data_lcmt, pd_tau_targets_lcmt, rc_command_lcmt
from pedi_drake.go1_driver.link import DrakeLcmTransport, Go1Link
from pedi_drake.go1_driver.safety import INTERVENTION_INDEX, INTERVENTIONS
from pedi_drake.scenario import Scenario, load_scenario
from pedi_drake.station_interface import STATION_PORTS

# Lock-step runs are faster than real time but not paced: generous watchdogs keep them
# deterministic on a loaded machine; the watchdogs themselves are tested on the wire.
LOCKSTEP_CONFIG = Go1DriverConfig(
    first_status_timeout=1.0, safety=Go1SafetyConfig(status_timeout=1.0, command_timeout=1.0)
)


def _lockstep_link(lcm: DrakeLcm, config: Go1DriverConfig = LOCKSTEP_CONFIG) -> Go1Link:
    return Go1Link(DrakeLcmTransport(lcm), config, url=lcm.get_lcm_url(), threaded=False)


def _wire_log(lcm: DrakeLcm, channel: str = c.COMMAND_CHANNEL) -> list[bytes]:
    received: list[bytes] = []
    lcm.Subscribe(channel, received.append)
    return received


class LockStep:
    """The simulator bridge and a driver diagram (station + a command source) advanced in turns."""

    def __init__(self, scenario: Scenario, command_source, config: Go1DriverConfig = LOCKSTEP_CONFIG):
        self.lcm = DrakeLcm("memq://")
        self.wire = _wire_log(self.lcm)
        self.bridge = MakeSimBridgeDiagram(scenario, self.lcm)
        builder = DiagramBuilder()
        self.link = _lockstep_link(self.lcm, config)
        station = builder.AddNamedSystem("station", MakeHardwareStation(config, self.link))
        source = builder.AddNamedSystem("controller", command_source)
        if source.HasInputPort("position_measured"):
            builder.Connect(station.GetOutputPort("go1.position_measured"), source.GetInputPort("position_measured"))
        builder.Connect(source.get_output_port(), station.GetInputPort("go1.command"))
        for i in range(station.num_output_ports()):
            builder.ExportOutput(station.get_output_port(i), station.get_output_port(i).get_name())
        builder.ExportInput(station.GetInputPort("driver.estop"), "driver.estop")
        self.driver = builder.Build()
        # The bridge publishes its first status at initialisation; the driver waits for it.
        self.bridge_simulator = Simulator(self.bridge)
        self.bridge_simulator.Initialize()
        self.driver_simulator = Simulator(self.driver)
        self.driver_context = self.driver_simulator.get_mutable_context()
        self.driver.GetInputPort("driver.estop").FixValue(self.driver_context, [0.0])
        self.driver_simulator.Initialize()

    def advance(self, duration: float, period: float = c.BRIDGE_PERIOD) -> None:
        """Runs `duration` [s] of ticks; both stop at the next tick's instant (tick times from an
        integer count: a sum of periods drifts off them)."""
        done = int(round(self.driver_context.get_time() / period))
        for k in range(done + 1, done + 1 + int(round(duration / period))):
            self.bridge_simulator.AdvanceTo(k * period)
            self.driver_simulator.AdvanceTo(k * period)
            # The tick's command left after the driver's receive handled the shared bus: deliver
            # it now (to the bridge and the log), as a network would, not at the next tick.
            self.lcm.HandleSubscriptions(0)

    def output(self, name: str) -> np.ndarray:
        return self.driver.GetOutputPort(name).Eval(self.driver_context)

    def count(self, name: str) -> int:
        return int(self.output("driver.status")[1 + INTERVENTION_INDEX[name]])

    def plant_state(self) -> np.ndarray:
        return self.bridge.GetOutputPort("sim.plant_state").Eval(self.bridge_simulator.get_context())

    def wire_commands(self) -> np.ndarray:
        return np.array([c.message_to_command(pd_tau_targets_lcmt.decode(data)) for data in self.wire])


@pytest.fixture(scope="module")
def scenario() -> Scenario:
    return load_scenario()


def test_station_exports_exactly_the_station_ports(scenario):
    station = MakeHardwareStation(scenario.go1_driver, _lockstep_link(DrakeLcm("memq://")))
    inputs = {station.get_input_port(i).get_name(): station.get_input_port(i) for i in range(station.num_input_ports())}
    outputs = {
        station.get_output_port(i).get_name(): station.get_output_port(i) for i in range(station.num_output_ports())
    }
    for name, (direction, size) in STATION_PORTS.items():
        ports = inputs if direction == "input" else outputs
        assert ports[name].size() == size, name
    extra = (set(inputs) | set(outputs)) - set(STATION_PORTS)
    assert all(name.startswith("driver.") for name in extra), extra


def test_round_trip_stands_the_robot_up(scenario):
    run = LockStep(scenario, StandController(scenario.stand))
    run.advance(2.5)
    # The robot stood up through the wire: trunk near the standing height (0.285 m for 0.9/-1.8).
    x = run.plant_state()
    _, plant_map = robot.make_go1_plant()
    assert x[plant_map.base_q_start + 6] == pytest.approx(robot.trunk_height_for(0.9, -1.8), abs=0.02)
    q = run.output("go1.position_measured")
    np.testing.assert_allclose(q[1::3], 0.9, atol=0.06)  # thighs
    np.testing.assert_allclose(q[2::3], -1.8, atol=0.06)  # calves
    # One command a tick on the wire; the bridge took in every one but the last (sent after its
    # final step), none was malformed, and it applies the latest it took in.
    counts = run.bridge.GetOutputPort("bridge.command_counts").Eval(run.bridge_simulator.get_context())
    assert len(run.wire) == 1250
    assert counts[1] == 0 and counts[0] == len(run.wire) - 1
    applied = run.bridge.GetOutputPort("bridge.applied_command").Eval(run.bridge_simulator.get_context())
    np.testing.assert_array_equal(applied, run.wire_commands()[int(counts[0]) - 1])
    # The driver's status stays clean: nothing latched, no malformed status messages.
    status = run.output("driver.status")
    assert status[0] == 0
    assert run.output("driver.message_counts")[[1, 3]].tolist() == [0, 0]


def test_waits_for_first_status_and_names_channel_and_url(scenario):
    config = dataclasses.replace(LOCKSTEP_CONFIG, first_status_timeout=0.2)
    station = MakeHardwareStation(config, _lockstep_link(DrakeLcm("memq://"), config))
    simulator = Simulator(station)
    station.GetInputPort("go1.command").FixValue(simulator.get_mutable_context(), np.zeros(60))
    start = time.monotonic()
    with pytest.raises(LcmTimeout, match=r"'leg_control_data' at memq://"):
        simulator.Initialize()
    assert 0.2 <= time.monotonic() - start < 1.0


def test_malformed_and_foreign_messages_are_dropped_and_counted(scenario):
    run = LockStep(scenario, ConstantVectorSource(pack_command(robot.LYING_Q, 0, 20, 1, 0)))
    run.advance(0.02)
    good = leg_control_data_lcmt.decode(_last_status(run))
    bad_fingerprint = bytearray(good.encode())
    bad_fingerprint[0] ^= 0xFF
    for data in (
        bytes(bad_fingerprint),  # wrong fingerprint, right size
        good.encode()[:100],  # truncated
        rc_command_lcmt().encode(),  # a foreign type on this channel
        good.encode() + b"\0",  # trailing garbage
    ):
        run.lcm.Publish(c.LEG_CONTROL_CHANNEL, data)
    run.lcm.Publish(c.STATE_ESTIMATOR_CHANNEL, b"")
    run.advance(0.02)
    counts = run.output("driver.message_counts")
    assert counts[1] == 4  # leg_control_data dropped
    assert counts[3] == 1  # state_estimator_data dropped
    assert np.all(np.isfinite(run.output("go1.position_measured")))
    assert run.output("driver.status")[0] == 0


class _TickCounter(LeafSystem):
    """A controller whose command names the tick that computed it: kp = 10 + 0.01 n on every joint
    at its n-th update (n from 0, one update a tick), kd 1, no torque."""

    def __init__(self, period: float = c.BRIDGE_PERIOD):
        super().__init__()
        self._updates = self.DeclareDiscreteState(1)
        self._command = self.DeclareDiscreteState(pack_command(robot.STANDING_Q, 0.0, 0.0, 1.0, 0.0))
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareStateOutputPort("command", self._command)

    def _update(self, context, discrete_state) -> None:
        n = context.get_discrete_state(self._updates).get_value()[0]
        discrete_state.get_mutable_vector(self._updates).SetAtIndex(0, n + 1)
        discrete_state.get_mutable_vector(self._command).SetFromVector(
            pack_command(robot.STANDING_Q, 0.0, 10.0 + 0.01 * n, 1.0, 0.0)
        )


def test_each_tick_sends_the_command_computed_in_it(scenario):
    run = LockStep(scenario, _TickCounter())
    run.advance(0.1)
    messages = [pd_tau_targets_lcmt.decode(data) for data in run.wire]
    # One message a tick, stamped with its tick's time, carrying that tick's command (the safety
    # filter and the sender run after the controller in the same tick).
    assert len(messages) == 50
    ticks = np.arange(50)
    np.testing.assert_array_equal([m.timestamp_us for m in messages], 2000 * ticks)
    kp = run.wire_commands()[:, 24:36]
    np.testing.assert_allclose(kp, np.repeat(10.0 + 0.01 * ticks, 12).reshape(50, 12), atol=1e-5)


def _last_status(run: LockStep) -> bytes:
    sample: list[bytes] = []
    run.lcm.Subscribe(c.LEG_CONTROL_CHANNEL, sample.append)
    run.advance(0.004)
    return sample[-1]


def test_nan_and_huge_controller_outputs_never_reach_the_wire(scenario, rng):
    command = pack_command(robot.STANDING_Q, 1e9, 1e6, -5, 1e12)
    command[rng.choice(60, 6, replace=False)] = np.nan
    run = LockStep(scenario, ConstantVectorSource(command))
    run.advance(0.2)
    wire = run.wire_commands()
    assert len(wire) >= 100 and np.all(np.isfinite(wire))
    for published in wire:
        _, qd_des, kp, kd, tau_ff = split_command(published)
        assert np.all(kp == 0) and np.all(kd > 0) and np.all(tau_ff == 0) and np.all(qd_des == 0)
    assert run.count("nonfinite_command") == len(wire)


def test_remote_button_latches_damping(scenario):
    run = LockStep(scenario, StandController(scenario.stand))
    run.advance(0.3)
    pressed = rc_command_lcmt()
    pressed.right_lower_right_switch = 1
    run.lcm.Publish(c.RC_COMMAND_CHANNEL, pressed.encode())
    run.lcm.Publish(c.RC_COMMAND_CHANNEL, rc_command_lcmt().encode())  # released before the next tick
    n_before = len(run.wire)
    run.advance(0.1)
    after = run.wire_commands()[n_before + 2 :]
    assert len(after) >= 40 and np.all(after[:, 24:36] == 0)
    assert np.all(after[:, 36:48] > 0) and np.all(after[:, 48:60] == 0)
    status = run.output("driver.status")
    assert INTERVENTIONS[int(status[0]) - 1] == "estop_remote"


def test_estop_port_latches_damping(scenario):
    run = LockStep(scenario, StandController(scenario.stand))
    run.advance(0.3)
    assert np.all(run.wire_commands()[-1][24:36] > 0)
    run.driver.GetInputPort("driver.estop").FixValue(run.driver_context, [1.0])
    run.advance(0.01)
    run.driver.GetInputPort("driver.estop").FixValue(run.driver_context, [0.0])
    n_before = len(run.wire)
    run.advance(0.1)
    after = run.wire_commands()[n_before:]
    assert np.all(after[:, 24:36] == 0) and np.all(after[:, 36:48] > 0)
    assert run.count("estop_port") == 5  # counted on every tick the input was held (10 ms)
