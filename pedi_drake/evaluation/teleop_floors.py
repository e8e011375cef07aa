"""The teleoperation floors, judged the same way in a lock-step simulation and at real time.

Three scenarios, each a scripted operator's stream (pedi_drake.operator.message_stream) on an
operator mission:

  * square (pedi_drake.evaluation.teleop_square): the lifted foot driven around a 10 cm square at
    0.1 m/s; floor: the true foot within 1 cm of the square while it is driven;
  * fuzz (pedi_drake.evaluation.command_fuzz): 10,000 foot commands, most of them broken; floor:
    no bound violated, every broken message rejected and counted under its reason;
  * switches (pedi_drake.evaluation.random_switches): 20 random mode switches; floor: every one
    made, no reference or command step beyond the rate limits (pedi_drake.evaluation.reference_steps).
And in all three: the robot never falls, no bound of a teleoperated foot is violated
(pedi_drake.evaluation.teleop_violations).

The truth (`Truth`: the true trunk and feet over diagram time, which no controller reads) comes
from the simulated plant's logged state (`truth_from_plant_log`) or from the simulator bridge's
truth log, put on the controller's diagram time through the wall clock both logged
(`truth_from_bridge_log`). `floor_figures` gives the figures every scenario shares; the
scenario's own come from its module. The runs themselves are pedi_drake.benchmarks.teleop's:
`lock_step_run` in simulation with the operator in lock step on an in-process bus, the benchmark
at real time over UDP.
"""

import dataclasses

import numpy as np

from pedi_drake import robot
from pedi_drake.evaluation.reference_steps import command_step, rate_limit_table, reference_steps
from pedi_drake.evaluation.teleop_violations import teleop_violations
from pedi_drake.fall import fell_during
from pedi_drake.go1_driver.safety import SafetyLimits
from pedi_drake.mission import spec
from pedi_drake.mission.mission_manager import MISSION_PERIOD
from pedi_drake.run_logs import SignalLog
from pedi_drake.scenario import Scenario

# Samples of the plant's state the truth takes (every 5th of the 2 ms log: the bridge's 100 Hz).
PLANT_LOG_STRIDE = 5
# Both sides of every run: the controller side of a hardware run (pedi_drake.apps.sil), the
# operator's foot commands on LCM.
SCENARIO_TEXT = "{controller: whole_body, estimator: kalman, operator: {source: lcm}}"


@dataclasses.dataclass
class Truth:
    """The true trunk and feet at `times` (N,) [s] (the controller's diagram time)."""

    times: np.ndarray
    p_WB: np.ndarray  # (N, 3) [m]
    quaternion_WB: np.ndarray  # (N, 4) (w, x, y, z)
    p_WF: np.ndarray  # (N, 4, 3) [m] foot centres FR, FL, RR, RL

    def fell(self, has_prongs: bool = False) -> bool:
        """The fall rule of pedi_drake.fall at any sample."""
        return fell_during(self.quaternion_WB.T, self.p_WB[:, 2], has_prongs=has_prongs)

    def foot(self, leg: str) -> np.ndarray:
        """(N, 3) the foot centre of `leg` [m]."""
        return self.p_WF[:, robot.LEG_NAMES.index(leg)]


def truth_from_plant_log(plant, plant_state: SignalLog) -> Truth:
    """The truth of a simulation from its logged plant state (`sim.plant_state`)."""
    context = plant.CreateDefaultContext()
    trunk = plant.GetBodyByName(robot.TRUNK_BODY_NAME)
    feet = [plant.GetBodyByName(name) for name in robot.FOOT_BODY_NAMES]
    columns = range(0, plant_state.data.shape[1], PLANT_LOG_STRIDE)
    p_WB, quaternion, p_WF = [], [], []
    for k in columns:
        plant.SetPositionsAndVelocities(context, plant_state.data[:, k])
        X_WB = trunk.EvalPoseInWorld(context)
        p_WB.append(X_WB.translation())
        quaternion.append(X_WB.rotation().ToQuaternion().wxyz())
        p_WF.append([foot.EvalPoseInWorld(context).translation() for foot in feet])
    return Truth(plant_state.times[list(columns)], np.array(p_WB), np.array(quaternion), np.array(p_WF))


def truth_from_bridge_log(truth: dict, wall_clock: SignalLog) -> Truth:
    """The truth of a real-time run from the bridge's truth log (pedi_drake.apps.sim_bridge:
    wall_time, p_WB, quaternion_WB, p_WF), on the diagram time of the controller's `wall_clock`
    log; only the samples while the controller ran."""
    wall, diagram = wall_clock.data[0], wall_clock.times
    inside = (truth["wall_time"] >= wall[0]) & (truth["wall_time"] <= wall[-1])
    times = np.interp(truth["wall_time"][inside], wall, diagram)
    return Truth(times, truth["p_WB"][inside], truth["quaternion_WB"][inside], truth["p_WF"][inside])


def floor_figures(
    result: dict, logs: dict[str, SignalLog], truth: Truth, scenario: Scenario, mission: spec.MissionSpec
) -> dict:
    """The figures every scenario shares: {fell, violations (pedi_drake.evaluation.teleop_violations),
    rate_limits (pedi_drake.evaluation.reference_steps), operator_messages, deadline_misses_per_1000
    (real time only)}. `result` is the run's (result.json's content), `logs` its logged signals."""
    has_prongs = mission.robot is not None and mission.robot.prongs is not None
    steps = reference_steps(
        logs["mission.body_reference"].times,
        logs["mission.body_reference"].data,
        logs["mission.leg_reference"].data,
        MISSION_PERIOD,
    )
    # The controller's first command is made at t = 0 (its first update), logged from the next sample.
    command = command_step(logs["go1.command"].times, logs["go1.command"].data, 0.0)
    max_target_step = SafetyLimits.from_config(scenario.go1_driver.safety).max_target_step
    loop = result.get("driver", {}).get("loop")
    return {
        "fell": bool(truth.fell(has_prongs)),
        "violations": teleop_violations(logs, mission, result["phases"], MISSION_PERIOD),
        "rate_limits": rate_limit_table(steps, command, max_target_step),
        "operator_messages": result["operator_messages"],
        "mode_switches": len(result["mode_switches"]),
        "deadline_misses_per_1000": None if loop is None else loop["deadline_misses_per_1000"],
        "ticks": None if loop is None else loop["ticks"],
    }
