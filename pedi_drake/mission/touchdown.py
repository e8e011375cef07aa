"""When a foot that is set down has touched the ground, as every phase that sets one down judges it."""

CONTACT_FORCE_THRESHOLD = 8.0  # [N] foot sensor reading that counts as touch-down
# [m] below the ground that a foot set down is aimed: it stops where its sensor feels the ground,
# which may be off the estimate's by millimetres.
PLACE_DEPTH = 0.015
