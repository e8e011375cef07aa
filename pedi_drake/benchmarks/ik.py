"""Leg IK benchmark reproducing paper 000, Section IV-A, plus an all-legs workspace sweep.

Paper cube: N targets (default 200) sampled uniformly (seeded) in a 30 x 30 x 30 cm cube centred
10 cm in front of and 20 cm below the FR hip joint, solved from the extended leg (the paper's
start) and from the standing pose by constrained FABRIK (at the paper's 1 cm threshold and at
1 mm), the closed-form solver and Drake's InverseKinematics with SNOPT. Every FABRIK miss is
classified with the closed-form solver: unreachable (inside the hip's lateral offset, beyond the
leg's length, or blocked by named joint limits) or a solver miss.

Workspace: for each leg, joint angles sampled uniformly within the limits, mapped through
forward kinematics to targets (reachable by construction), solved by FABRIK at 1 mm from both
starts.

    python -m pedi_drake.benchmarks.ik [--targets 200] [--seed 0] [--workspace-samples 2500]
                                      [--no-snopt] [--out benchmarks/results/ik.json]
"""

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np
from pydrake.multibody.inverse_kinematics import InverseKinematics
from pydrake.multibody.plant import MultibodyPlant
from pydrake.solvers import SnoptSolver

from pedi_drake import robot
from pedi_drake.benchmarks.machine import stamped
from pedi_drake.ik.analytic import leg_chain, leg_ik_solutions
from pedi_drake.ik.fabrik import extended_leg_q, solve_leg_ik
from pedi_drake.leg_kinematics import foot_position_B

CUBE_SIDE = 0.30  # [m]
CUBE_OFFSET_H = np.array([0.10, 0.0, -0.20])  # cube centre from the FR hip joint, trunk frame [m]
THRESHOLDS = (1e-2, 1e-3)  # the paper's 1 cm and the project's 1 mm [m]
PAPER = {"reached": 180, "targets": 200, "mean_error_m": 0.004, "mean_iterations": 1.76}
DEFAULT_OUT = Path("benchmarks/results/ik.json")
_JOINT_KINDS = robot.JOINT_KINDS


def paper_cube_targets(num_targets: int, seed: int) -> np.ndarray:
    """(num_targets, 3) FR foot targets in the trunk frame [m], uniform in the paper's cube."""
    centre = np.array(leg_chain("FR").p_BH) + CUBE_OFFSET_H
    rng = np.random.default_rng(seed)
    return centre + rng.uniform(-CUBE_SIDE / 2, CUBE_SIDE / 2, size=(num_targets, 3))


def classify_target(leg: str, p_target_B: np.ndarray) -> str:
    """Why a target is (un)reachable, from the closed-form solver.

    'reachable'; 'unreachable: inside the hip offset' (closer to the hip axis than the lateral
    thigh offset, so no leg plane passes through it); 'unreachable: beyond the leg' (farther from
    the thigh joint than the straight leg); or 'unreachable: joint limits (<joints>)' (the chain
    reaches it only with the named joints outside their limits).
    """
    if leg_ik_solutions(leg, p_target_B):
        return "reachable"
    unlimited = leg_ik_solutions(leg, p_target_B, respect_limits=False)
    if not unlimited:
        c = leg_chain(leg)
        _, y, z = c.to_local(p_target_B)
        return "unreachable: inside the hip offset" if y * y + z * z < c.lateral**2 else "unreachable: beyond the leg"
    c = leg_chain(leg)
    lo, hi = np.array(c.q_lower), np.array(c.q_upper)

    def violated(q: np.ndarray) -> set[str]:
        # A joint is in range if some 2 pi representation of its angle is.
        out = set()
        for k in range(3):
            shifts = q[k] + 2 * np.pi * np.arange(-1, 2)
            if not np.any((shifts >= lo[k]) & (shifts <= hi[k])):
                out.add(_JOINT_KINDS[k])
        return out

    # Name the joints of the solution that violates the fewest limits.
    names = min((violated(q) for q in unlimited), key=len)
    return f"unreachable: joint limits ({', '.join(sorted(names, key=_JOINT_KINDS.index))})"


class SnoptLegIk:
    """Drake InverseKinematics + SNOPT on a Go1 with its trunk welded to the world (W = B)."""

    def __init__(self):
        self.plant = MultibodyPlant(0.0)
        model = robot.add_go1(self.plant)
        self.plant.WeldFrames(
            self.plant.world_frame(), self.plant.GetBodyByName(robot.TRUNK_BODY_NAME, model).body_frame()
        )
        self.plant.Finalize()
        self.model = model
        joints = [self.plant.GetJointByName(name, model) for name in robot.JOINT_NAMES]
        self.q_index = np.array([j.position_start() for j in joints])
        self.context = self.plant.CreateDefaultContext()
        self.solver = SnoptSolver()

    def solve(self, leg: str, p_target_B: np.ndarray, q_init_leg: np.ndarray) -> tuple[np.ndarray, bool]:
        """(leg angles (hip, thigh, calf) [rad], solver success); foot-centre position equality."""
        ik = InverseKinematics(self.plant, self.context, with_joint_limits=True)
        foot = self.plant.GetBodyByName(f"{leg}_foot", self.model).body_frame()
        ik.AddPositionConstraint(foot, np.zeros(3), self.plant.world_frame(), p_target_B, p_target_B)
        q = ik.q()
        prog = ik.get_mutable_prog()
        # The other legs stay in the standing pose.
        sl = robot.leg_slice(leg)
        others = np.setdiff1d(np.arange(robot.NUM_JOINTS), np.arange(sl.start, sl.stop))
        prog.AddBoundingBoxConstraint(robot.STANDING_Q[others], robot.STANDING_Q[others], q[self.q_index[others]])
        guess = np.zeros(self.plant.num_positions())
        q_unitree = robot.STANDING_Q.copy()
        q_unitree[sl] = q_init_leg
        guess[self.q_index] = q_unitree
        result = self.solver.Solve(prog, guess)
        return result.GetSolution(q)[self.q_index[sl]], bool(result.is_success())


def _summary(
    errors: list[float],
    iterations: list[int] | None,
    times: list[float],
    threshold: float,
    sweeps: list[int] | None = None,
) -> dict:
    e = np.array(errors)
    finite = e[np.isfinite(e)]
    reached = e <= threshold
    out = {
        "threshold_m": threshold,
        "targets": int(len(e)),
        "reached": int(reached.sum()),
        "mean_error_reached_m": float(e[reached].mean()) if reached.any() else None,
        "max_error_reached_m": float(e[reached].max()) if reached.any() else None,
        # Over the targets with a finite error (the closed-form solver has none when unreachable).
        "mean_error_all_m": float(finite.mean()) if finite.size else None,
        "max_error_all_m": float(finite.max()) if finite.size else None,
        "median_time_us": 1e6 * statistics.median(times),
    }
    if iterations is not None:
        it = np.array(iterations)
        out["mean_iterations_reached"] = float(it[reached].mean()) if reached.any() else None
        out["mean_iterations_all"] = float(it.mean())
    if sweeps is not None:
        # The paper's iteration makes one compensation sweep; ours repeats it until it settles.
        sw = np.array(sweeps)
        out["mean_sweeps_reached"] = float(sw[reached].mean()) if reached.any() else None
    return out


def _run_fabrik(leg: str, targets: np.ndarray, q_start: np.ndarray, tol: float):
    errors, iterations, times, qs, sweeps = [], [], [], [], []
    for p in targets:
        t0 = time.perf_counter()
        r = solve_leg_ik(leg, p, q_start, tol=tol)
        times.append(time.perf_counter() - t0)
        errors.append(r.error)
        iterations.append(r.iterations)
        sweeps.append(r.compensation_sweeps)
        qs.append(r.q)
    return errors, iterations, times, qs, sweeps


def _run_closed_form(leg: str, targets: np.ndarray, q_start: np.ndarray):
    errors, times = [], []
    for p in targets:
        t0 = time.perf_counter()
        solutions = leg_ik_solutions(leg, p)
        q = min(solutions, key=lambda s: float(np.sum((s - q_start) ** 2))) if solutions else None
        times.append(time.perf_counter() - t0)
        errors.append(float(np.linalg.norm(foot_position_B(leg, q) - p)) if q is not None else np.inf)
    return errors, times


def _run_snopt(snopt: SnoptLegIk, leg: str, targets: np.ndarray, q_start: np.ndarray):
    errors, times = [], []
    lo, hi = np.array(leg_chain(leg).q_lower), np.array(leg_chain(leg).q_upper)
    for p in targets:
        t0 = time.perf_counter()
        q, _ = snopt.solve(leg, p, q_start)
        times.append(time.perf_counter() - t0)
        # SNOPT may end slightly outside the bounds (feasibility tolerance): measure the clipped q.
        errors.append(float(np.linalg.norm(foot_position_B(leg, np.clip(q, lo, hi)) - p)))
    return errors, times


def run_paper_cube(num_targets: int = 200, seed: int = 0, *, snopt: bool = True) -> dict:
    """The Section IV-A experiment on the FR leg; returns a JSON-ready dict."""
    leg = "FR"
    targets = paper_cube_targets(num_targets, seed)
    classes = [classify_target(leg, p) for p in targets]
    starts = {"extended": extended_leg_q(leg), "standing": robot.STANDING_Q[robot.leg_slice(leg)].copy()}
    snopt_ik = SnoptLegIk() if snopt else None
    rows, misses, per_target = [], [], {}
    for start_name, q_start in starts.items():
        for threshold in THRESHOLDS:
            errors, iterations, times, _, sweeps = _run_fabrik(leg, targets, q_start, threshold)
            summary = _summary(errors, iterations, times, threshold, sweeps)
            rows.append({"solver": "fabrik", "start": start_name, **summary})
            for i, e in enumerate(errors):
                if e > threshold:
                    kind = "solver miss" if classes[i] == "reachable" else classes[i]
                    misses.append(
                        {
                            "index": i,
                            "start": start_name,
                            "threshold_m": threshold,
                            "target_B": targets[i].tolist(),
                            "error_m": e,
                            "iterations": iterations[i],
                            "class": kind,
                        }
                    )
            if threshold == THRESHOLDS[-1]:
                per_target[start_name] = {"fabrik_error_m": errors, "fabrik_iterations": iterations}
        errors, times = _run_closed_form(leg, targets, q_start)
        for threshold in THRESHOLDS:
            rows.append({"solver": "closed_form", "start": start_name, **_summary(errors, None, times, threshold)})
        if snopt_ik is not None:
            errors, times = _run_snopt(snopt_ik, leg, targets, q_start)
            for threshold in THRESHOLDS:
                rows.append({"solver": "snopt", "start": start_name, **_summary(errors, None, times, threshold)})
    return {
        "leg": leg,
        "num_targets": num_targets,
        "seed": seed,
        "cube_centre_B": (np.array(leg_chain(leg).p_BH) + CUBE_OFFSET_H).tolist(),
        "cube_side_m": CUBE_SIDE,
        "starts": {k: v.tolist() for k, v in starts.items()},
        "reachable": int(sum(c == "reachable" for c in classes)),
        "target_classes": {c: classes.count(c) for c in sorted(set(classes))},
        "rows": rows,
        "misses": misses,
        "targets_B": targets.tolist(),
        "classes": classes,
        "per_target": per_target,
    }


def run_workspace(samples_per_leg: int = 2500, seed: int = 0, tol: float = 1e-3) -> dict:
    """FABRIK over each leg's whole reachable workspace (targets from FK of in-limit angles)."""
    rng = np.random.default_rng(seed + 1)
    legs = {}
    for leg in robot.LEG_NAMES:
        c = leg_chain(leg)
        q_samples = rng.uniform(c.q_lower, c.q_upper, size=(samples_per_leg, 3))
        targets = np.array([foot_position_B(leg, q) for q in q_samples])
        starts = {"extended": extended_leg_q(leg), "standing": robot.STANDING_Q[robot.leg_slice(leg)].copy()}
        legs[leg] = {}
        for start_name, q_start in starts.items():
            errors, iterations, times, _, _ = _run_fabrik(leg, targets, q_start, tol)
            summary = _summary(errors, iterations, times, tol)
            summary["reach_rate"] = summary["reached"] / samples_per_leg
            summary["misses"] = [
                {"q_sampled": q_samples[i].tolist(), "error_m": e, "iterations": iterations[i]}
                for i, e in enumerate(errors)
                if e > tol
            ]
            legs[leg][start_name] = summary
    total = sum(v["reached"] for leg in legs.values() for v in leg.values())
    count = sum(v["targets"] for leg in legs.values() for v in leg.values())
    return {"samples_per_leg": samples_per_leg, "tol_m": tol, "legs": legs, "reach_rate": total / count}


def run_benchmark(num_targets: int = 200, seed: int = 0, *, workspace_samples: int = 2500, snopt: bool = True) -> dict:
    """Both experiments and their floors (paper 000 Sec. IV-A), as one JSON-ready dict."""
    cube = run_paper_cube(num_targets, seed, snopt=snopt)
    workspace = run_workspace(workspace_samples, seed) if workspace_samples > 0 else None
    fab_1mm = [r for r in cube["rows"] if r["solver"] == "fabrik" and r["threshold_m"] == 1e-3]
    fab_1cm = [r for r in cube["rows"] if r["solver"] == "fabrik" and r["threshold_m"] == 1e-2]
    reachable_solver_misses = sum(1 for m in cube["misses"] if m["class"] == "solver miss")
    floors = {
        "reachable_reached_1mm_rate_cube": 1.0
        - sum(1 for m in cube["misses"] if m["class"] == "solver miss" and m["threshold_m"] == 1e-3)
        / max(1, cube["reachable"] * len(fab_1mm)),
        "workspace_reach_rate_1mm": workspace["reach_rate"] if workspace else None,
        "mean_error_reached_1mm_m": max(r["mean_error_reached_m"] or 0.0 for r in fab_1mm),
        # Both counts beside the paper's 1.76 iterations: FABRIK passes (forward, backward and
        # compensation) and compensation sweeps (one per pass in the paper's algorithm).
        "mean_iterations_reached_1cm": max(r["mean_iterations_reached"] or 0.0 for r in fab_1cm),
        "mean_sweeps_reached_1cm": max(r["mean_sweeps_reached"] or 0.0 for r in fab_1cm),
        "median_time_us": max(r["median_time_us"] for r in fab_1mm + fab_1cm),
        "solver_misses_cube": reachable_solver_misses,
    }
    floors["met"] = {
        "reach_99_5": floors["reachable_reached_1mm_rate_cube"] >= 0.995
        and (workspace is None or floors["workspace_reach_rate_1mm"] >= 0.995),
        "mean_error_below_0_2mm": floors["mean_error_reached_1mm_m"] < 2e-4,
        "median_time_below_100us": floors["median_time_us"] < 100.0,
    }
    return {
        "machine": _machine(),
        "paper": PAPER,
        "paper_cube": cube,
        "workspace": workspace,
        "floors": floors,
    }


def _machine() -> dict:
    """What the timings were measured on."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), cpu)
    except OSError:
        pass
    return {
        "platform": platform.platform(),
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
    }


def format_table(results: dict) -> str:
    """A plain-text table of the paper-cube rows, the workspace sweep and the floors."""
    lines = []
    cube = results["paper_cube"]
    lines.append(
        f"Paper cube: {cube['num_targets']} targets (seed {cube['seed']}), FR leg; "
        f"closed-form classes: {cube['target_classes']}"
    )
    header = (
        f"{'solver':<12}{'start':<10}{'thr [mm]':>9}{'reached':>9}{'mean err [mm]':>15}"
        f"{'max err [mm]':>14}{'mean it':>9}{'mean sw':>9}{'median [us]':>13}"
    )
    lines += [header, "-" * len(header)]

    def mm(v):
        return f"{1e3 * v:.3f}" if v is not None else "-"

    for r in cube["rows"]:
        it, sw = r.get("mean_iterations_reached"), r.get("mean_sweeps_reached")
        lines.append(
            f"{r['solver']:<12}{r['start']:<10}{1e3 * r['threshold_m']:>9.0f}"
            f"{r['reached']:>5}/{r['targets']:<3}{mm(r['mean_error_reached_m']):>15}{mm(r['max_error_reached_m']):>14}"
            f"{(f'{it:.2f}' if it is not None else '-'):>9}{(f'{sw:.2f}' if sw is not None else '-'):>9}"
            f"{r['median_time_us']:>13.1f}"
        )
    lines.append("FABRIK misses (closed-form classification):")
    counts: dict[str, int] = {}
    for m in cube["misses"]:
        key = f"  {m['start']:<9} {1e3 * m['threshold_m']:.0f} mm  {m['class']}"
        counts[key] = counts.get(key, 0) + 1
    lines += [f"{k}: {v}" for k, v in sorted(counts.items())] or ["  none"]
    ws = results["workspace"]
    if ws:
        lines.append(
            f"Workspace sweep: {ws['samples_per_leg']} reachable targets per leg, tol {1e3 * ws['tol_m']:.0f} mm"
        )
        for leg, by_start in ws["legs"].items():
            for start, s in by_start.items():
                lines.append(
                    f"  {leg} {start:<9} reached {s['reached']}/{s['targets']} ({100 * s['reach_rate']:.2f} %), "
                    f"mean err {mm(s['mean_error_reached_m'])} mm, mean it {s['mean_iterations_all']:.2f}, "
                    f"median {s['median_time_us']:.1f} us"
                )
        lines.append(f"  overall reach rate {100 * ws['reach_rate']:.3f} %")
    m = results["machine"]
    lines.append(f"Machine: {m['cpu']} x{m['cpu_count']}, Python {m['python']}; times are wall time per target")
    lines.append(f"Floors: {json.dumps(results['floors']['met'])}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--targets", type=int, default=200, help="paper-cube targets")
    parser.add_argument("--seed", type=int, default=0, help="random seed")
    parser.add_argument("--workspace-samples", type=int, default=2500, help="targets per leg (0 to skip)")
    parser.add_argument("--no-snopt", action="store_true", help="skip Drake InverseKinematics + SNOPT")
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT, help="JSON output path")
    args = parser.parse_args(argv)
    results = run_benchmark(args.targets, args.seed, workspace_samples=args.workspace_samples, snopt=not args.no_snopt)
    print(format_table(results))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(stamped(results), indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
