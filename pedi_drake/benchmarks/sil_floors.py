"""Software in the loop at real time, repeated: how often each mission succeeds over the wire.

    python -m pedi_drake.benchmarks.sil_floors [--missions hit_target_front open_door prong_push_box]
        [--runs 5] [--scenario_name default] [--separate | --callbacks] [--pin] [--flood_at S]
        [--robot drake|mujoco] [--operator_search_button HEADING_DEG]
        [--out benchmarks/results/sil_floors.json]

Each run is `python -m pedi_drake.apps.sil --mission M` (the simulator bridge in its own process,
the controller here, both at real time), judged by the bridge's ground truth. With `--separate`
the controller is its own program too, `run_sim.py --hardware`, as the README's two terminals run it. Per run: success,
the driver's latch, the largest true foot error, the loop's deadline misses per 1000 ticks and
the longest, its lateness, its stalls (gaps of more than two periods between commands: computing
or waiting, see docs/results.md), the robot side's pace (gaps of its ground-truth log: the bridge
stopped or fell behind, `apps.sil.bridge_pace`), and the load average before and after (this
machine may be shared). Each run is judged against the floors a hardware swap is held to
(`meets_floors`: succeeded, no damping latched, every true foot error under FOOT_ERROR_FLOOR_MM,
fewer than MISSES_FLOOR_PER_1000 deadline misses per 1000 ticks and none longer than
LONGEST_MISS_FLOOR_MS), and the summary counts the runs that met them. The JSON's
`machine.rt_throttling` is the share of each second Linux lets real-time threads run (None: not
throttled; see pedi_drake.runtime.realtime_priority).

`--callbacks` runs each mission with `apps.sil --callbacks`: every run also keeps the controller
side's callbacks and garbage collections over 1 ms (`slow_calls`), and the summary prints, per
run, the costliest of them beside the longest stalls: what the late ticks computed.
`--pin` runs them with `apps.sil --pin` (the bridge and the controller on CPUs of their own).
`--robot mujoco` puts the robot side in MuJoCo (`apps.sil --robot mujoco`: another engine, a Go1
with a real one's joint friction and rotor inertia, rubber feet of 23 mm that sink about 17 mm);
a run's success is then the mission's and every touch's by that engine's contact forces, and its
feet are held to the floor beyond the difference of the foot radii.
`--operator_search_button HEADING_DEG` adds the operator that finds an E-stop button by touch in a
third process (`apps.sil --operator_search_button`), for terrain/field_course; a run's success then
takes the mission's physical checks on the Drake robot side's plant state too (`truth_checks`: its
object push, button press and walks).
`--flood_at S` runs them with `apps.sil --flood_at S`: S seconds after the first command, a third
process floods every status channel with malformed messages for a second (500 a second of each
kind: a wrong fingerprint, truncated, NaN fields). Such a run meets the floors only if, besides,
the driver counted every malformed message by channel and reason and no tick logged during the
flood was past its period.
"""

import argparse
import json
import os
import platform
import time
from pathlib import Path

from pedi_drake.apps.sil import BRIDGES, flood_text, run_sil, slow_calls_text
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.robot import FOOT_RADIUS
from pedi_drake.runtime.realtime_priority import rt_throttling

DEFAULT_MISSIONS = ("hit_target_front", "open_door", "prong_push_box")

# The floors of a run at real time.
FOOT_ERROR_FLOOR_MM = 5.0  # every true foot error under it [mm]
MISSES_FLOOR_PER_1000 = 1.0  # deadline misses per 1000 ticks, under it
LONGEST_MISS_FLOOR_MS = 10.0  # no miss longer [ms]


def meets_floors(row: dict) -> bool:
    """Whether a run (a row of `one_run`) met every floor (see the module docstring): success by
    the robot side's ground truth (touches by its contact forces), and feet within
    FOOT_ERROR_FLOOR_MM beyond the difference between the robot's foot radius and the controller's."""
    error = row["max_true_foot_error_mm"]
    flood = row.get("flood")
    flood_held = flood is None or (
        "sent" in flood
        and flood["every_one_counted"]
        and flood["ticks_during"] > 0
        and flood["deadline_misses_during"] == 0
    )
    return (
        flood_held
        and row["success"]
        and row["latched"] is None
        and error is not None
        and error < FOOT_ERROR_FLOOR_MM + row.get("foot_radius_difference_mm", 0.0)
        and row["deadline_misses_per_1000"] < MISSES_FLOOR_PER_1000
        and row["longest_miss_ms"] <= LONGEST_MISS_FLOOR_MS
    )


def _steal_text(steal_ms: float | None) -> str:
    return "unknown" if steal_ms is None else f"{steal_ms:.0f} ms"


def _load() -> list[str] | None:
    path = Path("/proc/loadavg")
    return path.read_text().split()[:3] if path.exists() else None


def _live_suf_figures(summary: dict | None) -> dict | None:
    """The run's live SUF: its updates, fallbacks and the control ticks an update took."""
    if summary is None:
        return None
    keys = ("updates", "fallbacks", "ticks_median", "ticks_max")
    return {key: summary.get(key) for key in keys}


def one_run(
    mission: str,
    scenario_name: str,
    out_dir: Path,
    scenario_text: str = "{}",
    separate: bool = False,
    callbacks: bool = False,
    pin: bool = False,
    flood_at: float | None = None,
    robot_side: str = "drake",
    operator_search_button: float | None = None,
) -> dict:
    load_before = _load()
    start = time.monotonic()
    options = {"scenario_name": scenario_name, "separate": separate, "callbacks": callbacks, "pin": pin}
    options.update(flood_at=flood_at, robot=robot_side, operator_search_button=operator_search_button)
    result = run_sil(mission, out_dir, scenario_text=scenario_text, **options)
    driver, sil = result["driver"], result["sil"]
    height = sil["estimator_trunk_height_error"]
    errors = [row["true_error_m"] for row in sil["foot_errors"]]
    loop = driver["loop"]
    row = {
        "mission": mission,
        "robot": robot_side,
        # The mission's own success and every touch it requires by the robot side's contact forces.
        "success": bool(sil["success_by_truth"]),
        "reason": "; ".join(filter(None, [result["reason"], sil["touches_reason"], sil["truth_checks_reason"]])),
        "truth_checks": sil["truth_checks"],
        "touches": sil["touches"],
        "sensed_touches": result.get("sensed_touches"),
        "foot_radius_difference_mm": 1e3 * max(0.0, sil["robot_foot_radius_m"] - FOOT_RADIUS),
        "estimator_trunk_height_error_mm": {
            key: None if height[f"{key}_m"] is None else 1e3 * height[f"{key}_m"] for key in ("median", "max")
        },
        "latched": driver["latched"],
        "max_true_foot_error_mm": 1e3 * max(errors) if errors else None,
        "estimator_trunk_error_max_mm": 1e3 * sil["estimator_trunk_position_error"]["max_m"],
        "start": sil["start"],
        "bridge_pace": sil["bridge_pace"],
        "ticks": loop["ticks"],
        "deadline_misses_per_1000": loop["deadline_misses_per_1000"],
        "longest_miss_ms": loop["longest_miss_ms"],
        "lateness_ms": loop["lateness_ms"],
        "scheduling": {"controller": loop["scheduling"], "bridge": sil["bridge_scheduling"]},
        "wait": loop["wait"],
        "controller_process": sil["controller"],
        "command_interdeparture_ms": loop["command_interdeparture_ms"],
        "stalls": loop["stalls"],
        "controller_tick_ms": result["controller_tick_ms"],
        "real_time_factor": result["real_time_factor"],
        "live_suf": _live_suf_figures(result.get("live_suf")),
        "wall_s": time.monotonic() - start,
        "load_before": load_before,
        "load_after": _load(),
        "slow_calls": sil.get("slow_calls"),
        "cpu_steal_ms": sil.get("cpu_steal_ms"),
        "cpus": sil.get("cpus"),
        "flood": sil.get("flood"),
    }
    row["meets_floors"] = meets_floors(row)
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--missions", nargs="+", default=list(DEFAULT_MISSIONS))
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--scenario_name", default="default", help="e.g. control_250hz")
    parser.add_argument(
        "--scenario_text", default="{}", help="YAML onto the scenario, e.g. '{go1_driver: {realtime_priority: 0}}'"
    )
    parser.add_argument(
        "--separate", action="store_true", help="the controller as its own program, run_sim.py --hardware (README)"
    )
    parser.add_argument(
        "--callbacks", action="store_true", help="keep the controller side's callbacks over 1 ms (apps.sil --callbacks)"
    )
    parser.add_argument("--pin", action="store_true", help="the bridge and the controller on CPUs of their own")
    parser.add_argument(
        "--flood_at", type=float, default=None, help="a flood of malformed status this long after the first command [s]"
    )
    parser.add_argument(
        "--robot", choices=sorted(BRIDGES), default="drake", help="the robot side's physics engine (apps.sil --robot)"
    )
    parser.add_argument(
        "--operator_search_button", type=float, default=None, help="an operator finding an E-stop by touch [deg]"
    )
    parser.add_argument("--work", default="out/sil_floors", help="folder of the runs' outputs")
    parser.add_argument("--out", default="benchmarks/results/sil_floors.json")
    args = parser.parse_args()
    if args.separate and args.callbacks:
        parser.error("--callbacks times the controller side in this process: not with --separate")
    rows = []
    for run in range(args.runs):  # interleaved, so machine load affects every mission alike
        for mission in args.missions:
            work = Path(args.work) / f"{mission}_{run}"
            row = one_run(
                mission,
                args.scenario_name,
                work,
                args.scenario_text,
                args.separate,
                args.callbacks,
                args.pin,
                args.flood_at,
                args.robot,
                args.operator_search_button,
            )
            rows.append(row)
            error = row["max_true_foot_error_mm"]
            print(
                f"{mission:<18} run {run}: {'ok  ' if row['success'] else 'FAIL'} latched {row['latched']}, "
                f"wait {row['wait']}, "
                f"true foot error {error if error is None else round(error, 1)} mm, "
                f"trunk height estimate off by {row['estimator_trunk_height_error_mm']['max']} mm at most, "
                f"misses {row['deadline_misses_per_1000']:.2f}/1000 (longest {row['longest_miss_ms']:.1f} ms), "
                f"stalls {row['stalls']['computing']} computing / {row['stalls']['waiting']} waiting, "
                f"bridge gaps {row['bridge_pace']['gaps']}, "
                f"CPU stolen {_steal_text(row['cpu_steal_ms'])}, "
                f"load {row['load_before']} -> {row['load_after']}"
                f"{', meets the floors' if row['meets_floors'] else ''}",
                flush=True,
            )
            if row["flood"] is not None:
                print("  " + flood_text(row["flood"]), flush=True)
            if row["slow_calls"] is not None:
                stalls = row["stalls"]["longest"][:3]
                print(
                    "  longest stalls: "
                    + ", ".join(f"t = {x['t']:.3f} s {x['gap_ms']:.1f} ms ({x['loop_cpu_ms']:.1f} CPU)" for x in stalls)
                )
                print(slow_calls_text(row["slow_calls"], count=3), flush=True)
    print(
        f"{'mission':<18}{'successes':>10}{'misses/1000 (worst)':>21}{'longest miss [ms]':>19}"
        f"{'true foot error (worst) [mm]':>30}{'met the floors':>16}"
    )
    summary = {}
    for mission in args.missions:
        mine = [row for row in rows if row["mission"] == mission]
        ok = sum(row["success"] for row in mine)
        worst_rate = max(row["deadline_misses_per_1000"] for row in mine)
        longest = max(row["longest_miss_ms"] for row in mine)
        errors = [row["max_true_foot_error_mm"] for row in mine if row["max_true_foot_error_mm"] is not None]
        worst_error = max(errors) if errors else float("nan")
        met = sum(row["meets_floors"] for row in mine)
        summary[mission] = {
            "successes": ok,
            "runs": len(mine),
            "worst_misses_per_1000": worst_rate,
            "longest_miss_ms": longest,
            "worst_true_foot_error_mm": worst_error,
            "runs_meeting_floors": met,
        }
        print(
            f"{mission:<18}{f'{ok}/{len(mine)}':>10}{worst_rate:21.2f}{longest:19.1f}{worst_error:30.1f}"
            f"{f'{met}/{len(mine)}':>16}"
        )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    machine = {
        "processor": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        # The share of each second Linux lets real-time threads run (None: not throttled).
        "rt_throttling": rt_throttling(),
    }
    out.write_text(
        json.dumps(
            stamped(
                {
                    "scenario_name": args.scenario_name,
                    "scenario_text": args.scenario_text,
                    "separate": args.separate,
                    "callbacks": args.callbacks,
                    "pin": args.pin,
                    "flood_at": args.flood_at,
                    "robot": args.robot,
                    "machine": machine,
                    "summary": summary,
                    "runs": rows,
                }
            ),
            indent=2,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
