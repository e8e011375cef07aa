"""The dense QP solver (pedi_drake.control.dense_qp) against DAQP on QPs recorded from the controller.

    python -m pedi_drake.benchmarks.dense_qp [--fixture tests/fixtures/controller_qps.npz]
        [--repeats 9] [--batch 20] [--controller-ticks 4000] [--out benchmarks/results/dense_qp.json]

For every recorded level QP of the hierarchical whole-body controller (min 0.5 y'Hy + f'y s.t.
C y <= u, with the y DAQP returned in the controller) it measures the CPU time of one solve:

* dense_qp in numba: the compiled kernel called `--batch` times in a loop inside another
  compiled kernel (how a compiled controller would call it: no Python at all);
* dense_qp from Python: `dense_qp.solve_qp` (argument checks, allocation, numba's dispatch);
* daqp.solve from Python, as `pedi_drake.control.hqp` calls it (eps_prox = 1e-5), and DAQP's
  own report of its solve time (its C code alone, without the wrapper).

Each QP's time is the median over `--repeats` batches (the solvers interleaved, so they share
the machine's load); the table gives the median and p99 of that over all recorded QPs, and the
accuracy: the largest difference from DAQP's solution (relative to max(1, |y|_inf)) on the QPs
whose solution is unique, and the largest objective difference on all of them.

Then, in the controller: the controller side replays the first `--controller-ticks` ticks of
tests/fixtures/controller_side_reference.npz (hit_target_front, as in
pedi_drake.benchmarks.controller_latency) once per backend, and the CPU time spent in the level QP
solves (hqp._solve_dense_qp, Python wrapper included) is summed per tick. Writes JSON.

    python -m pedi_drake.benchmarks.dense_qp --record tests/fixtures/controller_qps.npz

records the fixture: each mission of RECORDED_MISSIONS simulated for its duration (default
scenario, the paper003 stack for prong_push_box as its mission asks) with
`hqp._solve_dense_qp` wrapped, and up to PER_LEVEL QPs per (mission, level) kept, evenly spread
over the run.
"""

import argparse
import dataclasses
import json
import platform
import statistics
import time
from pathlib import Path

import daqp
import numpy as np

from pedi_drake.control import dense_qp, hqp
from pedi_drake.runtime.jit import kernel

DEFAULT_FIXTURE = Path(__file__).resolve().parents[2] / "tests" / "fixtures" / "controller_qps.npz"
CONTROLLER_REFERENCE = DEFAULT_FIXTURE.with_name("controller_side_reference.npz")
# Mission and simulated duration [s]: standing up, lifting a leg and reaching (hit_target_front,
# paper 000's stack); leaning on the prongs and lifting both front legs (prong_push_box, paper 003).
RECORDED_MISSIONS = {"hit_target_front": 8.0, "prong_push_box": 10.0}
# QPs kept per (mission, level).
PER_LEVEL = 28
# DAQP's proximal weight in the controller (HqpSettings.proximal_weight).
EPS_PROX = 1e-5


@dataclasses.dataclass
class RecordedQp:
    """One level QP of the controller and DAQP's solution of it there."""

    mission: str
    level: str
    H: np.ndarray  # (n, n)
    f: np.ndarray  # (n,)
    C: np.ndarray  # (m, n)
    u: np.ndarray  # (m,)
    y_daqp: np.ndarray  # (n,)


def record_controller_qps(
    missions: dict[str, float] = RECORDED_MISSIONS, per_level: int = PER_LEVEL
) -> list[RecordedQp]:
    """Simulates each mission with the level QPs recorded (see the module docstring)."""
    from pedi_drake.run import simulate
    from pedi_drake.scenario import load_scenario

    kept: list[RecordedQp] = []
    original = hqp._solve_dense_qp
    for mission, duration in missions.items():
        recorded: list[RecordedQp] = []

        def recording(H, f, C, upper, level, eps_prox, backend="daqp", _mission=mission, _into=recorded):
            y = original(H, f, C, upper, level, eps_prox, backend)
            if C.shape[0] and backend == "daqp":
                _into.append(RecordedQp(_mission, level, H.copy(), f.copy(), C.copy(), upper.copy(), y.copy()))
            return y

        scenario = load_scenario(
            scenario_text=f"{{controller: whole_body, mission: {mission}, simulation_duration: {duration}}}"
        )
        hqp._solve_dense_qp = recording
        try:
            simulate(scenario=scenario, name=mission, quiet=True, replay=False)
        finally:
            hqp._solve_dense_qp = original
        for level in dict.fromkeys(qp.level for qp in recorded):
            of_level = [qp for qp in recorded if qp.level == level]
            picks = np.unique(np.linspace(0, len(of_level) - 1, min(per_level, len(of_level))).round().astype(int))
            kept.extend(of_level[i] for i in picks)
    return kept


def save_qps(path: Path, qps: list[RecordedQp]) -> None:
    """Writes the QPs to a compressed .npz (flat arrays with per-QP sizes)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        path,
        mission=np.array([qp.mission for qp in qps]),
        level=np.array([qp.level for qp in qps]),
        n=np.array([len(qp.f) for qp in qps]),
        m=np.array([len(qp.u) for qp in qps]),
        H=np.concatenate([qp.H.ravel() for qp in qps]),
        f=np.concatenate([qp.f for qp in qps]),
        C=np.concatenate([qp.C.ravel() for qp in qps]),
        u=np.concatenate([qp.u for qp in qps]),
        y_daqp=np.concatenate([qp.y_daqp for qp in qps]),
        eps_prox=EPS_PROX,
        daqp_version=daqp.__version__ if hasattr(daqp, "__version__") else "",
    )


def load_qps(path: Path = DEFAULT_FIXTURE) -> list[RecordedQp]:
    """The QPs written by `save_qps`."""
    data = np.load(path)
    qps = []
    h = c = vector = row = 0  # offsets into the flat arrays of H, C, f and y, u
    for mission, level, n, m in zip(data["mission"], data["level"], data["n"], data["m"], strict=True):
        n, m = int(n), int(m)
        qps.append(
            RecordedQp(
                mission=str(mission),
                level=str(level),
                H=data["H"][h : h + n * n].reshape(n, n),
                f=data["f"][vector : vector + n],
                C=data["C"][c : c + m * n].reshape(m, n),
                u=data["u"][row : row + m],
                y_daqp=data["y_daqp"][vector : vector + n],
            )
        )
        h += n * n
        c += m * n
        vector += n
        row += m
    return qps


def daqp_solve(qp: RecordedQp, eta_prox: float | None = None) -> tuple[np.ndarray, int, dict]:
    """DAQP as the controller calls it (eta_prox: DAQP's proximal stopping tolerance, its default
    when None)."""
    options = {"eps_prox": EPS_PROX}
    if eta_prox is not None:
        options["eta_prox"] = eta_prox
    y, _, exitflag, info = daqp.solve(qp.H, qp.f, qp.C, qp.u, np.full(len(qp.u), -1e30), **options)
    return np.asarray(y), int(exitflag), info


def objective(qp: RecordedQp, y: np.ndarray) -> float:
    return float(0.5 * y @ qp.H @ y + qp.f @ y)


def solution_is_unique(qp: RecordedQp, y: np.ndarray, multipliers: np.ndarray, tolerance: float = 1e-9) -> bool:
    """Whether H is positive definite on the null space of the rows with a positive multiplier
    (sufficient for a unique solution): then the solution is compared, else only its objective."""
    strongly_active = multipliers > tolerance * max(1.0, float(np.max(multipliers, initial=0.0)))
    n = len(qp.f)
    if strongly_active.any():
        _, sigma, Vt = np.linalg.svd(qp.C[strongly_active])
        rank = int(np.sum(sigma > 1e-10 * sigma[0]))
        Z = Vt[rank:].T
    else:
        Z = np.eye(n)
    if Z.shape[1] == 0:
        return True
    curvature = np.linalg.eigvalsh(Z.T @ qp.H @ Z)
    return bool(curvature[0] > tolerance * max(1.0, float(np.abs(qp.H).max())))


@kernel
def _solve_repeatedly(
    H, f, C, u, prox_weight, primal, dual, stationarity, max_iterations, y, multipliers, active, matrices,
    transposed, vectors, integers, repeats,
):  # fmt: skip
    """The dense QP kernel called `repeats` times from compiled code; returns the last status."""
    status = 0
    for _ in range(repeats):
        status, _, _ = dense_qp.solve_dense_qp_kernel(
            H, f, C, u, prox_weight, primal, dual, stationarity, max_iterations, y, multipliers, active, 0,
            matrices, transposed, vectors, integers,
        )  # fmt: skip
    return status


def time_solvers(qps: list[RecordedQp], repeats: int, batch: int) -> dict[str, list[float]]:
    """Per QP: the median over `repeats` batches of the CPU time of one solve [s], per solver."""
    settings = dense_qp.DenseQpSettings(prox_weight=EPS_PROX)
    n_max = max(len(qp.f) for qp in qps)
    m_max = max(len(qp.u) for qp in qps)
    workspace = dense_qp.make_workspace(n_max, m_max)
    times: dict[str, list[float]] = {"dense_qp in numba": [], "dense_qp from Python": [], "daqp.solve": []}
    daqp_internal: list[float] = []
    for qp in qps:
        n, m = len(qp.f), len(qp.u)
        lower = np.full(m, -1e30)
        y, multipliers, active = np.zeros(n), np.zeros(m), np.zeros(max(n, 1), dtype=np.int64)
        arguments = (
            qp.H, qp.f, qp.C, qp.u, settings.prox_weight, settings.primal_tolerance, settings.dual_tolerance,
            settings.stationarity_tolerance, settings.max_iterations, y, multipliers, active,
            workspace.matrices, workspace.transposed, workspace.vectors, workspace.integers,
        )  # fmt: skip
        _solve_repeatedly(*arguments, 1)  # compiled (or loaded from the cache) before timing
        samples: dict[str, list[float]] = {name: [] for name in times}
        internal = []
        for _ in range(repeats):
            start = time.thread_time()
            _solve_repeatedly(*arguments, batch)
            samples["dense_qp in numba"].append((time.thread_time() - start) / batch)
            start = time.thread_time()
            for _ in range(batch):
                dense_qp.solve_qp(qp.H, qp.f, qp.C, qp.u, settings, workspace)
            samples["dense_qp from Python"].append((time.thread_time() - start) / batch)
            start = time.thread_time()
            for _ in range(batch):
                _, _, _, info = daqp.solve(qp.H, qp.f, qp.C, qp.u, lower, eps_prox=EPS_PROX)
            samples["daqp.solve"].append((time.thread_time() - start) / batch)
            internal.append(info["solve_time"])
        for name, values in samples.items():
            times[name].append(statistics.median(values))
        daqp_internal.append(statistics.median(internal))
    times["daqp (its own solve_time)"] = daqp_internal
    return times


def accuracy(qps: list[RecordedQp]) -> dict:
    """dense_qp against DAQP (as recorded in the controller, and tightened: eta_prox = 1e-12)."""
    settings = dense_qp.DenseQpSettings(prox_weight=EPS_PROX)
    unique = 0
    worst_recorded = worst_tight = worst_objective = worst_violation = 0.0
    statuses: dict[str, int] = {}
    for qp in qps:
        solution = dense_qp.solve(qp.H, qp.f, qp.C, qp.u, settings)
        name = dense_qp.STATUS_NAMES[solution.status]
        statuses[name] = statuses.get(name, 0) + 1
        tight, _, _ = daqp_solve(qp, eta_prox=1e-12)
        scale = max(1.0, float(np.abs(tight).max()))
        worst_objective = max(worst_objective, abs(objective(qp, solution.y) - objective(qp, qp.y_daqp)) / scale)
        worst_violation = max(worst_violation, float(np.max(qp.C @ solution.y - qp.u)))
        if solution_is_unique(qp, solution.y, solution.multipliers):
            unique += 1
            worst_recorded = max(worst_recorded, float(np.abs(solution.y - qp.y_daqp).max()) / scale)
            worst_tight = max(worst_tight, float(np.abs(solution.y - tight).max()) / scale)
    return {
        "qps": len(qps),
        "statuses": statuses,
        "unique_solutions": unique,
        "max_rel_difference_from_daqp_recorded": worst_recorded,
        "max_rel_difference_from_daqp_eta_1e-12": worst_tight,
        "max_objective_difference_from_daqp_recorded": worst_objective,
        "max_violation": worst_violation,
    }


def qp_time_in_controller(backend: str, ticks: int) -> dict:
    """CPU time of the level QP solves in `ticks` replayed controller ticks (see the docstring)."""
    from pedi_drake.benchmarks.controller_latency import Replay

    reference = np.load(CONTROLLER_REFERENCE)
    status = reference["status"].astype(float)
    ticks = min(ticks, len(status) - 1)
    replay = Replay(str(reference["mission"]), float(reference["period"]), status, qp_backend=backend)
    spent: list[float] = []
    original = hqp._solve_dense_qp

    def timed(*args, **kwargs):
        start = time.thread_time()
        try:
            return original(*args, **kwargs)
        finally:
            spent.append(time.thread_time() - start)

    hqp._solve_dense_qp = timed
    try:
        replay.run(ticks)
    finally:
        hqp._solve_dense_qp = original
    return {
        "ticks": ticks,
        "solves_per_tick": len(spent) / ticks,
        "qp_cpu_ms_per_tick": 1e3 * sum(spent) / ticks,
        "per_solve_median_us": 1e6 * float(np.median(spent)) if spent else 0.0,
        "per_solve_p99_us": 1e6 * float(np.percentile(spent, 99)) if spent else 0.0,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--fixture", type=Path, default=DEFAULT_FIXTURE)
    parser.add_argument("--repeats", type=int, default=9, help="timed batches per QP (median)")
    parser.add_argument("--batch", type=int, default=20, help="solves per timed batch")
    parser.add_argument("--controller-ticks", type=int, default=4000, help="replayed controller ticks (0: none)")
    parser.add_argument("--out", default="benchmarks/results/dense_qp.json")
    parser.add_argument("--record", type=Path, help="record the controller QPs to this file and stop")
    args = parser.parse_args()
    if args.record:
        qps = record_controller_qps()
        save_qps(args.record, qps)
        print(f"wrote {len(qps)} QPs to {args.record}")
        return

    qps = load_qps(args.fixture)
    times = time_solvers(qps, args.repeats, args.batch)
    rows = {
        name: {
            "median_us": 1e6 * float(np.median(values)),
            "p99_us": 1e6 * float(np.percentile(values, 99)),
            "max_us": 1e6 * float(np.max(values)),
        }
        for name, values in times.items()
    }
    checked = accuracy(qps)
    sizes = [(len(qp.f), len(qp.u)) for qp in qps]
    print(
        f"{len(qps)} controller QPs ({min(s[0] for s in sizes)}-{max(s[0] for s in sizes)} variables, "
        f"{min(s[1] for s in sizes)}-{max(s[1] for s in sizes)} rows); CPU time per solve"
    )
    header = f"{'solver':<28}{'median us':>10}{'p99 us':>9}{'max us':>9}"
    print(header)
    print("-" * len(header))
    for name, row in rows.items():
        print(f"{name:<28}{row['median_us']:>10.1f}{row['p99_us']:>9.1f}{row['max_us']:>9.1f}")
    print("Accuracy:", json.dumps(checked))
    in_controller = {}
    if args.controller_ticks > 0:
        for backend in ("daqp", "dense_qp"):
            in_controller[backend] = qp_time_in_controller(backend, args.controller_ticks)
        ticks = in_controller["daqp"]["ticks"]
        print(f"In the controller ({ticks} replayed ticks of hit_target_front): level QP solves, CPU time")
        header = f"{'backend':<12}{'solves/tick':>12}{'ms/tick':>9}{'median us':>10}{'p99 us':>9}"
        print(header)
        print("-" * len(header))
        for backend, row in in_controller.items():
            print(
                f"{backend:<12}{row['solves_per_tick']:>12.2f}{row['qp_cpu_ms_per_tick']:>9.3f}"
                f"{row['per_solve_median_us']:>10.1f}{row['per_solve_p99_us']:>9.1f}"
            )
    print(f"Machine: {platform.processor() or platform.machine()}, Python {platform.python_version()}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(
        json.dumps(
            {
                "per_solve": rows,
                "accuracy": checked,
                "in_controller": in_controller,
                "repeats": args.repeats,
                "batch": args.batch,
            },
            indent=2,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
