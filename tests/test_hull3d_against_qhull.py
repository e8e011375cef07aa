"""The compiled incremental hull (pedi_drake.suf.hull3d) has Qhull's vertices and volume
(scipy.spatial.ConvexHull) on seeded point sets: clouds with points inside, and the vertices of
force polytopes with polygonal facets as the SUF projection finds them, built at once and grown one
point at a time."""

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from pedi_drake.benchmarks.hull3d import polytope_vertices
from pedi_drake.suf import hull3d
from pedi_drake.suf.warm_projection import HULL_EPS


def _point_sets():
    rng = np.random.default_rng(11)
    clouds = [rng.normal(scale=(120.0, 80.0, 300.0), size=(n, 3)) + (0.0, 0.0, 100.0) for n in (8, 30, 80)]
    polytopes = [polytope_vertices(rng, cuts) for cuts in (2, 12, 36)]
    return [*clouds, *polytopes]


POINT_SETS = _point_sets()


def _vertices_and_volume(hull) -> tuple[set[int], float]:
    points, faces, normals, _, alive, _, counts = hull
    live = np.flatnonzero(alive[: counts[1]] == 1)
    live = live[np.abs(normals[live]).sum(axis=1) > 0.0]
    corners = points[faces[live]]
    volume = np.linalg.det(corners - corners.reshape(-1, 3).mean(axis=0)).sum() / 6.0
    return {int(k) for k in np.unique(faces[live])}, float(volume)


@pytest.mark.parametrize("grown", [False, True], ids=["built", "grown"])
@pytest.mark.parametrize("points", POINT_SETS, ids=[f"set{i}" for i in range(len(POINT_SETS))])
def test_hull3d_has_qhulls_vertices_and_volume(points, grown):
    hull = hull3d.new_hull(200, 800)
    first = 6 if grown else len(points)
    hull[0][:first] = points[:first]
    assert hull3d.start_hull(*hull, first, HULL_EPS) == hull3d.STARTED
    indices = list(range(first))
    for k in range(first, len(points)):  # one by one, as the projection's LPs find them
        status = hull3d.insert_point(*hull, np.ascontiguousarray(points[k]), HULL_EPS)
        assert status in (hull3d.INSERTED, hull3d.INSIDE)
        if status == hull3d.INSERTED:
            indices.append(k)  # stored at the next free index; an inside point is not stored
    vertices, volume = _vertices_and_volume(hull)
    qhull = ConvexHull(points)
    assert {indices[k] for k in vertices} == {int(k) for k in qhull.vertices}
    assert volume == pytest.approx(qhull.volume, rel=1e-9)
