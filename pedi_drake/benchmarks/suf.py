"""Paper 003's Table I for the Go1: time and accuracy of the five SUF methods, two scenarios.

    python -m pedi_drake.benchmarks.suf [--configs 100] [--timed 10] [--seed 0]
                                       [--out benchmarks/results/suf.json]

Scenarios (random valid stances, seeded): teleoperation (FL, RR, RL stance, the FR foot is the
end-effector) and prong manipulation (both prongs and both rear feet, the FR foot is the
end-effector). For every configuration every method runs; times are medians over the first
`--timed` configurations (after one warm-up), accuracy (SUF / exact SUF) over all of them. The
exactness check samples forces 1% inside and 1% outside the exact polytope along random
directions and asks the feasibility LP. Prints a table beside the paper's figures, writes JSON.
"""

import argparse
import json
import platform
import statistics
import tempfile
from pathlib import Path

import numpy as np

from pedi_drake.batch.engines import ENGINES, make_engine
from pedi_drake.batch.runner import run_study
from pedi_drake.batch.study import load_study
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.exceptions import SufError
from pedi_drake.resources import studies_dir
from pedi_drake.suf.design import stance_for
from pedi_drake.suf.methods import METHODS, smallest_unrejectable_force
from pedi_drake.suf.ray_program import RfpLinearProgram
from pedi_drake.suf.stances import Go1Stance, stance_problem, with_prongs_at_height
from pedi_drake.viz.suf_plots import plot_accuracy, plot_rfp, plot_suf_vs_height

# Paper 003, Table I [ms] (i7-7830X): teleoperation, manipulation.
PAPER_MS = {
    "exact": (4301.0, 37747.0),
    "fibonacci": (588.8, 727.0),
    "affine": (13.8, 17.49),
    "quadratic": (84.169, 709.1),
    "single": (4.65, 4.93),
}
# Fig. 3 (heights swept: studies/suf_height_sweep.yaml): the range called practical (the Go1
# stands at 0.27-0.28 m).
PRACTICAL_HEIGHTS = (0.18, 0.26)
# Speed floors: at least this many times faster than the paper (teleoperation).
SPEEDUP_FLOOR = {"exact": 5.0, "affine": 5.0, "quadratic": 5.0, "single": 5.0, "fibonacci": 2.0}


def random_stance(scenario: str, rng: np.random.Generator) -> Go1Stance:
    """A random stance of `scenario`: trunk height, feet spread and the FR foot's position."""
    feet_x, feet_y = rng.uniform(0.15, 0.24), rng.uniform(0.10, 0.17)
    effector_B = (rng.uniform(0.18, 0.32), rng.uniform(-0.20, -0.08), rng.uniform(-0.22, -0.08))
    if scenario == "teleoperation":
        height = rng.uniform(0.22, 0.30)
        shift = rng.uniform(0.7, 1.0)  # how far the trunk leans over the support triangle's centroid
        return Go1Stance(
            height,
            feet_x,
            feet_y,
            ("FL", "RR", "RL"),
            "FR",
            effector_B,
            trunk_xy=(-shift * feet_x / 3, shift * feet_y / 3),
        )
    height = rng.uniform(0.15, 0.22)
    stance = Go1Stance(height, feet_x, feet_y, ("RR", "RL", "prong0", "prong1"), "FR", effector_B)
    return with_prongs_at_height(stance)


def exactness_check(problem, polytope, rng: np.random.Generator, samples: int = 10) -> tuple[int, int]:
    """(inside forces found rejectable, outside forces found unrejectable), of `samples` each."""
    lp = RfpLinearProgram(problem)
    inside_ok = outside_ok = 0
    for _ in range(samples):
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        reach = min(b / (a @ d) for a, b in zip(polytope.A, polytope.b, strict=True) if a @ d > 1e-12)
        inside_ok += lp.feasible(0.99 * reach * d)
        outside_ok += not lp.feasible(1.01 * reach * d)
    return inside_ok, outside_ok


def run_scenario(scenario: str, configs: int, timed: int, rng: np.random.Generator) -> dict:
    rows = []
    while len(rows) < configs:
        try:
            problem = stance_problem(random_stance(scenario, rng))
            results = {m: smallest_unrejectable_force(problem, m) for m in METHODS}
        except SufError:
            continue  # out of reach, or a stance that cannot even stand: draw another
        if results["exact"].value < 1.0:
            continue  # a stance on the verge of tipping: relative accuracy is meaningless
        inside, outside = exactness_check(problem, results["exact"].polytope, rng)
        rows.append(
            {
                "suf": {m: r.value for m, r in results.items()},
                "time_ms": {m: 1e3 * r.solve_time_s for m, r in results.items()},
                "exact_lps": results["exact"].num_programs,
                "inside_rejectable": inside,
                "outside_unrejectable": outside,
            }
        )
    summary = {}
    for m in METHODS:
        ratios = [r["suf"][m] / r["suf"]["exact"] for r in rows]
        times = [r["time_ms"][m] for r in rows[1 : timed + 1]]
        summary[m] = {
            "median_ms": statistics.median(times),
            "ratio_min": min(ratios),
            "ratio_median": statistics.median(ratios),
            "ratio_max": max(ratios),
            "overestimates": sum(x > 1.0 + 1e-3 for x in ratios),
        }
    summary["exactness"] = {
        "inside_rejectable": sum(r["inside_rejectable"] for r in rows),
        "outside_unrejectable": sum(r["outside_unrejectable"] for r in rows),
        "samples": 10 * len(rows),
    }
    summary["exact_suf_median_n"] = statistics.median(r["suf"]["exact"] for r in rows)
    return {"summary": summary, "rows": rows}


def height_sweep_rows(rows: list[dict]) -> list[dict]:
    """Fig. 3 rows (as `suf.design.height_sweep` makes them) from the rows of the height-sweep study."""
    by_height: dict[float, dict[bool, dict]] = {}
    for row in rows:
        if row["status"] != "ok":
            raise SufError(f"height sweep: task {row['task_id']} {row['status']}: {row['reason']}")
        height = row["factor.trunk_height"]
        by_height.setdefault(height, {})[row["factor.prongs"]] = {
            "trunk_height": height,
            "feet_x": row["feet_x_m"],
            "feet_y": row["feet_y_m"],
            "prongs": row["factor.prongs"],
            "suf": row["suf_n"],
        }
    sweep = []
    for height in sorted(by_height):
        without, with_prongs = by_height[height][False], by_height[height][True]
        benefit = 100.0 * (with_prongs["suf"] / without["suf"] - 1.0) if without["suf"] > 0 else float("inf")
        sweep.append({"height": height, "without": without, "with_prongs": with_prongs, "benefit_percent": benefit})
    return sweep


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--configs", type=int, default=100, help="random configurations per scenario")
    parser.add_argument("--timed", type=int, default=10, help="configurations whose times give the median")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="benchmarks/results/suf.json")
    parser.add_argument("--engine", choices=ENGINES, default="serial", help="engine of the height-sweep study")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    scenarios = {s: run_scenario(s, args.configs, args.timed, rng) for s in ("teleoperation", "prong_manipulation")}
    print(
        f"{'method':<10}{'tele ms':>10}{'paper':>9}{'x faster':>9}{'manip ms':>10}{'paper':>9}"
        f"{'SUF/exact tele (min, med, max)':>33}{'manip (min, med, max)':>26}{'over':>6}"
    )
    floors = {}
    for m in METHODS:
        t, p = scenarios["teleoperation"]["summary"][m], scenarios["prong_manipulation"]["summary"][m]
        speedup = PAPER_MS[m][0] / t["median_ms"]
        floors[f"{m}_speedup"] = speedup >= SPEEDUP_FLOOR[m]
        print(
            f"{m:<10}{t['median_ms']:10.2f}{PAPER_MS[m][0]:9.1f}{speedup:9.1f}{p['median_ms']:10.2f}{PAPER_MS[m][1]:9.1f}"
            f"   {t['ratio_min']:.3f} {t['ratio_median']:.3f} {t['ratio_max']:.3f}           "
            f"{p['ratio_min']:.3f} {p['ratio_median']:.3f} {p['ratio_max']:.3f}"
            f"{t['overestimates'] + p['overestimates']:6d}"
        )
    both = [scenarios[s]["summary"] for s in scenarios]
    floors["fibonacci_within_2pct"] = all(
        s["fibonacci"]["ratio_min"] >= 0.98 and s["fibonacci"]["ratio_max"] <= 1.001 for s in both
    )
    floors["quadratic_within_2pct"] = all(
        s["quadratic"]["ratio_min"] >= 0.98 and s["quadratic"]["ratio_max"] <= 1.001 for s in both
    )
    floors["affine_within_10pct_never_above"] = all(
        s["affine"]["ratio_min"] >= 0.90 and s["affine"]["ratio_max"] <= 1.001 for s in both
    )
    floors["exactness"] = all(
        s["exactness"]["inside_rejectable"] == s["exactness"]["samples"]
        and s["exactness"]["outside_unrejectable"] == s["exactness"]["samples"]
        for s in both
    )
    for name, s in zip(scenarios, both, strict=True):
        e = s["exactness"]
        print(
            f"{name}: exact SUF median {s['exact_suf_median_n']:.1f} N; exactness: "
            f"{e['inside_rejectable']}/{e['samples']} "
            f"inside rejectable, {e['outside_unrejectable']}/{e['samples']} outside unrejectable; single overestimates "
            f"{s['single']['overestimates']}/{args.configs}"
        )
    print(f"Machine: {platform.machine()}, Python {platform.python_version()}; LPs by CLP, cone programs by Clarabel")
    figures = Path(args.out).parent
    figures.mkdir(parents=True, exist_ok=True)
    ratios = {m: [r["suf"][m] / r["suf"]["exact"] for r in scenarios["teleoperation"]["rows"]] for m in METHODS}
    plot_accuracy({m: v for m, v in ratios.items() if m != "exact"}, figures / "suf_accuracy.png")
    study = load_study(studies_dir() / "suf_height_sweep.yaml")
    with tempfile.TemporaryDirectory() as folder:
        sweep = height_sweep_rows(run_study(study, Path(folder), make_engine(args.engine), quiet=True).rows)
    plot_suf_vs_height(sweep, figures / "suf_vs_height.png")
    for row in sweep:
        print(
            f"height {row['height']:.2f} m: best SUF {row['without']['suf']:.1f} N without prongs, "
            f"{row['with_prongs']['suf']:.1f} N with ({row['benefit_percent']:+.1f} %)"
        )
    practical = [r["benefit_percent"] for r in sweep if PRACTICAL_HEIGHTS[0] <= r["height"] <= PRACTICAL_HEIGHTS[1]]
    print(f"prong benefit at practical heights {PRACTICAL_HEIGHTS} m: up to {max(practical):+.1f} %")
    rfp = {
        label: smallest_unrejectable_force(stance_problem(stance_for(0.22, 0.20, 0.14, prongs)), "exact")
        for label, prongs in (("without prongs", False), ("with prongs", True))
    }
    plot_rfp(rfp, figures / "suf_rfp.png", limit=150)
    print(f"figures: {figures}/suf_accuracy.png, suf_vs_height.png, suf_rfp.png")
    print("Floors:", json.dumps(floors))
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(
        json.dumps(
            stamped({"scenarios": scenarios, "floors": floors, "paper_ms": PAPER_MS, "height_sweep": sweep}), indent=2
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
