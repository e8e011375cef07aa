"""The lifted foot through the edge of its reach and back, on both controllers
(missions/evaluations/reach_edge.yaml: paper 002's "singularity configuration" on a leg that has
none within its joint limits, so its workspace boundary instead).

    python -m pedi_drake.benchmarks.reach_edge [--out benchmarks/results/reach_edge.json]
        [--plot out/benchmarks/reach_edge.png]

From the simulation's ground truth, per controller:

  * the stretch beyond reach: the ticks at which the foot's reference, in the trunk's true frame,
    has no solution of the leg's closed-form IK within the joint limits;
  * the foot error (true foot centre to its reference): its largest value in that stretch, and its
    largest after the reference is back in reach and the return has ended (the back_in_reach
    phase);
  * the applied motor torques: the largest share of any motor's effort limit, and the largest
    change of a torque from one control tick to the next (a spike) against the same over the
    rest of the run;
  * the mission's success and no fall (the judge's).

Floors (the issue's row): the peak torque under the limits, the foot error under 2 cm through
the stretch and under 5 mm after it, no fall, both controllers. The plot shows the foot error,
the knee angle against its limit and the FR torques over the sweep for both controllers.
"""

import argparse
import json
from pathlib import Path

import numpy as np
from pydrake.common.eigen_geometry import Quaternion

from pedi_drake import robot
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.control.references import LEG_MODE_FOOT
from pedi_drake.evaluation.judge import judge_run
from pedi_drake.evaluation.mission_results import foot_positions_W
from pedi_drake.ik.analytic import leg_ik_solutions
from pedi_drake.resources import missions_dir
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario

MISSION = missions_dir() / "evaluations" / "reach_edge.yaml"
CONTROLLERS = ("whole_body", "projected_impedance")
LEG = "FR"
STRETCH = ("sweep_out", "back_in_reach")  # the phases the sweep spans
AFTER = "back_in_reach"
STRETCH_ERROR_FLOOR_M = 0.02
AFTER_ERROR_FLOOR_M = 0.005
KNEE = 3 * robot.LEG_NAMES.index(LEG) + 2


def sweep_trace(record, result: dict) -> dict:
    """Times [s], the foot's reference and true position (N, 3) [m], whether the reference was
    beyond reach (N,), the FR joints (N, 3) [rad] and the applied torques (12, N) [N m] over the
    sweep, and the window of the AFTER phase."""
    phases = {row["name"]: row for row in result["phases"]}
    t0, t1 = phases[STRETCH[0]]["t_start"], phases[STRETCH[1]]["t_end"]
    plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
    states, legs = record.logs["sim.plant_state"], record.logs["mission.leg_reference"]
    window = np.flatnonzero((states.times >= t0) & (states.times <= t1))
    times = states.times[window]
    feet = foot_positions_W(plant, states.data.astype(float), window)[:, robot.LEG_NAMES.index(LEG)]
    at = np.clip(np.searchsorted(legs.times, times), 0, len(legs.times) - 1)
    block = 12 * robot.LEG_NAMES.index(LEG)
    # The samples at which the leg follows a foot reference (at the sweep's first instant the
    # logged reference may still be the lift's joint angles).
    foot_mode = np.round(legs.data[block, at]) == LEG_MODE_FOOT
    window, times, feet, at = window[foot_mode], times[foot_mode], feet[foot_mode], at[foot_mode]
    reference = legs.data[block + 1 : block + 4, at].T.astype(float)
    q0 = robot.Go1PlantMap.from_plant(plant).base_q_start
    beyond = np.zeros(len(times), bool)
    for k, x in enumerate(states.data[:, window].T.astype(float)):
        quaternion = x[q0 : q0 + 4] / np.linalg.norm(x[q0 : q0 + 4])
        R_WB, p_WB = Quaternion(quaternion).rotation(), x[q0 + 4 : q0 + 7]
        beyond[k] = not leg_ik_solutions(LEG, R_WB.T @ (reference[k] - p_WB), respect_limits=True)
    measured = record.logs["go1.position_measured"]
    joints = measured.data[3 * robot.LEG_NAMES.index(LEG) : 3 * robot.LEG_NAMES.index(LEG) + 3]
    joints = joints[:, np.clip(np.searchsorted(measured.times, times), 0, len(measured.times) - 1)].T
    torque = record.logs["sim.motor_torque"]
    return {
        "times": times,
        "reference": reference,
        "foot": feet,
        "beyond": beyond,
        "joints": joints,
        "torque_times": torque.times,
        "torques": torque.data.astype(float),
        "after": (phases[AFTER]["t_start"], phases[AFTER]["t_end"]),
    }


def sweep_figures(trace: dict) -> dict:
    """The figures of the module docstring from a `sweep_trace`."""
    error = np.linalg.norm(trace["foot"] - trace["reference"], axis=1)
    times, beyond = trace["times"], trace["beyond"]
    after = (times >= trace["after"][0]) & (times <= trace["after"][1])
    torques, torque_times = trace["torques"], trace["torque_times"]
    steps = np.max(np.abs(np.diff(torques, axis=1)), axis=0)
    in_sweep = (torque_times[1:] >= times[0]) & (torque_times[1:] <= times[-1])
    later = torque_times[1:] > 1.0  # the stand-up's first second: the motors take the weight
    return {
        "beyond_reach_s": float(np.sum(beyond) * np.median(np.diff(times))) if beyond.any() else 0.0,
        "foot_error_beyond_reach_max_m": float(np.max(error[beyond], initial=0.0)),
        "foot_error_after_max_m": float(np.max(error[after], initial=0.0)),
        "knee_min_rad": float(np.max(trace["joints"][:, 2])),
        "knee_limit_rad": float(robot.Q_UPPER[KNEE]),
        "torque_share_of_limit_max": float(np.max(np.abs(torques).T / robot.EFFORT_LIMIT)),
        "torque_step_in_sweep_max_nm": float(np.max(steps[in_sweep], initial=0.0)),
        "torque_step_elsewhere_max_nm": float(np.max(steps[~in_sweep & later], initial=0.0)),
    }


def one_run(controller: str) -> tuple[dict, dict | None]:
    """(row, trace) of the mission on `controller`; trace None if the sweep did not run."""
    scenario = load_scenario(scenario_text=f"{{mission: {MISSION}, controller: {controller}, simulation_duration: 40}}")
    record = simulate(scenario=scenario, name=f"reach_edge {controller}", quiet=True, replay=False)
    result = judge_run(record)
    row = {"controller": controller, "success": bool(result["success"]), "reason": result["reason"]}
    row["fell"] = bool(result["fell"])
    phases = {r["name"]: r for r in result["phases"]}
    if any(phases.get(name, {}).get("t_end") is None for name in STRETCH):
        return row, None
    trace = sweep_trace(record, result)
    row.update(sweep_figures(trace))
    return row, trace


def floors_met(row: dict) -> bool:
    return (
        row["success"]
        and not row["fell"]
        and "foot_error_beyond_reach_max_m" in row
        and row["beyond_reach_s"] > 0.0
        and row["torque_share_of_limit_max"] < 1.0
        and row["foot_error_beyond_reach_max_m"] < STRETCH_ERROR_FLOOR_M
        and row["foot_error_after_max_m"] < AFTER_ERROR_FLOOR_M
    )


def plot(traces: dict[str, dict], path: Path) -> None:
    """Foot error, knee angle and the FR torques over the sweep, one column per controller."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, len(traces), figsize=(6 * len(traces), 8), sharex="col", squeeze=False)
    for column, (controller, trace) in enumerate(traces.items()):
        t = trace["times"] - trace["times"][0]
        error = 1000 * np.linalg.norm(trace["foot"] - trace["reference"], axis=1)
        ax = axes[0, column]
        ax.plot(t, error)
        ax.fill_between(t, 0, error.max(), where=trace["beyond"], alpha=0.2, label="reference beyond reach")
        ax.set_ylabel("foot error [mm]")
        ax.set_title(controller)
        ax.legend(loc="upper right")
        ax = axes[1, column]
        ax.plot(t, trace["joints"][:, 2], label="knee")
        ax.axhline(robot.Q_UPPER[KNEE], color="k", linestyle="--", label="knee limit")
        ax.set_ylabel("knee [rad]")
        ax.legend(loc="lower right")
        ax = axes[2, column]
        keep = (trace["torque_times"] >= trace["times"][0]) & (trace["torque_times"] <= trace["times"][-1])
        leg = 3 * robot.LEG_NAMES.index(LEG)
        for j, name in enumerate(("hip", "thigh", "knee")):
            ax.plot(trace["torque_times"][keep] - trace["times"][0], trace["torques"][leg + j, keep], label=name)
        ax.set_ylabel(f"{LEG} torque [N m]")
        ax.set_xlabel("time from the sweep's start [s]")
        ax.legend(loc="upper right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="benchmarks/results/reach_edge.json")
    parser.add_argument("--plot", default="out/benchmarks/reach_edge.png")
    args = parser.parse_args()
    rows, traces = [], {}
    print(
        f"{'controller':<21}{'beyond reach [s]':>17}{'error there [mm]':>17}{'after [mm]':>11}{'knee [rad]':>11}"
        f"{'torque/limit':>13}{'step [N m]':>11}{'elsewhere':>10}  ok"
    )
    for controller in CONTROLLERS:
        row, trace = one_run(controller)
        rows.append(row)
        if trace is None:
            print(f"{controller:<21}  NO: {row['reason']}", flush=True)
            continue
        traces[controller] = trace
        print(
            f"{controller:<21}{row['beyond_reach_s']:>17.2f}{1000 * row['foot_error_beyond_reach_max_m']:>17.1f}"
            f"{1000 * row['foot_error_after_max_m']:>11.2f}{row['knee_min_rad']:>11.3f}"
            f"{row['torque_share_of_limit_max']:>13.2f}{row['torque_step_in_sweep_max_nm']:>11.2f}"
            f"{row['torque_step_elsewhere_max_nm']:>10.2f}  {'yes' if floors_met(row) else 'NO: ' + row['reason']}",
            flush=True,
        )
    summary = {"runs": len(rows), "floors_met": sum(floors_met(row) for row in rows)}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped({"summary": summary, "runs": rows}), indent=2))
    if traces:
        plot(traces, Path(args.plot))
        print(f"plotted {args.plot}")
    print(f"floors met on {summary['floors_met']} of {summary['runs']} controllers; wrote {out}")


if __name__ == "__main__":
    main()
