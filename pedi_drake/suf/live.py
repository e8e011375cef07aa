"""The live SUF: the exact SUF of the stance the robot is in, from its state estimate, every update.

`LiveSuf.update` takes the state estimate, the measured joints, the loaded contacts (the mission's
contact set: feet and prong tips) and the lifted foot whose disturbance is analysed, and returns
one vector (layout below) and the warm start for the next update:

1. the RFP rows of paper 003 (Eqs. 1-6, 8) at that configuration, standing still (qdd_d = 0,
   v = 0, as `suf.problem.build_problem`), from the compiled Go1 dynamics
   (pedi_drake.dynamics.go1_dynamics: gravity and the contact Jacobians, no Drake call);
2. the exact projection warm-started from the previous update's vertices
   (pedi_drake.suf.warm_projection), within a budget of `max_lps` LPs;
3. the SUF in the requested direction: the exact polytope's extent along it, or, when the budget
   ran out, the single-direction LP along it (and the SUF value that update is the
   single-direction SUF along the last exact worst direction: an upper bound, flagged).

Everything after the Python call is compiled and releases the GIL. A change of the contact set
(a different number of contacts) makes the next projection cold.

The same update can be done in pieces: `LiveSuf.start` puts its inputs into a `LiveSufWorkspace`
(allocated once, reused by every update), and each `LiveSuf.advance` goes on with it for a budget
of work counted in LPs (step 1 first, then step 2 step by step, then step 3;
warm_projection.project_within), so a control loop can spread it over its ticks. Any sequence of
budgets gives the vector and warm start of `update`, bit for bit.

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
    slices           the calls (control ticks, in a LiveSufSystem) this update took
    stance_time      the time of the inputs (the stance) this update describes [s] (NaN: not given)
"""

import copy
import dataclasses
import math

import numpy as np

from pedi_drake import robot
from pedi_drake.dynamics.go1_dynamics import Go1Dynamics, go1_dynamics
from pedi_drake.friction import friction_pyramid_rows
from pedi_drake.prongs import ProngDesign
from pedi_drake.runtime.jit import kernel
from pedi_drake.suf import hull3d
from pedi_drake.suf import warm_projection as wp
from pedi_drake.suf.ray_program import RAY_CAP

NONE = 0
SUF_SIZE = 16
_STATUS, _LEG, _VALUE, _DIRECTION, _REACH, _REQUEST, _LPS, _FACETS, _UPDATES, _FALLBACKS, _SLICES, _STANCE_TIME = (
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
    14,
    15,
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
    slices: int = 1
    stance_time: float = math.nan  # [s]

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
            slices=int(x[_SLICES]),
            stance_time=float(x[_STANCE_TIME]),
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
    x[_VALUE] = x[_REACH] = x[_STANCE_TIME] = math.nan
    if previous is not None:
        x[_UPDATES], x[_FALLBACKS] = previous[_UPDATES], previous[_FALLBACKS]
    return x


def without_timing(x: np.ndarray) -> np.ndarray:
    """A copy of the vector `x` with its `slices` and `stance_time` zeroed: what one update has
    in common however many calls it took and whenever it ran."""
    y = np.array(x, dtype=float)
    y[_SLICES] = y[_STANCE_TIME] = 0.0
    return y


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
def live_rows(
    model_record, out_record, base_state, q_joints, contact_loaded, effector, pyramid, limits, v_actuated, base_v
):
    """(G, h, N_F, F_0, feasible): the LP rows of one live update (`warm_projection.eliminate_equalities`
    of the RFP rows at the estimated configuration, standing still); arguments as `rfp_rows`'s,
    the estimate `base_state` (13,) and the joints `q_joints` (12,) [rad]."""
    state = base_state.copy()
    for i in range(7, 13):
        state[i] = 0.0
    go1_dynamics(model_record, state, q_joints, np.zeros(12), out_record)
    A_eq, b_eq, A_in, b_in = rfp_rows(out_record, contact_loaded, effector, pyramid, limits, v_actuated, base_v)
    return wp.eliminate_equalities(A_eq, b_eq, A_in, b_in, RAY_CAP)


@kernel
def live_slice(
    G,
    h,
    N_F,
    F0,
    feasible,
    effector,
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
    points,
    faces,
    normals,
    offsets,
    alive,
    certified,
    counts,
    directions,
    actives,
    num_actives,
    progress,
    budget,
    result,
    next_directions,
    next_active,
    next_num_active,
    next_shape,
):
    """Goes on with one live update (see the module docstring) for at most about `budget` work
    [LP, warm_projection.project_within]; (done, work). When done, `result` (SUF_SIZE, counters
    as given) holds its vector and the next_* arrays the next warm start (next_shape = [vertices,
    rows, nz]); until then the hull's arrays (points to counts, hull3d), the points' `directions`,
    `actives` and `num_actives` (project_within's meta) and `progress` hold the projection so far.
    (Arrays one by one, not in tuples: numba types a tuple argument far more slowly.)"""
    hull = (points, faces, normals, offsets, alive, certified, counts)
    meta = (directions, actives, num_actives)
    m, nz = G.shape[0], G.shape[1]
    result[_SLICES] += 1.0
    work = 0.0
    status = wp.INFEASIBLE
    if feasible:
        use_warm = num_warm if (warm_rows == m and warm_nz == nz) else 0
        status, work = wp.project_within(
            G, h, N_F, F0, warm_directions, warm_active, warm_num_active, use_warm, tol, max_lps, hull, meta,
            progress, budget,
        )  # fmt: skip
        if status == wp.PENDING or work >= budget:
            return False, work  # the rest (and the finishing step) in later calls
    next_shape[0], next_shape[1], next_shape[2] = 0, m, nz
    result[_LEG] = effector
    result[_UPDATES] += 1.0
    for i in range(3):
        result[7 + i] = request[i]
    result[_STATUS] = status
    result[_LPS] = wp.progress_lps(progress)
    result[_FACETS] = 0
    if status == wp.INFEASIBLE or status == wp.FLAT:
        result[_VALUE], result[_REACH] = 0.0, 0.0
        return True, work
    if status == wp.EXACT or status == wp.INCOMPLETE:
        next_shape[0] = wp.vertex_warm_start(hull, meta, next_directions, next_active, next_num_active)
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
        return True, work
    if status == wp.INCOMPLETE:
        result[_FALLBACKS] += 1.0
    # The single-direction SUF: along the request, and along the last worst direction.
    ray_status, reach = wp.ray_suf(G, h, N_F, F0, request)
    value_status, value = wp.ray_suf(G, h, N_F, F0, last_direction)
    result[_LPS] += 2
    work += 2 * wp.LP_WORK
    if ray_status == wp.INFEASIBLE or value_status == wp.INFEASIBLE:
        result[_STATUS], result[_VALUE], result[_REACH] = wp.INFEASIBLE, 0.0, 0.0
        return True, work
    if ray_status != wp.EXACT or value_status != wp.EXACT:
        result[_STATUS], result[_VALUE], result[_REACH] = wp.NUMERICAL, math.nan, math.nan
        return True, work
    result[_VALUE], result[_REACH] = value, reach
    for i in range(3):
        result[3 + i] = last_direction[i]
    return True, work


def contact_index(leg: str) -> int:
    """The controller's contact index of a foot (Unitree leg order)."""
    return robot.LEG_NAMES.index(leg)


@dataclasses.dataclass
class LiveSufWorkspace:
    """Everything one live update carries from one call of `LiveSuf.advance` to the next, and the
    warm start one update leaves the next: arrays allocated once (`LiveSuf.new_workspace`) and
    reused by every update, changed in place.

    A LiveSufSystem keeps it as abstract state of its Context, which its discrete updates change
    in place: no array is copied or allocated per control tick (an unrestricted update would
    copy it twice per event), and nothing else reads it. Copying it (`copy.deepcopy`, as a Context
    is cloned) copies every array, so a clone goes on alone.
    """

    hull: tuple  # hull3d arrays (LIVE_POINT_CAP points, LIVE_FACE_CAP faces)
    meta: tuple  # project_within's meta: each point's direction, active set and its size
    progress: np.ndarray  # warm_projection.new_progress
    warm: tuple  # (directions, active sets, their sizes) of the warm start in use
    warm_shape: np.ndarray  # int64 [vertices, rows, nz] of `warm` (fewer than 4 vertices: none)
    spare: tuple  # the same arrays, for the warm start the update under way leaves
    spare_shape: np.ndarray
    result: np.ndarray  # (SUF_SIZE,) the vector of the update under way (the last one's when done)
    base_state: np.ndarray  # (13,) the update's inputs
    q_joints: np.ndarray  # (12,) [rad]
    loaded: np.ndarray  # (num_contacts,) > 0.5: loaded
    request: np.ndarray  # (3,) unit, world
    last_direction: np.ndarray  # (3,) unit, world
    dynamics: np.ndarray | None = None  # the Go1 dynamics' output record (go1_dynamics)
    effector: int = -1
    rows: tuple | None = None  # (G, h, N_F, F_0, feasible) of the update under way, once built
    under_way: bool = False  # an update started and not yet done

    def warm_start(self) -> wp.WarmStart | None:
        """A copy of the warm start in use (None: the next update is cold)."""
        k, rows, nz = (int(v) for v in self.warm_shape)
        if k < 4:
            return None
        directions, active, num_active = self.warm
        return wp.WarmStart(directions[:k].copy(), active[:k, :nz].copy(), num_active[:k].copy(), rows, nz)

    def set_warm_start(self, warm: wp.WarmStart | None) -> None:
        """Makes `warm` (None: none) the warm start of the next update."""
        self.warm_shape[:] = (0, -1, -1)
        if warm is not None:
            k, nz = len(warm.directions), warm.nz
            directions, active, num_active = self.warm
            directions[:k], active[:k, :nz], num_active[:k] = warm.directions, warm.active, warm.num_active
            self.warm_shape[:] = (k, warm.num_rows, nz)

    def __deepcopy__(self, memo) -> "LiveSufWorkspace":
        return dataclasses.replace(
            self,
            **{
                field.name: copy.deepcopy(getattr(self, field.name), memo)
                for field in dataclasses.fields(self)
                if isinstance(getattr(self, field.name), np.ndarray | tuple)
            },
        )


# The work of the rows (the Go1's dynamics and the equalities eliminated), charged to an update's
# first `advance` [LP]. Alone, the rows cost what six LPs do (measured as warm_projection's
# constants); in the control loop, with its caches cold, they cost what about
# fifteen LPs of a slice do (pedi_drake.benchmarks.suf_offload --replay: the live SUF's handler at
# its start tick against the ticks after it), and a tick is what the budget is for.
ROWS_WORK = 15.0


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
        self._max_nz = 3 + 3 * self.num_contacts
        self.tol, self.max_lps = float(tol), int(max_lps)
        self._warm_up()

    def _warm_up(self) -> None:
        """Compiles the kernels (or loads them from numba's cache): never inside a control tick."""
        base = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.27, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        loaded = np.concatenate([[0.0, 1.0, 1.0, 1.0], np.zeros(self.num_contacts - 4)])
        push = np.array([1.0, 0.0, 0.0])
        vector, warm = self.update(None, idle_vector(), base, robot.STANDING_Q, loaded, 0, push)
        # Once more from the warm start, in small slices, and once with a budget that runs out
        # (the fallback path).
        work = self.new_workspace()
        work.set_warm_start(warm)
        self.start(work, vector, base, robot.STANDING_Q, loaded, 0, push)
        while work.under_way:
            self.advance(work, 1.0)
        budget, self.max_lps = self.max_lps, 1
        self.update(None, vector, base, robot.STANDING_Q, loaded, 0, push)
        self.max_lps = budget

    def new_workspace(self) -> LiveSufWorkspace:
        """A workspace for this robot's updates, with no warm start."""

        def warm_arrays():
            return (
                np.zeros((LIVE_POINT_CAP, 3)),
                np.zeros((LIVE_POINT_CAP, self._max_nz), np.int64),
                np.zeros(LIVE_POINT_CAP, np.int64),
            )

        return LiveSufWorkspace(
            hull=hull3d.new_hull(LIVE_POINT_CAP, LIVE_FACE_CAP),
            meta=warm_arrays(),
            progress=wp.new_progress(),
            warm=warm_arrays(),
            warm_shape=np.array([0, -1, -1], np.int64),
            spare=warm_arrays(),
            spare_shape=np.array([0, -1, -1], np.int64),
            result=idle_vector(),
            base_state=np.zeros(13),
            q_joints=np.zeros(12),
            loaded=np.zeros(self.num_contacts),
            request=np.zeros(3),
            last_direction=np.zeros(3),
            dynamics=self._dynamics.new_output(),
        )

    def start(
        self,
        work: LiveSufWorkspace,
        previous: np.ndarray,
        base_state: np.ndarray,
        q_joints: np.ndarray,
        contact_set: np.ndarray,
        effector: int,
        request: np.ndarray,
        stance_time: float = math.nan,
    ) -> None:
        """Starts in `work` (from its warm start) an update of the foot of leg index `effector`
        with the contacts `contact_set` (> 0.5: loaded; 4 feet then prong tips) at the estimate
        `base_state` (13,) and joints `q_joints` (12,) [rad], read at `stance_time` [s];
        `request` (3,): the direction to report the reach along (zero: the last worst direction);
        `previous`: the last vector. Nothing is computed until `advance`."""
        work.result[:] = previous
        work.result[_SLICES] = 0.0
        work.result[_STANCE_TIME] = stance_time
        last = work.result[_DIRECTION]
        size = float(np.linalg.norm(last))
        work.last_direction[:] = last / size if size > 0.5 else (0.0, 0.0, -1.0)
        norm = float(np.linalg.norm(request))
        work.request[:] = np.asarray(request, float) / norm if norm > 1e-9 else work.last_direction
        work.base_state[:] = base_state
        work.q_joints[:] = q_joints
        work.loaded[:] = 0.0
        count = min(len(contact_set), self.num_contacts)
        work.loaded[:count] = np.asarray(contact_set, float)[:count]
        work.effector = int(effector)
        work.progress[:] = 0
        work.rows = None
        work.under_way = True

    def advance(self, work: LiveSufWorkspace, budget: float = math.inf) -> float:
        """Goes on with the update under way in `work` for about `budget` work [LP]
        (warm_projection.project_within; the first call also builds the rows, ROWS_WORK); the
        work done [LP]. When it is done (`work.under_way` false) its vector is `work.result` and
        its warm start that of the next update. Any sequence of budgets gives the same vector
        and warm start as one call with an infinite one."""
        if not work.under_way:
            return 0.0
        done_work = 0.0
        if work.rows is None:
            work.rows = live_rows(
                self._dynamics.model_record,
                work.dynamics,
                work.base_state,
                work.q_joints,
                work.loaded,
                work.effector,
                self._pyramid,
                self._limits,
                self._v_actuated,
                self._base_v,
            )
            done_work = ROWS_WORK
        G, h, N_F, F0, feasible = work.rows
        num_warm, rows, nz = (int(v) for v in work.warm_shape)
        done, slice_work = live_slice(
            G,
            h,
            N_F,
            F0,
            feasible,
            work.effector,
            work.request,
            *work.warm,
            num_warm,
            rows,
            nz,
            work.last_direction,
            self.tol,
            self.max_lps,
            *work.hull,
            *work.meta,
            work.progress,
            float(budget - done_work),
            work.result,
            *work.spare,
            work.spare_shape,
        )
        if done:
            # The warm start this update leaves becomes the one in use.
            work.warm, work.spare = work.spare, work.warm
            work.warm_shape, work.spare_shape = work.spare_shape, work.warm_shape
            work.under_way = False
        return done_work + slice_work

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
        """A whole update in one call, from the warm start `warm` (None: cold; the rest as
        `start`'s): (the SUF vector, the next warm start)."""
        work = self.new_workspace()
        work.set_warm_start(warm)
        self.start(work, previous, base_state, q_joints, contact_set, effector, request)
        self.advance(work)
        return work.result.copy(), work.warm_start()
