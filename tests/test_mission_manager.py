"""MissionManager in closed loop: phase transitions, failures with reasons, recovery to four legs."""

import copy
import dataclasses
from pathlib import Path

import numpy as np
import pytest
from pydrake.math import RotationMatrix
from pydrake.systems.analysis import Simulator

from pedi_drake import robot
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.evaluation.mission_results import estimated_foot_errors
from pedi_drake.exceptions import UnreachableTarget
from pedi_drake.ik import leg_ik_system
from pedi_drake.mission import reference_table
from pedi_drake.mission.phases import IkAnswer, ReachRunner, receive_ik_answers
from pedi_drake.mission.progress import (
    FAILED,
    LEG_MODE_FOOT,
    STATUS_CODES,
    SUCCEEDED,
    IkPlan,
    LegTrajectory,
    MissionProgress,
    PhaseRecord,
    References,
)
from pedi_drake.mission.spec import CompanionReach, Reach
from pedi_drake.scenario import load_scenario
from pedi_drake.trajectory import QuinticSegment, sample_rotation_into, sample_vector_into

QUICK_START = """
  - {kind: stand_up, height: 0.28, duration: 1.5, timeout: 3.0}
  - {kind: leg_to_pedipulation, leg: FR, duration: 1.0, timeout: 4.0}
"""


def _run_mission(tmp_path: Path, phases: str, duration: float):
    path = tmp_path / "mission.yaml"
    path.write_text("phases:" + phases)
    scenario = load_scenario(
        scenario_text=f"{{mission: {path}, controller: whole_body, simulation_duration: {duration}}}"
    )
    built = MakePedipulationDiagram(scenario)
    simulator = Simulator(built.diagram)
    simulator.Initialize()
    manager = built.diagram.GetSubsystemByName("mission")
    context = simulator.get_context()
    manager_context = manager.GetMyContextFromRoot(context)
    t = 0.0
    while t < duration:
        t = min(t + 0.5, duration)
        simulator.AdvanceTo(t)
        if manager.progress(manager_context).status in (SUCCEEDED, FAILED):
            simulator.AdvanceTo(t + 0.5)
            break
    station = built.diagram.GetSubsystemByName("station")
    station_context = station.GetMyContextFromRoot(context)
    return manager.progress(manager_context), station, station_context


def test_phases_run_in_order_and_the_mission_succeeds(tmp_path):
    phases = (
        QUICK_START
        + """
  - {kind: reach, name: reach_front, leg: FR, target: [0.30, -0.13, 0.18], duration: 0.8, tolerance: 0.005, hold: 0.1}
  - {kind: leg_to_support, leg: FR, duration: 1.0}
"""
    )
    progress, _, _ = _run_mission(tmp_path, phases, 14.0)
    assert progress.status == SUCCEEDED, progress.reason
    assert [r.status for r in progress.records] == ["succeeded"] * 4
    starts = [r.t_start for r in progress.records]
    ends = [r.t_end for r in progress.records]
    assert starts == sorted(starts) and all(e >= s for s, e in zip(starts, ends, strict=True))
    assert progress.records[2].metrics["error_m"] < 0.005


def test_body_move_with_a_height_takes_the_trunk_to_that_height(tmp_path):
    phases = """
  - {kind: stand_up, height: 0.28, duration: 1.5, timeout: 3.0}
  - {kind: body_move, offset: [0.02, 0.0, 0.05], height: 0.22, duration: 1.0, timeout: 3.0}
"""
    progress, station, station_context = _run_mission(tmp_path, phases, 6.0)
    assert progress.status == SUCCEEDED, progress.reason
    plant = station.GetSubsystemByName("plant")
    trunk = plant.GetBodyByName("trunk").EvalPoseInWorld(station.GetSubsystemContext(plant, station_context))
    stood, moved = (record.t_end for record in progress.records)
    start = progress.references.body_position.sample(stood).position
    goal = progress.references.body_position.sample(moved).position
    # The height replaces the offset's z; its x and y still apply.
    np.testing.assert_allclose(goal - start, [0.02, 0.0, 0.22 - start[2]], atol=1e-9)
    assert goal[2] == pytest.approx(0.22)
    assert np.linalg.norm(trunk.translation() - goal) < 0.01


def test_unreachable_target_fails_cleanly_and_ends_on_four_legs(tmp_path):
    phases = (
        QUICK_START
        + """
  - {kind: reach, name: too_far, leg: FR, target: [1.5, -0.13, 0.2]}
  - {kind: leg_to_support, leg: FR}
"""
    )
    progress, station, station_context = _run_mission(tmp_path, phases, 16.0)
    assert progress.status == FAILED
    assert "too_far" in progress.reason and "IK" in progress.reason
    statuses = {r.name: r.status for r in progress.records}
    assert statuses["too_far"] == "failed" and statuses["3_leg_to_support"] == "skipped"
    assert statuses["recover_FR"] == "succeeded"
    # Standing on four legs: every foot carries load, the trunk is up.
    forces = station.GetOutputPort("go1.foot_contact").Eval(station_context)
    assert np.all(forces > 15.0), forces
    state = station.GetOutputPort("sim.plant_state").Eval(station_context)
    assert state[6] > 0.25


def test_reach_without_pedipulation_mode_fails_with_a_reason(tmp_path):
    phases = """
  - {kind: stand_up, height: 0.28, duration: 1.5, timeout: 3.0}
  - {kind: reach, name: no_leg_lifted, leg: FL, target: [0.3, 0.13, 0.18]}
"""
    progress, _, _ = _run_mission(tmp_path, phases, 6.0)
    assert progress.status == FAILED
    assert "not in pedipulation mode" in progress.reason


def test_reach_with_a_companion_leg_not_in_pedipulation_mode_fails_with_a_reason(tmp_path):
    phases = (
        QUICK_START
        + """
  - {kind: reach, name: both, leg: FR, target: [0.3, -0.13, 0.18], together: [{leg: FL, target: [0.3, 0.13, 0.18]}]}
"""
    )
    progress, _, _ = _run_mission(tmp_path, phases, 10.0)
    assert progress.status == FAILED
    assert "both: FL is not in pedipulation mode" in progress.reason


def test_a_reach_with_companions_reports_every_leg():
    metrics = {
        "leg": "FR",
        "error_m": 0.002,
        "target_W": [0.3, -0.17, 0.05],
        "legs": [
            {"leg": "FR", "target_W": [0.3, -0.17, 0.05], "error_m": 0.002},
            {"leg": "FL", "target_W": [0.3, 0.17, 0.05], "error_m": 0.012},
        ],
    }
    progress = MissionProgress(records=[PhaseRecord("push", "reach", SUCCEEDED, 1.0, 2.0, metrics=metrics)])
    rows = estimated_foot_errors(progress)
    assert [(row["phase"], row["leg"], row["error"], row["target_W"]) for row in rows] == [
        ("push", "FR", 0.002, [0.3, -0.17, 0.05]),
        ("push", "FL", 0.012, [0.3, 0.17, 0.05]),
    ]
    phase = Reach(name="push", tolerance=0.01, together=[CompanionReach(leg="FL", target=[0.3, 0.17, 0.05])])
    assert ReachRunner.timeout_reason(phase, progress).startswith("foot error FL 12.0 mm still above")


def test_timeout_fails_the_phase_with_the_remaining_error(tmp_path):
    phases = (
        QUICK_START
        + """
  - {kind: reach, name: hurried, leg: FR, target: [0.30, -0.13, 0.18], duration: 1.0, timeout: 1.0,
     tolerance: 0.0001, hold: 0.5}
"""
    )
    progress, _, _ = _run_mission(tmp_path, phases, 14.0)
    assert progress.status == FAILED
    assert "hurried: timed out after 1.0 s" in progress.reason and "mm" in progress.reason


def test_body_reference_starts_from_the_measured_trunk_pose(tmp_path):
    """The first phase starts its trajectories where the trunk is (not at the origin).

    At initialisation the estimate is not yet available; a reference made from it pulled the
    trunk towards z = 0 for the first second of the stand-up.
    """
    path = tmp_path / "mission.yaml"
    path.write_text("phases:" + QUICK_START)
    scenario = load_scenario(scenario_text=f"{{mission: {path}, controller: whole_body, robot: {{prongs: {{}}}}}}")
    built = MakePedipulationDiagram(scenario)
    simulator = Simulator(built.diagram)
    simulator.Initialize()
    simulator.AdvanceTo(0.1)
    context = simulator.get_context()
    manager = built.diagram.GetSubsystemByName("mission")
    station = built.diagram.GetSubsystemByName("station")
    p_ref = manager.GetOutputPort("body_reference").Eval(manager.GetMyContextFromRoot(context))[:3]
    p_true = station.GetOutputPort("sim.plant_state").Eval(station.GetMyContextFromRoot(context))[4:7]
    assert np.linalg.norm(p_ref - p_true) < 0.01, (p_ref, p_true)


def test_leg_to_support_after_a_press_puts_the_foot_down_at_its_footprint(tmp_path):
    """The foot sensor still feels the pressed obstacle when leg_to_support starts: that reading
    must not count as touch-down (the contact would be restored with the foot up at the obstacle)."""
    path = tmp_path / "mission.yaml"
    path.write_text(
        """
scene:
  - {kind: fixed_obstacle, name: wall, position: [0.47, -0.30, 0.0]}
phases:"""
        + QUICK_START
        + """
  - {kind: reach, name: touch, leg: FR, target: [0.40, -0.22, 0.17], tolerance: 0.01, timeout: 5.0}
  - {kind: press, name: press, leg: FR, direction: [1.0, 0.0, 0.0], force: 12.0, max_displacement: 0.04}
  - {kind: leg_to_support, name: place, leg: FR, duration: 1.0}
"""
    )
    scenario = load_scenario(scenario_text=f"{{mission: {path}, controller: whole_body, simulation_duration: 14.0}}")
    built = MakePedipulationDiagram(scenario)
    simulator = Simulator(built.diagram)
    simulator.Initialize()
    manager = built.diagram.GetSubsystemByName("mission")
    manager_context = manager.GetMyContextFromRoot(simulator.get_context())
    while simulator.get_context().get_time() < 14.0:
        simulator.AdvanceTo(simulator.get_context().get_time() + 0.5)
        if manager.progress(manager_context).status in (SUCCEEDED, FAILED):
            break
    progress = manager.progress(manager_context)
    assert progress.status == SUCCEEDED, progress.reason
    records = {r.name: r for r in progress.records}
    assert records["press"].metrics["stopped_by"] == "force"
    assert records["place"].metrics["placement_error_m"] < 0.02, records["place"].metrics


def test_a_stored_progress_is_shared_by_state_copies_and_changed_only_through_copy():
    # Drake deep-copies the whole State for every unrestricted update (the plant's, each step):
    # the progress is shared then, and the manager changes a copy() that owns all its parts.
    progress = MissionProgress()
    progress.records.append(PhaseRecord("stand", "stand_up", "running", 0.0))
    progress.memo["samples"] = [1.0]
    assert copy.deepcopy(progress) is progress
    changed = progress.copy()
    changed.index = 2
    changed.records.append(PhaseRecord("reach", "reach", "running", 1.0))
    changed.records[0].status = SUCCEEDED
    changed.memo["samples"].append(2.0)
    assert progress.index == 0 and len(progress.records) == 1 and progress.records[0].status == "running"
    assert progress.memo == {"samples": [1.0]}


def _plan_for_FR(*targets_B) -> IkPlan:
    return IkPlan.ask("reach", np.array([1.0, 0, 0, 0, 0, 0, 0.28]), {"FR": list(targets_B)}, robot.STANDING_Q)


def test_an_ik_answer_to_an_earlier_target_is_not_taken_for_the_pending_one():
    plan = _plan_for_FR([0.2, -0.13, -0.2], [0.3, -0.13, -0.1])
    stale = IkAnswer(np.array([0.0, 0.8, -1.5]), True, 1e-4, np.array([0.25, -0.13, -0.25]))
    assert receive_ik_answers(plan, {"FR": stale}) is plan


def test_ik_answers_chain_the_seed_along_the_waypoints():
    plan = _plan_for_FR([0.2, -0.13, -0.2], [0.3, -0.13, -0.1])
    q_first = np.array([0.05, 0.7, -1.4])
    plan = receive_ik_answers(plan, {"FR": IkAnswer(q_first, True, 1e-4, np.array([0.2, -0.13, -0.2]))})
    np.testing.assert_array_equal(plan.pending("FR"), [0.3, -0.13, -0.1])
    np.testing.assert_array_equal(plan.q_seed[robot.leg_slice("FR")], q_first)  # the next solve starts there
    assert not plan.done
    q_second = np.array([0.05, 0.5, -1.0])
    plan = receive_ik_answers(plan, {"FR": IkAnswer(q_second, True, 1e-4, np.array([0.3, -0.13, -0.1]))})
    assert plan.done
    np.testing.assert_array_equal(np.array(plan.solutions["FR"]), [q_first, q_second])


def test_an_unreached_ik_target_raises_with_the_phase_and_the_miss():
    plan = _plan_for_FR([1.5, -0.13, 0.2])
    answer = IkAnswer(np.array([0.0, -0.5, -0.9]), False, 0.91, np.array([1.5, -0.13, 0.2]))
    with pytest.raises(UnreachableTarget, match=r"reach: IK for FR .* closest miss 910.0 mm"):
        receive_ik_answers(plan, {"FR": answer})


def test_a_progress_copy_owns_every_container_the_runners_change():
    refs = References.holding(np.zeros(3), RotationMatrix(), 0.0, num_prongs=2)
    refs.legs["FR"] = LegTrajectory(LEG_MODE_FOOT, QuinticSegment(np.zeros(3), np.ones(3), 0.0, 1.0))
    refs.press = dict(leg="FR", start=np.zeros(3), direction=np.array([1.0, 0, 0]), speed=0.05, ramp=0.1, t0=0.0)
    refs.press["frozen_at"] = None
    progress = MissionProgress(references=refs, memo={"counts": {"speed": 0}, "goal": np.zeros(3)})
    progress.records.append(PhaseRecord("reach", "reach", "running", 0.0, metrics={"legs": [{"error_m": 0.1}]}))
    progress.interlude, progress.recovery = [Reach(name="a")], [Reach(name="b")]
    changed = progress.copy()
    changed.references.legs.pop("FR")
    changed.references.contacts[0] = 0.0
    changed.references.press["frozen_at"] = 1.0
    changed.memo["counts"]["speed"] += 1
    changed.memo["goal"][0] = 1.0
    changed.records[-1].metrics["legs"][0]["error_m"] = 0.0
    changed.interlude.append(Reach(name="c"))
    changed.recovery.clear()
    changed.switches.append(None)
    changed.target_requests.append(None)
    changed.friction_changes.append((1.0, 0.2, "mission"))
    changed.pre_posture["FR"] = (np.zeros(3), None)
    assert progress.target_requests == [] and progress.pre_posture == {} and progress.friction_changes == []
    assert "FR" in progress.references.legs and progress.references.contacts[0] == 1.0
    assert progress.references.press["frozen_at"] is None
    assert progress.memo["counts"]["speed"] == 0 and progress.memo["goal"][0] == 0.0
    assert progress.records[-1].metrics["legs"][0]["error_m"] == 0.1
    assert len(progress.interlude) == 1 and len(progress.recovery) == 1 and progress.switches == []
    # Values are shared, not copied: a tick's copy does not copy trajectories.
    assert changed.references.body_position is progress.references.body_position


def test_every_progress_field_is_either_shared_or_duplicated_by_copy():
    # A new field of MissionProgress must be placed in copy(): a value (shared) or a container
    # that the runners change in place (duplicated).
    assert {field.name for field in dataclasses.fields(MissionProgress)} == {
        "index",
        "status",
        "reason",
        "started",
        "phase_start",
        "plan_wait",
        "memo",
        "references",
        "records",
        "recovery",
        "ik",
        "interlude",
        "resume_index",
        "operator_mode",
        "teleop_pending",
        "controller_request",
        "friction",
        "friction_changes",
        "operator_friction",
        "switches",
        "target_requests",
        "last_target",
        "target_pending",
        "interlude_mode",
        "pre_posture",
        "target_anchors",
        "push",  # a frozen FootPush: shared
    }


@pytest.fixture(scope="module")
def stepped_run(tmp_path_factory):
    """The QUICK_START mission and a reach, stepped at the manager's period: per update, the
    manager's state outputs and what its progress says they are; and the compiled signatures of
    the kernels a tick runs, after the diagram was built and after the run."""
    path = tmp_path_factory.mktemp("mission") / "mission.yaml"
    path.write_text(
        "phases:"
        + QUICK_START
        + "  - {kind: reach, name: reach_front, leg: FR, target: [0.30, -0.13, 0.18], duration: 0.8, tolerance: 0.01}\n"
    )
    scenario = load_scenario(scenario_text=f"{{mission: {path}, controller: whole_body, robot: {{prongs: {{}}}}}}")
    built = MakePedipulationDiagram(scenario)
    kernels = [sample_vector_into, sample_rotation_into, reference_table.references_into, leg_ik_system._retarget]
    compiled_at_build = [len(getattr(k, "signatures", ())) for k in kernels]
    simulator = Simulator(built.diagram)
    simulator.Initialize()
    manager = built.diagram.GetSubsystemByName("mission")
    context = manager.GetMyContextFromRoot(simulator.get_context())
    rows = []
    while context.get_time() < 6.0:
        simulator.AdvanceTo(context.get_time() + manager.period)
        progress = manager.progress(context)
        plan = progress.ik
        ports = {name: manager.GetOutputPort(name).Eval(context).copy() for name in ("contact_set", "mission_status")}
        ports["ik"] = np.concatenate([manager.GetOutputPort(n).Eval(context) for n in ("ik_X_WB", "ik_q_seed")])
        ports["ik_target"] = manager.GetOutputPort("ik_foot_target_W.FR").Eval(context).copy()
        expected = {
            "contact_set": progress.references.contacts,
            "mission_status": [progress.index, STATUS_CODES[progress.status], float(bool(progress.references.legs)), 3],
            "ik": np.concatenate([plan.X_WB, plan.q_seed]) if plan else np.r_[1.0, np.zeros(6), robot.STANDING_Q],
            "ik_target": manager._ik_target_W(plan, "FR"),
        }
        rows.append((ports, expected, plan is not None and plan.pending("FR") is not None))
    compiled_after = [len(getattr(k, "signatures", ())) for k in kernels]
    return rows, manager.progress(context), compiled_at_build, compiled_after


def test_state_outputs_are_what_the_progress_says(stepped_run):
    rows, progress, _, _ = stepped_run
    assert progress.records[-1].name == "reach_front", [r.name for r in progress.records]
    assert any(asked for _, _, asked in rows), "the run never asked the IK"
    for ports, expected, _ in rows:
        for name, value in ports.items():
            np.testing.assert_array_equal(value, expected[name], err_msg=name)


def test_no_kernel_of_a_tick_is_compiled_during_the_run(stepped_run):
    # The constructors compile (or load) every signature the ticks use. (Run alone, this module
    # sees the constructors' work only; after other tests it may find them compiled already.)
    pytest.importorskip("numba")
    _, _, compiled_at_build, compiled_after = stepped_run
    assert compiled_after == compiled_at_build
