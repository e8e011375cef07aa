"""The floating-base state estimate: one 13-vector shared by estimators, controllers and missions.

Layout (all in the world frame W, trunk frame B):
    [0:4]   quaternion of R_WB, (w, x, y, z)
    [4:7]   p_WB, trunk origin position [m]
    [7:10]  w_WB, trunk angular velocity expressed in W [rad/s]
    [10:13] v_WB, trunk origin translational velocity expressed in W [m/s]
This matches the order of Drake's quaternion floating joint (q = [quat, p], v = [w, v]), so
`Go1PlantMap.full_positions/full_velocities` rebuild the plant state from it directly.
"""

import dataclasses

import numpy as np
from pydrake.common.eigen_geometry import Quaternion
from pydrake.math import RigidTransform, RotationMatrix

BASE_STATE_SIZE = 13


@dataclasses.dataclass(frozen=True)
class BaseState:
    """Unpacked view of a base-state vector."""

    quaternion_wxyz: np.ndarray  # (4,)
    p_WB: np.ndarray  # (3,) [m]
    w_WB: np.ndarray  # (3,) [rad/s]
    v_WB: np.ndarray  # (3,) [m/s]

    @staticmethod
    def from_vector(x: np.ndarray) -> "BaseState":
        x = np.asarray(x, dtype=float)
        return BaseState(x[0:4], x[4:7], x[7:10], x[10:13])

    def to_vector(self) -> np.ndarray:
        return np.concatenate([self.quaternion_wxyz, self.p_WB, self.w_WB, self.v_WB])

    def rotation(self) -> RotationMatrix:
        q = self.quaternion_wxyz / np.linalg.norm(self.quaternion_wxyz)
        return RotationMatrix(Quaternion(q))

    def pose(self) -> RigidTransform:
        """X_WB."""
        return RigidTransform(self.rotation(), self.p_WB)
