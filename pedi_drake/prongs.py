"""Prong designs: rigid rods fixed under the trunk, each ending in a small sphere (point contact).

A design is plain data so that the SUF design optimiser can try designs without files on disk;
`pedi_drake.robot.add_go1(plant, prongs=design)` builds the bodies from it.
"""

import dataclasses
import math

import numpy as np

from pedi_drake.exceptions import ProngDesignError

# Half height of the Go1 trunk collision box [m]: prongs attach to its bottom face by default.
TRUNK_HALF_HEIGHT = 0.057
# The widest half-spacing of two centre-line prongs [m]: as far apart as the legs allow (paper
# 003), which for the Go1 is the trunk's own end, as long as no hip turns its leg inwards by more
# than PRONG_HIP_INWARD_LIMIT. Derived by pedi_drake.suf.prong_clearance.widest_prong_spacing
# (tests/test_prong_clearance.py checks it).
WIDEST_PRONG_HALF_SPACING = 0.182
# [rad] the inward hip angle that spacing is derived for: the missions turn a hip inwards by at
# most 0.3 rad; beyond 0.50-0.58 rad a leg reaches under the trunk to the prongs at any spacing.
PRONG_HIP_INWARD_LIMIT = 0.5
# The shipped design's half-spacing [m]: the widest (paper 003 places its prongs as far apart as
# the legs allow).
PRONG_HALF_SPACING = WIDEST_PRONG_HALF_SPACING


@dataclasses.dataclass
class ProngDesign:
    """Prongs on the Go1 trunk. Every prong points straight down (-z of the trunk frame).

    The default has two prongs on the trunk's x axis near its front and rear ends
    (+-PRONG_HALF_SPACING), whose tips touch flat ground when the trunk is lowered to a height of
    about 0.17 m.
    """

    # Attachment points p_BA in the trunk frame B [m], one [x, y, z] per prong.
    attachment_points: list[list[float]] = dataclasses.field(
        default_factory=lambda: [
            [PRONG_HALF_SPACING, 0.0, -TRUNK_HALF_HEIGHT],
            [-PRONG_HALF_SPACING, 0.0, -TRUNK_HALF_HEIGHT],
        ]
    )
    # Rod length from the attachment point to the centre of the tip sphere [m].
    length: float = 0.098
    # Radius of the tip sphere, the only collision geometry of a prong [m].
    tip_radius: float = 0.015
    # Mass of one prong (rod and tip) [kg].
    mass: float = 0.05
    # Coulomb friction coefficient of the tips [-].
    friction: float = 0.8

    def validate(self, where: str = "prongs") -> None:
        """Raises ProngDesignError naming the offending field when the design is malformed."""
        if len(self.attachment_points) == 0:
            raise ProngDesignError(f"{where}.attachment_points: a prong design needs at least one prong")
        for i, point in enumerate(self.attachment_points):
            if len(point) != 3 or not all(math.isfinite(float(v)) for v in point):
                raise ProngDesignError(
                    f"{where}.attachment_points[{i}]: expected 3 finite numbers [x, y, z] in metres, got {point!r}"
                )
        for name, lower in (("length", 0.0), ("tip_radius", 0.0), ("friction", 0.0)):
            value = getattr(self, name)
            if not math.isfinite(value) or value <= lower:
                raise ProngDesignError(f"{where}.{name}: must be a finite number > {lower}, got {value!r}")
        if not math.isfinite(self.mass) or self.mass < 0.0:
            raise ProngDesignError(f"{where}.mass: must be a finite number >= 0, got {self.mass!r}")

    @property
    def num_prongs(self) -> int:
        return len(self.attachment_points)

    def tip_positions_B(self) -> np.ndarray:
        """Centres of the tip spheres in the trunk frame, shape (n, 3) [m]."""
        points = np.asarray(self.attachment_points, dtype=float).reshape(-1, 3)
        return points - np.array([0.0, 0.0, self.length])

    def ground_contact_height(self) -> float:
        """Trunk height at which the lowest tip touches flat ground, trunk level [m]."""
        return float(-np.min(self.tip_positions_B()[:, 2]) + self.tip_radius)

    @staticmethod
    def for_trunk_height(
        height: float, x_positions=(PRONG_HALF_SPACING, -PRONG_HALF_SPACING), tip_radius: float = 0.015
    ) -> "ProngDesign":
        """Returns a centre-line design whose tips touch the ground at `height` [m]."""
        length = height - TRUNK_HALF_HEIGHT - tip_radius
        design = ProngDesign(
            attachment_points=[[float(x), 0.0, -TRUNK_HALF_HEIGHT] for x in x_positions],
            length=length,
            tip_radius=tip_radius,
        )
        design.validate()
        return design
