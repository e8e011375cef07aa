"""How far the capture point stayed inside the Mission Manager's safety polygon (evaluation only).

The capture point is the whole-body controller's own (its diagnostics), the polygon the one the
manager sent it (logged `mission.safety_polygon`); both are in the estimate's world frame, as
the controller saw them.
"""

import numpy as np

from pedi_drake import robot
from pedi_drake.control.references import safety_polygon_vertices_W
from pedi_drake.control.whole_body_controller import diagnostics_layout
from pedi_drake.polygon import polygon_halfplanes


def polygon_margin(point_xy: np.ndarray, vertices_W: np.ndarray) -> float:
    """Signed margin of `point_xy` [m] in the convex polygon `vertices_W` (k, 2) [m].

    The smallest slack d_i - n_i p over the polygon's edges: inside, the distance to the nearest
    edge; outside, negative (minus the distance past the most violated edge's line).
    """
    N, d = polygon_halfplanes(vertices_W, 0.0)
    return float(np.min(d - N @ np.asarray(point_xy, float)))


def three_leg_margin(
    times: np.ndarray, diagnostics: np.ndarray, polygons: np.ndarray, contact_sets: np.ndarray, phases: list[dict]
) -> dict | None:
    """The smallest capture-point margin [m] while exactly three feet were in the contact set.

    Args:
        times: (n,) sample times of the three logs [s] (logged at the same period).
        diagnostics: (m, n) controller diagnostics (`diagnostics_layout`).
        polygons: (20, n) the manager's `safety_polygon` output.
        contact_sets: (4 + prongs, n) the manager's `contact_set` output; prong tips may be loaded.
        phases: result.json's `phases`, to name the phase of the worst sample.

    Returns:
        {"min": margin [m], "t": its time [s], "phase": its phase, "samples": samples judged}, or
        None when no sample had three feet in the contact set and a polygon.
    """
    n = min(len(times), diagnostics.shape[1], polygons.shape[1], contact_sets.shape[1])
    capture_point = diagnostics[diagnostics_layout(contact_sets.shape[0])["capture_point"], :n]
    feet = np.sum(contact_sets[: len(robot.LEG_NAMES), :n] > 0.5, axis=0)
    best = None
    count = 0
    for k in np.flatnonzero((feet == 3) & (np.round(polygons[0, :n]) >= 3)):
        margin = polygon_margin(capture_point[:, k], safety_polygon_vertices_W(polygons[:, k]))
        count += 1
        if best is None or margin < best[0]:
            best = (margin, float(times[k]))
    if best is None:
        return None
    phase = next(
        (p["name"] for p in phases if p["t_start"] <= best[1] and (p["t_end"] is None or best[1] <= p["t_end"])), None
    )
    return {"min": best[0], "t": best[1], "phase": phase, "samples": count}
