"""The live SUF: the exact SUF of the stance the robot is in, from its state estimate, every update.

`LiveSuf.update` takes the state estimate, the measured joints, the loaded contacts (the mission's
contact set: feet and prong tips) and the lifted foot whose disturbance is analysed, and returns
one vector (layout below) and the warm start for the next update:

1. the RFP rows of paper 003 (Eqs. 1-6, 8) at that configuration, standing still (qdd_d = 0,
   v = 0, as `suf.problem.build_problem`), from the compiled Go1 dynamics
   (pedi_drake.control.go1_dynamics: gravity and the contact Jacobians, no Drake call);
2. the exact projection warm-started from the previous update's vertices
   (pedi_drake.suf.warm_projection), within a budget of `max_lps` LPs;
3. the SUF in the requested direction: the exact polytope's extent along it, or, when the budget
   ran out, the single-direction LP along it (and the SUF value that update is the
   single-direction SUF along the last exact worst direction: an upper bound, flagged).

Everything after the Python call is compiled and releases the GIL. A change of the contact set
(a different number of contacts) makes the next projection cold.

The vector (SUF_SIZE):

    status           NONE (no lifted foot asked for), or a warm_projection status: EXACT,
                     INCOMPLETE (single-direction values this update), INFEASIBLE, FLAT (SUF 0),
                     NUMERICAL
    leg              the end-effector leg's index (Unitree order), -1 with NONE
    value            the SUF [N] (see status)
    direction (3)    the worst force's unit direction, world
    reach            the largest rejectable force along `request` [N]
    request (3)      the unit direction asked about, world (the last worst direction when none)
    lps              LPs solved in this update
    facets           facets of the exact polytope (0 unless EXACT)
    updates          updates with a lifted foot so far
    fallbacks        of those, the ones that used the single-direction SUF (INCOMPLETE)
"""

import dataclasses
import math

import numpy as np

from pedi_drake import robot
from pedi_drake.control.go1_dynamics import Go1Dynamics, go1_dynamics
from pedi_drake.friction import friction_pyramid_rows
from pedi_drake.jit import kernel
from pedi_drake.prongs import ProngDesign
from pedi_drake.suf import hull3d
from pedi_drake.suf import warm_projection as wp
from pedi_drake.suf.ray_program import RAY_CAP

NONE = 0
SUF_SIZE = 16
_STATUS, _LEG, _VALUE, _DIRECTION, _REACH, _REQUEST, _LPS, _FACETS, _UPDATES, _FALLBACKS = (
    0,
    1,
    2,
    slice(3, 6),
    6,
    slice(7, 10),
    10,
    11,
    12,
    13,
)
# Budget of LPs per update: a cold projection of a three-foot stance takes 20 to 30, a warm one
# along a teleoperated path 0 to 10 (pedi_drake.benchmarks.live_suf).
DEFAULT_MAX_LPS = 60
# Hull sizes of the live projection (the Go1's polytopes have 20 to 60 vertices).
LIVE_POINT_CAP = 200
LIVE_FACE_CAP = 800


@dataclasses.dataclass(frozen=True)
class LiveSufReading:
    """One live SUF vector, by field (see the module docstring)."""

    status: int
    leg: int
    value: float  # [N]
    direction: np.ndarray  # (3,) world
    reach: float  # [N] along `request`
    request: np.ndarray  # (3,) world
    lps: int
    facets: int
    updates: int
    fallbacks: int

    @staticmethod
    def from_vector(x: np.ndarray) -> "LiveSufReading":
        x = np.asarray(x, float)
        return LiveSufReading(
            status=int(x[_STATUS]),
            leg=int(x[_LEG]),
            value=float(x[_VALUE]),
            direction=x[_DIRECTION].copy(),
            reach=float(x[_REACH]),
            request=x[_REQUEST].copy(),
            lps=int(x[_LPS]),
            facets=int(x[_FACETS]),
            updates=int(x[_UPDATES]),
            fallbacks=int(x[_FALLBACKS]),
        )

    @property
    def exact(self) -> bool:
        return self.status == wp.EXACT

    @property
    def usable(self) -> bool:
        """Whether `value` and `reach` describe this stance (exact, or the single-direction SUF)."""
        return self.status in (wp.EXACT, wp.INCOMPLETE, wp.INFEASIBLE, wp.FLAT)


def idle_vector(previous: np.ndarray | None = None) -> np.ndarray:
    """The vector of an update with no lifted foot (counters kept from `previous`)."""
    x = np.zeros(SUF_SIZE)
    x[_LEG] = -1.0
    x[_VALUE] = x[_REACH] = math.nan
    if previous is not None:
        x[_UPDATES], x[_FALLBACKS] = previous[_UPDATES], previous[_FALLBACKS]
    return x


@kernel
def rfp_rows(out_record, contact_loaded, effector, pyramid, limits, v_actuated, base_v):
    """(A_eq, b_eq, A_in, b_in) of paper 003's RFP over x = [F; lambda], as
    `suf.problem.build_problem` writes them, from a `go1_dynamics` output at zero velocity.

    contact_loaded (nc,) > 0.5 marks the contacts that carry the robot (controller order: feet,
    then prong tips); effector: the contact index of the end-effector foot; pyramid (5, 3): the
    friction rows of one contact; limits (12,) [N m], v_actuated (12,): the plant velocity index
    of each Unitree joint; base_v: the trunk's first velocity index.
    """
    out = out_record[0]
    J = out.J_contacts  # (3 nc_all, nv)
    b = out.h  # M qdd_d + h at qdd_d = 0, v = 0: -tau_g [N m, N]
    nc_all = contact_loaded.shape[0]
    loaded = np.zeros(nc_all, dtype=np.int64)
    nc = 0
    for c in range(nc_all):
        if contact_loaded[c] > 0.5 and c != effector:
            loaded[nc] = c
            nc += 1
    nx = 3 + 3 * nc
    A_eq = np.zeros((6, nx))
    b_eq = np.zeros(6)
    for i in range(6):
        v = base_v + i
        for k in range(3):
            A_eq[i, k] = J[3 * effector + k, v]
        for j in range(nc):
            for k in range(3):
                A_eq[i, 3 + 3 * j + k] = J[3 * loaded[j] + k, v]
        b_eq[i] = b[v]
    A_in = np.zeros((24 + 5 * nc, nx))
    b_in = np.zeros(24 + 5 * nc)
    for u in range(12):
        v = v_actuated[u]
        # tau = T x + b_a with T = -[J_e,a^T  J_c,a^T]; |tau| <= limits.
        for k in range(3):
            A_in[u, k] = -J[3 * effector + k, v]
        for j in range(nc):
            for k in range(3):
                A_in[u, 3 + 3 * j + k] = -J[3 * loaded[j] + k, v]
        for k in range(nx):
            A_in[12 + u, k] = -A_in[u, k]
        b_in[u] = limits[u] - b[v]
        b_in[12 + u] = limits[u] + b[v]
    for j in range(nc):
        for r in range(5):
            for k in range(3):
                A_in[24 + 5 * j + r, 3 + 3 * j + k] = pyramid[r, k]
    return A_eq, b_eq, A_in, b_in


@kernel
def live_suf_kernel(
    model_record,
    out_record,
    base_state,
    q_joints,
    contact_loaded,
    effector,
    pyramid,
    limits,
    v_actuated,
    base_v,
    request,
    warm_directions,
    warm_active,
    warm_num_active,
    num_warm,
    warm_rows,
    warm_nz,
    last_direction,
    tol,
    max_lps,
    result,
    next_directions,
    next_active,
    next_num_active,
    next_shape,
):
    """One live update (see the module docstring): fills `result` (SUF_SIZE, counters as given)
    and the next warm start (next_* arrays; next_shape = [vertices, rows, nz])."""
    state = base_state.copy()
    for i in range(7, 13):
        state[i] = 0.0
    go1_dynamics(model_record, state, q_joints, np.zeros(12), out_record)
    A_eq, b_eq, A_in, b_in = rfp_rows(out_record, contact_loaded, effector, pyramid, limits, v_actuated, base_v)
    G, h, N_F, F0, feasible = wp.eliminate_equalities(A_eq, b_eq, A_in, b_in, RAY_CAP)
    m, nz = G.shape[0], G.shape[1]
    next_shape[0], next_shape[1], next_shape[2] = 0, m, nz
    result[_LEG] = effector
    result[_UPDATES] += 1.0
    for i in range(3):
        result[7 + i] = request[i]
    if not feasible:
        result[_STATUS], result[_VALUE], result[_REACH], result[_LPS], result[_FACETS] = wp.INFEASIBLE, 0.0, 0.0, 0, 0
        return
    use_warm = num_warm if (warm_rows == m and warm_nz == nz) else 0
    hull = hull3d.new_hull(LIVE_POINT_CAP, LIVE_FACE_CAP)
    meta = (
        np.zeros((LIVE_POINT_CAP, 3)),
        np.zeros((LIVE_POINT_CAP, max(nz, 1)), dtype=np.int64),
        np.zeros(LIVE_POINT_CAP, dtype=np.int64),
    )
    status, lps = wp.project(
        G, h, N_F, F0, warm_directions, warm_active, warm_num_active, use_warm, tol, max_lps, hull, meta
    )
    result[_STATUS] = status
    result[_LPS] = lps
    result[_FACETS] = 0
    if status == wp.EXACT or status == wp.INCOMPLETE:
        next_shape[0] = wp.vertex_warm_start(hull, meta, next_directions, next_active, next_num_active)
    points, faces, normals, offsets, alive, certified, counts = hull
    if status == wp.EXACT:
        direction = np.zeros(3)
        value = hull3d.smallest_offset(normals, offsets, alive, counts, direction)
        result[_VALUE] = max(value, 0.0)
        for i in range(3):
            result[3 + i] = direction[i]
        result[_REACH] = max(hull3d.ray_length(normals, offsets, alive, counts, request), 0.0)
        facets = 0
        for f in range(counts[1]):
            if alive[f] == 1:
                unique = True
                for g in range(f):
                    if alive[g] == 1 and abs(offsets[g] - offsets[f]) <= wp.HULL_EPS:
                        difference = 0.0
                        for i in range(3):
                            difference = max(difference, abs(normals[g, i] - normals[f, i]))
                        if difference <= wp.SAME_NORMAL:
                            unique = False
                            break
                if unique:
                    facets += 1
        result[_FACETS] = facets
        return
    if status == wp.INFEASIBLE or status == wp.FLAT:
        result[_VALUE], result[_REACH] = 0.0, 0.0
        return
    if status == wp.INCOMPLETE:
        result[_FALLBACKS] += 1.0
    # The single-direction SUF: along the request, and along the last worst direction.
    ray_status, reach = wp.ray_suf(G, h, N_F, F0, request)
    value_status, value = wp.ray_suf(G, h, N_F, F0, last_direction)
    result[_LPS] = lps + 2
    if ray_status == wp.INFEASIBLE or value_status == wp.INFEASIBLE:
        result[_STATUS], result[_VALUE], result[_REACH] = wp.INFEASIBLE, 0.0, 0.0
        return
    if ray_status != wp.EXACT or value_status != wp.EXACT:
        result[_STATUS], result[_VALUE], result[_REACH] = wp.NUMERICAL, math.nan, math.nan
        return
    result[_VALUE], result[_REACH] = value, reach
    for i in range(3):
        result[3 + i] = last_direction[i]


def contact_index(leg: str) -> int:
    """The controller's contact index of a foot (Unitree leg order)."""
    return robot.LEG_NAMES.index(leg)


class LiveSuf:
    """The live SUF of one robot variant (see the module docstring); holds no changing state."""

    def __init__(
        self,
        prongs: ProngDesign | None = None,
        *,
        mu: float = 0.6,
        torque_limits: np.ndarray | None = None,
        tol: float = wp.TOLERANCE,
        max_lps: int = DEFAULT_MAX_LPS,
    ):
        """
        Args:
            prongs: the robot's prongs (their tips are contacts when loaded), or None.
            mu: friction coefficient of every contact's pyramid [-].
            torque_limits: |tau| bounds [N m] in Unitree order; the model's effort limits by default.
            tol: certification tolerance of a facet [N].
            max_lps: LPs one update may solve before it falls back to the single-direction SUF.
        """
        self._dynamics = Go1Dynamics(prongs)
        self.num_contacts = self._dynamics.num_contacts
        self._pyramid = np.ascontiguousarray(friction_pyramid_rows(mu))
        self._limits = np.ascontiguousarray(robot.EFFORT_LIMIT if torque_limits is None else torque_limits, float)
        self._v_actuated = np.ascontiguousarray(self._dynamics.plant_map.v_index, dtype=np.int64)
        self._base_v = int(self._dynamics.plant_map.base_v_start)
        self.tol, self.max_lps = float(tol), int(max_lps)
        self._warm_up()

    def _warm_up(self) -> None:
        """Compiles the kernels (or loads them from numba's cache): never inside a control tick."""
        base = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.27, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        loaded = np.concatenate([[0.0, 1.0, 1.0, 1.0], np.zeros(self.num_contacts - 4)])
        vector, warm = self.update(None, idle_vector(), base, robot.STANDING_Q, loaded, 0, np.array([1.0, 0, 0]))
        # Once more from the warm start, and once with a budget that runs out (the fallback path).
        self.update(warm, vector, base, robot.STANDING_Q, loaded, 0, np.array([1.0, 0, 0]))
        budget, self.max_lps = self.max_lps, 1
        self.update(None, vector, base, robot.STANDING_Q, loaded, 0, np.array([1.0, 0, 0]))
        self.max_lps = budget

    def update(
        self,
        warm: wp.WarmStart | None,
        previous: np.ndarray,
        base_state: np.ndarray,
        q_joints: np.ndarray,
        contact_set: np.ndarray,
        effector: int,
        request: np.ndarray,
    ) -> tuple[np.ndarray, wp.WarmStart | None]:
        """(the SUF vector, the next warm start) for the foot of leg index `effector` with the
        contacts `contact_set` (> 0.5: loaded; 4 feet then prong tips) at the estimate
        `base_state` (13,) and joints `q_joints` (12,) [rad]; `request` (3,): the direction to
        report the reach along (zero: the last worst direction); `previous`: the last vector."""
        result = np.array(previous, dtype=float)
        last = result[_DIRECTION]
        last_direction = last / np.linalg.norm(last) if np.linalg.norm(last) > 0.5 else np.array([0.0, 0.0, -1.0])
        norm = float(np.linalg.norm(request))
        request = np.asarray(request, float) / norm if norm > 1e-9 else last_direction
        loaded = np.zeros(self.num_contacts)
        count = min(len(contact_set), self.num_contacts)
        loaded[:count] = np.asarray(contact_set, float)[:count]
        if warm is None:
            directions, active, num_active, num_warm, rows, nz = (
                np.zeros((1, 3)),
                np.zeros((1, 1), np.int64),
                np.zeros(1, np.int64),
                0,
                -1,
                -1,
            )
        else:
            directions, active, num_active = warm.directions, warm.active, warm.num_active
            num_warm, rows, nz = len(warm.directions), warm.num_rows, warm.nz
        max_nz = 3 + 3 * self.num_contacts
        next_directions = np.zeros((LIVE_POINT_CAP, 3))
        next_active = np.zeros((LIVE_POINT_CAP, max_nz), np.int64)
        next_num_active = np.zeros(LIVE_POINT_CAP, np.int64)
        next_shape = np.zeros(3, np.int64)
        live_suf_kernel(
            self._dynamics.model_record,
            self._dynamics.new_output(),
            np.ascontiguousarray(base_state, dtype=float),
            np.ascontiguousarray(q_joints, dtype=float),
            loaded,
            int(effector),
            self._pyramid,
            self._limits,
            self._v_actuated,
            self._base_v,
            np.ascontiguousarray(request, dtype=float),
            np.ascontiguousarray(directions, dtype=float),
            np.ascontiguousarray(active, dtype=np.int64),
            np.ascontiguousarray(num_active, dtype=np.int64),
            int(num_warm),
            int(rows),
            int(nz),
            np.ascontiguousarray(last_direction, dtype=float),
            self.tol,
            self.max_lps,
            result,
            next_directions,
            next_active,
            next_num_active,
            next_shape,
        )
        k, rows, nz = (int(v) for v in next_shape)
        next_warm = None
        if k >= 4:
            next_warm = wp.WarmStart(
                next_directions[:k].copy(), next_active[:k, :nz].copy(), next_num_active[:k].copy(), rows, nz
            )
        return result, next_warm
