"""The balance bound in simulation: a scripted operator drives the lifted FR foot into a rigid wall
(a block welded to the floor) and keeps pushing; the foot's force stays below half the live SUF
along the push, the robot does not tip, and the operator feels the force on the feedback channel.

The robot moves only through go1.command; the mission reads the estimate and the operator input.
Ground truth (the plant's contact force between the FR foot and the wall, the trunk's attitude,
the stance feet) is read only here. Run with -s to see the figures.
"""

from pathlib import Path

import numpy as np
import pytest
from pydrake.lcm import DrakeLcm
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from pedi_drake import robot
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.evaluation.live_suf import live_suf_summary, update_samples
from pedi_drake.evaluation.mission_results import phase_table
from pedi_drake.fall import fell_during
from pedi_drake.go1_driver.lcmtypes import foot_feedback_lcmt
from pedi_drake.operator.command import MODE_TELEOP
from pedi_drake.operator.config import DEFAULT_FOOT_FEEDBACK_CHANNEL
from pedi_drake.operator.scripted_operator import ScriptedOperator, ScriptStep
from pedi_drake.scenario import load_scenario
from pedi_drake.station.scene_contact import scene_contact_index
from pedi_drake.suf.warm_projection import EXACT

MISSION = Path(__file__).parent / "fixtures" / "teleop_wall.yaml"
MARGIN = 0.5  # the mission's balance_margin
PUSH_START, END = 2.4, 7.0  # [s]: the operator pushes forward at 0.1 m/s from PUSH_START on
# Floors: the stance feet stay loaded (none lifts: the robot does not tip) and the trunk tilts
# less than this; the true wall force stays below the margin of the SUF along the push.
MAX_TILT = np.radians(10.0)
STANCE_FOOT_MIN_FORCE = 5.0  # [N]
# The wall is touched when its true force on the foot first exceeds TOUCH_FORCE [N]; the impact
# lasts IMPACT [s] (see the balance test).
TOUCH_FORCE = 1.0
IMPACT = 0.02


# The balance bound alone, on a controller whose model is the plant: the trunk's load compensation
# would learn the estimator's small biases (about 0.2 m/s^2) and move the stance's share of the
# push by a fraction of a percent, which the strict floor below is not about.
@pytest.fixture(scope="module")
def wall_run():
    lcm = DrakeLcm("memq://")
    feedback = []
    lcm.Subscribe(DEFAULT_FOOT_FEEDBACK_CHANNEL, lambda data: feedback.append(foot_feedback_lcmt.decode(data)))
    scenario = load_scenario(
        scenario_text=(
            f"{{mission: {MISSION}, simulation_duration: {END}, robot: {{initial_pose: standing}}, "
            "operator: {source: lcm}, controller: whole_body, trunk_load_compensation: {enabled: false}}"
        )
    )
    built = MakePedipulationDiagram(scenario, operator_lcm=lcm)
    builder = DiagramBuilder()
    diagram = builder.AddSystem(built.diagram)
    script = [ScriptStep(0.0, mode_request=MODE_TELEOP), ScriptStep(PUSH_START, (0.1, 0.0, 0.0))]
    builder.AddSystem(ScriptedOperator(lcm, script))
    simulator = Simulator(builder.Build())
    simulator.Initialize()
    simulator.AdvanceTo(END)
    lcm.HandleSubscriptions(0)
    root = simulator.get_context()
    manager = diagram.GetSubsystemByName("mission")
    progress = manager.progress(manager.GetMyContextFromRoot(root))
    scene_names = [obj.instance_name for obj in built.mission.scene]
    plant = built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    q0 = robot.Go1PlantMap.from_plant(plant).base_q_start
    return built.logs(root), progress, feedback, scene_names, q0


def _teleop_record(progress):
    return next(record for record in progress.records if record.kind == "teleop_foot")


def test_the_foot_pushes_the_wall_and_the_balance_bound_limits_it(wall_run):
    logs, progress, _, scene_names, _ = wall_run
    record = _teleop_record(progress)
    contact = logs["sim.scene_contact_forces"]
    wall_force = contact.data[scene_contact_index("wall", "FR", scene_names)]
    _, readings = update_samples(logs["mission.suf"].times, logs["mission.suf"].data)
    # Each update from the time of the stance it describes (its inputs'), however many control
    # ticks it then took.
    t_suf = np.array([r.stance_time for r in readings])
    pushing = (t_suf >= PUSH_START) & (np.array([r.leg for r in readings]) == 0)
    limits = np.array([MARGIN * r.reach for r in readings])[pushing]
    # The true force at every tick, against the limit of the live SUF update in force then.
    in_force = np.searchsorted(t_suf[pushing], contact.times, side="right") - 1
    during = (contact.times >= PUSH_START) & (in_force >= 0)
    allowed = limits[in_force[during]]
    force = wall_force[during]
    # The bound acts on the mission's force estimate, which lags the contact: the impact of a foot
    # reaching a rigid wall at 0.1 m/s is a spike that no estimate sees in time. So the floor is
    # that the true force stays below the limit at every tick except those within IMPACT of the
    # first touch (the impact's peak is printed); that a spike that short cannot tip the robot is
    # the next test's.
    t = contact.times[during]
    touch = t[np.argmax(force > TOUCH_FORCE)]
    above = force > allowed
    k = np.argmax(force)
    print(
        f"\nwall: first touch at {touch:.3f} s; true force max {force[k]:.1f} N at {t[k]:.3f} s, the limit "
        f"then {allowed[k]:.1f} N (limits {limits.min():.1f} to {limits.max():.1f} N); above the limit at "
        f"{above.sum()} ticks, at {np.round(t[above], 3).tolist()[:10]} s; after the impact max "
        f"{force[t > touch + IMPACT].max():.1f} N; balance bound acted "
        f"{record.metrics['bound_activations']['balance']} times; {record.metrics['balance']}"
    )
    assert record.metrics["bound_activations"]["balance"] > 0
    after = t > touch + IMPACT
    j = np.argmax(force[after])
    assert force[after][j] > 0.5 * allowed[after][j]  # the operator did push hard
    assert np.all(t[above] <= touch + IMPACT)


def test_pushing_into_the_wall_cannot_tip_the_robot(wall_run):
    logs, progress, _, _, q0 = wall_run
    plant_state = logs["sim.plant_state"].data
    assert not fell_during(plant_state[q0 : q0 + 4], plant_state[q0 + 6], has_prongs=False)
    w, x, y, z = plant_state[q0 : q0 + 4]
    tilt = np.arccos(np.clip(1.0 - 2.0 * (x * x + y * y), -1.0, 1.0))  # the trunk's z axis from vertical
    feet = logs["sim.foot_contact_forces"]
    pushing = feet.times >= PUSH_START
    stance = [robot.LEG_NAMES.index(leg) for leg in ("FL", "RR", "RL")]
    normal = feet.data.reshape(4, 3, -1)[:, 2]  # FR, FL, RR, RL x (x, y, z)
    print(
        f"\ntilt max {np.degrees(tilt.max()):.1f} deg; smallest stance-foot force while pushing "
        f"{normal[stance][:, pushing].min():.1f} N"
    )
    assert tilt.max() < MAX_TILT
    assert normal[stance][:, pushing].min() > STANCE_FOOT_MIN_FORCE
    assert _teleop_record(progress).status == "running"


def test_the_live_suf_is_exact_along_the_push_and_summarised(wall_run):
    logs, progress, _, _, _ = wall_run
    summary = live_suf_summary(logs["mission.suf"].times, logs["mission.suf"].data, phase_table(progress))
    print(f"\nlive SUF: {summary}")
    assert summary["updates"] > 400 and summary["exact"] + summary["fallbacks"] == summary["updates"]
    assert summary["fallback_share"] < 0.01
    teleop = next(row for row in summary["phases"] if row["kind"] == "teleop_foot")
    assert teleop["exact"] > 0 and 10.0 < teleop["min_n"] <= teleop["median_n"] <= teleop["max_n"]
    _, readings = update_samples(logs["mission.suf"].times, logs["mission.suf"].data)
    assert any(r.status == EXACT for r in readings)


def test_the_operator_feels_the_foot_force_on_the_feedback_channel(wall_run):
    _, _, feedback, _, _ = wall_run
    assert [m.sequence for m in feedback] == list(range(1, len(feedback) + 1))
    assert len(feedback) == pytest.approx(END / 0.01, abs=2)  # the operator period
    pushing = [m for m in feedback if m.timestamp_us >= 1e6 * (PUSH_START + 1.0) and m.leg == 0]
    assert pushing and all(np.isfinite(m.force_limit) for m in pushing)
    assert any(m.bound_active for m in pushing)
    # The wall pushes the foot back (-x) with about the limit once the bound holds it.
    last = pushing[-1]
    assert last.force[0] < -0.5 * last.force_limit
