"""The dynamics terms every whole-body control task is built from, at one instant.

Velocity coordinates are the plant's: v = [w_WB (3, world); v_WB (3, world); joint rates], with
the joints at `plant_map.v_index` in Unitree order. Filled by `ControllerModel.update` (from
`Go1Dynamics` or, for reference, from Drake).
"""

import dataclasses

import numpy as np


@dataclasses.dataclass
class RobotSnapshot:
    """Dynamics terms at the current estimate. Shapes use nv = 18 and nc contacts."""

    q: np.ndarray  # (nq,) plant positions
    v: np.ndarray  # (nv,) plant velocities
    M: np.ndarray  # (nv, nv) mass matrix, reflected rotor inertia included [kg, kg m, kg m^2]
    h: np.ndarray  # (nv,) C(q, v) v - tau_g(q) + joint damping: all but M vdot on the dynamics' left side
    J_contacts: np.ndarray  # (3 nc, nv) world translational Jacobians of the contact points
    Jdot_v_contacts: np.ndarray  # (3 nc,) their bias accelerations [m/s^2]
    p_contacts: np.ndarray  # (nc, 3) contact point positions in world [m]
    J_trunk: np.ndarray  # (6, nv) trunk spatial Jacobian [angular; translational], world frame
    Jdot_v_trunk: np.ndarray  # (6,) trunk spatial bias acceleration
    R_WB: np.ndarray  # (3, 3) trunk orientation
    p_WB: np.ndarray  # (3,) trunk origin [m]
    p_com: np.ndarray  # (3,) centre of mass in world [m]
    J_com: np.ndarray  # (3, nv) centre-of-mass Jacobian
    Jdot_v_com: np.ndarray  # (3,) centre-of-mass bias acceleration [m/s^2]
    q_joints: np.ndarray  # (12,) Unitree order [rad]
    v_joints: np.ndarray  # (12,) Unitree order [rad/s]
    V_trunk: np.ndarray  # (6,) trunk spatial velocity [w; v] in world [rad/s, m/s]
    v_com: np.ndarray  # (3,) centre-of-mass velocity in world [m/s]
    # (T, t0) of the torque map (tau = T x + t0), filled on first use.
    torque_map: tuple[np.ndarray, np.ndarray] | None = None
    # ControllerModel.calf_orientation of the legs with a 5-D foot task, by Unitree leg index.
    calf_orientations: dict = dataclasses.field(default_factory=dict)

    @property
    def num_contacts(self) -> int:
        return self.p_contacts.shape[0]
