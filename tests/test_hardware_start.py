"""A hardware run starts from the robot's first status, as a simulation starts from its plant, and
each tick estimates from the status it latched.

The status receiver waits for the robot's first messages while the diagram initialises. The state
estimator initialises from them in the same Initialize, so the mission manager's first update (at
t = 0) plans from an estimated trunk, never from the estimator's unset output (a trunk at the
world origin, which made every stand-up on hardware begin by pushing the trunk down to z = 0).
At every tick the receiver latches before the estimator updates, so the estimate is never a
status older than the tick's own.
"""

from pathlib import Path

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RollPitchYaw, RotationMatrix

from pedi_drake.apps.status_sample import IMU_QUATERNION
from pedi_drake.benchmarks.controller_latency import Replay

FIXTURE = Path(__file__).parent / "fixtures" / "controller_side_reference.npz"


def test_first_mission_update_plans_from_an_estimated_trunk():
    reference = np.load(FIXTURE)
    replay = Replay(str(reference["mission"]), float(reference["period"]), reference["status"].astype(float))
    replay.run(3)
    context = replay.simulator.get_context()
    estimator = replay.diagram.GetSubsystemByName("estimator")
    base_state = estimator.GetOutputPort("base_state").Eval(estimator.GetMyContextFromRoot(context))
    trunk_height = base_state[6]
    # The recorded run starts lying down: the trunk a few centimetres above the floor.
    assert 0.05 < trunk_height < 0.3
    body_reference = replay.manager.GetOutputPort("body_reference").Eval(replay.manager.GetMyContextFromRoot(context))
    # Three ticks into a 2 s stand-up the reference has barely left where the stand-up began.
    assert abs(body_reference[2] - trunk_height) < 0.005


def test_each_tick_estimates_from_the_status_it_latched():
    reference = np.load(FIXTURE)
    status = reference["status"].astype(float)[:40].copy()
    # Every sample's IMU says a different yaw (1 mrad steps), so the estimate names its sample.
    for k in range(len(status)):
        rotation = RotationMatrix(RollPitchYaw(0.0, 0.0, 0.3 + 1e-3 * k))
        status[k, IMU_QUATERNION] = rotation.ToQuaternion().wxyz()
    replay = Replay(str(reference["mission"]), float(reference["period"]), status)
    ticks = 10
    # The replay publishes sample k + 1 before tick k (sample 0 is the start's status), so the
    # last tick, tick 9, latches sample 10.
    replay.run(ticks)
    estimator = replay.diagram.GetSubsystemByName("estimator")
    context = estimator.GetMyContextFromRoot(replay.simulator.get_context())
    quaternion = estimator.GetOutputPort("base_state").Eval(context)[0:4]
    yaw = RollPitchYaw(RotationMatrix(Quaternion(quaternion / np.linalg.norm(quaternion)))).yaw_angle()
    # Float32 on the wire: the yaw within 1e-5 rad of its sample's, 1e-3 from the neighbours'.
    assert abs(yaw - (0.3 + 1e-3 * ticks)) < 1e-5, f"estimated yaw {yaw:.5f}: sample {(yaw - 0.3) / 1e-3:.2f}"
