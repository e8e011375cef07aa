"""How far apart centre-line prongs can be without a leg hitting them (paper 003, Sec. III).

Paper 003 places its two prongs on the trunk's x axis "as far apart as possible without
interfering with the leg motion", because the SUF grows with their spacing. Here that limit is
computed from the Go1's own collision geometry (`pedi_drake.robot`): every leg is swept over a
grid of its joint limits, configurations where it would pass through the trunk are left out (the
trunk stops it first), and the clearance between the leg's thigh, calf and foot and each prong
(its rod, a cylinder of radius `PRONG_ROD_RADIUS`, and its tip sphere) is the smallest signed
distance over the sweep.

For the Go1 the sweep finds that the spacing is not what the legs limit: each leg moves in a
plane 0.13 m to the side of the centre line, and its thigh and calf sweep the whole length of the
trunk at every hip angle, so a leg meets a centre-line prong only when its hip turns it inwards
under the trunk, beyond 0.50-0.58 rad (the sweep's grid), and then at any spacing. `hip_inward_reach` gives that
angle; `widest_prong_spacing` gives the spacing for a bound on it, at most the trunk's own
half-length less the rod's radius (a prong is attached to the trunk's bottom face).
"""

import functools

import numpy as np
from pydrake.geometry import Role
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.systems.framework import DiagramBuilder

from pedi_drake import robot
from pedi_drake.exceptions import ProngDesignError
from pedi_drake.prongs import ProngDesign

# Joint grid of the sweep: samples per joint over its limits (hip, thigh, calf).
SWEEP_GRID = (25, 27, 11)
ROD_SAMPLES = 8  # points along a prong's rod at which its distance to the legs is taken
SPACING_STEP = 0.005  # [m] resolution of the widest spacing
# [m] the largest clearance computed: a leg farther than this from a prong reads as this (what
# matters is whether a leg comes within a margin of a prong, and each geometry within a query's
# reach costs a result).
CLEARANCE_CAP = 0.05


class _LegSweep:
    """The Go1's collision geometry in a SceneGraph, posed leg by leg over the joint grid."""

    def __init__(self):
        builder = DiagramBuilder()
        plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
        robot.add_go1(plant)
        plant.Finalize()
        self.diagram = builder.Build()
        self.plant, self.scene_graph = plant, scene_graph
        self.plant_map = robot.Go1PlantMap.from_plant(plant)
        inspector = scene_graph.model_inspector()
        self.geometry_body = {
            g: plant.GetBodyFromFrameId(inspector.GetFrameId(g)).name()
            for g in inspector.GetAllGeometryIds(Role.kProximity)
        }
        self.trunk = next(g for g, body in self.geometry_body.items() if body == robot.TRUNK_BODY_NAME)

    def poses(self, leg: str):
        """Yields (inward hip angle [rad], query object, the leg's geometry ids) for every grid
        configuration of `leg` whose links stay out of the trunk; the other legs are folded under
        their hips. A right hip turns its leg inwards with a positive angle, a left one with a
        negative angle."""
        context = self.diagram.CreateDefaultContext()
        plant_context = self.plant.GetMyMutableContextFromRoot(context)
        scene_context = self.scene_graph.GetMyContextFromRoot(context)
        lower, upper = robot.HARDWARE_Q_LOWER[:3], robot.HARDWARE_Q_UPPER[:3]
        index = robot.LEG_NAMES.index(leg)
        inward = 1.0 if leg.endswith("R") else -1.0
        mine = {g for g, body in self.geometry_body.items() if body.startswith(f"{leg}_")}
        q = np.tile([0.0, 0.8, -1.6], 4)
        for hip in np.linspace(lower[0], upper[0], SWEEP_GRID[0]):
            for thigh in np.linspace(lower[1], upper[1], SWEEP_GRID[1]):
                for calf in np.linspace(lower[2], upper[2], SWEEP_GRID[2]):
                    q[3 * index : 3 * index + 3] = (hip, thigh, calf)
                    positions = self.plant_map.full_positions(
                        np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), q, self.plant.num_positions()
                    )
                    self.plant.SetPositions(plant_context, positions)
                    query = self.scene_graph.get_query_output_port().Eval(scene_context)
                    if min(query.ComputeSignedDistancePairClosestPoints(self.trunk, g).distance for g in mine) < 0.0:
                        continue
                    yield inward * hip, query, mine


@functools.cache
def _sweep() -> _LegSweep:
    return _LegSweep()


def _prong_spheres(design: ProngDesign) -> list[tuple[np.ndarray, float]]:
    """(centre in the trunk frame [m], radius [m]) of spheres covering each prong's rod and tip."""
    spheres = []
    for p_BA in np.asarray(design.attachment_points, float):
        for depth in np.linspace(0.0, design.length, ROD_SAMPLES):
            spheres.append((p_BA - [0.0, 0.0, depth], robot.PRONG_ROD_RADIUS))
        spheres.append((p_BA - [0.0, 0.0, design.length], design.tip_radius))
    return spheres


@functools.lru_cache(maxsize=16)
def _clearances(key: tuple) -> tuple[np.ndarray, np.ndarray]:
    """(inward hip angle [rad], clearance to the prongs [m], at most CLEARANCE_CAP) of every swept
    leg configuration of the design `robot.design_key` gives `key` for."""
    design = ProngDesign(**dict(key))
    spheres = _prong_spheres(design)
    angles, clearances = [], []
    for leg in robot.LEG_NAMES:
        for angle, query, mine in _sweep().poses(leg):
            clearance = CLEARANCE_CAP
            for centre, radius in spheres:
                for result in query.ComputeSignedDistanceToPoint(centre, radius + CLEARANCE_CAP):
                    if result.id_G in mine:
                        clearance = min(clearance, result.distance - radius)
            angles.append(angle)
            clearances.append(clearance)
    return np.array(angles), np.array(clearances)


def leg_prong_clearance(design: ProngDesign, hip_inward_limit: float = np.inf) -> float:
    """The smallest distance [m] between any leg and any prong of `design` over the legs' joint
    limits, each hip turned inwards by at most `hip_inward_limit` [rad] (< 0: they collide), at
    most CLEARANCE_CAP."""
    design.validate()
    angles, clearances = _clearances(robot.design_key(design))
    return float(np.min(clearances[angles <= hip_inward_limit + 1e-9], initial=np.inf))


def widest_prong_spacing(length: float, tip_radius: float, hip_inward_limit: float, margin: float = 0.01) -> float:
    """The largest half-spacing x [m] of two centre-line prongs at (+-x, 0) under the trunk, `length`
    and `tip_radius` [m] as `ProngDesign`'s, at which every leg clears both by `margin` [m] over its
    joint limits with its hip turned inwards by at most `hip_inward_limit` [rad]. At most the
    trunk's half-length less the rod's radius; raises ProngDesignError if no spacing clears."""
    widest = robot.TRUNK_HALF_EXTENTS[0] - robot.PRONG_ROD_RADIUS
    for x in np.arange(widest, 0.0, -SPACING_STEP):
        design = ProngDesign(
            attachment_points=[[x, 0.0, -robot.TRUNK_HALF_EXTENTS[2]], [-x, 0.0, -robot.TRUNK_HALF_EXTENTS[2]]],
            length=length,
            tip_radius=tip_radius,
        )
        if leg_prong_clearance(design, hip_inward_limit) >= margin:
            return float(x)
    raise ProngDesignError(
        f"no centre-line prong spacing clears the legs by {margin} m with the hips turned inwards by up to "
        f"{hip_inward_limit} rad"
    )


def hip_inward_reach(design: ProngDesign, margin: float = 0.01) -> float:
    """The largest inward hip angle [rad] of the sweep's grid up to which every leg clears the
    prongs of `design` by `margin` [m] over the rest of its joint limits."""
    design.validate()
    angles, clearances = _clearances(robot.design_key(design))
    too_close = angles[clearances < margin]
    if too_close.size == 0:
        return float(np.max(angles))
    return float(np.max(angles[angles < np.min(too_close)], initial=0.0))
