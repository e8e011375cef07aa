"""The terrain floors: static walks over terrain in simulation, seed 0 without noise and more seeds
with sensor noise, on the Kalman estimate, judged by ground truth (pedi_drake.evaluation.walks).

    python -m pedi_drake.benchmarks.terrain [--missions terrain/slope_up_and_down,...]
        [--controllers whole_body] [--noise-seeds 1,2,3,4,5] [--engine ray|serial]
        [--out benchmarks/results/terrain.json]

Each mission runs as shipped and, when it changes the controllers' friction coefficient
(set_friction phases), also without those phases ("<name>_friction_unchanged", written for the
run): what happens when nobody tells the controllers the ground is slippery. The table is the
walking benchmark's (pedi_drake.benchmarks.walking): successes, falls in the failures, the
largest stance foot slip (how far a loaded foot slid within one stance), the estimate's drift.
"""

import shutil
import tempfile
from pathlib import Path

from pedi_drake.benchmarks.walking import report, seeds_of, study_parser
from pedi_drake.mission.spec import SetFriction, load_mission, resolve_mission

TERRAIN_MISSIONS = ["terrain/slope_up_and_down", "terrain/climb_turn_descend", "terrain/slippery_bridge"]


def without_friction_changes(mission: str, folder: Path) -> Path | None:
    """`mission` without its set_friction phases, written into `folder`; None if it has none."""
    spec = load_mission(mission)
    if not any(isinstance(phase, SetFriction) for phase in spec.phases):
        return None
    source = resolve_mission(mission)
    kept = [line for line in source.read_text().splitlines() if "kind: set_friction" not in line]
    path = folder / f"{source.stem}_friction_unchanged.yaml"
    path.write_text("\n".join(kept) + "\n")
    if any(isinstance(phase, SetFriction) for phase in load_mission(str(path)).phases):
        raise ValueError(f"{source}: write its set_friction phases one per line ({{kind: set_friction, ...}})")
    return path


def main() -> None:
    args = study_parser(__doc__, TERRAIN_MISSIONS, ["whole_body"], "benchmarks/results/terrain.json").parse_args()
    missions = [m for m in args.missions.split(",") if m]
    written = Path(tempfile.mkdtemp(prefix="terrain_benchmark_"))
    try:
        variants = [without_friction_changes(mission, written) for mission in missions]
        missions += [str(path) for path in variants if path is not None]
        controllers = [c for c in args.controllers.split(",") if c]
        report(missions, controllers, seeds_of(args.noise_seeds), args.engine, Path(args.out))
    finally:
        shutil.rmtree(written)


if __name__ == "__main__":
    main()
