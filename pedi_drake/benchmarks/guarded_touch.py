"""Touches confirmed by contact, in both engines: hit_target_front with its cardboard cat where the
mission planned it, moved away after planning, and moved into the planned target.

    python -m pedi_drake.benchmarks.guarded_touch [--offsets 0.0 0.03 -0.01] [--engines drake mujoco]
        [--work out/guarded_touch] [--out benchmarks/results/guarded_touch.json]

The mission plans its touch for the cat at x = 0.47 m; the cat stands `offset` [m] further along
the approach (+: away from the robot, nothing where the foot is sent; -: into the target, met
early). `drake`: the project's simulation in lock step (`run_sim.py`'s run); `mujoco`: over the
Go1 LCM wire at real time against the MuJoCo robot (`apps.sil --robot mujoco`). Per run: the
mission's success (by the engine's ground truth for MuJoCo: the mission's and its touch's by the
engine's contact forces), its reason, the touch as the robot sensed it (confirmed, force [N] by
which estimate, where along the approach from the target [mm]) and the largest true contact force
between the foot and the cat [N]. A target moved away must fail with "no contact felt"; one moved
into the cat must still be touched.
"""

import argparse
import json
import time
from pathlib import Path

from pydrake.common.yaml import yaml_load

from pedi_drake.apps.sil import run_sil
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.resources import missions_dir
from pedi_drake.run import run
from pedi_drake.scenario import load_scenario

MISSION = "hit_target_front"
ENGINES = ("drake", "mujoco")


def moved_target_mission(offset: float, path: Path) -> Path:
    """hit_target_front with its scene's object `offset` [m] further along x, written to `path`
    (JSON, which is YAML) for both sides of a run to load."""
    mission = yaml_load(filename=str(missions_dir() / f"{MISSION}.yaml"))
    (obj,) = mission["scene"]
    obj["position"][0] += offset
    mission["description"] = f"{mission['description'].strip()} Its object moved {offset:+.3f} m along x."
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(mission, indent=2))
    return path


def one_run(engine: str, offset: float, work: Path) -> dict:
    """One run of the moved-target mission in `engine`; its row (module docstring)."""
    mission = moved_target_mission(offset, work / "mission.yaml")
    start = time.monotonic()
    if engine == "drake":
        scenario = load_scenario()
        scenario.mission, scenario.controller = str(mission), "whole_body"
        result = run(scenario=scenario, name=MISSION, out_dir=work / "run", quiet=True, replay=False)
        success, touches = result["success"], result["touches"]
    else:
        result = run_sil(str(mission), work / "run", robot=engine)
        success, touches = result["sil"]["success_by_truth"], result["sil"]["touches"]
    (sensed,) = result["sensed_touches"] or [None]
    return {
        "engine": engine,
        "offset_m": offset,
        "success": bool(success),
        "reason": result["reason"],
        "sensed": sensed,
        "true_force_n": max((row["max_normal_force_n"] for row in touches or []), default=None),
        "no_contact_felt": "no contact felt" in (result["reason"] or ""),
        "wall_s": time.monotonic() - start,
    }


def expected(row: dict) -> bool:
    """Whether a run did what a guarded touch must: a target moved away fails with "no contact
    felt"; any other is touched with at least the mission's required true force."""
    if row["offset_m"] > 0.0:
        return not row["success"] and row["no_contact_felt"]
    return row["success"] and row["sensed"] is not None and row["sensed"]["confirmed"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--offsets", type=float, nargs="+", default=[0.0, 0.03, -0.01])
    parser.add_argument("--engines", nargs="+", choices=ENGINES, default=list(ENGINES))
    parser.add_argument("--work", default="out/guarded_touch")
    parser.add_argument("--out", default="benchmarks/results/guarded_touch.json")
    args = parser.parse_args()
    rows = []
    header = f"{'engine':<8}{'offset [mm]':>12}  {'outcome':<10}{'sensed [N]':>11}{'felt at [mm]':>13}"
    print(header + f"{'true [N]':>10}  as it must")
    for engine in args.engines:
        for offset in args.offsets:
            row = one_run(engine, offset, Path(args.work) / f"{engine}_{1000 * offset:+.0f}mm")
            row["as_it_must"] = expected(row)
            rows.append(row)
            sensed = row["sensed"] or {}
            felt = sensed.get("felt_from_target_m")
            print(
                f"{engine:<8}{1000 * offset:>12.0f}  {'touched' if row['success'] else 'failed':<10}"
                f"{sensed.get('force_n', float('nan')):>11.2f}"
                f"{(1000 * felt if felt is not None else float('nan')):>13.1f}"
                f"{(row['true_force_n'] if row['true_force_n'] is not None else float('nan')):>10.2f}  "
                f"{'yes' if row['as_it_must'] else 'NO'}" + ("" if row["success"] else f"  ({row['reason']})"),
                flush=True,
            )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped({"runs": rows}), indent=2))
    print(f"{sum(row['as_it_must'] for row in rows)} of {len(rows)} runs as they must; wrote {out}")


if __name__ == "__main__":
    main()
