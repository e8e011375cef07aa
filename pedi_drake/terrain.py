"""Terrain: slopes, platforms and patches of other friction on the flat ground, as scene objects.

Three scene kinds (pedi_drake.scenario.SceneObject) are terrain rather than models: each is one
box welded to the world, sized by the object's `size`, with its own friction coefficient
(`friction`; 0: the ground's).

  slope           size [length, width] [m], `angle` [deg] in (0, MAX_SLOPE_ANGLE]: a ramp whose
                  surface rises from the ground at its foot, the edge through `position` (the
                  edge's middle), uphill along the object's x (`yaw`), `length` along the surface
  platform        size [length, width, height] [m]: a block, `position` the middle of its bottom
  friction_patch  size [length, width, height] [m] and its own `friction` (required): a slab, as
                  the platform, a few millimetres thick so that a foot on it touches it and not
                  the ground around it (a bridge, a wet tile)

`surface_at` gives the height, normal and friction under a point of the ground plan: what a
foothold, the estimator's ground or a contact's friction cone takes from the terrain. Both
simulators build the same boxes (`terrain_box`). `terrain_table` packs a scene's terrain for
compiled code, where `terrain_height` reads the height under a point from it.
"""

import dataclasses
import math

import numpy as np
from pydrake.math import RigidTransform, RollPitchYaw

from pedi_drake.friction import FRICTION_RANGE
from pedi_drake.runtime.jit import kernel

TERRAIN_KINDS = ("slope", "platform", "friction_patch")
MAX_SLOPE_ANGLE = 35.0  # [deg] steeper than any the Go1's static walk is asked to climb
SLOPE_THICKNESS = 0.1  # [m] of the ramp's box below its surface (its foot lies under the ground)
# The size each kind takes: [length, width] for a slope, [length, width, height] otherwise.
SIZE_ENTRIES = {"slope": 2, "platform": 3, "friction_patch": 3}
TERRAIN_COLOUR = {"slope": [0.62, 0.58, 0.5, 1.0], "platform": [0.6, 0.56, 0.5, 1.0]}
SLIPPERY_COLOUR = [0.55, 0.7, 0.85, 1.0]  # a surface of lower friction than the ground's


@dataclasses.dataclass(frozen=True)
class TerrainBox:
    """The box a terrain object is: its centre pose in the world, its full extents [m] and its
    friction coefficient [-] (the ground's when the object gives none)."""

    X_WC: RigidTransform
    size: np.ndarray
    friction: float


@dataclasses.dataclass(frozen=True)
class Surface:
    """The ground under a point: height [m], unit normal (world), friction coefficient [-], and
    the terrain object it belongs to ("" for the flat ground)."""

    height: float
    normal: np.ndarray
    friction: float
    name: str = ""


def is_terrain(obj) -> bool:
    """Whether scene object `obj` is terrain (a kind of TERRAIN_KINDS)."""
    return obj.kind in TERRAIN_KINDS


def placement(obj) -> RigidTransform:
    """X_WO: the object's placement frame (`position`, `yaw` about world z)."""
    return RigidTransform(RollPitchYaw(0.0, 0.0, obj.yaw), obj.position)


def terrain_box(obj, ground_friction: float) -> TerrainBox:
    """The box of terrain object `obj` (see the module docstring), its friction `obj.friction` or
    `ground_friction` [-] when that is 0."""
    friction = obj.friction or ground_friction
    X_WO = placement(obj)
    if obj.kind == "slope":
        length, width = obj.size
        a = math.radians(obj.angle)
        # Pitched so that the box's x runs up the slope; its top face passes through the foot edge.
        R_OC = RollPitchYaw(0.0, -a, 0.0)
        top_centre = np.array([0.5 * length * math.cos(a), 0.0, 0.5 * length * math.sin(a)])
        normal = np.array([-math.sin(a), 0.0, math.cos(a)])
        X_OC = RigidTransform(R_OC, top_centre - 0.5 * SLOPE_THICKNESS * normal)
        return TerrainBox(X_WO @ X_OC, np.array([length, width, SLOPE_THICKNESS]), friction)
    length, width, height = obj.size
    return TerrainBox(X_WO @ RigidTransform([0.0, 0.0, 0.5 * height]), np.array([length, width, height]), friction)


def terrain_colour(obj, ground_friction: float) -> list[float]:
    """RGBA of the object's surface: blue where it is more slippery than the ground."""
    if obj.friction and obj.friction < ground_friction:
        return SLIPPERY_COLOUR
    return TERRAIN_COLOUR.get(obj.kind, TERRAIN_COLOUR["platform"])


def _surface_of(obj, ground_friction: float, x: float, y: float) -> Surface | None:
    """The surface of terrain object `obj` over the world point (x, y), or None if it is not over it."""
    X_WO = placement(obj)
    p_O = X_WO.inverse().multiply(np.array([x, y, obj.position[2]]))
    friction = obj.friction or ground_friction
    if obj.kind == "slope":
        length, width = obj.size
        a = math.radians(obj.angle)
        run = length * math.cos(a)
        if not (0.0 <= p_O[0] <= run and abs(p_O[1]) <= 0.5 * width):
            return None
        normal = X_WO.rotation().multiply(np.array([-math.sin(a), 0.0, math.cos(a)]))
        return Surface(float(obj.position[2] + p_O[0] * math.tan(a)), normal, friction, obj.instance_name)
    length, width, height = obj.size
    if abs(p_O[0]) > 0.5 * length or abs(p_O[1]) > 0.5 * width:
        return None
    return Surface(float(obj.position[2] + height), np.array([0.0, 0.0, 1.0]), friction, obj.instance_name)


def surface_at(scene, ground_friction: float, x: float, y: float) -> Surface:
    """The ground under the world point (x, y) [m]: the highest terrain surface over it among the
    objects of `scene` (others are skipped), or the flat ground z = 0 of `ground_friction`."""
    highest = Surface(0.0, np.array([0.0, 0.0, 1.0]), ground_friction)
    for obj in scene:
        if not is_terrain(obj):
            continue
        surface = _surface_of(obj, ground_friction, x, y)
        if surface is not None and surface.height > highest.height:
            highest = surface
    return highest


# Columns of a `terrain_table` row.
TABLE_COLUMNS = 9
_SLOPE_ROW, _BLOCK_ROW = 0.0, 1.0


def terrain_table(scene) -> np.ndarray:
    """(k, TABLE_COLUMNS) of the terrain objects of `scene` (others skipped), for `terrain_height`:
    per row [kind (0 slope, 1 platform or patch), x, y, z of the placement, cos yaw, sin yaw,
    extent along x (a slope's run), width, top height (a slope's tan angle)] [m, -]."""
    rows = []
    for obj in scene:
        if not is_terrain(obj):
            continue
        x, y, z = obj.position
        head = [x, y, z, math.cos(obj.yaw), math.sin(obj.yaw)]
        if obj.kind == "slope":
            a = math.radians(obj.angle)
            rows.append([_SLOPE_ROW, *head, obj.size[0] * math.cos(a), obj.size[1], math.tan(a)])
        else:
            rows.append([_BLOCK_ROW, *head, *obj.size])
    return np.array(rows, dtype=float).reshape(len(rows), TABLE_COLUMNS)


def terrain_map(table: np.ndarray | None) -> np.ndarray:
    """`table` (a `terrain_table`) as the contiguous float array compiled code takes, the flat
    ground's empty table for None; refused unless it has TABLE_COLUMNS columns."""
    if table is None:
        return np.zeros((0, TABLE_COLUMNS))
    table = np.ascontiguousarray(table, dtype=float)
    if table.ndim != 2 or table.shape[1] != TABLE_COLUMNS:
        raise ValueError(f"a terrain table has {TABLE_COLUMNS} columns per row, got shape {table.shape}")
    return table


@kernel
def _highest_row(table: np.ndarray, x: float, y: float) -> tuple:
    """(row of `table` whose surface is the highest over the world point (x, y), or -1 for the flat
    ground; that surface's height [m])."""
    highest, row = 0.0, -1
    for k in range(table.shape[0]):
        dx, dy = x - table[k, 1], y - table[k, 2]
        c, s = table[k, 4], table[k, 5]
        along, across = c * dx + s * dy, -s * dx + c * dy
        if abs(across) > 0.5 * table[k, 7]:
            continue
        if table[k, 0] == _SLOPE_ROW:
            if not 0.0 <= along <= table[k, 6]:
                continue
            height = table[k, 3] + along * table[k, 8]
        else:
            if abs(along) > 0.5 * table[k, 6]:
                continue
            height = table[k, 3] + table[k, 8]
        if height > highest:
            highest, row = height, k
    return row, highest


@kernel
def terrain_height(table: np.ndarray, x: float, y: float) -> float:
    """[m] the height of the terrain of `table` (`terrain_table`) under the world point (x, y), or
    of the flat ground (0) where there is none: `surface_at`'s height, for compiled code."""
    return _highest_row(table, x, y)[1]


@kernel
def terrain_normal(table: np.ndarray, x: float, y: float, normal: np.ndarray) -> None:
    """Writes into `normal` (3,) the unit normal (world) of the terrain of `table` under the world
    point (x, y), z where there is none: `surface_at`'s normal, for compiled code."""
    row = _highest_row(table, x, y)[0]
    normal[0], normal[1], normal[2] = 0.0, 0.0, 1.0
    if row >= 0 and table[row, 0] == _SLOPE_ROW:
        # A slope rises along its placement's x: its normal leans back against that direction.
        cos_a = 1.0 / math.sqrt(1.0 + table[row, 8] ** 2)
        sin_a = table[row, 8] * cos_a
        normal[0] = -sin_a * table[row, 4]
        normal[1] = -sin_a * table[row, 5]
        normal[2] = cos_a


def terrain_problems(obj, where: str) -> list[str]:
    """What is wrong with the terrain fields of scene object `obj` ("<where>.<field>: <problem>"):
    a terrain kind needs its `size` and no model; any other kind takes none of size, angle,
    friction. A friction coefficient must lie in FRICTION_RANGE."""
    low, high = FRICTION_RANGE
    if not is_terrain(obj):
        given = [name for name in ("size", "angle", "friction") if getattr(obj, name)]
        return [f"{where}.{name}: only terrain ({', '.join(TERRAIN_KINDS)}) takes {name}" for name in given]
    problems = []
    entries = SIZE_ENTRIES[obj.kind]
    names = "[length, width]" if entries == 2 else "[length, width, height]"
    if len(obj.size) != entries or not all(math.isfinite(v) and v > 0 for v in obj.size):
        problems.append(f"{where}.size: a {obj.kind} takes {names} in metres, each > 0, got {obj.size}")
    if obj.model:
        problems.append(f"{where}.model: terrain is built from its size, not from a model file")
    if obj.kind == "slope":
        if not (math.isfinite(obj.angle) and 0.0 < obj.angle <= MAX_SLOPE_ANGLE):
            problems.append(
                f"{where}.angle: a slope's angle must be in (0, {MAX_SLOPE_ANGLE:g}] degrees, got {obj.angle}"
            )
    elif obj.angle:
        problems.append(f"{where}.angle: only a slope takes an angle")
    if obj.kind == "friction_patch" and not obj.friction:
        problems.append(f"{where}.friction: a friction_patch needs its friction coefficient, in [{low}, {high}]")
    elif obj.friction and not (math.isfinite(obj.friction) and low <= obj.friction <= high):
        problems.append(f"{where}.friction: must be in [{low}, {high}] (or 0: the ground's), got {obj.friction}")
    return problems
