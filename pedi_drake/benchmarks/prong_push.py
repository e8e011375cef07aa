"""Paper 003's push experiment (Section VII-A) as a controlled comparison: does a pair of prongs
lower the knee torque a push on the trunk demands, and which placement does?

    python -m pedi_drake.benchmarks.prong_push [--out benchmarks/results/prong_push.json]

Each run is the shipped push_recovery mission (the trunk lowered to the prongs' height, 0.17 m;
30 N at the trunk's origin, ramped over 1 s, held 5 s) on the HQP with paper 003's stack, varied
in two ways:

  * the push's direction: along x (forwards) and along y (to the robot's right);
  * the prongs: none (the trunk held at the same height by the feet alone), a pair on the
    trunk's centre line (x = +-PRONG_HALF_SPACING, the shipped design) and a pair spread to the
    trunk's sides (y = +-SIDE_HALF_SPACING, at the middle of its length).

A pair of prongs touches the ground at two points, so it takes no moment about the line through
them: a pair on the centre line can take a pitch moment (a push along x loads the front legs and
unloads the hind ones) but no roll moment, a pair at the sides the reverse. Reported per run and
per knee: the calf motor's mean torque at full force minus its mean just before the push (what
the push adds), the largest stance-foot slide, and what the prongs carried. Judged by physics
(simulation ground truth), like every mission.
"""

import argparse
import json
import tempfile
from pathlib import Path

from pydrake.common.yaml import yaml_dump, yaml_load

from pedi_drake import robot
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.evaluation.judge import judge_run
from pedi_drake.prongs import PRONG_HALF_SPACING, TRUNK_HALF_HEIGHT
from pedi_drake.resources import missions_dir
from pedi_drake.run import simulate
from pedi_drake.scenario import load_scenario

# Where a side prong sits across the trunk [m]: at its side wall (half its 0.0935 m width).
SIDE_HALF_SPACING = robot.TRUNK_HALF_EXTENTS[1]
DIRECTIONS = {"x": [1.0, 0.0, 0.0], "y": [0.0, -1.0, 0.0]}
# Each design's prong attachment points in the trunk frame [m] (None: no prongs).
DESIGNS = {
    "none": None,
    "centre_line": [[PRONG_HALF_SPACING, 0.0, -TRUNK_HALF_HEIGHT], [-PRONG_HALF_SPACING, 0.0, -TRUNK_HALF_HEIGHT]],
    "sides": [[0.0, SIDE_HALF_SPACING, -TRUNK_HALF_HEIGHT], [0.0, -SIDE_HALF_SPACING, -TRUNK_HALF_HEIGHT]],
}
MISSIONS = {"none": "push_recovery_no_prongs", "with": "push_recovery_prongs"}


def variant_mission(design: str, direction: str, folder: Path) -> Path:
    """A mission file in `folder`: the shipped push_recovery mission with `design`'s prongs (or
    none) and the push along `direction`."""
    spec = yaml_load(filename=str(missions_dir() / f"{MISSIONS['none' if DESIGNS[design] is None else 'with']}.yaml"))
    if DESIGNS[design] is not None:
        spec["robot"] = {"prongs": {"attachment_points": DESIGNS[design]}}
    for push in spec["pushes"]:
        push["direction"] = DIRECTIONS[direction]
    path = folder / f"push_{direction}_{design}.yaml"
    path.write_text(yaml_dump(spec))
    return path


def one_run(design: str, direction: str, folder: Path) -> dict:
    """The judged push of one (design, direction) run."""
    mission = variant_mission(design, direction, folder)
    scenario = load_scenario(scenario_text=f"{{mission: {mission}, controller: whole_body, simulation_duration: 60.0}}")
    result = judge_run(simulate(scenario=scenario, name=mission.stem, quiet=True, replay=False))
    push = result["pushes"][0]
    added = {
        leg: push["knee_torque_full_force_Nm"][leg] - push["knee_torque_before_Nm"][leg] for leg in robot.LEG_NAMES
    }
    return {
        "design": design,
        "direction": direction,
        "success": bool(result["success"]),
        "reason": result["reason"],
        "knee_torque_added_Nm": added,
        "largest_knee_torque_added_Nm": max(abs(value) for value in added.values()),
        "knee_torque_before_Nm": push["knee_torque_before_Nm"],
        "max_foot_slide_m": push["max_foot_slide_m"],
        "trunk_displacement_m": push["trunk_displacement_m"],
        "prong_load_N": push["prong_load_N"],
        "prong_share_of_push": push["prong_share_of_push"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--designs", nargs="+", choices=list(DESIGNS), default=list(DESIGNS))
    parser.add_argument("--directions", nargs="+", choices=list(DIRECTIONS), default=list(DIRECTIONS))
    parser.add_argument("--out", default="benchmarks/results/prong_push.json")
    args = parser.parse_args()
    rows = []
    print(f"{'push':<6}{'prongs':<13}{'added knee torque FR FL RR RL [N m]':>38}{'largest':>9}{'slide [mm]':>12}  ok")
    with tempfile.TemporaryDirectory() as folder:
        for direction in args.directions:
            for design in args.designs:
                row = one_run(design, direction, Path(folder))
                rows.append(row)
                added = "".join(f"{row['knee_torque_added_Nm'][leg]:>+9.2f}" for leg in robot.LEG_NAMES)
                print(
                    f"{direction:<6}{design:<13}{added:>38}{row['largest_knee_torque_added_Nm']:>9.2f}"
                    f"{1000 * row['max_foot_slide_m']:>12.2f}  {'yes' if row['success'] else 'NO: ' + row['reason']}",
                    flush=True,
                )
    summary = {
        direction: {
            row["design"]: round(row["largest_knee_torque_added_Nm"], 3)
            for row in rows
            if row["direction"] == direction
        }
        for direction in args.directions
    }
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped({"summary": summary, "runs": rows}), indent=2))
    for direction, by_design in summary.items():
        print(
            f"push along {direction}: largest knee torque added "
            + ", ".join(f"{k} {v:.2f}" for k, v in by_design.items())
        )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
