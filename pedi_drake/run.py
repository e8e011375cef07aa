"""One simulated run of a scenario or mission: build, simulate, judge, write the results.

`run(scenario=..., name=..., out_dir=...)` is what run_sim.py, the mission benchmark, the tests
and the notebooks call. It writes result.json (DESIGN.md section 5), replay.html, PNG plots and the logged signals
(logs.npz, read back with `pedi_drake.evaluation.run_logs.read_run_logs`).
"""

import time
from pathlib import Path

import numpy as np
from pydrake.geometry import Meshcat
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import EventStatus

from pedi_drake import robot
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.evaluation import mission_results
from pedi_drake.evaluation.result_file import write_result
from pedi_drake.evaluation.run_logs import SignalLog, write_run_logs
from pedi_drake.fall import fell_during
from pedi_drake.go1_driver.safety import driver_report
from pedi_drake.mission.progress import FAILED, SUCCEEDED
from pedi_drake.scenario import Scenario
from pedi_drake.viz import plots

SETTLE_AFTER_MISSION = 0.5  # [s] simulated after the mission ends, then the run stops
PROGRESS_EVERY = 2.0  # [s] of simulated time between progress lines
MONITOR_PERIOD = 0.005  # [s] between looks at the mission's status (it changes at 100 Hz)


def run(
    *,
    scenario: Scenario,
    name: str,
    out_dir: Path,
    meshcat: Meshcat | None = None,
    quiet: bool = False,
    hardware: bool = False,
    replay: bool = True,
    realtime_rate: float = 1.0,
) -> dict:
    """Simulates `scenario`, writes result.json, replay.html, plots and logs.npz to `out_dir`; returns the result.

    With `hardware=True` the station is the Go1 LCM driver (a Go1, or the simulator bridge in
    another process) and the diagram runs in real time. There is no ground truth then: the
    results (foot errors, drift, falls) come from the state estimate, and no replay is written.
    `replay=False` skips the Meshcat recording too (a run without any visualisation).
    `realtime_rate` paces a hardware run (below 1 only against the simulator bridge run at the
    same rate: a slow-motion run for a machine too slow for both processes in real time).
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    if not hardware and replay:
        # A Meshcat is made even when nobody watches live: it records the replay.
        meshcat = meshcat or Meshcat()
    built = MakePedipulationDiagram(scenario, meshcat, hardware=hardware)
    diagram = built.diagram
    simulator = Simulator(diagram)
    if hardware:
        simulator.set_target_realtime_rate(realtime_rate)
    manager = diagram.GetSubsystemByName("mission") if built.mission is not None else None
    state = {"next_print": PROGRESS_EVERY, "ended": None, "next_check": 0.0}

    def monitor(root_context):
        t = root_context.get_time()
        # The mission's status changes only at the manager's updates: no need to look every step.
        if t < state["next_check"]:
            return EventStatus.Succeeded()
        state["next_check"] = t + MONITOR_PERIOD
        progress = manager.progress(manager.GetMyContextFromRoot(root_context)) if manager else None
        if not quiet and t >= state["next_print"]:
            state["next_print"] += PROGRESS_EVERY
            if progress is not None:
                phase = progress.records[-1].name if progress.records else "-"
                count = len(built.mission.phases)
                print(f"  t = {t:5.1f} s  phase {progress.index + 1}/{count} {phase} ({progress.status})")
            else:
                print(f"  t = {t:5.1f} s")
        if progress is not None and progress.status in (SUCCEEDED, FAILED):
            state["ended"] = state["ended"] or t
            if t >= state["ended"] + SETTLE_AFTER_MISSION:
                return EventStatus.ReachedTermination(diagram, "mission over")
        return EventStatus.Succeeded()

    simulator.set_monitor(monitor)
    simulator.Initialize()
    if meshcat is not None and not hardware:
        meshcat.StartRecording(set_visualizations_while_recording=False)
    wall_start = time.perf_counter()
    simulator.AdvanceTo(scenario.simulation_duration)
    wall_time = time.perf_counter() - wall_start
    if meshcat is not None and not hardware:
        meshcat.StopRecording()
        meshcat.PublishRecording()
        (out_dir / "replay.html").write_text(meshcat.StaticHtml())

    context = simulator.get_context()
    logs = {name: diagram.GetSubsystemByName(logger).FindLog(context) for name, logger in built.loggers.items()}
    t_cmd, command = logs["go1.command"].sample_times(), logs["go1.command"].data()
    position, velocity = logs["go1.position_measured"].data(), logs["go1.velocity_measured"].data()
    base = logs["base_state"].data()
    has_prongs = scenario.robot.prongs is not None
    if hardware:
        # The estimate is all there is: the trunk pose [quaternion; position] of base_state.
        plant = plant_map = None
        t_state, states = logs["base_state"].sample_times(), None
        p_WB = base[4:7]
        fell = fell_during(base[0:4], base[6], has_prongs=has_prongs)
    else:
        plant = diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
        plant_map = robot.Go1PlantMap.from_plant(plant)
        t_state, states = logs["sim.plant_state"].sample_times(), logs["sim.plant_state"].data()
        p_WB = states[plant_map.base_q_start + 4 : plant_map.base_q_start + 7]
        q0 = plant_map.base_q_start
        fell = fell_during(states[q0 : q0 + 4], states[q0 + 6], has_prongs=has_prongs)
    sim_time = float(context.get_time())
    result = {
        "mission": built.mission.name if built.mission else None,
        "scenario": name,
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
        "force_estimate": (built.mission.force_estimate if built.mission else "") or scenario.force_estimate,
        "hardware": hardware,
        # Where foot errors, drift and falls come from: simulation ground truth, or the estimate.
        "judged_by": "state_estimate" if hardware else "ground_truth",
        "random_seed": scenario.random_seed,
        "sensor_noise": scenario.sensor_noise.enabled,
        "final_trunk_height_m": float(p_WB[2, -1]),
    }
    if hardware:
        station = diagram.GetSubsystemByName("station")
        station_context = station.GetMyContextFromRoot(context)
        result["driver"] = driver_report(
            station.GetOutputPort("driver.status").Eval(station_context),
            station.GetOutputPort("driver.message_counts").Eval(station_context),
        )
    if "controller.diagnostics" in logs:
        tick_ms = 1e3 * logs["controller.diagnostics"].data()[2]
        tick_ms = tick_ms[tick_ms > 0]
        result["controller_tick_ms"] = {
            "median": float(np.median(tick_ms)),
            "p99": float(np.percentile(tick_ms, 99)),
            "max": float(np.max(tick_ms)),
        }
    plots.plot_joint_tracking(t_cmd, command[:12], position, out_dir / "joint_positions.png", title=name)
    plots.plot_foot_forces(
        logs["go1.foot_contact"].sample_times(), logs["go1.foot_contact"].data(), out_dir / "foot_forces.png"
    )

    if manager is not None:
        progress = manager.progress(manager.GetMyContextFromRoot(context))
        mission_ok = progress.status == SUCCEEDED
        result["success"] = mission_ok and not fell
        result["reason"] = progress.reason if not mission_ok else ("the trunk fell" if fell else "")
        if progress.status not in (SUCCEEDED, FAILED):
            result["reason"] = f"the simulation ended ({sim_time:.1f} s) before the mission did"
        result["phases"] = mission_results.phase_table(progress)
        status_log, body_log = logs["mission.status"].data(), logs["mission.body_reference"].data()
        result["max_base_drift_m"] = mission_results.max_base_drift(p_WB, body_log, status_log)
        result["presses"] = mission_results.press_results(progress)
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
        leg = mission_results.pedipulation_leg(logs["mission.leg_reference"].data())
        if leg is not None:
            plots.plot_leg_tracking(
                t_cmd, command, position, velocity, leg, result["phases"], out_dir / "leg_tracking.png"
            )
            if not hardware:
                plots.plot_mission_errors(
                    t_state, states, body_log, status_log, plant, result, out_dir / "mission_errors.png"
                )
    if hardware and result["driver"]["latched"] is not None:
        # Damping took over: whatever the estimate says afterwards, the run did not go as planned.
        result["success"] = False
        result["reason"] = f"the driver latched damping ({result['driver']['latched']}); " + result["reason"]
    write_run_logs(out_dir, {name: SignalLog(log.sample_times(), log.data()) for name, log in logs.items()})
    write_result(out_dir, result)
    return result
