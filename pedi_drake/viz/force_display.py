"""ForceDisplay: the teleoperated foot's haptic feedback drawn in the Meshcat page.

What the operator's device feels (pedi_drake.operator.feedback: the estimated force on the driven
foot and the limit the bounds hold it under) is shown in the live view, updated at the feedback's
period:

  * an arrow at the foot along the estimated force of the environment on it, 1 cm per newton
    (ARROW_METRES_PER_NEWTON), hidden while the force is below FORCE_SHOWN (the estimate's noise);
  * a bar beside the trunk: a translucent column as tall as the limit (BAR_METRES_PER_NEWTON), and
    inside it a solid one as tall as the force along the limit's direction, green with room
    left, orange over the last fifth, red at the limit;
  * two gauges in the control pane, "foot force [N]" and "force limit [N]": sliders the display
    sets at each update (a value dragged there is put back at the next), which a person and a
    browser can read as numbers.

The foot is placed from the state estimate and the measured joints (the leg's kinematics), as the
mission sees it: the same display runs on the hardware path. Inputs: `operator_feedback`
(FEEDBACK_SIZE), `base_state` (13), `position_measured` (12).
"""

import math

import numpy as np
from pydrake.geometry import Box, Cylinder, Meshcat, Rgba, Sphere
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import EventStatus

from pedi_drake.estimation.base_state import BASE_STATE_SIZE, BaseState
from pedi_drake.estimation.leg_odometry import foot_kinematics_B
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.operator.feedback import FEEDBACK_SIZE

PATH = "/operator/force"
FORCE_GAUGE = "foot force [N]"
LIMIT_GAUGE = "force limit [N]"
GAUGE_RANGE = 100.0  # [N]
# An estimated force below this is noise, not a touch: no arrow [N].
FORCE_SHOWN = 3.0
ARROW_METRES_PER_NEWTON = 0.01
ARROW_RADIUS = 0.006  # [m]
BAR_METRES_PER_NEWTON = 0.005
BAR_WIDTH = 0.03  # [m]
# The bar stands beside the trunk, on its left, in the trunk's frame [m].
BAR_OFFSET_B = np.array([0.0, 0.18, 0.0])
# The bar turns orange over the last APPROACH of the limit, as the bounds slow the foot there.
APPROACH = 0.2
ARROW_COLOUR = Rgba(0.85, 0.1, 0.7, 1.0)
LIMIT_COLOUR = Rgba(0.6, 0.6, 0.6, 0.35)
FILL_COLOURS = {"room": Rgba(0.2, 0.7, 0.2, 1.0), "near": Rgba(1.0, 0.6, 0.0, 1.0), "at": Rgba(0.9, 0.1, 0.1, 1.0)}


def _scaled(X: RigidTransform, scale: np.ndarray) -> np.ndarray:
    """The 4x4 matrix of X with its frame's axes scaled by `scale` (3,)."""
    matrix = X.GetAsMatrix4()
    matrix[:3, :3] = matrix[:3, :3] @ np.diag(scale)
    return matrix


def arrow_pose(p_foot_W: np.ndarray, force_W: np.ndarray) -> tuple[RigidTransform, float]:
    """(pose of a unit cylinder's frame whose z axis runs along the force from the foot, its
    length [m]): the shaft's centre half way along."""
    magnitude = float(np.linalg.norm(force_W))
    length = ARROW_METRES_PER_NEWTON * magnitude
    direction = force_W / magnitude
    R = RotationMatrix.MakeFromOneVector(direction, 2)
    return RigidTransform(R, p_foot_W + 0.5 * length * direction), length


def fill_state(along: float, limit: float) -> str:
    """ "room", "near" (the last APPROACH of the limit) or "at" (the limit reached) for the force
    `along` the limit's direction [N] against `limit` [N]."""
    if along >= limit:
        return "at"
    return "near" if along >= (1.0 - APPROACH) * limit else "room"


class ForceDisplay(LeafSystemWithoutWitnesses):
    """The haptic feedback drawn in `meshcat` every `period` [s] (see the module docstring)."""

    def __init__(self, meshcat: Meshcat, period: float):
        super().__init__()
        self._meshcat = meshcat
        self._feedback = self.DeclareVectorInputPort("operator_feedback", FEEDBACK_SIZE)
        self._base_state = self.DeclareVectorInputPort("base_state", BASE_STATE_SIZE)
        self._position = self.DeclareVectorInputPort("position_measured", 12)
        meshcat.SetObject(f"{PATH}/arrow/shaft", Cylinder(ARROW_RADIUS, 1.0), ARROW_COLOUR)
        meshcat.SetObject(f"{PATH}/arrow_tip", Sphere(2.0 * ARROW_RADIUS), ARROW_COLOUR)
        meshcat.SetObject(f"{PATH}/bar/limit", Box(BAR_WIDTH, BAR_WIDTH, 1.0), LIMIT_COLOUR)
        for state, colour in FILL_COLOURS.items():
            meshcat.SetObject(f"{PATH}/bar/fill_{state}", Box(0.8 * BAR_WIDTH, 0.8 * BAR_WIDTH, 1.0), colour)
        for gauge in (FORCE_GAUGE, LIMIT_GAUGE):
            meshcat.DeleteSlider(gauge, strict=False)
            meshcat.AddSlider(gauge, 0.0, GAUGE_RANGE, 0.1, 0.0)
        self._hide_all()
        self.DeclarePeriodicPublishEvent(period, 0.0, self._draw)

    def _hide_all(self) -> None:
        for path in ("arrow", "arrow_tip", "bar"):
            self._meshcat.SetProperty(f"{PATH}/{path}", "visible", False)

    def _draw(self, context) -> EventStatus:
        x = self._feedback.Eval(context)
        meshcat = self._meshcat
        leg = int(x[0])
        if leg < 0 or not np.all(np.isfinite(x[1:4])):
            self._hide_all()
            for gauge in (FORCE_GAUGE, LIMIT_GAUGE):
                meshcat.SetSliderValue(gauge, 0.0)
            return EventStatus.Succeeded()
        force_W, limit = np.asarray(x[1:4], float), float(x[4])
        base = BaseState.from_vector(self._base_state.Eval(context))
        X_WB = base.pose()
        p_foot_W = X_WB @ foot_kinematics_B(np.asarray(self._position.Eval(context)))[0][leg]
        magnitude = float(np.linalg.norm(force_W))
        meshcat.SetSliderValue(FORCE_GAUGE, min(magnitude, GAUGE_RANGE))
        meshcat.SetSliderValue(LIMIT_GAUGE, min(limit, GAUGE_RANGE) if math.isfinite(limit) else 0.0)
        shown = magnitude >= FORCE_SHOWN
        meshcat.SetProperty(f"{PATH}/arrow", "visible", shown)
        meshcat.SetProperty(f"{PATH}/arrow_tip", "visible", shown)
        if shown:
            X_arrow, length = arrow_pose(p_foot_W, force_W)
            meshcat.SetTransform(f"{PATH}/arrow/shaft", _scaled(X_arrow, np.array([1.0, 1.0, length])))
            meshcat.SetTransform(f"{PATH}/arrow_tip", RigidTransform(p_foot_W + length * force_W / magnitude))
        if not (math.isfinite(limit) and limit > 0.0):
            meshcat.SetProperty(f"{PATH}/bar", "visible", False)
            return EventStatus.Succeeded()
        # The force along its own direction, as the bounds measure it (the limit's direction).
        along = magnitude
        state = fill_state(along, limit)
        X_bar = RigidTransform(X_WB.rotation(), X_WB @ BAR_OFFSET_B)
        height_limit = BAR_METRES_PER_NEWTON * limit
        height_fill = BAR_METRES_PER_NEWTON * min(along, limit)
        meshcat.SetProperty(f"{PATH}/bar", "visible", True)
        meshcat.SetTransform(
            f"{PATH}/bar/limit",
            _scaled(X_bar @ RigidTransform([0.0, 0.0, 0.5 * height_limit]), np.array([1.0, 1.0, height_limit])),
        )
        for each in FILL_COLOURS:
            meshcat.SetProperty(f"{PATH}/bar/fill_{each}", "visible", each == state and height_fill > 0.0)
        if height_fill > 0.0:
            meshcat.SetTransform(
                f"{PATH}/bar/fill_{state}",
                _scaled(X_bar @ RigidTransform([0.0, 0.0, 0.5 * height_fill]), np.array([1.0, 1.0, height_fill])),
            )
        return EventStatus.Succeeded()
