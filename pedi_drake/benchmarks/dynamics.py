"""Controller dynamics benchmark: Drake's calls against the compiled `go1_dynamics`, per call.

    python -m pedi_drake.benchmarks.dynamics [--samples 200] [--out benchmarks/results/dynamics.json]

For the Go1 without prongs and with the default prong design, on a fixed set of random states
(orientations, positions, velocities and joints within limits), the median CPU time per call
(`time.thread_time`, so a loaded machine slows it less than wall time) of:

* `ControllerModel.update_with_drake`: the Drake reference path (set the context, one call per term);
* `ControllerModel.calf_orientation_with_drake`: the Drake calls a 5-D foot task adds per leg;
* `ControllerModel.update`: the compiled path, returning a RobotSnapshot of fresh arrays;
* `go1_dynamics` called from Python into preallocated outputs (numba's dispatch included);
* `go1_dynamics` called from another compiled kernel: what a compiled controller tick pays.

The compiled rows include the calves' terms, which `go1_dynamics` always computes. Each sample
times a block of calls and divides; the median is over `--samples` blocks. Writes the rows as JSON.
"""

import argparse
import json
import platform
import statistics
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from pedi_drake import robot
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.control.robot_model import ControllerModel
from pedi_drake.dynamics.go1_dynamics import go1_dynamics
from pedi_drake.prongs import ProngDesign
from pedi_drake.runtime.jit import kernel

NUM_STATES = 64
SEED = 20261203
DEFAULT_OUT = Path("benchmarks/results/dynamics.json")


def random_states(num_states: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(base_states (n, 13), q_joints (n, 12), v_joints (n, 12)) within the Go1's limits."""
    rng = np.random.default_rng(seed)
    bases = np.concatenate(
        [
            rng.normal(size=(num_states, 4)),
            rng.uniform(-2.0, 2.0, (num_states, 3)),
            rng.uniform(-2.0, 2.0, (num_states, 3)),
            rng.uniform(-1.0, 1.0, (num_states, 3)),
        ],
        axis=1,
    )
    q = rng.uniform(robot.Q_LOWER, robot.Q_UPPER, (num_states, 12))
    v = rng.uniform(-robot.VELOCITY_LIMIT, robot.VELOCITY_LIMIT, (num_states, 12)) / 2
    return bases, q, v


@kernel
def _repeat_go1_dynamics(model, bases, q_joints, v_joints, out, repeats):
    """`go1_dynamics` on states bases[k % n] for k < repeats, from compiled code."""
    n = bases.shape[0]
    for k in range(repeats):
        go1_dynamics(model, bases[k % n], q_joints[k % n], v_joints[k % n], out)


def median_us_per_call(run_block: Callable[[], None], calls_per_block: int, samples: int) -> float:
    """Median over `samples` blocks of CPU time per call [us]; one block is `run_block()`."""
    run_block()  # caches warm
    per_call = []
    for _ in range(samples):
        start = time.thread_time()
        run_block()
        per_call.append((time.thread_time() - start) / calls_per_block)
    return 1e6 * statistics.median(per_call)


def measure(prongs: ProngDesign | None, samples: int) -> dict[str, float]:
    """Median CPU time per call [us] of each path for one prong configuration."""
    bases, q, v = random_states(NUM_STATES, SEED)
    drake = ControllerModel(prongs, compiled=False)
    compiled = ControllerModel(prongs)
    dynamics = compiled.dynamics
    out = dynamics.new_output()
    _repeat_go1_dynamics(dynamics.model_record, bases, q, v, out, 1)  # compiled here, not timed
    states = list(zip(bases, q, v, strict=True))

    def block(function, calls):
        def run():
            for k in range(calls):
                function(*states[k % NUM_STATES])

        return run

    def drake_calf(base, q_joints, v_joints):
        drake.calf_orientation_with_drake(0)

    drake.update_with_drake(bases[0], q[0], v[0])
    return {
        "drake update": median_us_per_call(block(drake.update_with_drake, 8), 8, samples),
        "drake calf_orientation (one leg)": median_us_per_call(block(drake_calf, 8), 8, samples),
        "compiled update (RobotSnapshot)": median_us_per_call(block(compiled.update, 64), 64, samples),
        "go1_dynamics from Python": median_us_per_call(
            block(lambda b, qj, vj: go1_dynamics(dynamics.model_record, b, qj, vj, out), 64), 64, samples
        ),
        "go1_dynamics from compiled code": median_us_per_call(
            lambda: _repeat_go1_dynamics(dynamics.model_record, bases, q, v, out, 1024), 1024, samples
        ),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--samples", type=int, default=200, help="timed blocks per row (median)")
    parser.add_argument("--out", default=str(DEFAULT_OUT))
    args = parser.parse_args()

    configurations = {"no prongs": None, "default prongs": ProngDesign()}
    rows = {label: measure(prongs, args.samples) for label, prongs in configurations.items()}
    header = f"{'median CPU per call [us]':<36}" + "".join(f"{label:>16}" for label in rows)
    print(header)
    print("-" * len(header))
    for case in next(iter(rows.values())):
        print(f"{case:<36}" + "".join(f"{rows[label][case]:16.1f}" for label in rows))
    for label, row in rows.items():
        drake = row["drake update"] + row["drake calf_orientation (one leg)"]
        speedup = drake / row["compiled update (RobotSnapshot)"]
        print(f"{label}: Drake update + one calf / compiled update = {speedup:.1f}x")
    print(f"Machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(
        json.dumps(stamped({"unit": "us CPU per call, median", "samples": args.samples, "rows": rows}), indent=2)
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
