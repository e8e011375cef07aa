"""Paper 002's controller against the HQP: one comparison table from one run of each case.

    python -m pedi_drake.benchmarks.paper002 [--out benchmarks/results/paper002.json]
        [--missions torso_circle_foot_hold hit_target_front ...] [--controllers ...]
        [--obstacle-seeds 0,1,2] [--skip-demos] [--reuse]

Cases, each on both controllers (`whole_body`, the paper-000 HQP, and `projected_impedance`):

* the scripted demos (ground-truth estimator, the controller alone): `three_leg_hold` for the
  controller tick on three stance feet (median and p99 of the `tick_time` diagnostic), foot
  error, trunk drift and stance slip; `push_foot` for the measured foot stiffness (a known force
  on the lifted foot) and the Eq. 11 force estimate's error against that force;
* the missions (Kalman estimate, as shipped): success, foot errors, trunk drift, tick; for
  `torso_circle_foot_hold` (evaluation IV-A) the held foot's position and orientation errors and
  the torso's circle tracking, with the plots of Figs. 3 to 5 in `--plots`;
* `prong_pivot_rotations` (evaluation IV-B): the trunk's rotation about the prong reached in
  roll, pitch and yaw, the lifted front feet's drift and the prong tip's slip, with Fig. 7 in
  `--plots`;
* `obstacle_sensing`: on both controllers as shipped (presses stopped by the joint-torque
  estimate), and on paper 002's controller over `--obstacle-seeds` (seed 0 without sensor noise,
  the others with, as the mission benchmark runs it) with the presses stopped by the impedance
  estimate: the RMS error of each foot force estimate against the simulated contact force at the
  foot during the presses, and each estimate's rigid/soft call;
* `hit_target_front`, `open_door`, `prong_push_box`: success, foot errors, drift, tick.

Prints the table and which floors hold; writes the rows and the floors to `--out` (JSON).

The figures come from simulation ground truth, for evaluation only.
"""

import argparse
import json
import platform
from pathlib import Path

import numpy as np

from pedi_drake.benchmarks.demos import demo_scenario, simulate_demo
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.benchmarks.missions import EXPECTED_OBSTACLES
from pedi_drake.benchmarks.paper002_plots import plot_foot_hold, plot_pivot_rotations
from pedi_drake.diagram import apply_mission
from pedi_drake.evaluation import paper002 as evaluation
from pedi_drake.evaluation.controller_metrics import controller_metrics
from pedi_drake.mission.spec import load_mission
from pedi_drake.run import run
from pedi_drake.run_logs import read_run_logs
from pedi_drake.scenario import Scenario, load_scenario
from pedi_drake.station_interface import MakeStation

CONTROLLERS = ("whole_body", "projected_impedance")
MISSIONS = (
    "torso_circle_foot_hold",
    "prong_pivot_rotations",
    "hit_target_front",
    "obstacle_sensing",
    "open_door",
    "prong_push_box",
)
TICK_MEDIAN_FLOOR_MS = 0.5
FOOT_STIFFNESS_TOLERANCE = 0.10
FORCE_ESTIMATE_RMS_FLOOR_N = 2.0


def demo_rows() -> list[dict]:
    """three_leg_hold and push_foot (missions/demos/) on both controllers."""
    rows = []
    for name in ("three_leg_hold", "push_foot"):
        for controller in CONTROLLERS:
            scenario = demo_scenario(name)
            scenario.controller = controller
            record, judged = simulate_demo(name, scenario)
            r = controller_metrics(record, judged)
            row = {
                "case": f"demo {name}",
                "controller": controller,
                "success": judged["success"],
                "fell": r.fell,
                "qp_failures": r.qp_failures,
                "tick_median_ms": r.tick_median_ms,
                "tick_p99_ms": r.tick_p99_ms,
                "foot_error_max_m": max(r.foot_errors) if r.foot_errors else float("nan"),
                "trunk_drift_m": r.trunk_drift,
                "stance_slip_m": r.stance_slip,
                "real_time_factor": r.real_time_factor,
            }
            if name == "push_foot":
                plant = record.built.diagram.GetSubsystemByName("station").GetSubsystemByName("plant")
                push = apply_mission(record.scenario, record.built.mission).pushes[0]
                response = evaluation.foot_push_response(plant, record.logs, push)
                row["foot_stiffness_n_per_m"] = response.stiffness_n_per_m
                row["force_estimate_rms_n"] = response.force_estimate_rms_n
                if controller == "projected_impedance":
                    row["commanded_stiffness_n_per_m"] = scenario.projected_impedance.foot_stiffness[0]
            rows.append(row)
    return rows


def _station_plant(scenario: Scenario):
    """A plant with the state layout of the run's simulation (for reading its logged states)."""
    return MakeStation(scenario).GetSubsystemByName("plant")


def press_figures(result: dict, logs: dict) -> dict:
    """The press phases of an obstacle_sensing run: each foot force estimate's RMS error against
    the simulated contact force at the foot [N] and whether its rigid/soft and fixed/mobile calls
    are all right."""
    errors = evaluation.press_force_errors(logs, result["phases"])
    calls: dict[str, dict] = {}
    for press in result["presses"]:
        for source, figures in press.get("by_estimate", {}).items():
            calls.setdefault(source, {})[press["phase"]] = (figures["classified_as"], figures["mobility"])
    row = {"true_force_max_n": errors["true_force_max_n"]}
    for source, rms in errors["rms_n"].items():
        row[f"force_estimate_rms_{source}_n"] = rms
        row[f"classified_right_{source}"] = calls.get(source) == EXPECTED_OBSTACLES["obstacle_sensing"]
    return row


def mission_row(
    mission: str,
    controller: str,
    out_dir: Path,
    plots: Path | None,
    *,
    scenario_text: str = "",
    case: str = "",
    reuse: bool = False,
) -> dict:
    """One mission (shipped name or YAML path) on one controller, default scenario with the Kalman
    estimate, judged on ground truth. `scenario_text`: more scenario fields, a YAML mapping's
    inside ("random_seed: 1, sensor_noise: {enabled: true}"); `case`: the row's name (default
    "mission NAME"); `plots`: where the IV-A and IV-B figures go (per controller). `reuse`: judge
    the run already in `out_dir` (its result.json and logs.npz) instead of simulating it again.

    Every row has success, foot errors, trunk drift and tick; a mission with a body_path phase
    (IV-A) adds the held foot's errors and the torso tracking, one turning about a prong (IV-B)
    the rotations reached and the front feet's drift, one with presses both force estimates'
    errors and calls."""
    extra = f", {scenario_text}" if scenario_text else ""
    scenario = load_scenario(scenario_text=f"{{mission: {mission}, controller: {controller}{extra}}}")
    spec = load_mission(mission)
    scenario.simulation_duration = max(scenario.simulation_duration, spec.longest_duration())
    if reuse and (out_dir / "result.json").exists() and (out_dir / "logs.npz").exists():
        result = json.loads((out_dir / "result.json").read_text())
    else:
        result = run(scenario=scenario, name=spec.name, out_dir=out_dir, quiet=True, replay=False)
    row = {
        "case": case or f"mission {spec.name}",
        "controller": controller,
        "success": result["success"],
        "reason": result["reason"],
        "fell": result["fell"],
        "foot_error_max_m": max((r["error"] for r in result["foot_errors_m"]), default=float("nan")),
        "trunk_drift_m": result["max_base_drift_m"],
        "tick_median_ms": result["controller_tick_ms"]["median"],
        "tick_p99_ms": result["controller_tick_ms"]["p99"],
        "real_time_factor": result["real_time_factor"],
    }
    merged = apply_mission(scenario, spec)
    logs = None
    turns = evaluation.phase_window(spec, result["phases"], "body_rotate", pivoted=True)
    if turns is not None:
        logs = read_run_logs(out_dir)
        tip = [0.0, 0.0, -merged.robot.prongs.length]
        pivot = evaluation.evaluate_pivot_rotations(
            _station_plant(merged), logs, *turns, evaluation.pivot_prong(spec), tip
        )
        row.update(pivot.summary())
        if plots is not None:
            row["plots"] = [str(plot_pivot_rotations(pivot, plots / controller, title=controller))]
    circle = evaluation.phase_window(spec, result["phases"], "body_path")
    if circle is not None:
        logs = logs or read_run_logs(out_dir)
        hold = evaluation.evaluate_foot_hold(_station_plant(merged), logs, *circle)
        row.update(hold.summary())
        if plots is not None:
            row["plots"] = [str(path) for path in plot_foot_hold(hold, plots / controller, title=controller)]
    if result.get("presses"):
        row.update(press_figures(result, logs or read_run_logs(out_dir)))
    return row


def obstacle_row(seed: int, out_dir: Path, reuse: bool = False) -> dict:
    """obstacle_sensing on paper 002's controller, presses stopped by the impedance estimate
    (seed 0 without sensor noise, others with): both estimates against the true contact force,
    and each estimate's rigid/soft call."""
    noise = "true" if seed else "false"
    row = mission_row(
        "obstacle_sensing",
        "projected_impedance",
        out_dir,
        None,
        scenario_text=f"force_estimate: impedance, random_seed: {seed}, sensor_noise: {{enabled: {noise}}}",
        case=f"obstacle_sensing seed {seed}",
        reuse=reuse,
    )
    row["sensor_noise"] = bool(seed)
    return row


def floors(rows: list[dict]) -> dict:
    """Which of the acceptance floors each measured row meets (paper 002's controller)."""
    checks = {}
    for row in rows:
        if row["controller"] != "projected_impedance":
            continue
        if row["case"] == "demo three_leg_hold":
            checks["tick_median_below_0.5_ms"] = row["tick_median_ms"] < TICK_MEDIAN_FLOOR_MS
        if row["case"] == "demo push_foot":
            commanded = row["commanded_stiffness_n_per_m"]
            checks["foot_stiffness_within_10_percent"] = (
                abs(row["foot_stiffness_n_per_m"] - commanded) <= FOOT_STIFFNESS_TOLERANCE * commanded
            )
            checks["force_estimate_rms_below_2_n"] = row["force_estimate_rms_n"] < FORCE_ESTIMATE_RMS_FLOOR_N
        if row["case"] == "mission torso_circle_foot_hold" and "torso_tracking_rms_m" in row:
            checks["iva_foot_position_below_5_mm"] = row["foot_position_error_max_m"] < evaluation.FOOT_POSITION_FLOOR_M
            checks["iva_foot_orientation_below_2_deg"] = row["foot_orientation_error_max_deg"] < 2.0
            checks["iva_torso_rms_below_1_cm"] = row["torso_tracking_rms_m"] < evaluation.TORSO_TRACKING_RMS_FLOOR_M
        if row["case"] == "mission prong_pivot_rotations" and "rotation_reached_deg" in row:
            checks["ivb_rotations_reach_5_deg_each_way"] = row["rotation_reached_min_deg"] >= 5.0
            checks["ivb_front_feet_within_5_mm"] = row["front_feet_drift_max_m"] < 0.005
    for row in rows:
        if row["case"].startswith("mission"):
            checks[f"{row['case']}_succeeds_on_{row['controller']}"] = bool(row["success"])
    obstacle = [row for row in rows if row["case"].startswith("obstacle_sensing seed")]
    if obstacle:
        checks["force_estimate_rms_below_2_n_in_presses_all_seeds"] = all(
            row["force_estimate_rms_impedance_n"] < FORCE_ESTIMATE_RMS_FLOOR_N for row in obstacle
        )
        checks["impedance_estimate_beats_joint_torque_all_seeds"] = all(
            row["force_estimate_rms_impedance_n"] < row["force_estimate_rms_joint_torque_n"] for row in obstacle
        )
        checks["obstacles_classified_right_all_seeds_impedance"] = all(
            row["classified_right_impedance"] for row in obstacle
        )
        checks["obstacles_classified_right_all_seeds_joint_torque"] = all(
            row["classified_right_joint_torque"] for row in obstacle
        )
    return checks


def print_table(rows: list[dict]) -> None:
    columns = [
        ("case", "{}"),
        ("controller", "{}"),
        ("success", "{}"),
        ("tick_median_ms", "{:.3f}"),
        ("tick_p99_ms", "{:.3f}"),
        ("foot_error_max_m", "{:.4f}"),
        ("trunk_drift_m", "{:.4f}"),
        ("foot_stiffness_n_per_m", "{:.0f}"),
        ("force_estimate_rms_n", "{:.2f}"),
        ("foot_position_error_max_m", "{:.4f}"),
        ("foot_orientation_error_max_deg", "{:.2f}"),
        ("torso_tracking_rms_m", "{:.4f}"),
        ("rotation_reached_min_deg", "{:.2f}"),
        ("front_feet_drift_max_m", "{:.4f}"),
        ("force_estimate_rms_impedance_n", "{:.2f}"),
        ("force_estimate_rms_joint_torque_n", "{:.2f}"),
        ("classified_right_impedance", "{}"),
        ("classified_right_joint_torque", "{}"),
    ]
    print(" | ".join(name for name, _ in columns))
    for row in rows:
        cells = []
        for name, fmt in columns:
            value = row.get(name, "")
            if isinstance(value, float) and not np.isfinite(value):
                value = "nan"
            cells.append(fmt.format(value) if value not in ("", "nan") and not isinstance(value, bool) else str(value))
        print(" | ".join(cells))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="benchmarks/results/paper002.json", help="JSON file of the rows.")
    parser.add_argument("--runs", default="out/paper002_benchmark", help="Folder of the mission runs.")
    parser.add_argument("--plots", default="out/paper002_benchmark/plots", help="Folder of the IV-A plots.")
    parser.add_argument("--missions", nargs="*", default=list(MISSIONS), help="Missions to run on both controllers.")
    parser.add_argument(
        "--obstacle-seeds",
        default="0,1,2,3,4,5",
        help="obstacle_sensing seeds on paper 002's controller (0 without sensor noise, others with; '' for none)",
    )
    parser.add_argument("--skip-demos", action="store_true", help="Leave out the scripted demos.")
    parser.add_argument("--controllers", nargs="*", default=list(CONTROLLERS), help="Controllers the missions run on.")
    parser.add_argument(
        "--reuse", action="store_true", help="Judge mission runs already in --runs instead of simulating them again."
    )
    args = parser.parse_args()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    rows: list[dict] = []

    def record(new_rows: list[dict]) -> None:
        # Written after every case: a long benchmark stopped early keeps what it measured.
        rows.extend(new_rows)
        report = {"machine": platform.processor() or platform.machine(), "rows": rows, "floors": floors(rows)}
        out.write_text(json.dumps(stamped(report), indent=2, default=float))

    if not args.skip_demos:
        record(demo_rows())
    for seed in [int(s) for s in args.obstacle_seeds.split(",") if s]:
        record([obstacle_row(seed, Path(args.runs) / "obstacle_seeds" / str(seed), reuse=args.reuse)])
    runs, plots = Path(args.runs), Path(args.plots)
    for mission in args.missions:
        for controller in args.controllers:
            record([mission_row(mission, controller, runs / controller / mission, plots, reuse=args.reuse)])
    print_table(rows)
    for name, ok in floors(rows).items():
        print(f"{'ok  ' if ok else 'MISS'} {name}")
    print(f"written {out}")


if __name__ == "__main__":
    main()
