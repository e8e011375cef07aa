"""The Rejectable Force Polytope problem (paper 003, Eqs. 1-6 and 8) for the Go1 with or without prongs.

Dynamics (Eq. 1), with the generalised acceleration fixed at its desired value qdd_d:

    M qdd_d + h = B tau + J_c^T lambda + J_e^T F

for joint torques tau (12), contact forces lambda (3 per point contact: stance feet and prong
tips, world frame) and the disturbance F (3, world frame) at the end-effector point. The six
unactuated rows tie lambda and F; the twelve actuated rows give tau = b_a - J_c,a^T lambda -
J_e,a^T F, so the torque limits |tau| <= tau_max (Eq. 6) are linear in (F, lambda) too. With the
friction pyramids (Eqs. 2-5: lambda_z >= 0, |lambda_x|, |lambda_y| <= (sqrt(2)/2) mu lambda_z on flat ground)
every condition is linear, and the RFP (Eq. 8) is the projection onto F of

    x = [F; lambda]:   A_eq x = b_eq,   A_in x <= b_in.

The same constraints in the (tau, lambda) form of the paper's control-law approximations are
kept too: W y = b - J_e^T F with y = [tau; lambda], W = [B  J_c^T], and G_y y <= g_y.
"""

import dataclasses

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JacobianWrtVariable

from pedi_drake import robot
from pedi_drake.exceptions import SufError
from pedi_drake.friction import friction_pyramid_rows

# Contact names: the feet by leg name, the prong tips as "prong0", "prong1", ...
PRONG_PREFIX = "prong"


@dataclasses.dataclass(frozen=True)
class ContactPoint:
    """A point contact: a point fixed on a body (its frame), where a force lambda acts [m]."""

    name: str
    body: str
    p_BoC_B: np.ndarray  # the point in the body frame [m]


@dataclasses.dataclass
class RejectableForceProblem:
    """Everything a SUF method needs, as dense arrays (see the module docstring)."""

    contact_names: tuple[str, ...]
    end_effector: str
    mu: float  # friction coefficient of the pyramids [-]
    # x = [F (3); lambda (3 nc)]
    A_eq: np.ndarray  # (6, 3 + 3 nc)
    b_eq: np.ndarray  # (6,)
    A_in: np.ndarray  # (m, 3 + 3 nc)
    b_in: np.ndarray  # (m,)
    # The control-law form: W y + J_e^T F = b, G_y y <= g_y, y = [tau (12); lambda (3 nc)].
    W: np.ndarray  # (nv, 12 + 3 nc)
    Je_T: np.ndarray  # (nv, 3)
    b: np.ndarray  # (nv,) M qdd_d + h
    G_y: np.ndarray  # (m, 12 + 3 nc)
    g_y: np.ndarray  # (m,)
    p_WE: np.ndarray  # end-effector point in world [m], for plots
    torque_limits: np.ndarray  # (12,) [N m], Unitree order

    @property
    def num_contacts(self) -> int:
        return len(self.contact_names)

    @property
    def num_x(self) -> int:
        return 3 + 3 * self.num_contacts


def build_problem(
    plant: MultibodyPlant,
    q: np.ndarray,
    contacts: list[ContactPoint],
    end_effector: ContactPoint,
    *,
    mu: float = 0.6,
    qdd_desired: np.ndarray | None = None,
    torque_limits: np.ndarray | None = None,
) -> RejectableForceProblem:
    """The RFP problem of `plant` (a Go1 plant from `robot.make_go1_plant`) at positions `q`.

    Args:
        q: the plant's positions (floating base first as Drake orders them).
        contacts: the point contacts that carry the robot (feet, prong tips).
        end_effector: where the disturbance acts.
        mu: friction coefficient [-] of every contact's pyramid.
        qdd_desired: generalised acceleration to keep (nv,); zero (standing still) by default.
        torque_limits: |tau| bounds [N m] in Unitree order; the model's effort limits by default.
    """
    if not contacts:
        raise SufError("the problem needs at least one contact (stance foot or prong tip); got none")
    if not (np.isfinite(mu) and mu > 0.0):
        raise SufError(f"mu: must be a finite number > 0, got {mu!r}")
    q = np.asarray(q, dtype=float)
    if q.shape != (plant.num_positions(),) or not np.all(np.isfinite(q)):
        raise SufError(f"q: expected {plant.num_positions()} finite plant positions, got shape {q.shape}")
    plant_map = robot.Go1PlantMap.from_plant(plant)
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q)
    plant.SetVelocities(context, np.zeros(plant.num_velocities()))
    nv = plant.num_velocities()
    qdd = np.zeros(nv) if qdd_desired is None else np.asarray(qdd_desired, dtype=float)
    if qdd.shape != (nv,) or not np.all(np.isfinite(qdd)):
        raise SufError(f"qdd_desired: expected {nv} finite accelerations, got shape {qdd.shape}")
    limits = robot.EFFORT_LIMIT if torque_limits is None else np.asarray(torque_limits, dtype=float)
    if limits.shape != (12,) or np.any(~(limits > 0)):
        raise SufError(f"torque_limits: expected 12 positive limits [N m], got {limits!r}")

    M = plant.CalcMassMatrix(context)
    h = plant.CalcBiasTerm(context) - plant.CalcGravityGeneralizedForces(context)
    b = M @ qdd + h
    world = plant.world_frame()

    def jacobian(point: ContactPoint) -> tuple[np.ndarray, np.ndarray]:
        try:
            frame = plant.GetBodyByName(point.body).body_frame()
        except RuntimeError:
            raise SufError(f"{point.name}: no body named {point.body!r} in the plant") from None
        J = plant.CalcJacobianTranslationalVelocity(context, JacobianWrtVariable.kV, frame, point.p_BoC_B, world, world)
        p = plant.CalcPointsPositions(context, frame, point.p_BoC_B.reshape(3, 1), world).ravel()
        return J, p

    Jc = np.vstack([jacobian(c)[0] for c in contacts])  # (3 nc, nv)
    Je, p_WE = jacobian(end_effector)
    nc = len(contacts)
    # B maps the 12 motor torques (Unitree order) onto the joints' velocity rows.
    B = np.zeros((nv, 12))
    B[plant_map.v_index, np.arange(12)] = 1.0
    actuated = plant_map.v_index
    unactuated = np.setdiff1d(np.arange(nv), actuated)

    # x = [F; lambda]. Unactuated rows: J_c,u^T lambda + J_e,u^T F = b_u.
    A_eq = np.hstack([Je[:, unactuated].T, Jc[:, unactuated].T])
    b_eq = b[unactuated]
    # Actuated rows: tau = b_a - J_c,a^T lambda - J_e,a^T F; |tau| <= limits.
    T = -np.hstack([Je[:, actuated].T, Jc[:, actuated].T])  # tau = T x + b_a
    pyramid = friction_pyramid_rows(mu)
    friction = np.zeros((5 * nc, 3 + 3 * nc))
    for i in range(nc):
        friction[5 * i : 5 * i + 5, 3 + 3 * i : 6 + 3 * i] = pyramid
    A_in = np.vstack([T, -T, friction])
    b_in = np.concatenate([limits - b[actuated], limits + b[actuated], np.zeros(5 * nc)])

    # y = [tau; lambda]: W y + J_e^T F = b, torque box and pyramids on y.
    W = np.hstack([B, Jc.T])
    G_y = np.zeros((24 + 5 * nc, 12 + 3 * nc))
    G_y[:12, :12] = np.eye(12)
    G_y[12:24, :12] = -np.eye(12)
    for i in range(nc):
        G_y[24 + 5 * i : 29 + 5 * i, 12 + 3 * i : 15 + 3 * i] = pyramid
    g_y = np.concatenate([limits, limits, np.zeros(5 * nc)])
    return RejectableForceProblem(
        contact_names=tuple(c.name for c in contacts),
        end_effector=end_effector.name,
        mu=float(mu),
        A_eq=A_eq,
        b_eq=b_eq,
        A_in=A_in,
        b_in=b_in,
        W=W,
        Je_T=Je.T,
        b=b,
        G_y=G_y,
        g_y=g_y,
        p_WE=p_WE,
        torque_limits=limits,
    )
