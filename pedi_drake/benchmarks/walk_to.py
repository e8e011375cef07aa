"""Where to stop, planned with the task: walk_to's SUF-chosen stop against the fixed stop.

    python -m pedi_drake.benchmarks.walk_to [--missions walking/walk_to_hit_target]
        [--noise-seeds 1,2,3,4,5] [--engine ray|serial] [--out benchmarks/results/walk_to.json]

Two parts. The plan, for every shipped reach target (the world-frame targets of the standing
missions' lifted leg, `TARGET_MISSIONS`): the stop `pedi_drake.suf.stop.choose_stop` takes within
its default box about the mission's own stance (the fixed stop: where the robot stands in the
mission), and the SUF of the optimal posture the lift would then take (`optimise_posture`, as a
lift with posture: optimal does) at the fixed stop and at the chosen one. Missions on the prongs
are left out: there the trunk rests on them, which no posture choice applies to.

The runs, in simulation (seed 0 without noise and the noise seeds with sensor noise, the Kalman
estimate, judged by ground truth): each walk_to mission as shipped (`stop: suf`) and with
`stop: fixed`, the same walk ending at the fixed stop; per variant the successes, the touch's true
foot error, the SUF of the lift's optimal posture at the stance really reached, and the stops.
"""

import json
import shutil
import statistics
import tempfile
from pathlib import Path

from pedi_drake import robot
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.benchmarks.walking import measure, seeds_of, study_parser
from pedi_drake.leg_kinematics import working_position_B
from pedi_drake.locomotion.footholds import NOMINAL_FEET_B
from pedi_drake.mission.spec import LegToPedipulation, load_mission, reach_goal, resolve_mission
from pedi_drake.suf.posture import optimise_posture
from pedi_drake.suf.stop import StopCase, choose_stop

WALK_TO_MISSIONS = ["walking/walk_to_hit_target"]
# The standing missions whose lifted leg reaches world-frame targets off the prongs.
TARGET_MISSIONS = [
    "hit_target_front",
    "hit_target_side",
    "hit_target_behind",
    "push_light_box",
    "open_door",
    "obstacle_sensing",
    "obstacle_sensing_mobile",
]
STANDING_HEIGHT = 0.28  # [m] the trunk's height the missions stand up to


def stop_case(mission: str) -> tuple[StopCase, tuple[float, float, float]]:
    """(the stop case of the first lift of `mission`, the fixed stop: the robot's initial x, y and
    heading in the mission)."""
    spec = load_mission(mission)
    i, lift = next((i, p) for i, p in enumerate(spec.phases) if isinstance(p, LegToPedipulation))
    goal = reach_goal(spec.phases, i, f"{mission}: phases[{i}]")
    if goal.frame != "world":
        raise ValueError(f"{mission}: the lift's targets are in the {goal.frame} frame")
    x, y = spec.robot.initial_xy if spec.robot is not None and spec.robot.initial_xy else (0.0, 0.0)
    case = StopCase(
        leg=lift.leg,
        targets=tuple(tuple(float(v) for v in p) for p in goal.targets),
        reach_only=tuple(tuple(float(v) for v in p) for p in goal.reach_only),
        lift_B=tuple(float(v) for v in working_position_B(lift.leg, lift.working_depth)),
        feet_B=tuple(tuple(float(v) for v in p) for p in NOMINAL_FEET_B),
        height=STANDING_HEIGHT,
        ground=0.0,
        prongs_key=robot.design_key(None),
    )
    return case, (float(x), float(y), 0.0)


def plan_row(mission: str) -> dict:
    """The plan's figures for `mission`: the stops, their balanced-posture SUFs, and the SUF of the
    optimal posture the lift takes at each [N]."""
    case, fixed = stop_case(mission)
    result = choose_stop(case, fixed)

    def optimal(stop) -> dict:
        posture_case, start = case.posture_case(stop)
        best = optimise_posture(posture_case, start).best
        return {"suf_n": best.suf, "feasible": best.feasible, "reason": best.reason}

    return {
        "mission": mission,
        "leg": case.leg,
        "targets": [list(p) for p in case.targets],
        "fixed_stop": list(result.fixed.stop),
        "chosen_stop": list(result.best.stop),
        "fixed_balanced_suf_n": result.fixed.posture.suf,
        "chosen_balanced_suf_n": result.best.posture.suf,
        "fixed_optimal": optimal(result.fixed.stop),
        "chosen_optimal": optimal(result.best.stop),
        "evaluations": result.evaluations,
    }


def with_fixed_stop(mission: str, folder: Path) -> Path:
    """`mission` with its walk_to phases told `stop: fixed`, written into `folder`."""
    source = resolve_mission(mission)
    text = source.read_text()
    if "kind: walk_to," not in text:
        raise ValueError(f"{source}: write its walk_to phases as {{kind: walk_to, ...}}")
    path = folder / f"{source.stem}_fixed_stop.yaml"
    path.write_text(text.replace("kind: walk_to,", "kind: walk_to, stop: fixed,"))
    return path


def run_summary(runs: list[dict]) -> dict:
    """Per variant: successes, the touch's largest true foot error, the lift's optimal SUF."""
    sufs = [p["optimal"]["suf_n"] for run in runs for p in run.get("postures", []) if p.get("taken") == "optimal"]
    stops = [w["stop"]["taken_W"] for run in runs for w in run.get("walks", []) if "stop" in w]
    errors = [row["error"] for run in runs for row in run.get("foot_errors_m", []) if row.get("status") == "succeeded"]
    return {
        "runs": len(runs),
        "succeeded": sum(run["success"] for run in runs),
        "fell": sum(run["fell"] for run in runs),
        "true_foot_error_max_m": max(errors, default=None),
        "lift_optimal_suf_min_n": min(sufs, default=None),
        "lift_optimal_suf_median_n": statistics.median(sufs) if sufs else None,
        "stops_taken_W": stops,
        "failures": [run["reason"] for run in runs if not run["success"]],
    }


def main() -> None:
    parser = study_parser(__doc__, WALK_TO_MISSIONS, ["whole_body"], "benchmarks/results/walk_to.json")
    parser.add_argument("--plan-only", action="store_true", help="the plan's table only, no simulation")
    args = parser.parse_args()
    plans = [plan_row(mission) for mission in TARGET_MISSIONS]
    print(f"{'reach target':<26}{'fixed stop SUF [N]':>20}{'chosen stop SUF [N]':>21}  chosen stop (x, y, yaw)")
    for row in plans:
        stop = ", ".join(f"{v:+.3f}" for v in row["chosen_stop"])
        fixed, chosen = row["fixed_optimal"]["suf_n"], row["chosen_optimal"]["suf_n"]
        print(f"{row['mission']:<26}{fixed:>20.1f}{chosen:>21.1f}  ({stop})")
    runs: dict[str, dict] = {}
    if not args.plan_only:
        missions = [m for m in args.missions.split(",") if m]
        written = Path(tempfile.mkdtemp(prefix="walk_to_benchmark_"))
        try:
            variants = missions + [str(with_fixed_stop(mission, written)) for mission in missions]
            results = measure(
                variants, [c for c in args.controllers.split(",") if c], seeds_of(args.noise_seeds), args.engine
            )
        finally:
            shutil.rmtree(written)
        runs = {key: run_summary(value) for key, value in results.items()}
        print(f"\n{'run':<44}{'ok':>6}{'largest true foot error [mm]':>30}{'lift SUF min / median [N]':>28}")
        for key, row in runs.items():
            error, suf = row["true_foot_error_max_m"], row["lift_optimal_suf_min_n"]
            error_text = "-" if error is None else f"{1000 * error:.1f}"
            suf_text = "-" if suf is None else f"{suf:.1f} / {row['lift_optimal_suf_median_n']:.1f}"
            print(f"{key:<44}{row['succeeded']:>3}/{row['runs']:<2}{error_text:>30}{suf_text:>28}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped({"plans": plans, "runs": runs}), indent=2) + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
