"""The exact SUF along a teleoperated path: warm-started and compiled, beside the cold exact SUF.

    python -m pedi_drake.benchmarks.live_suf [--steps 320] [--out benchmarks/results/live_suf.json]

The path (`teleoperated_path`): paper 003's teleoperation stance (FL, RR, RL on the ground, the
trunk over their centroid) while the FR foot goes once round an 8 cm square in the trunk's x-z
plane about its working position and the trunk height swings by +-1 cm; at 320 steps one step is
1 mm of foot travel, what a foot at 0.1 m/s moves between two live-SUF updates (100 Hz).

At every configuration, on the same problem, each timed in CPU time (time.thread_time):

* exact, cold (CLP): `methods.suf_exact` (Drake's CLP and scipy's qhull), the reference;
* exact, compiled, cold: `warm_projection.suf_exact_warm` without a warm start;
* exact, compiled, warm: the same from the previous configuration's WarmStart;
* live update: `suf.live.LiveSuf.update` from the state (the rows built from the compiled
  dynamics, the warm projection, the reach along the push), what a run's LiveSufSystem does.

Prints a table (median, p90 and max ms, LPs, the largest relative difference from the cold
exact SUF, and how many live updates ran out of their LP budget) and writes JSON. Floors: the
warm median under 2 ms, every warm and live SUF within 0.1 % of the cold exact SUF.
"""

import argparse
import dataclasses
import json
import platform
import time
from pathlib import Path

import numpy as np

from pedi_drake.benchmarks.machine import stamped
from pedi_drake.suf import warm_projection as wp
from pedi_drake.suf.live import LiveSuf, LiveSufReading, idle_vector
from pedi_drake.suf.methods import suf_exact
from pedi_drake.suf.stances import Go1Stance, stance_problem, teleoperation_stance

SQUARE_SIDE = 0.08  # [m]
HEIGHT_SWING = 0.01  # [m]
WARM_MEDIAN_FLOOR_MS = 2.0
RELATIVE_TOLERANCE = 1e-3


def teleoperated_path(steps: int) -> list[Go1Stance]:
    """`steps` stances along the lap (see the module docstring)."""
    start = teleoperation_stance()
    centre = start.end_effector_position_B()
    half = SQUARE_SIDE / 2
    corners = np.array([[-half, -half], [half, -half], [half, half], [-half, half], [-half, -half]])
    stances = []
    for k in range(steps):
        s = 4.0 * k / steps  # position along the perimeter in sides
        side = int(s)
        x, z = corners[side] + (s - side) * (corners[side + 1] - corners[side])
        height = start.trunk_height + HEIGHT_SWING * np.sin(2 * np.pi * k / steps)
        effector = (centre[0] + x, centre[1], centre[2] + z)
        stances.append(dataclasses.replace(start, trunk_height=float(height), end_effector_B=effector))
    return stances


def stance_state(stance: Go1Stance) -> tuple[np.ndarray, np.ndarray]:
    """The base state (13,) and joints (12,) of a stance, as the estimator would give them."""
    base = np.array([1.0, 0.0, 0.0, 0.0, *stance.trunk_xy, stance.trunk_height, *np.zeros(6)])
    return base, stance.joint_angles()


def _timed(function):
    start = time.thread_time()
    value = function()
    return value, time.thread_time() - start


def _row(times_s: list[float], lps: list[int], values: list[float], reference: list[float]) -> dict:
    ms = 1e3 * np.asarray(times_s)
    errors = np.abs(np.asarray(values) - reference) / np.asarray(reference)
    return {
        "median_ms": float(np.median(ms)),
        "p90_ms": float(np.percentile(ms, 90)),
        "max_ms": float(np.max(ms)),
        "median_lps": float(np.median(lps)),
        "max_lps": int(np.max(lps)),
        "max_relative_difference": float(np.max(errors)),
    }


def run(steps: int) -> dict:
    wp.warm_up()
    live = LiveSuf(mu=0.6)
    push = np.array([-1.0, 0.0, 0.0])  # a wall ahead pushes the foot back
    loaded = np.array([0.0, 1.0, 1.0, 1.0])
    columns = {name: ([], [], []) for name in ("cold_clp", "cold_compiled", "warm_compiled", "live_update")}
    reference = []
    warm = live_warm = None
    live_vector = idle_vector()
    fallbacks = 0
    for stance in teleoperated_path(steps):
        problem = stance_problem(stance)
        base, q = stance_state(stance)
        cold, elapsed = _timed(lambda problem=problem: suf_exact(problem))
        reference.append(cold.value)
        columns["cold_clp"][0].append(elapsed)
        columns["cold_clp"][1].append(cold.num_programs)
        columns["cold_clp"][2].append(cold.value)
        (result, _), elapsed = _timed(lambda problem=problem: wp.suf_exact_warm(problem))
        columns["cold_compiled"][0].append(elapsed)
        columns["cold_compiled"][1].append(result.num_programs)
        columns["cold_compiled"][2].append(result.value)
        (result, warm), elapsed = _timed(lambda problem=problem, warm=warm: wp.suf_exact_warm(problem, warm))
        columns["warm_compiled"][0].append(elapsed)
        columns["warm_compiled"][1].append(result.num_programs)
        columns["warm_compiled"][2].append(result.value)
        (live_vector, live_warm), elapsed = _timed(
            lambda base=base, q=q, w=live_warm, v=live_vector: live.update(w, v, base, q, loaded, 0, push)
        )
        reading = LiveSufReading.from_vector(live_vector)
        fallbacks = reading.fallbacks
        columns["live_update"][0].append(elapsed)
        columns["live_update"][1].append(reading.lps)
        columns["live_update"][2].append(reading.value)
    rows = {name: _row(*column, reference) for name, column in columns.items()}
    floors = {
        "warm_median_under_2ms": rows["warm_compiled"]["median_ms"] < WARM_MEDIAN_FLOOR_MS,
        "live_median_under_2ms": rows["live_update"]["median_ms"] < WARM_MEDIAN_FLOOR_MS,
        "warm_within_0.1pct": rows["warm_compiled"]["max_relative_difference"] <= RELATIVE_TOLERANCE,
        "live_within_0.1pct": rows["live_update"]["max_relative_difference"] <= RELATIVE_TOLERANCE,
    }
    return {
        "steps": steps,
        "step_mm": 1e3 * 4 * SQUARE_SIDE / steps,
        "suf_n": {"min": float(np.min(reference)), "max": float(np.max(reference))},
        "rows": rows,
        "live_fallbacks": fallbacks,
        "live_budget_lps": live.max_lps,
        "floors": floors,
        "machine": f"{platform.machine()}, Python {platform.python_version()}",
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=320, help="configurations along the lap")
    parser.add_argument("--out", default="benchmarks/results/live_suf.json")
    args = parser.parse_args()
    report = run(args.steps)
    labels = {
        "cold_clp": "exact, cold (CLP)",
        "cold_compiled": "exact, compiled, cold",
        "warm_compiled": "exact, compiled, warm",
        "live_update": "live update (warm)",
    }
    print(
        f"{report['steps']} configurations, {report['step_mm']:.2f} mm of foot travel apart; "
        f"SUF {report['suf_n']['min']:.1f} to {report['suf_n']['max']:.1f} N"
    )
    print(f"{'method':<24}{'median ms':>10}{'p90 ms':>9}{'max ms':>9}{'LPs med':>9}{'LPs max':>9}{'max rel diff':>14}")
    for name, label in labels.items():
        row = report["rows"][name]
        print(
            f"{label:<24}{row['median_ms']:10.3f}{row['p90_ms']:9.3f}{row['max_ms']:9.3f}"
            f"{row['median_lps']:9.0f}{row['max_lps']:9d}{row['max_relative_difference']:14.2e}"
        )
    print(
        f"live updates that ran out of their budget of {report['live_budget_lps']} LPs (single-direction SUF "
        f"instead): {report['live_fallbacks']} of {report['steps']}"
    )
    print("Floors:", json.dumps(report["floors"]))
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped(report), indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
