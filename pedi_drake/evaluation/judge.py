"""Judging a finished run: its result (the rows of result.json) and the files written beside it.

In simulation the judge reads ground truth (the logged plant state), which no controller ever
reads; on hardware the state estimate is all there is, and `judged_by` says which it was.
"""

from pathlib import Path

import numpy as np

from pedi_drake import robot
from pedi_drake.evaluation import mission_results
from pedi_drake.evaluation.estimator_accuracy import estimate_errors
from pedi_drake.evaluation.result_file import write_result
from pedi_drake.evaluation.run_logs import write_run_logs
from pedi_drake.fall import fell_during
from pedi_drake.go1_driver.safety import driver_report
from pedi_drake.mission.progress import FAILED, SUCCEEDED
from pedi_drake.viz import plots


def judge_run(record) -> dict:
    """The result of `record` (a `pedi_drake.run.RunRecord`): success, phases, errors, timing."""
    scenario, logs, hardware = record.scenario, record.logs, record.hardware
    base = logs["base_state"].data
    has_prongs = scenario.robot.prongs is not None
    if hardware:
        # The estimate is all there is: the trunk pose [quaternion; position] of base_state.
        p_WB = base[4:7]
        fell = fell_during(base[0:4], base[6], has_prongs=has_prongs)
    else:
        plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
        q0 = robot.Go1PlantMap.from_plant(plant).base_q_start
        states = logs["sim.plant_state"].data
        p_WB = states[q0 + 4 : q0 + 7]
        fell = fell_during(states[q0 : q0 + 4], states[q0 + 6], has_prongs=has_prongs)
    sim_time, wall_time = record.sim_time, record.wall_time
    result = {
        "mission": record.built.mission.name if record.built.mission else None,
        "scenario": record.name,
        "success": not fell,
        "reason": "the trunk fell" if fell else "",
        "phases": [],
        "foot_errors_m": [],
        "max_base_drift_m": 0.0,
        "fell": fell,
        "sim_time_s": sim_time,
        "wall_time_s": wall_time,
        "real_time_factor": sim_time / wall_time if wall_time > 0 else None,
        "controller_tick_ms": None,
        "controller": scenario.controller,
        "estimator": scenario.estimator,
        # The foot force estimate the press phases stopped on (every available one is in "presses").
        "force_estimate": (record.built.mission.force_estimate if record.built.mission else "")
        or scenario.force_estimate,
        "hardware": hardware,
        # Where foot errors, drift and falls come from: simulation ground truth, or the estimate.
        "judged_by": "state_estimate" if hardware else "ground_truth",
        "random_seed": scenario.random_seed,
        "sensor_noise": scenario.sensor_noise.enabled,
        "final_trunk_height_m": float(p_WB[2, -1]),
    }
    if hardware:
        station, station_context = record.subsystem("station")
        result["driver"] = driver_report(
            station.GetOutputPort("driver.status").Eval(station_context),
            station.GetOutputPort("driver.message_counts").Eval(station_context),
        )
    if "controller.diagnostics" in logs:
        tick_ms = 1e3 * logs["controller.diagnostics"].data[2]
        tick_ms = tick_ms[tick_ms > 0]
        result["controller_tick_ms"] = {
            "median": float(np.median(tick_ms)),
            "p99": float(np.percentile(tick_ms, 99)),
            "max": float(np.max(tick_ms)),
        }
    progress = record.mission_progress()
    if progress is not None:
        mission_ok = progress.status == SUCCEEDED
        result["success"] = mission_ok and not fell
        result["reason"] = progress.reason if not mission_ok else ("the trunk fell" if fell else "")
        if progress.status not in (SUCCEEDED, FAILED):
            result["reason"] = f"the simulation ended ({sim_time:.1f} s) before the mission did"
        result["phases"] = mission_results.phase_table(progress)
        status_log, body_log = logs["mission.status"].data, logs["mission.body_reference"].data
        result["max_base_drift_m"] = mission_results.max_base_drift(p_WB, body_log, status_log)
        result["presses"] = mission_results.press_results(progress)
        if hardware:
            result["foot_errors_m"] = mission_results.estimated_foot_errors(progress)
        else:
            t_state = logs["sim.plant_state"].times
            result["foot_errors_m"] = mission_results.foot_errors(progress, plant, t_state, states)
            door = mission_results.door_opening(plant, states)
            if door is not None:
                result["door"] = door
            box = mission_results.box_displacement(plant, states)
            if box is not None:
                result["box"] = box
    if not hardware and scenario.estimator == "kalman":
        plant_map = robot.Go1PlantMap.from_plant(plant)
        result["estimator_errors"] = estimate_errors(
            logs["base_state"], logs["sim.plant_state"], plant_map, plant.num_positions()
        )
    if hardware and result["driver"]["latched"] is not None:
        # Damping took over: whatever the estimate says afterwards, the run did not go as planned.
        result["success"] = False
        result["reason"] = f"the driver latched damping ({result['driver']['latched']}); " + result["reason"]
    return result


def write_run(record, result: dict, out_dir: Path) -> None:
    """Writes result.json, logs.npz, the PNG plots and (when recorded) replay.html to `out_dir`."""
    out_dir = Path(out_dir)
    logs, name = record.logs, record.name
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
            plots.plot_leg_tracking(
                command.times,
                command.data,
                position.data,
                velocity,
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
    write_run_logs(out_dir, logs)
    write_result(out_dir, result)
