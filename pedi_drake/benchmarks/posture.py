"""The SUF the optimal posture gains on the shipped missions' reach targets, and its reach errors.

    python -m pedi_drake.benchmarks.posture [--missions a,b] [--method-samples 10] [--skip-fixed]
        [--out benchmarks/results/posture.json]

For every shipped mission (missions/*.yaml) with reach phases, a variant with `posture: optimal`
on every leg_to_pedipulation that the optimiser serves (one lifted leg, the trunk on its feet;
a lift it cannot serve keeps the fixed posture and the table says why) runs in simulation (seed
0, no sensor noise, `run_sim.py` in its own process, judged on ground truth). Per reach target:

  * the SUF at the target with today's fixed posture (the CoM shifted over the centroid of the
    other feet, height and attitude kept) and with the optimal one: the optimiser's model
    (pedi_drake.suf.posture) at the stance the run measured when it planned;
  * the gain (none where the lift found no feasible posture and took the fixed one), and the true
    foot error at the end of the reach with the optimal posture (the floor: within 5 mm) and,
    unless `--skip-fixed`, with the shipped mission's fixed posture (the same run without the
    optimiser).

Then the SUF methods on those cases (`--method-samples` random postures of each case's search
box, plus its fixed and optimal postures): CPU time per SUF (median) and the value against the
exact method, which justifies the optimiser's choice of method. Prints both tables, writes JSON.
"""

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from pydrake.common.yaml import yaml_dump, yaml_load

from pedi_drake.benchmarks.machine import stamped
from pedi_drake.exceptions import MissionFileError
from pedi_drake.mission import spec
from pedi_drake.mission.posture_planner import PLAN_LATENCY, POSTURE_DURATION
from pedi_drake.resources import missions_dir
from pedi_drake.suf.methods import smallest_unrejectable_force
from pedi_drake.suf.posture import Posture, PostureCase, PostureLimits, posture_box, posture_problems

REACH_FLOOR = 0.005  # [m] every target reached within 5 mm
# Time an optimal lift may take beyond planning, the posture move and the lift [s].
LIFT_EXTRA_TIME = 3.0
METHODS = {"affine": {}, "exact": {}, "fibonacci": {"num_directions": 256}}


def optimal_variant(name: str, folder: Path) -> tuple[Path | None, list[dict]]:
    """(the variant's file, or None when no lift can be optimal; one row per lift: its phase and
    whether it is optimal, or why not). Lifts are tried one at a time, in order."""
    raw = yaml_load(filename=str(missions_dir() / f"{name}.yaml"))
    lifts = [k for k, phase in enumerate(raw["phases"]) if phase.get("kind") == "leg_to_pedipulation"]
    rows, path = [], folder / f"{name}.yaml"
    for k in lifts:
        phase = dict(raw["phases"][k])
        trial = dict(phase, posture="optimal")
        least = PLAN_LATENCY + POSTURE_DURATION + trial.get("duration", spec.LegToPedipulation.duration)
        trial["timeout"] = max(trial.get("timeout", 0.0), least + LIFT_EXTRA_TIME)
        raw["phases"][k] = trial
        path.write_text(yaml_dump(raw))
        try:
            spec.load_mission(str(path))
            rows.append({"phase": k, "leg": phase.get("leg", "FR"), "optimal": True, "reason": ""})
        except MissionFileError as error:
            raw["phases"][k] = phase
            rows.append({"phase": k, "leg": phase.get("leg", "FR"), "optimal": False, "reason": str(error)})
    if not any(row["optimal"] for row in rows):
        return None, rows
    path.write_text(yaml_dump(raw))
    return path, rows


def goal_reaches(mission: spec.MissionSpec) -> dict[str, list[str]]:
    """Per optimal lift (phase name), the names of the reach phases whose targets its goal holds."""
    found = {}
    for i, phase in enumerate(mission.phases):
        if not (isinstance(phase, spec.LegToPedipulation) and phase.goal is not None):
            continue
        names = []
        for later in mission.phases[i + 1 :]:
            if isinstance(later, spec.LegToSupport) and later.leg == phase.leg:
                break
            if isinstance(later, spec.Reach) and later.leg == phase.leg:
                names.append(later.name)
        found[phase.name] = names
    return found


def run_variant(path: Path, out: Path) -> dict:
    """The variant's result.json after a simulated run (seed 0, no noise)."""
    command = [sys.executable, "run_sim.py", "--mission", str(path), "--out", str(out)]
    command += ["--scenario_text", "{random_seed: 0, sensor_noise: {enabled: false}}"]
    completed = subprocess.run(command, capture_output=True, text=True, cwd=Path(__file__).parents[2])
    result_file = out / "result.json"
    if not result_file.is_file():
        raise RuntimeError(f"{path.name}: run_sim.py wrote no result ({completed.stderr.strip()[-400:]})")
    return json.loads(result_file.read_text())


def target_rows(name: str, mission: spec.MissionSpec, result: dict) -> list[dict]:
    """One row per reach target of an optimal lift: SUF fixed and optimal, gain, true reach error."""
    reaches = goal_reaches(mission)
    errors = {row["phase"]: row for row in result.get("foot_errors_m", [])}
    rows = []
    for posture in result.get("postures", []):
        # A lift that found no feasible posture took the fixed one: no gain.
        taken = posture.get("taken", "optimal")
        for k, reach in enumerate(reaches.get(posture["phase"], [])):
            fixed = posture["fixed"]["suf_per_target_n"][k]
            optimal = posture["optimal" if taken == "optimal" else "fixed"]["suf_per_target_n"][k]
            error = errors.get(reach, {}).get("error", math.nan)
            rows.append(
                {
                    "mission": name,
                    "reach": reach,
                    "leg": posture["leg"],
                    "frame": posture["frame"],
                    "target": posture["targets"][k],
                    "suf_fixed_n": fixed,
                    "suf_optimal_n": optimal,
                    "gain_percent": 100.0 * (optimal / fixed - 1.0) if fixed > 0 else math.inf,
                    "reach_error_m": error,
                    "within_floor": bool(error <= REACH_FLOOR),
                    "posture_taken": taken,
                    "fallback": posture.get("fallback", ""),
                    "fixed_posture": {key: posture["fixed"][key] for key in ("p_WB", "rpy", "feasible", "reason")},
                    "optimal_posture": {key: posture["optimal"][key] for key in ("p_WB", "rpy")},
                    "mission_success": result.get("success", False),
                    "mission_reason": result.get("reason", ""),
                }
            )
    return rows


def case_of(posture: dict) -> PostureCase:
    """The optimiser's case recorded in a result's `postures` row."""
    return PostureCase(
        stance_W=tuple((leg, tuple(p)) for leg, p in posture["stance_W"].items()),
        leg=posture["leg"],
        targets=tuple(tuple(p) for p in posture["targets"]),
        frame=posture["frame"],
        reach_only=tuple(tuple(p) for p in posture["reach_only"]),
        lift_B=tuple(posture["lift_B"]) if "lift_B" in posture else None,
    )


def method_comparison(postures: list[dict], samples: int, rng: np.random.Generator) -> dict:
    """CPU time per SUF [ms] (median) and the value against `exact` of every method, at the
    fixed and optimal posture of every case and `samples` random postures of its box."""
    times = {m: [] for m in METHODS}
    ratios = {m: [] for m in METHODS}
    for row in postures:
        case = case_of(row)
        fixed = Posture(tuple(row["fixed"]["p_WB"]), tuple(row["fixed"]["rpy"]))
        optimal = Posture(tuple(row["optimal"]["p_WB"]), tuple(row["optimal"]["rpy"]))
        lower, upper = posture_box(fixed, PostureLimits())
        candidates = [fixed, optimal] + [Posture.from_vector(rng.uniform(lower, upper)) for _ in range(samples)]
        for posture in candidates:
            problems, _, _ = posture_problems(case, posture)
            for problem in problems or []:
                values = {}
                for method, options in METHODS.items():
                    start = time.thread_time()
                    values[method] = smallest_unrejectable_force(problem, method, **options).value
                    times[method].append(1e3 * (time.thread_time() - start))
                if values["exact"] > 1e-6:
                    for method in METHODS:
                        ratios[method].append(values[method] / values["exact"])
    return {
        method: {
            "median_ms": statistics.median(times[method]) if times[method] else math.nan,
            "ratio_min": min(ratios[method], default=math.nan),
            "ratio_median": statistics.median(ratios[method]) if ratios[method] else math.nan,
            "ratio_max": max(ratios[method], default=math.nan),
            "problems": len(times[method]),
        }
        for method in METHODS
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--missions", default="", help="comma-separated mission names (default: every shipped one)")
    parser.add_argument("--method-samples", type=int, default=10, help="random postures per case for the methods")
    parser.add_argument(
        "--skip-fixed", action="store_true", help="do not run the shipped (fixed-posture) missions for comparison"
    )
    parser.add_argument("--out", default="benchmarks/results/posture.json")
    args = parser.parse_args()
    names = [n for n in args.missions.split(",") if n] or spec.shipped_missions()
    rows, lifts, results = [], {}, {}
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        for name in names:
            if not any(isinstance(p, spec.Reach) for p in spec.load_mission(name).phases):
                continue
            path, lifts[name] = optimal_variant(name, folder)
            if path is None:
                print(f"{name}: no lift served ({'; '.join(row['reason'] for row in lifts[name])})", flush=True)
                continue
            started = time.perf_counter()
            results[name] = run_variant(path, folder / f"out_{name}")
            found = target_rows(name, spec.load_mission(str(path)), results[name])
            took = time.perf_counter() - started
            print(f"{name}: ran in {took:.0f} s, success {results[name]['success']}", flush=True)
            if not args.skip_fixed:
                shipped = run_variant(missions_dir() / f"{name}.yaml", folder / f"out_{name}_fixed")
                fixed_errors = {row["phase"]: row["error"] for row in shipped.get("foot_errors_m", [])}
                for row in found:
                    row["reach_error_fixed_posture_m"] = fixed_errors.get(row["reach"], math.nan)
                print(f"{name} (fixed posture): success {shipped['success']}", flush=True)
            rows += found
    print()
    header = (
        f"{'mission':<26}{'reach':<14}{'leg':<5}{'SUF fixed':>10}{'optimal':>10}{'gain %':>8}{'error mm':>10}"
        f"{'fixed mm':>10}  posture taken: height [m], roll/pitch/yaw [rad]"
    )
    print(header)
    print("-" * len(header))
    for row in rows:
        p_WB, rpy = row["optimal_posture"]["p_WB"], row["optimal_posture"]["rpy"]
        taken = "fixed (none feasible)" if row["posture_taken"] == "fixed" else f"{p_WB[2]:.3f}, {np.round(rpy, 2)}"
        print(
            f"{row['mission']:<26}{row['reach']:<14}{row['leg']:<5}{row['suf_fixed_n']:>10.2f}"
            f"{row['suf_optimal_n']:>10.2f}{row['gain_percent']:>8.1f}{1000 * row['reach_error_m']:>10.2f}"
            f"{1000 * row.get('reach_error_fixed_posture_m', math.nan):>10.2f}  {taken}"
        )
    for name, rows_of_lifts in lifts.items():
        for row in rows_of_lifts:
            if not row["optimal"]:
                print(f"not served: {name} phase {row['phase']} ({row['leg']}): {row['reason'].split(': ', 1)[-1]}")
    every = [p for result in results.values() for p in result.get("postures", [])]
    methods = method_comparison(every, args.method_samples, np.random.default_rng(0))
    print(f"\n{'method':<12}{'median ms':>10}{'ratio min':>10}{'median':>8}{'max':>8}{'problems':>10}")
    for method, row in methods.items():
        print(
            f"{method:<12}{row['median_ms']:>10.2f}{row['ratio_min']:>10.4f}{row['ratio_median']:>8.4f}"
            f"{row['ratio_max']:>8.4f}{row['problems']:>10d}"
        )
    floor = {
        "every_target_gains": bool(rows) and all(row["suf_optimal_n"] > row["suf_fixed_n"] for row in rows),
        "every_target_within_5_mm": bool(rows) and all(row["within_floor"] for row in rows),
    }
    print(f"\nfloor: {floor}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    report = {"targets": rows, "lifts": lifts, "methods": methods, "floor": floor}
    out.write_text(json.dumps(stamped(report), indent=1))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
