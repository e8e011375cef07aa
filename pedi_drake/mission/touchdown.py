"""When a foot that is set down has touched the ground, as every phase that sets one down judges it."""

from pedi_drake import robot

CONTACT_FORCE_THRESHOLD = 8.0  # [N] foot sensor reading that counts as touch-down
# [m] below the ground that a foot set down is aimed: it stops where its sensor feels the ground,
# which may be off the estimate's by millimetres.
PLACE_DEPTH = 0.015
# [m] a swinging foot counts as down only this close above the ground it aims at, by the estimate:
# a noisy foot sensor can read a touch-down's force in the air, and a foot loaded there tips the
# trunk over it.
TOUCHDOWN_HEIGHT = 0.03


def swing_foot_down(view, leg: str, ground_z: float) -> bool:
    """Whether the swinging foot of `leg` is down on ground at height `ground_z` [m]: its sensor
    reads a touch-down and the estimate has its centre within TOUCHDOWN_HEIGHT above its height
    on that ground."""
    k = robot.LEG_NAMES.index(leg)
    near = view.foot_W(leg)[2] < ground_z + robot.FOOT_RADIUS + TOUCHDOWN_HEIGHT
    return bool(view.foot_force[k] > CONTACT_FORCE_THRESHOLD and near)
