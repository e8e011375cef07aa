"""The robot's side of the Go1 LCM protocol, around the simulated Go1: a stand-in for the real bridge.

    python -m pedi_drake.apps.sim_bridge [--scenario_file F] [--scenario_name N]
        [--scenario_text YAML] [--mission NAME] [--duration S] [--lcm_url URL] [--latency S]
        [--drop_probability P] [--truth_log FILE]

Runs `MakeStation(scenario, hardware=False)` in real time and, like walk-these-ways' `lcm_position`
on a Go1, at 500 Hz: publishes `leg_control_data` and `state_estimator_data`, filling only the
fields the real bridge fills (q, qd, tau_est; quat, rpy, omegaBody, aBody, contact_estimate; the
world-frame fields stay 0), and applies the last `pd_plustau_targets` it received (holding the
initial pose until the first one). Optional latency and dropped messages; sensor noise comes
from the scenario's `sensor_noise`. A controller started with `MakeStation(..., hardware=True)`
on the same URL (default udpm://239.255.76.67:7667?ttl=0, this host only) drives it over UDP,
e.g. `python run_sim.py --hardware --mission hit_target_front` in a second terminal.

`--mission` adds the mission's scene objects and robot variant, as run_sim does. `--truth_log`
writes the simulated ground truth on exit (wall-clock time [s], trunk pose, foot positions in
world, the robot's normal contact forces on each scene object), which no controller
sees: `pedi_drake.apps.sil` uses it to judge a run over the wire.
"""

import argparse
import math
import signal
import sys
import time
from pathlib import Path

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.lcm import DrakeLcm, DrakeLcmInterface
from pydrake.math import RollPitchYaw
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import BasicVector, DiagramBuilder, DiscreteValues
from pydrake.systems.lcm import LcmInterfaceSystem
from pydrake.systems.primitives import VectorLogSink

from pedi_drake import robot
from pedi_drake.apps.bridge_options import add_bridge_arguments, bridge_settings
from pedi_drake.apps.status_encoder import StatusEncoder
from pedi_drake.apps.status_sample import (
    IMU_ACCELEROMETER,
    IMU_GYRO,
    IMU_QUATERNION,
    SAMPLE,
    SAMPLE_SIZE,
    STATUS_SIGNALS,
)
from pedi_drake.exceptions import ConfigError
from pedi_drake.go1_command import COMMAND_SIZE, pack_command
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.config import Go1BridgeConfig
from pedi_drake.go1_driver.hardware_station import go1_lcm_url
from pedi_drake.go1_driver.lcmtypes import leg_control_data_lcmt, state_estimator_lcmt
from pedi_drake.go1_driver.link import Inbox
from pedi_drake.go1_driver.status_receiver import MakeLcmReceiver, ReceiverChannel
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.runtime.interrupt import ctrl_c_raises
from pedi_drake.runtime.realtime_priority import realtime_priority
from pedi_drake.runtime.wall_clock import WallClock
from pedi_drake.scenario import Scenario
from pedi_drake.station_interface import MakeStation

# Period of the ground-truth log [s].
TRUTH_LOG_PERIOD = 0.01

# Gains with which the bridge holds the initial pose until the first command [N m/rad], [N m s/rad].
HOLD_KP = 60.0
HOLD_KD = 2.0


class Go1BridgeCommandHold(LeafSystemWithoutWitnesses):
    """received command + its message count + measured pose -> the command applied to the motors.

    Before the first command arrives the bridge holds the pose measured at its first tick (as the
    real bridge does); afterwards it applies the last command received, every tick, unchanged.
    State: [q_start (12), captured flag].
    """

    def __init__(self, period: float = c.BRIDGE_PERIOD):
        super().__init__()
        self._received = self.DeclareVectorInputPort("received_command", COMMAND_SIZE)
        self._counts = self.DeclareVectorInputPort("message_counts", 2)
        self._q = self.DeclareVectorInputPort("position_measured", 12)
        self._start = self.DeclareDiscreteState(13)
        self.DeclareInitializationDiscreteUpdateEvent(self._capture)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._capture)
        # Not a function of the measured pose (only of the pose captured in the state): no loop.
        self.DeclareVectorOutputPort(
            "command", COMMAND_SIZE, self._calc, {self._received.ticket(), self._counts.ticket(), self.xd_ticket()}
        )

    def _capture(self, context, discrete_state: DiscreteValues) -> None:
        x = context.get_discrete_state(self._start).get_value()
        if x[12] == 0.0:
            discrete_state.set_value(self._start, np.concatenate([self._q.Eval(context), [1.0]]))

    def _calc(self, context, output: BasicVector) -> None:
        if self._counts.Eval(context)[0] > 0:
            output.SetFromVector(self._received.Eval(context))
            return
        q_start = context.get_discrete_state(self._start).get_value()[:12]
        output.SetFromVector(pack_command(q_start, 0.0, HOLD_KP, HOLD_KD, 0.0))


class Go1BridgeStatusPublisher(LeafSystemWithoutWitnesses):
    """Station outputs -> leg_control_data and state_estimator_data at 500 Hz, optionally late or dropped.

    Latency is modelled in the Context: a ring of the last ceil(latency / period) + 1 samples,
    of which the oldest is published. A tick is dropped when a draw seeded by (seed, tick) falls
    below drop_probability, so drops are reproducible and need no random state.
    """

    def __init__(
        self, lcm: DrakeLcmInterface, config: Go1BridgeConfig, *, seed: int = 0, period: float = c.BRIDGE_PERIOD
    ):
        super().__init__()
        self._lcm = lcm
        self._config = config
        self._seed = seed
        self._period = period
        self._depth = int(math.ceil(config.latency / period - 1e-9)) + 1
        # One input per station output of the sample, named without the "go1." prefix.
        self._inputs = [
            self.DeclareVectorInputPort(name.removeprefix("go1."), SAMPLE[name].stop - SAMPLE[name].start)
            for name in STATUS_SIGNALS
        ]
        self._sample_slices = [SAMPLE[name] for name in STATUS_SIGNALS]
        self._encoder = StatusEncoder()
        # [ring of samples (depth x 50), newest slot index, tick]
        self._ring = self.DeclareDiscreteState(self._depth * SAMPLE_SIZE + 2)
        self.DeclareInitializationDiscreteUpdateEvent(self._fill)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._push)
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish)

    def _sample(self, context) -> np.ndarray:
        return np.concatenate([port.Eval(context) for port in self._inputs])

    def _fill(self, context, discrete_state: DiscreteValues) -> None:
        sample = self._sample(context)
        discrete_state.set_value(self._ring, np.concatenate([np.tile(sample, self._depth), [0.0, 0.0]]))

    def _push(self, context, discrete_state: DiscreteValues) -> None:
        # The update's state starts as a copy of the current one: written in place.
        x = discrete_state.get_mutable_value(self._ring)
        newest = (int(x[-2]) + 1) % self._depth
        start = newest * SAMPLE_SIZE
        for port, rows in zip(self._inputs, self._sample_slices, strict=True):
            x[start + rows.start : start + rows.stop] = port.Eval(context)
        x[-2] = newest
        x[-1] += 1

    def _publish(self, context) -> None:
        x = context.get_discrete_state(self._ring).get_value()
        tick = int(x[-1])
        p = self._config.drop_probability
        if p > 0.0 and np.random.default_rng([self._seed, tick]).random() < p:
            return
        oldest = (int(x[-2]) + 1) % self._depth
        sample = x[oldest * SAMPLE_SIZE : (oldest + 1) * SAMPLE_SIZE]
        t = context.get_time()
        leg, estimator = self._encoder.encode(sample, tick)
        self._lcm.Publish(c.LEG_CONTROL_CHANNEL, leg, t)
        self._lcm.Publish(c.STATE_ESTIMATOR_CHANNEL, estimator, t)


def status_messages(sample: np.ndarray, tick: int) -> tuple[leg_control_data_lcmt, state_estimator_lcmt]:
    """The two status messages of one status sample (`status_sample`), filled as the real bridge fills them."""
    leg = leg_control_data_lcmt()
    leg.q = sample[SAMPLE["go1.position_measured"]].tolist()
    leg.qd = sample[SAMPLE["go1.velocity_measured"]].tolist()
    leg.tau_est = sample[SAMPLE["go1.torque_estimated"]].tolist()
    leg.id = tick
    estimator = state_estimator_lcmt()
    quaternion = sample[IMU_QUATERNION] / np.linalg.norm(sample[IMU_QUATERNION])
    estimator.quat = quaternion.tolist()
    estimator.rpy = RollPitchYaw(Quaternion(quaternion)).vector().tolist()
    estimator.omegaBody = sample[IMU_GYRO].tolist()
    estimator.aBody = sample[IMU_ACCELEROMETER].tolist()
    estimator.contact_estimate = sample[SAMPLE["go1.foot_contact"]].tolist()
    estimator.id = tick
    return leg, estimator


def MakeSimBridgeDiagram(scenario: Scenario, lcm: DrakeLcmInterface, config: Go1BridgeConfig | None = None):
    """The simulated station ("station") wired to the robot side of the protocol on `lcm`."""
    config = config if config is not None else scenario.go1_driver.bridge
    builder = DiagramBuilder()
    builder.AddNamedSystem("lcm", LcmInterfaceSystem(lcm))
    station = builder.AddNamedSystem("station", MakeStation(scenario, hardware=False))
    inbox = Inbox(c.COMMAND_CHANNEL, c.CHANNEL_TYPES[c.COMMAND_CHANNEL], c.message_to_command)
    lcm.Subscribe(c.COMMAND_CHANNEL, inbox.handle)
    receiver = builder.AddNamedSystem(
        "command_receiver",
        MakeLcmReceiver(
            [ReceiverChannel(inbox, np.zeros(COMMAND_SIZE), {"command": slice(0, COMMAND_SIZE)})],
            period=c.BRIDGE_PERIOD,
        ),
    )
    hold = builder.AddNamedSystem("command_hold", Go1BridgeCommandHold())
    builder.Connect(receiver.GetOutputPort("command"), hold.GetInputPort("received_command"))
    builder.Connect(receiver.GetOutputPort("message_counts"), hold.GetInputPort("message_counts"))
    builder.Connect(station.GetOutputPort("go1.position_measured"), hold.GetInputPort("position_measured"))
    builder.Connect(hold.GetOutputPort("command"), station.GetInputPort("go1.command"))
    publisher = builder.AddNamedSystem(
        "status_publisher", Go1BridgeStatusPublisher(lcm, config, seed=scenario.random_seed)
    )
    for name in STATUS_SIGNALS:
        builder.Connect(station.GetOutputPort(name), publisher.GetInputPort(name.removeprefix("go1.")))
    builder.ExportOutput(hold.GetOutputPort("command"), "bridge.applied_command")
    builder.ExportOutput(receiver.GetOutputPort("message_counts"), "bridge.command_counts")
    builder.ExportOutput(station.GetOutputPort("sim.plant_state"), "sim.plant_state")
    clock = builder.AddNamedSystem("wall_clock", WallClock())
    logged = [
        ("log.plant_state", station.GetOutputPort("sim.plant_state")),
        ("log.wall_clock", clock.clock),
        ("log.foot_contact_forces", station.GetOutputPort("sim.foot_contact_forces")),
    ]
    if scenario.scene:  # the robot's contact forces on each scene object (none without a scene)
        logged.append(("log.scene_contact_forces", station.GetOutputPort("sim.scene_contact_forces")))
    for name, port in logged:
        logger = builder.AddNamedSystem(name, VectorLogSink(port.size(), TRUTH_LOG_PERIOD))
        builder.Connect(port, logger.get_input_port())
    diagram = builder.Build()
    diagram.set_name("go1_sim_bridge")
    return diagram


# The truth log's keys that only this bridge writes (the MuJoCo robot's has the others): its plant's
# state is what apps.sil judges a mission's physical checks on.
DRAKE_ONLY_TRUTH = ("plant_states", "foot_contact_forces")


def write_truth_log(
    diagram, context, path: Path, scene_names: list[str] = (), foot_radius: float = robot.FOOT_RADIUS
) -> Path:
    """Writes the bridge's ground truth to `path` (npz): wall_time (N,) [s], p_WB (N, 3) [m],
    quaternion_WB (N, 4) (w, x, y, z), p_WF (N, 4, 3) foot centres FR, FL, RR, RL [m],
    scene_names (the scene's object names, in order) and scene_contact_forces (N, len(scene_names) * 5)
    [N]: the true normal contact forces between each object and each foot / the rest of the robot
    (`sim.scene_contact_forces`, in the order of pedi_drake.station.scene_contact.scene_contact_index),
    foot_radius, the simulated feet's [m], plant_states (N, nx), the whole plant's state (the scene's
    objects too: what the mission's physical checks read), and foot_contact_forces (N, 12) [N], the
    true contact force on each foot, world frame."""
    plant = diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    states = diagram.GetSubsystemByName("log.plant_state").FindLog(context).data()
    wall = diagram.GetSubsystemByName("log.wall_clock").FindLog(context).data()[0]
    plant_context = plant.CreateDefaultContext()
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME)
    feet = [plant.GetBodyByName(name) for name in robot.FOOT_BODY_NAMES]
    logged_forces = (
        diagram.GetSubsystemByName("log.scene_contact_forces").FindLog(context).data() if scene_names else None
    )
    foot_forces = diagram.GetSubsystemByName("log.foot_contact_forces").FindLog(context).data()
    n = min(
        states.shape[1],
        len(wall),
        foot_forces.shape[1],
        logged_forces.shape[1] if logged_forces is not None else len(wall),
    )
    p_WB, quaternion, p_WF = np.zeros((n, 3)), np.zeros((n, 4)), np.zeros((n, 4, 3))
    for k in range(n):
        plant.SetPositionsAndVelocities(plant_context, states[:, k])
        X_WB = plant.EvalBodyPoseInWorld(plant_context, trunk)
        p_WB[k], quaternion[k] = X_WB.translation(), X_WB.rotation().ToQuaternion().wxyz()
        for i, foot in enumerate(feet):
            p_WF[k, i] = plant.EvalBodyPoseInWorld(plant_context, foot).translation()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    forces = logged_forces[:, :n].T if logged_forces is not None else np.zeros((n, 0))
    np.savez_compressed(
        path,
        wall_time=wall[:n],
        p_WB=p_WB,
        quaternion_WB=quaternion,
        p_WF=p_WF,
        scene_names=np.asarray(list(scene_names), dtype=str),
        scene_contact_forces=forces,
        foot_radius=foot_radius,
        plant_states=states[:, :n].T,
        foot_contact_forces=foot_forces[:, :n].T,
    )
    return path


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bridge_arguments(parser)
    args = parser.parse_args(argv)
    try:
        scenario, config = bridge_settings(args)
    except ConfigError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    lcm = DrakeLcm(args.lcm_url or go1_lcm_url(scenario.lcm_buses))
    diagram = MakeSimBridgeDiagram(scenario, lcm, config)
    simulator = Simulator(diagram)
    simulator.set_target_realtime_rate(args.realtime_rate)
    # SIGTERM ends the run like Ctrl-C, so a supervising test or script can stop the bridge cleanly.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    ctrl_c_raises()
    simulator.Initialize()
    try:
        with realtime_priority(config.realtime_priority, who="go1_sim_bridge") as scheduling:
            print(f"go1_sim_bridge: running on {lcm.get_lcm_url()} ({scheduling})", flush=True)
            # AdvanceTo needs a finite time: advance in 1 s chunks until the duration (or forever).
            while simulator.get_context().get_time() < args.duration:
                simulator.AdvanceTo(min(simulator.get_context().get_time() + 1.0, args.duration))
    except KeyboardInterrupt:
        pass
    finally:
        if args.truth_log:
            scene_names = [obj.instance_name for obj in scenario.scene]
            radius = scenario.model_error.foot_radius
            path = write_truth_log(diagram, simulator.get_context(), args.truth_log, scene_names, radius)
            print(f"go1_sim_bridge: ground truth written to {path} ({time.time():.3f})", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
