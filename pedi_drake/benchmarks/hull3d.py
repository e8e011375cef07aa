"""The compiled incremental hull (pedi_drake.suf.hull3d) against Qhull (scipy.spatial.ConvexHull).

    python -m pedi_drake.benchmarks.hull3d [--cuts 2 8 20 36] [--sets 8] [--repeats 15] [--batch 40]
        [--out benchmarks/results/hull3d.json]

The point sets are shaped like the exact SUF projection's: the vertices of a polytope in force
space (what its LPs return), here `--sets` seeded polytopes per entry of `--cuts`, each a box of
+-280 N cut by that many random half-spaces 200 to 260 N from the origin, then stretched to
extents of 450 to 900 N and shifted by 100 N along z (`polytope_vertices`; 10 to 60 vertices,
polygonal facets whose corners are coplanar, as the projection's are), in a seeded random order.

Per point set, the CPU time of the calling thread (time.thread_time) per call, the median over
`--repeats` batches of `--batch` calls, the methods interleaved:

* hull3d build: `start_tetrahedron`, then `insert_existing` for every other point, as
  warm_projection.project_within's tetrahedron and hull stages do, in the live projection's arrays
  (live.LIVE_POINT_CAP, LIVE_FACE_CAP), looped inside one compiled kernel (no Python);
* hull3d add: `insert_point` of the last vertex into the hull of the others, as the certification
  stage adds an LP's point, looped in compiled code with the hull restored from a copy before
  each insertion (the restore alone is timed too and subtracted);
* Qhull build: `ConvexHull(points)` called from Python;
* Qhull add: `add_points` of that last vertex on `ConvexHull(others, incremental=True)`
  (the hulls built before the timed loop);
* Qhull build via objmode: `ConvexHull(points).equations` inside a numba `objmode` block in a
  compiled loop, the facet planes handed back to compiled code: what the compiled projection would
  pay to build with Qhull.

And two costs of leaving nopython code, once: an `objmode` block that hands the points to Python and
gets an array back (the least a compiled caller pays per Qhull call, on top of Qhull), and a
compiled call with the hull's seven arrays made from Python (what splitting the compiled
projection around each hull step would pay per step).

The ratios are Qhull's, with the objmode crossing added, over hull3d's, for a build and for one
added point. Every point set is checked first: hull3d's hull (built, and built without the last
point and then given it) and Qhull's have the same vertices, volume (to 1e-9 relative) and
distinct facet planes. Prints a table of medians [us] and writes JSON.
"""

import argparse
import itertools
import json
import statistics
import time
from pathlib import Path

import numba
import numpy as np
import scipy
from scipy.spatial import ConvexHull

from pedi_drake.benchmarks.machine import stamped
from pedi_drake.runtime.jit import kernel
from pedi_drake.suf import hull3d
from pedi_drake.suf.live import LIVE_FACE_CAP, LIVE_POINT_CAP
from pedi_drake.suf.warm_projection import HULL_EPS

BOX = 280.0  # [N]
CUT_OFFSETS = (200.0, 260.0)  # [N]
STRETCH = np.array([0.8, 1.0, 1.6])
SHIFT = np.array([0.0, 0.0, 100.0])  # [N]
# Distinct facet planes: unit normals within this [-] and offsets within PLANE_OFFSET [N] are one.
PLANE_NORMAL = 1e-7
PLANE_OFFSET = 1e-6
VOLUME_RELATIVE = 1e-9
SEED = 3


def polytope_vertices(rng: np.random.Generator, num_cuts: int) -> np.ndarray:
    """The vertices (k, 3) [N] of a box cut by `num_cuts` random half-spaces, stretched, shifted and
    shuffled (see the module docstring): every triple of planes solved, the feasible points kept."""
    normals = rng.normal(size=(num_cuts, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    A = np.vstack([normals, np.eye(3), -np.eye(3)])
    b = np.concatenate([rng.uniform(*CUT_OFFSETS, num_cuts), np.full(6, BOX)])
    triples = np.array(list(itertools.combinations(range(len(A)), 3)))
    M = A[triples]
    regular = np.abs(np.linalg.det(M)) > 1e-9
    points = np.linalg.solve(M[regular], b[triples[regular]][..., None])[..., 0]
    feasible = np.all(points @ A.T <= b + 1e-9 * BOX, axis=1)
    vertices = np.unique(np.round(points[feasible], 9), axis=0)
    return rng.permutation(vertices * STRETCH + SHIFT)


# --- the facts compared -------------------------------------------------------------------------


def distinct_planes(planes: np.ndarray) -> np.ndarray:
    """The rows (normal, offset) of `planes` with equal planes (PLANE_NORMAL, PLANE_OFFSET) once."""
    kept: list[np.ndarray] = []
    for plane in planes:
        if not any(_same_plane(plane, other) for other in kept):
            kept.append(plane)
    return np.array(kept)


def _same_plane(p: np.ndarray, q: np.ndarray) -> bool:
    return bool(np.abs(p[:3] - q[:3]).max() <= PLANE_NORMAL and abs(p[3] - q[3]) <= PLANE_OFFSET)


def hull3d_facts(hull) -> dict:
    """Vertices (point indices), volume [N^3] and distinct facet planes of a hull3d hull."""
    points, faces, normals, offsets, alive, _, counts = hull
    live = np.flatnonzero(alive[: counts[1]] == 1)
    live = live[np.abs(normals[live]).sum(axis=1) > 0.0]  # zero-area triangles hold no plane
    corners = points[faces[live]]  # (faces, 3, 3)
    centre = corners.reshape(-1, 3).mean(axis=0)
    volume = float(np.linalg.det(corners - centre).sum() / 6.0)
    return {
        "vertices": frozenset(int(k) for k in np.unique(faces[live])),
        "volume": volume,
        "planes": distinct_planes(np.column_stack([normals[live], offsets[live]])),
    }


def qhull_facts(hull: ConvexHull) -> dict:
    """The same of a scipy ConvexHull (its equations n . x + c = 0: offset -c)."""
    equations = hull.equations
    return {
        "vertices": frozenset(int(k) for k in hull.vertices),
        "volume": float(hull.volume),
        "planes": distinct_planes(np.column_stack([equations[:, :3], -equations[:, 3]])),
    }


def compare(ours: dict, theirs: dict) -> float:
    """Asserts that two hulls' facts agree; the relative volume difference."""
    assert ours["vertices"] == theirs["vertices"], (sorted(ours["vertices"]), sorted(theirs["vertices"]))
    difference = abs(ours["volume"] - theirs["volume"]) / theirs["volume"]
    assert difference <= VOLUME_RELATIVE, (ours["volume"], theirs["volume"])
    assert len(ours["planes"]) == len(theirs["planes"]), (len(ours["planes"]), len(theirs["planes"]))
    for plane in ours["planes"]:
        assert any(_same_plane(plane, other) for other in theirs["planes"]), plane
    return difference


def hull_of(points: np.ndarray, add_last: bool = False):
    """hull3d's hull of `points` in the live projection's arrays: all of them at once (start_hull),
    or all but the last, then the last added (insert_point)."""
    hull = hull3d.new_hull(LIVE_POINT_CAP, LIVE_FACE_CAP)
    n = len(points) - 1 if add_last else len(points)
    hull[0][:n] = points[:n]
    assert hull3d.start_hull(*hull, n, HULL_EPS) == hull3d.STARTED
    if add_last:
        assert hull3d.insert_point(*hull, np.ascontiguousarray(points[-1]), HULL_EPS) == hull3d.INSERTED
    return hull


def check(points: np.ndarray) -> float:
    """hull3d against Qhull on `points` (built, and extended by the last point); the larger
    relative volume difference."""
    qhull = qhull_facts(ConvexHull(points))
    worst = compare(hull3d_facts(hull_of(points)), qhull)
    worst = max(worst, compare(hull3d_facts(hull_of(points, add_last=True)), qhull))
    incremental = ConvexHull(points[:-1], incremental=True)
    incremental.add_points(points[-1:])
    worst = max(worst, compare(hull3d_facts(hull_of(points, add_last=True)), qhull_facts(incremental)))
    incremental.close()
    return worst


# --- compiled loops -----------------------------------------------------------------------------


@kernel
def _build_repeatedly(points, faces, normals, offsets, alive, certified, counts, num_points, repeats) -> int:
    """The hull of the first `num_points` points, `repeats` times, as project_within builds it."""
    corners = np.zeros(4, dtype=np.int64)
    status = hull3d.STARTED
    for _ in range(repeats):
        status = hull3d.start_tetrahedron(
            points, faces, normals, offsets, alive, certified, counts, num_points, HULL_EPS, corners
        )
        if status != hull3d.STARTED:
            return status
        for k in range(num_points):
            if not hull3d.is_corner(corners, k):
                if hull3d.insert_existing(points, faces, normals, offsets, alive, certified, counts, k, HULL_EPS) == (
                    hull3d.FULL
                ):
                    return hull3d.FULL
    return status


@kernel
def _restore(saved_points, saved_faces, saved_normals, saved_offsets, saved_alive, saved_counts, points, faces,
             normals, offsets, alive, certified, counts):  # fmt: skip
    """The saved hull back in the working arrays (only the slots it uses)."""
    for k in range(saved_counts[0]):
        for i in range(3):
            points[k, i] = saved_points[k, i]
    for f in range(saved_counts[1]):
        for i in range(3):
            faces[f, i] = saved_faces[f, i]
            normals[f, i] = saved_normals[f, i]
        offsets[f] = saved_offsets[f]
        alive[f] = saved_alive[f]
        certified[f] = 0
    counts[0], counts[1] = saved_counts[0], saved_counts[1]


@kernel
def _add_repeatedly(saved_points, saved_faces, saved_normals, saved_offsets, saved_alive, saved_counts, points, faces,
                    normals, offsets, alive, certified, counts, p, repeats, insert) -> int:  # fmt: skip
    """`repeats` times: the saved hull restored, then (if `insert`) p added as the certification
    stage adds an LP's point."""
    status = hull3d.INSIDE
    for _ in range(repeats):
        _restore(saved_points, saved_faces, saved_normals, saved_offsets, saved_alive, saved_counts, points, faces,
                 normals, offsets, alive, certified, counts)  # fmt: skip
        if insert:
            status = hull3d.insert_point(points, faces, normals, offsets, alive, certified, counts, p, HULL_EPS)
    return status


@kernel
def _touch(points, faces, normals, offsets, alive, certified, counts) -> int:
    """Nothing with the hull's arrays: a compiled call's dispatch from Python."""
    return counts[0]


def _same(points: np.ndarray) -> np.ndarray:
    return points


def _qhull_planes(points: np.ndarray) -> np.ndarray:
    return ConvexHull(points).equations


# objmode blocks: numba's own decorator, uncached (the blocks are Python, compiled per process).
@numba.njit
def _cross_repeatedly(points, repeats) -> float:
    """`repeats` objmode blocks, each handing `points` to Python and an array back."""
    total = 0.0
    for _ in range(repeats):
        with numba.objmode(out="float64[:, ::1]"):
            out = _same(points)
        total += out[0, 0]
    return total


@numba.njit
def _qhull_repeatedly(points, repeats) -> float:
    """`repeats` Qhull builds from compiled code, the facet planes handed back."""
    total = 0.0
    for _ in range(repeats):
        with numba.objmode(planes="float64[:, ::1]"):
            planes = _qhull_planes(points)
        total += planes[0, 3]
    return total


# --- timing -------------------------------------------------------------------------------------

METHODS = ("hull3d build", "Qhull build", "Qhull build via objmode", "hull3d add", "Qhull add")


def _per_call(run, batch: int) -> float:
    """CPU time of `run()` (which makes `batch` calls) per call [s]."""
    start = time.thread_time()
    run()
    return (time.thread_time() - start) / batch


def time_point_set(points: np.ndarray, repeats: int, batch: int) -> dict[str, float]:
    """Median CPU time per call [s] of each of METHODS on `points` (see the module docstring)."""
    n = len(points)
    work = hull3d.new_hull(LIVE_POINT_CAP, LIVE_FACE_CAP)
    work[0][:n] = points
    saved = hull_of(points[:-1])  # the hull of the others, which the last point extends
    saved_arrays = (saved[0], saved[1], saved[2], saved[3], saved[4], saved[6])
    last = np.ascontiguousarray(points[-1])
    others, last_row = np.ascontiguousarray(points[:-1]), points[-1:]

    def hull3d_build():
        assert _build_repeatedly(*work, n, batch) == hull3d.STARTED

    def hull3d_add():
        assert _add_repeatedly(*saved_arrays, *work, last, batch, True) == hull3d.INSERTED

    def hull3d_restore():
        _add_repeatedly(*saved_arrays, *work, last, batch, False)

    def qhull_build():
        for _ in range(batch):
            ConvexHull(points)

    def qhull_via_objmode():
        _qhull_repeatedly(points, batch)

    for run in (hull3d_build, hull3d_add, hull3d_restore, qhull_via_objmode):
        run()  # compiled (or loaded from the cache) before timing
    samples: dict[str, list[float]] = {name: [] for name in (*METHODS, "hull3d restore")}
    for _ in range(repeats):
        samples["hull3d build"].append(_per_call(hull3d_build, batch))
        samples["hull3d add"].append(_per_call(hull3d_add, batch))
        samples["hull3d restore"].append(_per_call(hull3d_restore, batch))
        samples["Qhull build"].append(_per_call(qhull_build, batch))
        samples["Qhull build via objmode"].append(_per_call(qhull_via_objmode, batch))
        incremental = [ConvexHull(others, incremental=True) for _ in range(batch)]

        def qhull_add(hulls=incremental):
            for hull in hulls:
                hull.add_points(last_row)

        samples["Qhull add"].append(_per_call(qhull_add, batch))
        for hull in incremental:
            hull.close()
    medians = {name: statistics.median(values) for name, values in samples.items()}
    medians["hull3d add"] -= medians.pop("hull3d restore")
    return medians


def time_crossings(points: np.ndarray, repeats: int, batch: int) -> dict[str, float]:
    """Median CPU time per call [s] of an objmode crossing and of a compiled call from Python."""
    hull = hull_of(points)
    _cross_repeatedly(points, 1)
    _touch(*hull)

    def cross():
        _cross_repeatedly(points, batch)

    def dispatch():
        for _ in range(batch):
            _touch(*hull)

    return {
        "objmode crossing": statistics.median(_per_call(cross, batch) for _ in range(repeats)),
        "compiled call from Python": statistics.median(_per_call(dispatch, batch) for _ in range(repeats)),
    }


def _ratios(medians: dict[str, float], crossing: float) -> dict[str, float]:
    return {
        "build": (medians["Qhull build"] + crossing) / medians["hull3d build"],
        "add": (medians["Qhull add"] + crossing) / medians["hull3d add"],
        "build_without_crossing": medians["Qhull build"] / medians["hull3d build"],
        "add_without_crossing": medians["Qhull add"] / medians["hull3d add"],
    }


def run(cuts: list[int], sets: int, repeats: int, batch: int, seed: int = SEED) -> dict:
    rng = np.random.default_rng(seed)
    point_sets = {k: [polytope_vertices(rng, k) for _ in range(sets)] for k in cuts}
    worst_volume = max(check(points) for group in point_sets.values() for points in group)
    crossings = time_crossings(point_sets[cuts[-1]][0], repeats, 10 * batch)
    rows = []
    every: dict[str, list[float]] = {name: [] for name in METHODS}
    for k, group in point_sets.items():
        per_set = [time_point_set(points, repeats, batch) for points in group]
        medians = {name: statistics.median(m[name] for m in per_set) for name in METHODS}
        for name in METHODS:
            every[name].extend(m[name] for m in per_set)
        rows.append(
            {
                "cuts": k,
                "vertices": sorted(len(points) for points in group),
                "median_us": {name: 1e6 * value for name, value in medians.items()},
                "ratio": _ratios(medians, crossings["objmode crossing"]),
            }
        )
    overall = {name: statistics.median(values) for name, values in every.items()}
    return {
        "rows": rows,
        "all_sets": {
            "median_us": {name: 1e6 * value for name, value in overall.items()},
            "ratio": _ratios(overall, crossings["objmode crossing"]),
        },
        "crossings_median_us": {name: 1e6 * value for name, value in crossings.items()},
        "checks": {
            "point_sets": sum(len(group) for group in point_sets.values()),
            "same_vertices_volume_and_planes": True,
            "max_volume_relative_difference": worst_volume,
        },
        "sets": sets,
        "repeats": repeats,
        "batch": batch,
        "seed": seed,
        "hull_caps": [LIVE_POINT_CAP, LIVE_FACE_CAP],
        "versions": {"scipy": scipy.__version__, "numba": numba.__version__, "numpy": np.__version__},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cuts", type=int, nargs="+", default=[2, 8, 20, 36], help="half-spaces cutting the box")
    parser.add_argument("--sets", type=int, default=8, help="seeded polytopes per number of cuts")
    parser.add_argument("--repeats", type=int, default=15, help="timed batches per point set (median)")
    parser.add_argument("--batch", type=int, default=40, help="calls per timed batch")
    parser.add_argument("--out", default="benchmarks/results/hull3d.json")
    args = parser.parse_args()
    report = run(args.cuts, args.sets, args.repeats, args.batch)
    crossings = report["crossings_median_us"]
    print(
        f"{report['checks']['point_sets']} point sets: hull3d and Qhull give the same vertices, facet planes and "
        f"volume (largest relative difference {report['checks']['max_volume_relative_difference']:.1e})"
    )
    crossing = crossings["objmode crossing"]
    print(f"CPU time per call, medians [us]; ratios = (Qhull + objmode crossing {crossing:.2f} us) / hull3d")
    header = (
        f"{'vertices':<10}{'hull3d build':>13}{'Qhull build':>12}{'via objmode':>12}{'ratio':>7}"
        f"{'hull3d add':>11}{'Qhull add':>10}{'ratio':>7}"
    )
    print(header)
    print("-" * len(header))
    for row in [*report["rows"], {"vertices": None, **report["all_sets"]}]:
        us, ratio = row["median_us"], row["ratio"]
        label = "all" if row["vertices"] is None else f"{row['vertices'][0]}-{row['vertices'][-1]}"
        print(
            f"{label:<10}{us['hull3d build']:>13.2f}{us['Qhull build']:>12.2f}{us['Qhull build via objmode']:>12.2f}"
            f"{ratio['build']:>7.1f}{us['hull3d add']:>11.2f}{us['Qhull add']:>10.2f}{ratio['add']:>7.1f}"
        )
    print(
        f"Leaving compiled code: objmode crossing {crossings['objmode crossing']:.2f} us, "
        f"a compiled call with the hull's arrays from Python {crossings['compiled call from Python']:.2f} us"
    )
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(stamped(report), indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
