"""A hardware run starts from the robot's first status, as a simulation starts from its plant.

The status receiver waits for the robot's first messages while the diagram initialises. The state
estimator initialises from them in the same Initialize, so the mission manager's first update (at
t = 0) plans from an estimated trunk, never from the estimator's unset output (a trunk at the
world origin, which made every stand-up on hardware begin by pushing the trunk down to z = 0).
"""

from pathlib import Path

import numpy as np

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
