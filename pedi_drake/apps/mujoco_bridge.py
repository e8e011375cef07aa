"""The robot's side of the Go1 LCM protocol around a Go1 in MuJoCo: sim_bridge with another engine.

    python -m pedi_drake.apps.mujoco_bridge [--scenario_file F] [--scenario_name N]
        [--scenario_text YAML] [--mission NAME] [--duration S] [--lcm_url URL] [--latency S]
        [--drop_probability P] [--realtime_rate R] [--truth_log FILE]

The same command line, wire and ground truth as `pedi_drake.apps.sim_bridge`, with the physics of
MuJoCo (`pedi_drake.apps.mujoco_go1.MujocoGo1`: the Go1 of models/go1/go1.xml, generated from the
project's URDF with a real Go1's rotor armature, joint damping and friction and rubber feet, and
the scene converted from the same SDF files) instead of the project's own Drake simulation: a
controller that works against both is not tuned to one engine's contact model.

At 500 Hz of wall time (times `--realtime_rate`) it applies the last `pd_plustau_targets` it
received (holding its first measured pose before the first), advances the physics one bridge
period (two 1 ms steps, the motor law at each) and publishes `leg_control_data` and
`state_estimator_data` from MuJoCo's sensors, filling the fields the real bridge fills
(`StatusEncoder`), optionally late or dropped as sim_bridge does. SIGTERM ends it like Ctrl-C.
`--truth_log` writes on exit sim_bridge's keys (wall_time, p_WB, quaternion_WB, p_WF) plus
`scene_names` and `scene_contact_forces` (N, len(scene_names) * 5): the true normal contact
forces between each scene object and each foot / the rest of the robot
(pedi_drake.station.scene_contact's layout), from which apps.sil judges touches by physics.
"""

import argparse
import collections
import math
import signal
import sys
import time
from pathlib import Path

import numpy as np
from pydrake.lcm import DrakeLcm, DrakeLcmInterface

from pedi_drake.apps.bridge_options import add_bridge_arguments, bridge_settings
from pedi_drake.apps.mujoco_go1 import MujocoGo1, mujoco_foot_radius
from pedi_drake.apps.sim_bridge import TRUTH_LOG_PERIOD
from pedi_drake.apps.status_encoder import StatusEncoder
from pedi_drake.exceptions import ConfigError
from pedi_drake.go1_driver import constants as c
from pedi_drake.go1_driver.config import Go1BridgeConfig
from pedi_drake.go1_driver.hardware_station import go1_lcm_url
from pedi_drake.go1_driver.link import Inbox
from pedi_drake.runtime.interrupt import ctrl_c_raises
from pedi_drake.runtime.realtime_priority import realtime_priority

# Longest the bridge sleeps between two looks at the socket [s], so a late command is taken
# within a fraction of a tick.
_NAP = 0.0005


class TruthLog:
    """The ground truth every TRUTH_LOG_PERIOD of simulated time, stamped with the host's clock."""

    def __init__(self, scene_names: list[str], foot_radius: float):
        self.scene_names = list(scene_names)
        self.foot_radius = float(foot_radius)  # of the robot's feet [m]
        self.rows: dict[str, list] = {key: [] for key in ("wall_time", "p_WB", "quaternion_WB", "p_WF", "forces")}

    def record(self, robot: MujocoGo1) -> None:
        truth = robot.truth_sample()
        self.rows["wall_time"].append(time.time())
        self.rows["p_WB"].append(truth.p_WB)
        self.rows["quaternion_WB"].append(truth.quaternion_WB)
        self.rows["p_WF"].append(truth.p_WF)
        self.rows["forces"].append(truth.scene_contact_forces)

    def write(self, path: Path) -> Path:
        """Writes the npz of the module docstring."""
        n = len(self.rows["wall_time"])
        width = 5 * len(self.scene_names)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(
            path,
            wall_time=np.asarray(self.rows["wall_time"], float).reshape(n),
            p_WB=np.asarray(self.rows["p_WB"], float).reshape(n, 3),
            quaternion_WB=np.asarray(self.rows["quaternion_WB"], float).reshape(n, 4),
            p_WF=np.asarray(self.rows["p_WF"], float).reshape(n, 4, 3),
            scene_names=np.asarray(self.scene_names, dtype=str),
            scene_contact_forces=np.asarray(self.rows["forces"], float).reshape(n, width),
            foot_radius=self.foot_radius,
        )
        return path


class MujocoBridge:
    """MujocoGo1 on the wire: one `tick` takes the newest command, advances a bridge period and
    publishes the status (late by `config.latency`, dropped with `config.drop_probability`)."""

    def __init__(self, robot: MujocoGo1, lcm: DrakeLcmInterface, config: Go1BridgeConfig, *, seed: int = 0):
        self.robot = robot
        self._lcm = lcm
        self._config = config
        self._seed = seed
        self._inbox = Inbox(c.COMMAND_CHANNEL, c.CHANNEL_TYPES[c.COMMAND_CHANNEL], c.message_to_command)
        lcm.Subscribe(c.COMMAND_CHANNEL, self._inbox.handle)
        self._encoder = StatusEncoder()
        depth = int(math.ceil(config.latency / robot.period - 1e-9)) + 1
        self._ring = collections.deque([robot.status_sample()] * depth, maxlen=depth)
        self.truth = TruthLog(robot.scene_names, mujoco_foot_radius())
        self._truth_every = max(1, int(round(TRUTH_LOG_PERIOD / robot.period)))

    def tick(self) -> None:
        """Publishes the status of now, then takes the newest command and advances one period."""
        robot = self.robot
        if robot.ticks % self._truth_every == 0:
            self.truth.record(robot)
        self._publish(robot.ticks)
        self._lcm.HandleSubscriptions(0)
        command, received, _, _ = self._inbox.snapshot()
        if received > 0:
            robot.apply_command(command)
        robot.tick()
        self._ring.append(robot.status_sample())

    def _publish(self, tick: int) -> None:
        p = self._config.drop_probability
        if p > 0.0 and np.random.default_rng([self._seed, tick]).random() < p:
            return
        leg, estimator = self._encoder.encode(self._ring[0], tick)
        t = self.robot.time
        self._lcm.Publish(c.LEG_CONTROL_CHANNEL, leg, t)
        self._lcm.Publish(c.STATE_ESTIMATOR_CHANNEL, estimator, t)

    def commands_received(self) -> int:
        return self._inbox.counts()["received"]


def run_paced(bridge: MujocoBridge, duration: float, realtime_rate: float) -> None:
    """Ticks `bridge` on a schedule of wall time: tick k at start + k period / realtime_rate; a late
    tick runs at once (the schedule is kept, as Drake's Simulator keeps it), looking at the socket
    while it waits."""
    period = bridge.robot.period / realtime_rate
    start = time.monotonic()
    while bridge.robot.time < duration - 1e-9:
        due = start + bridge.robot.ticks * period
        while (wait := due - time.monotonic()) > 0.0:
            time.sleep(min(wait, _NAP))
        bridge.tick()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_bridge_arguments(parser)
    args = parser.parse_args(argv)
    try:
        scenario, config = bridge_settings(args)
        robot = MujocoGo1(scenario)
    except ConfigError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    lcm = DrakeLcm(args.lcm_url or go1_lcm_url(scenario.lcm_buses))
    bridge = MujocoBridge(robot, lcm, config, seed=scenario.random_seed)
    # SIGTERM ends the run like Ctrl-C, so a supervising test or script can stop the bridge cleanly.
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(0))
    ctrl_c_raises()
    try:
        with realtime_priority(config.realtime_priority, who="go1_mujoco_bridge") as scheduling:
            print(f"go1_mujoco_bridge: running on {lcm.get_lcm_url()} ({scheduling})", flush=True)
            run_paced(bridge, args.duration, args.realtime_rate)
    except KeyboardInterrupt:
        pass
    finally:
        if args.truth_log:
            path = bridge.truth.write(args.truth_log)
            print(f"go1_mujoco_bridge: ground truth written to {path} ({time.time():.3f})", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
