"""Whole-body controller benchmark: tick time, closed-loop speed, three-leg hold and push floors.

    python -m pedi_drake.benchmarks.control [--repeats 3] [--out benchmarks/results/control.json]

Runs the controller demonstrations of `pedi_drake.benchmarks.demos` (missions of missions/demos/
on scenarios/wbc_demos.yaml, through MakePedipulationDiagram) in simulation (500 Hz control,
1 ms plant) and prints one table:

* controller tick (state in, command out, hierarchical QP solved) on three legs with the
  paper-000 stack; median and p99 over all ticks on three legs of `--repeats` runs;
* closed-loop real-time factor (sim time / wall time, no visualisation);
* three-leg hold: FR foot error, trunk drift, stance-foot slip, peak torque / effort limit;
* paper 003's push test: 30 N horizontal on the trunk for 5 s while on three legs, without
  and with the prongs loaded (a `pushes` entry of the mission, applied by the simulated station):
  trunk displacement and peak stance knee torque;
* the 1 kHz variant of the stand demo.

The metrics (`pedi_drake.evaluation.controller_metrics`) are computed from the run's logs, from
simulation ground truth for evaluation only; the controller reads the state estimate and go1.*
signals. Writes the rows and the floors to JSON.
"""

import argparse
import dataclasses
import json
import platform
import statistics
from pathlib import Path

import numpy as np

from pedi_drake.benchmarks.demos import demo_scenario, run_demo
from pedi_drake.evaluation.controller_metrics import ControllerMetrics

# Floors the whole-body controller is held to.
TICK_MEDIAN_FLOOR_MS = 1.0
REAL_TIME_FACTOR_FLOOR = 1.0
FOOT_ERROR_FLOOR_M = 0.005
TRUNK_DRIFT_FLOOR_M = 0.01
STANCE_SLIP_FLOOR_M = 0.002


@dataclasses.dataclass
class Case:
    """One benchmark row: a demo with scenario overrides, run `repeats` times."""

    label: str
    demo: str
    overrides: dict
    repeats: int


def cases(repeats: int) -> list[Case]:
    return [
        Case("three_leg_hold", "three_leg_hold", {}, repeats),
        Case("three_leg_hold paper003", "three_leg_hold", {"stack": "paper003"}, 1),
        Case("stand 1 kHz", "stand", {"period": 0.001}, 1),
        Case("push_no_prongs", "push_no_prongs", {}, 1),
        Case("push_prongs", "push_prongs", {}, 1),
    ]


def _median(values: list[float]) -> float:
    finite = [v for v in values if np.isfinite(v)]
    return float(statistics.median(finite)) if finite else float("nan")


def summarise(case: Case, results: list[ControllerMetrics]) -> dict:
    """Medians over the repeats of one case (worst case for the safety figures)."""
    return {
        "label": case.label,
        "demo": case.demo,
        "overrides": case.overrides,
        "runs": len(results),
        "fell": any(r.fell for r in results),
        "mission_succeeded": all(r.mission_succeeded for r in results),
        "tick_median_ms": _median([r.tick_median_ms for r in results]),
        "tick_p99_ms": _median([r.tick_p99_ms for r in results]),
        "real_time_factor": _median([r.real_time_factor for r in results]),
        "foot_error_max_m": max((max(r.foot_errors) for r in results if r.foot_errors), default=float("nan")),
        "trunk_drift_m": max(r.trunk_drift for r in results),
        "stance_slip_m": max(r.stance_slip for r in results),
        "max_torque_ratio": max(r.max_torque_ratio for r in results),
        "qp_failures": sum(r.qp_failures for r in results),
        "push_displacement_m": _median([r.push_displacement for r in results]),
        "peak_knee_torque_Nm": _median([r.peak_knee_torque for r in results]),
        "prong_load_N": _median([r.prong_load for r in results]),
        "push_while_manipulating": all(r.push_while_manipulating for r in results),
    }


def floors(rows: dict[str, dict]) -> dict[str, bool]:
    hold = rows["three_leg_hold"]
    return {
        "tick_median_below_1ms": hold["tick_median_ms"] < TICK_MEDIAN_FLOOR_MS,
        "closed_loop_real_time_factor_at_least_1": hold["real_time_factor"] >= REAL_TIME_FACTOR_FLOOR,
        "three_leg_foot_error_below_5mm": hold["foot_error_max_m"] < FOOT_ERROR_FLOOR_M,
        "three_leg_trunk_drift_below_1cm": hold["trunk_drift_m"] < TRUNK_DRIFT_FLOOR_M,
        "three_leg_stance_slip_below_2mm": hold["stance_slip_m"] < STANCE_SLIP_FLOOR_M,
        "torques_within_limits": all(r["max_torque_ratio"] <= 1.0 + 1e-9 for r in rows.values()),
        "push_does_not_topple": not rows["push_no_prongs"]["fell"] and not rows["push_prongs"]["fell"],
        # The push figures mean something only if the push came while FR was lifted.
        "push_applied_on_three_legs": rows["push_no_prongs"]["push_while_manipulating"]
        and rows["push_prongs"]["push_while_manipulating"],
    }


def _fmt(value: float, scale: float = 1.0, width: int = 8, digits: int = 2) -> str:
    return f"{scale * value:{width}.{digits}f}" if np.isfinite(value) else f"{'-':>{width}}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3, help="runs of the main three-leg case (median)")
    parser.add_argument("--out", default="benchmarks/results/control.json")
    args = parser.parse_args()

    rows: dict[str, dict] = {}
    for case in cases(args.repeats):
        results = [run_demo(case.demo, demo_scenario(case.demo, **case.overrides)) for _ in range(case.repeats)]
        rows[case.label] = summarise(case, results)
        print(f"  ran {case.label} x{case.repeats}", flush=True)

    header = (
        f"{'case':<31}{'tick med':>9}{'p99':>7}{'RTF':>6}{'foot mm':>8}{'drift mm':>9}"
        f"{'slip mm':>8}{'tau/lim':>8}{'push mm':>8}{'knee Nm':>8}{'fell':>5}"
    )
    print(header)
    print("-" * len(header))
    for label, r in rows.items():
        print(
            f"{label:<31}{_fmt(r['tick_median_ms'], 1, 9, 3)}{_fmt(r['tick_p99_ms'], 1, 7, 2)}"
            f"{_fmt(r['real_time_factor'], 1, 6, 2)}"
            f"{_fmt(r['foot_error_max_m'], 1e3, 8, 2)}{_fmt(r['trunk_drift_m'], 1e3, 9, 2)}"
            f"{_fmt(r['stance_slip_m'], 1e3, 8, 2)}{_fmt(r['max_torque_ratio'], 1, 8, 2)}"
            f"{_fmt(r['push_displacement_m'], 1e3, 8, 1)}{_fmt(r['peak_knee_torque_Nm'], 1, 8, 1)}"
            f"{'yes' if r['fell'] else 'no':>5}"
        )
    met = floors(rows)
    print(f"Machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}")
    print("Floors:", json.dumps(met))
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps({"rows": rows, "floors": met}, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
