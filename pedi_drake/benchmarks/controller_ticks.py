"""CPU time per tick of the two whole-body controllers on the same recorded inputs.

    python -m pedi_drake.benchmarks.controller_ticks [--demo three_leg_hold] [--passes 3] [--warm]
        [--out benchmarks/results/controller_ticks.json]

1. Records: the demo (ground-truth estimator) is simulated on paper 002's controller; every
   tick's controller inputs (the eight input ports, as the diagram evaluated them) are kept.
2. Replays: paper 002's `projected_impedance` and the paper-000 HQP `whole_body` each get every
   recorded tick's inputs fixed on their own context and run their discrete update (the
   controller's state carries over from tick to tick; the plant does not respond: the same
   inputs for both). Only the update is timed, in the thread's CPU time (`time.thread_time`,
   which a loaded machine disturbs less than wall time). The controllers alternate tick by tick,
   so a change of the machine's load falls on both alike; one untimed pass first compiles or
   loads every kernel.

With `--warm`, every update is run a second time at once on the same inputs and state (the
same result), and that second call is timed too: the cost with the update's code and data in the
processor's caches, against the first call's, which follows the other controller's update as a
control loop's update follows the rest of its tick.

Prints the median, 99th and 99.9th percentiles per tick of each controller [ms] and the share of
ticks each solved (status 0), and writes them as JSON. Three-leg hold is the acceptance case of paper 002's
tick (a median under 0.5 ms with three stance feet).
"""

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from pedi_drake.benchmarks.demos import DEMOS, demo_scenario, simulate_demo
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.control.projected_impedance_controller import ProjectedImpedanceController
from pedi_drake.diagram import whole_body_controller

DEFAULT_OUT = Path("benchmarks/results/controller_ticks.json")
PORTS = (
    "base_state",
    "position_measured",
    "velocity_measured",
    "body_reference",
    "leg_reference",
    "contact_set",
    "safety_polygon",
    "friction",
)
CONTROLLERS = ("projected_impedance", "whole_body")


def record_inputs(demo: str) -> tuple[list[dict[str, np.ndarray]], object]:
    """(every tick's controller inputs by port name, the demo's scenario) of `demo` simulated on
    paper 002's controller."""
    scenario = demo_scenario(demo)
    scenario.controller = "projected_impedance"
    ticks: list[dict[str, np.ndarray]] = []
    original = ProjectedImpedanceController._update

    def recording(controller, context, discrete_state):
        ticks.append(
            {
                name: controller.GetInputPort(name).Eval(context).copy()
                for name in PORTS
                if controller.GetInputPort(name).HasValue(context)
            }
        )
        original(controller, context, discrete_state)

    ProjectedImpedanceController._update = recording
    try:
        simulate_demo(demo, scenario)
    finally:
        ProjectedImpedanceController._update = original
    return ticks, scenario


class _Variant:
    """One controller with its own context, replaying the recorded inputs."""

    def __init__(self, scenario, controller: str) -> None:
        self.system = whole_body_controller(scenario, controller)
        self.name = controller
        self.context = self.system.CreateDefaultContext()
        self.values = self.system.AllocateDiscreteVariables()
        self.ports = {name: self.system.GetInputPort(name) for name in PORTS}
        self.status = self.system.diag["status"].start

    def tick(self, inputs: dict[str, np.ndarray], warm: bool = False) -> tuple[float, bool, float]:
        """(CPU time of the update [s], whether it solved, CPU time of the same update run again
        at once when `warm`, else NaN [s]) at one tick's inputs."""
        for name, value in inputs.items():
            self.ports[name].FixValue(self.context, value)
        start = time.thread_time()
        self.system.CalcForcedDiscreteVariableUpdate(self.context, self.values)
        elapsed = time.thread_time() - start
        again = float("nan")
        if warm:
            start = time.thread_time()
            self.system.CalcForcedDiscreteVariableUpdate(self.context, self.values)
            again = time.thread_time() - start
        self.context.SetDiscreteState(self.values)
        solved = self.values.get_vector(self.system.diagnostics_state).value()[self.status] == 0.0
        return elapsed, solved, again


def measure(demo: str, passes: int, warm: bool = False) -> list[dict]:
    """One row per controller: median and p99 CPU per tick [ms] over `passes` replays of the demo
    (and of the update run again at once, with `warm`)."""
    ticks, scenario = record_inputs(demo)
    variants = [_Variant(scenario, controller) for controller in CONTROLLERS]
    times: dict[str, list[float]] = {v.name: [] for v in variants}
    warm_times: dict[str, list[float]] = {v.name: [] for v in variants}
    solved: dict[str, list[bool]] = {v.name: [] for v in variants}
    for replay in range(passes + 1):
        for variant in variants:  # each pass from the first tick's state
            variant.context = variant.system.CreateDefaultContext()
        for inputs in ticks:
            for variant in variants:
                elapsed, ok, again = variant.tick(inputs, warm)
                if replay > 0:  # the first pass compiles or loads the kernels
                    times[variant.name].append(elapsed)
                    warm_times[variant.name].append(again)
                    solved[variant.name].append(ok)
    rows = []
    for variant in variants:
        per_tick = np.array(times[variant.name]) * 1e3
        row = {
            "demo": demo,
            "controller": variant.name,
            "ticks": len(per_tick),
            "tick_median_ms": float(np.median(per_tick)),
            "tick_p99_ms": float(np.percentile(per_tick, 99)),
            "tick_p99_9_ms": float(np.percentile(per_tick, 99.9)),
            "solved_fraction": float(np.mean(solved[variant.name])),
        }
        if warm:
            again = np.array(warm_times[variant.name]) * 1e3
            row["warm_tick_median_ms"] = float(np.median(again))
            row["warm_tick_p99_ms"] = float(np.percentile(again, 99))
        rows.append(row)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--demo", default="three_leg_hold", choices=DEMOS)
    parser.add_argument("--passes", type=int, default=3, help="timed replays of the recorded ticks")
    parser.add_argument("--warm", action="store_true", help="also time each update run again at once")
    parser.add_argument("--out", default=str(DEFAULT_OUT), help="JSON file of the rows")
    args = parser.parse_args()
    rows = measure(args.demo, args.passes, args.warm)
    warm_header = f" {'warm median':>12s} {'warm p99':>9s}" if args.warm else ""
    header = f"{'controller':34s} {'median ms':>10s} {'p99 ms':>8s} {'p99.9 ms':>9s} {'solved':>7s}{warm_header}"
    print(f"{header}  ({rows[0]['ticks']} ticks)")
    for row in rows:
        warm_columns = f" {row['warm_tick_median_ms']:12.3f} {row['warm_tick_p99_ms']:9.3f}" if args.warm else ""
        print(
            f"{row['controller']:34s} {row['tick_median_ms']:10.3f} {row['tick_p99_ms']:8.3f} "
            f"{row['tick_p99_9_ms']:9.3f} {row['solved_fraction']:7.3f}{warm_columns}"
        )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    report = {"machine": platform.processor() or platform.machine(), "command": "controller_ticks", "rows": rows}
    out.write_text(json.dumps(stamped(report), indent=2))
    print(f"written {out}")


if __name__ == "__main__":
    main()
