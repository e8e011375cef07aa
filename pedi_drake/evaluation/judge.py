"""Judging a finished run: its result (the rows of result.json) and the files written beside it.

In simulation the judge reads ground truth (the logged plant state), which no controller ever
reads; on hardware the state estimate is all there is, and `judged_by` says which it was.
"""

from pathlib import Path

import numpy as np

from pedi_drake import robot
from pedi_drake.diagram import apply_mission
from pedi_drake.evaluation import capture_point, mission_results
from pedi_drake.evaluation.box_lift import box_lift_trace, judge_box_lift
from pedi_drake.evaluation.button_press import judge_button_press, plunger_travel
from pedi_drake.evaluation.controller_switches import switch_problem, switch_summary
from pedi_drake.evaluation.estimator_accuracy import estimate_errors
from pedi_drake.evaluation.live_suf import live_suf_summary, update_samples
from pedi_drake.evaluation.object_push import judge_object_push
from pedi_drake.evaluation.off_trunk import judge_off_trunk, off_trunk_trace
from pedi_drake.evaluation.push_response import STANCE_FOOT_SLIDE_LIMIT, push_response
from pedi_drake.evaluation.result_file import write_result
from pedi_drake.evaluation.touches import judge_touches
from pedi_drake.evaluation.walks import WALK_KIND_NAMES, WALK_KINDS, judge_walks
from pedi_drake.fall import fell_during, first_fallen_sample
from pedi_drake.go1_driver.hardware_station import hardware_link
from pedi_drake.go1_driver.safety import driver_report
from pedi_drake.mission.progress import FAILED, SUCCEEDED
from pedi_drake.operator.meshcat_panel import MeshcatOperatorPanel
from pedi_drake.run_checks import control_period
from pedi_drake.run_logs import SignalLog, write_run_logs
from pedi_drake.viz import plots
from pedi_drake.viz.suf_plots import plot_live_suf

# The trunk has stood when it is within this of its commanded height [m]: a centimetre-level
# sag under the PD's own compliance is a stand, an object under the trunk is not.
STAND_HEIGHT_TOLERANCE = 0.02
# A foot that slid this far on the ground while the robot failed to stand slipped [m].
SLIP_DISTANCE = 0.03


def commanded_stand_height(scenario) -> float:
    """Trunk height the stand controller's target pose puts the trunk at, feet under the hips [m]."""
    _, thigh, calf = scenario.stand.target_leg_pose
    return float(robot.trunk_height_for(thigh, calf))


def judge_run(record) -> dict:
    """The result of `record` (a `pedi_drake.run.RunRecord`): success, phases, errors, timing."""
    scenario, logs, hardware = record.scenario, record.logs, record.hardware
    base = logs["base_state"].data
    mission = record.built.mission
    # The scenario as run: with the mission's pushes, robot variant and task stack.
    simulated = apply_mission(scenario, mission) if mission is not None else scenario
    # A mission's robot variant replaces the scenario's (as the diagram applied it).
    prongs = mission.robot.prongs if mission is not None and mission.robot is not None else scenario.robot.prongs
    has_prongs = prongs is not None
    estimate_fell = fell_during(base[0:4], base[6], has_prongs=has_prongs) if base.shape[1] else False
    plant = states = t_state = None
    if hardware:
        # The estimate is all there is: the trunk pose [quaternion; position] of base_state.
        p_WB, t_WB = base[4:7], logs["base_state"].times
        fell = estimate_fell
    else:
        plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
        q0 = robot.Go1PlantMap.from_plant(plant).base_q_start
        states, t_state = logs["sim.plant_state"].data, logs["sim.plant_state"].times
        p_WB, t_WB = states[q0 + 4 : q0 + 7], t_state
        fell = fell_during(states[q0 : q0 + 4], states[q0 + 6], has_prongs=has_prongs) if states.shape[1] else False
    sim_time, wall_time = record.sim_time, record.wall_time
    final_height = float(p_WB[2, -1]) if p_WB.shape[1] else None
    result = {
        "mission": record.built.mission.name if record.built.mission else None,
        "scenario": record.name,
        "success": not fell,
        "reason": "",
        "interrupted": record.interrupted is not None,
        "interrupt_reason": record.interrupted or "",
        "phases": [],
        "mode_switches": [],
        "friction_changes": [],
        "postures": [],
        "operator_targets": {"requests": [], "refused": 0},
        "teleop": [],
        "operator_messages": _operator_messages(record),
        "foot_errors_m": [],
        "max_base_drift_m": 0.0,
        "fell": fell,
        "estimate_fell": estimate_fell,
        "sim_time_s": sim_time,
        "wall_time_s": wall_time,
        "real_time_factor": sim_time / wall_time if wall_time > 0 else None,
        "controller_tick_ms": None,
        "controller": scenario.controller,
        "stack": simulated.whole_body.stack if scenario.controller == "whole_body" else None,
        "estimator": scenario.estimator,
        # The foot force estimate the press phases stopped on (every available one is in "presses").
        "force_estimate": (record.built.mission.force_estimate if record.built.mission else "")
        or scenario.force_estimate,
        "hardware": hardware,
        # Where foot errors, drift and falls come from: simulation ground truth, or the estimate.
        "judged_by": "state_estimate" if hardware else "ground_truth",
        "random_seed": scenario.random_seed,
        "sensor_noise": scenario.sensor_noise.enabled,
        "final_trunk_height_m": final_height,
    }
    if hardware:
        station, station_context = record.subsystem("station")
        result["driver"] = driver_report(
            station.GetOutputPort("driver.status").Eval(station_context),
            station.GetOutputPort("driver.message_counts").Eval(station_context),
        )
        # The link's own view: every message by channel (rejected ones by reason), the loop's
        # lateness and deadline misses, and whether its guard had to damp a silent loop.
        link_report = hardware_link(station).report()
        result["driver"].update(link_report)
        if result["driver"]["latched"] is None and link_report["guard"]["latched"] == "controller_silence":
            result["driver"]["latched"] = "controller_silence"
    if "controller.diagnostics" in logs:
        tick_ms = 1e3 * logs["controller.diagnostics"].data[2]
        tick_ms = tick_ms[tick_ms > 0]
        if tick_ms.size:
            result["controller_tick_ms"] = {
                "median": float(np.median(tick_ms)),
                "p99": float(np.percentile(tick_ms, 99)),
                "max": float(np.max(tick_ms)),
            }
    switch_reason = ""
    if "controller.switch" in logs:
        result["controller_switches"] = switch_summary(
            logs["controller.switch"],
            logs["go1.command"],
            scenario.whole_body.period,
            scenario.go1_driver.safety.max_target_rate,
            None if hardware else logs.get("sim.motor_torque"),
        )
        switch_reason = switch_problem(result["controller_switches"])
    progress = record.mission_progress()
    reason = ""
    if progress is None:
        reason = _stand_reason(scenario, final_height, sim_time)
    else:
        result["phases"] = mission_results.phase_table(progress)
        result["mode_switches"] = mission_results.mode_switch_table(progress)
        result["friction_changes"] = mission_results.friction_table(progress)
        result["postures"] = mission_results.posture_table(progress)
        result["operator_targets"] = mission_results.target_table(progress)
        result["teleop"] = mission_results.teleop_table(progress)
        if not hardware:
            _check_stand_up_phases(result["phases"], record.built.mission, p_WB, t_WB)
        failed = [row for row in result["phases"] if row["status"] == FAILED]
        if progress.status == SUCCEEDED and not failed:
            reason = ""
        elif progress.status not in (SUCCEEDED, FAILED):
            reason = f"the simulation ended ({sim_time:.1f} s) before the mission did"
        else:
            reason = failed[0]["reason"] if failed else progress.reason
        status_log, body_log = logs["mission.status"].data, logs["mission.body_reference"].data
        result["max_base_drift_m"] = mission_results.max_base_drift(p_WB, body_log, status_log)
        result["presses"] = mission_results.press_results(progress)
        result["sensed_touches"] = mission_results.sensed_touches(progress)
        result["prong_leans"] = mission_results.prong_leans(progress)
        if "mission.suf" in logs:
            result["live_suf"] = live_suf_summary(logs["mission.suf"].times, logs["mission.suf"].data, result["phases"])
        polygon = logs["mission.safety_polygon"]
        result["three_leg_capture_point_margin_m"] = capture_point.three_leg_margin(
            polygon.times,
            logs["controller.diagnostics"].data,
            polygon.data,
            logs["mission.contact_set"].data,
            result["phases"],
        )
        if hardware:
            result["foot_errors_m"] = mission_results.estimated_foot_errors(progress)
        else:
            result["foot_errors_m"] = mission_results.foot_errors(progress, plant, t_state, states)
            door = mission_results.door_opening(plant, states)
            if door is not None:
                result["door"] = door
            box = mission_results.box_displacement(plant, states)
            if box is not None:
                result["box"] = box
            if mission.box_lift is not None and states.shape[1]:
                trace = box_lift_trace(
                    plant,
                    scene_graph_inspector(record),
                    mission.box_lift,
                    t_state,
                    states,
                    logs["sim.foot_contact_forces"].times,
                    logs["sim.foot_contact_forces"].data,
                )
                result["box_lift"], lift_problem = judge_box_lift(trace, mission.box_lift, result["phases"])
                reason = "; ".join(filter(None, [reason, lift_problem]))
            if mission.touches:
                contact = logs["sim.scene_contact_forces"]
                scene_names = [obj.instance_name for obj in simulated.scene]
                result["touches"], touch_problem = judge_touches(
                    mission.touches, scene_names, result["phases"], contact.times, contact.data
                )
                reason = "; ".join(filter(None, [reason, touch_problem]))
            if mission.button_press is not None and states.shape[1]:
                check = mission.button_press
                phase = next(phase for phase in mission.phases if phase.name == check.phase)
                contact = logs["sim.scene_contact_forces"]
                result["button_press"], press_problem = judge_button_press(
                    check,
                    phase.max_force,
                    result["phases"],
                    t_state,
                    plunger_travel(plant, check.button, states),
                    [obj.instance_name for obj in simulated.scene],
                    contact.times,
                    contact.data,
                )
                reason = "; ".join(filter(None, [reason, press_problem]))
            if mission.object_push is not None and states.shape[1]:
                result["object_push"], push_problem = judge_object_push(
                    plant, mission.object_push, result["phases"], t_state, states
                )
                reason = "; ".join(filter(None, [reason, push_problem]))
            if any(isinstance(phase, WALK_KINDS) for phase in mission.phases) and states.shape[1]:
                metrics = {r.name: r.metrics for r in progress.records}
                result["walks"], walk_problem = judge_walks(
                    mission,
                    result["phases"],
                    metrics,
                    plant,
                    t_state,
                    states,
                    logs["base_state"],
                    logs["sim.foot_contact_forces"],
                )
                reason = "; ".join(filter(None, [reason, walk_problem]))
            if mission.leaves_trunk and states.shape[1]:
                trace = off_trunk_trace(plant, mission.leaves_trunk, t_state, states)
                result[mission.leaves_trunk], left_problem = judge_off_trunk(mission.leaves_trunk, trace)
                reason = "; ".join(filter(None, [reason, left_problem]))
    if not hardware:
        manager_saw_fall = progress is not None and any(r.metrics.get("estimate_fell") for r in progress.records)
        reason = _fall_reason(reason, fell, estimate_fell, manager_saw_fall)
        stand_failed = (progress is None and reason) or any(
            row["kind"] == "stand_up" and row["status"] == FAILED for row in result["phases"]
        )
        if stand_failed and states.shape[1]:
            t_fail = next((row["t_end"] for row in result["phases"] if row["status"] == FAILED), sim_time)
            if fell:
                # Feet that slid away while the trunk was still up made it fall; the collapse
                # itself moves the feet too, so only the slide before it counts.
                first = first_fallen_sample(states[q0 : q0 + 4], states[q0 + 6], has_prongs=has_prongs)
                t_fail = min(t_fail, float(t_state[first]))
            slip = mission_results.max_foot_slip(plant, states, t_state, t_fail)
            if slip > SLIP_DISTANCE:
                reason = (
                    f"friction too low to stand: the feet slid {100 * slip:.0f} cm on the ground "
                    f"(ground_friction {scenario.ground_friction}); " + reason
                )
        if simulated.pushes:
            walking = [
                (row["t_start"], sim_time if row["t_end"] is None else row["t_end"])
                for row in result.get("phases", [])
                if row["kind"] in WALK_KIND_NAMES and row["status"] != "skipped"
            ]
            result["pushes"], slid = judge_pushes(plant, logs, simulated.pushes, walking)
            reason = "; ".join(filter(None, [reason, slid]))
    elif fell and not reason:
        reason = "the trunk fell (state estimate)"
    if not hardware and scenario.estimator == "kalman" and base.shape[1]:
        plant_map = robot.Go1PlantMap.from_plant(plant)
        result["estimator_errors"] = estimate_errors(
            logs["base_state"], logs["sim.plant_state"], plant_map, plant.num_positions()
        )
    if hardware and result["driver"]["latched"] is not None:
        # Damping took over: whatever the estimate says afterwards, the run did not go as planned.
        reason = f"the driver latched damping ({result['driver']['latched']}); " + reason
    reason = "; ".join(filter(None, [reason, switch_reason]))
    if record.interrupted is not None:
        # What ran is judged as it stands; the run as a whole did not happen.
        reason = f"interrupted at t = {sim_time:.2f} s ({record.interrupted})" + (f"; {reason}" if reason else "")
    result["reason"] = reason
    result["success"] = not reason
    return result


def _operator_messages(record) -> dict | None:
    """What the operator input took and dropped ({received, dropped, rejected: {reason: count}}),
    None without an operator."""
    diagram = record.built.diagram
    if not diagram.HasSubsystemNamed("operator"):
        return None
    operator, context = record.subsystem("operator")
    return operator.counts(context) if isinstance(operator, MeshcatOperatorPanel) else operator.counts()


def scene_graph_inspector(record):
    """The simulated station's SceneGraphInspector (the shapes and poses of the collision geometry)."""
    return record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("scene_graph").model_inspector()


def judge_pushes(plant, logs, pushes, walking: list[tuple[float, float]] = ()) -> tuple[list[dict], str]:
    """result.json's `pushes` rows (None for a push the run ended before) and why a stance foot
    failed to hold (empty when every one slid at most STANCE_FOOT_SLIDE_LIMIT). A push that
    starts within one of the `walking` (start, end) windows [s] is not judged by its feet's motion
    (they step on purpose): the walk's own stance slip judges them (pedi_drake.evaluation.walks)."""
    rows, problems = [], []
    for i, push in enumerate(pushes):
        response = push_response(plant, logs, push)
        rows.append(None if response is None else response.row())
        stepping = any(start <= push.start <= end for start, end in walking)
        if response is not None and response.foot_slide and not stepping:
            leg, slide = response.max_foot_slide()
            if slide > STANCE_FOOT_SLIDE_LIMIT:
                problems.append(
                    f"the {leg} foot slid {100 * slide:.1f} cm under pushes[{i}] "
                    f"(a stance foot may slide at most {100 * STANCE_FOOT_SLIDE_LIMIT:.0f} cm)"
                )
    return rows, "; ".join(problems)


def _stand_reason(scenario, final_height: float | None, sim_time: float) -> str:
    """Why a run without a mission did not stand ("" when it did): the trunk must end at the
    height the stand controller commands, within STAND_HEIGHT_TOLERANCE."""
    if scenario.controller != "stand_pd":
        return ""
    if sim_time < scenario.stand.duration:
        return f"the run ended ({sim_time:.2f} s) before the stand did ({scenario.stand.duration} s)"
    target = commanded_stand_height(scenario)
    if final_height is None or abs(final_height - target) > STAND_HEIGHT_TOLERANCE:
        shown = "unknown" if final_height is None else f"{final_height:.3f} m"
        return (
            f"did not stand: the trunk ended at {shown}, not at the commanded {target:.3f} m "
            f"(within {STAND_HEIGHT_TOLERANCE} m)"
        )
    return ""


def _check_stand_up_phases(phases: list[dict], mission, p_WB: np.ndarray, t_WB: np.ndarray) -> None:
    """Fails a stand_up phase the mission manager passed on the estimate when the true trunk did
    not reach the phase's height (the estimate can be wrong; physics is the judge)."""
    heights = {phase.name: phase.height for phase in mission.phases if hasattr(phase, "height")}
    for row in phases:
        if row["kind"] != "stand_up" or row["status"] != SUCCEEDED or row["name"] not in heights:
            continue
        height = mission_results.trunk_height_at(p_WB, t_WB, row["t_end"])
        target = heights[row["name"]]
        if abs(height - target) > STAND_HEIGHT_TOLERANCE:
            row["status"] = FAILED
            row["reason"] = (
                f"{row['name']}: the estimate reached {target} m but the trunk was at {height:.3f} m "
                "(ground truth): the robot did not stand"
            )


def _fall_reason(reason: str, fell: bool, estimate_fell: bool, manager_saw_fall: bool) -> str:
    """The reason, saying whether the robot fell (ground truth) or only its estimate did."""
    if fell:
        said = " as the state estimate said" if estimate_fell else ""
        return f"the robot fell (ground truth: trunk height or tilt out of range){said}" + (
            f"; {reason}" if reason else ""
        )
    if manager_saw_fall:
        return f"the state estimate failed, not the robot: {reason}; the robot did not fall (ground truth)"
    return reason


def first_valid_index(times: np.ndarray) -> int:
    """Index of the first logged sample that follows the estimator's first update.

    The sample logged at t = 0 is published at initialisation, before any periodic update has
    run: the estimate, the mission's references and the held sensor values there are initial
    guesses, not measurements, and show up as spikes at the start of every plot.
    """
    later = np.nonzero(np.asarray(times) > 0.0)[0]
    return int(later[0]) if later.size else 0


def _from_first_estimate(logs: dict) -> dict:
    """Every log from the first valid estimate on (see `first_valid_index`)."""
    base_times = logs["base_state"].times
    t0 = base_times[first_valid_index(base_times)] if len(base_times) else 0.0
    trimmed = {}
    for name, log in logs.items():
        keep = np.asarray(log.times) >= t0
        trimmed[name] = SignalLog(log.times[keep], log.data[:, keep]) if np.any(keep) else log
    return trimmed


def write_run(record, result: dict, out_dir: Path) -> None:
    """Writes result.json, logs.npz, the PNG plots and (when recorded) replay.html to `out_dir`.

    logs.npz keeps every sample; the plots start at the first valid estimate. result.json is
    written last and atomically, so a folder with a result.json holds a finished run's files.
    """
    out_dir = Path(out_dir)
    name = record.name
    logs = _from_first_estimate(record.logs)
    if record.replay_html is not None:
        (out_dir / "replay.html").write_text(record.replay_html)
    command, position = logs["go1.command"], logs["go1.position_measured"]
    plots.plot_joint_tracking(
        command.times, command.data[:12], position.data, out_dir / "joint_positions.png", title=name
    )
    foot_contact = logs["go1.foot_contact"]
    plots.plot_foot_forces(foot_contact.times, foot_contact.data, out_dir / "foot_forces.png")
    if record.built.mission is not None:
        leg = mission_results.pedipulation_leg(logs["mission.leg_reference"].data)
        if leg is not None:
            velocity = logs["go1.velocity_measured"].data
            plots.plot_leg_command(
                command.times, command.data, position.data, velocity, leg, result["phases"], out_dir / "leg_command.png"
            )
            reference = logs["mission.leg_reference"]
            n = min(reference.data.shape[1], position.data.shape[1], velocity.shape[1])
            plots.plot_leg_tracking(
                reference.times[:n],
                reference.data[:, :n],
                position.data[:, :n],
                velocity[:, :n],
                leg,
                result["phases"],
                out_dir / "leg_tracking.png",
            )
            if not record.hardware:
                plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
                states = logs["sim.plant_state"]
                plots.plot_mission_errors(
                    states.times,
                    states.data,
                    logs["mission.body_reference"].data,
                    logs["mission.status"].data,
                    plant,
                    result,
                    out_dir / "mission_errors.png",
                )
        if "mission.suf" in logs:
            suf_times, readings = update_samples(logs["mission.suf"].times, logs["mission.suf"].data)
            if readings:
                plot_live_suf(suf_times, readings, result["phases"], out_dir / "live_suf.png")
    write_run_logs(out_dir, record.logs)
    write_result(out_dir, result, time_step=control_period(record.scenario))
