"""ReferenceTable: the controller references of a mission's progress as numbers, sampled by kernels.

The MissionManager's `body_reference` and `leg_reference` outputs are sampled at every control
tick (500 Hz) from trajectory objects that change only at the manager's updates (100 Hz).
Sampling the objects costs tens of microseconds of Python a tick; so at each update the
References are packed once (`reference_table`: the trajectories' packed forms, see
pedi_drake.trajectory) and a tick runs one compiled kernel (`references_into`: both vectors, one
after the other; or `body_reference_into`, `leg_reference_into`) that writes the controller's
vectors in place: the same formulas as `sample`, no Python object made.

Layouts (float arrays):
    body  [index of the orientation part, the position trajectory's packed form, the orientation's
          (GEODESIC) packed form]
    legs  per leg in Unitree order: [mode (0: no task), kp [1/s^2], kd [1/s] (0: the controller's
          gains), 1 if the calf's reference rotation replaces the acceleration, that rotation
          vector (3) [rad], size L of the trajectory's packed form, that form (L)]; then the
          press: [1 while it drives, leg index, t0 [s], ramp [s], speed [m/s], start (3) [m],
          direction (3)]
The vectors' layouts are those of pedi_drake.control.references.
"""

import dataclasses

import numpy as np

from pedi_drake import robot
from pedi_drake.control.references import BODY_REFERENCE_SIZE, LEG_BLOCK, LEG_REFERENCE_SIZE
from pedi_drake.exceptions import PediError
from pedi_drake.mission.progress import LEG_MODE_FOOT, References
from pedi_drake.runtime.jit import kernel
from pedi_drake.trajectory import sample_rotation_into, sample_vector_into, smooth_start_kernel

_LEG_HEADER = 8  # mode, kp, kd, calf flag, calf rotation (3), packed size
_PRESS_SIZE = 11
# `references_into`'s vector: body_reference, then leg_reference.
REFERENCES_SIZE = BODY_REFERENCE_SIZE + LEG_REFERENCE_SIZE


@dataclasses.dataclass(frozen=True)
class ReferenceTable:
    """The packed references (layouts in the module docstring); read-only arrays."""

    body: np.ndarray
    legs: np.ndarray

    def __deepcopy__(self, memo) -> "ReferenceTable":
        # A value: Drake copies the whole State for every unrestricted update.
        return self


def _read_only(parts: list) -> np.ndarray:
    x = np.concatenate([np.ravel(np.asarray(part, dtype=float)) for part in parts])
    x.flags.writeable = False
    return x


def reference_table(refs: References) -> ReferenceTable:
    """The ReferenceTable of `refs`. Raises PediError for a press with a ramp that is not > 0 s."""
    position = refs.body_position.packed
    body = _read_only([[1 + position.size], position, refs.body_orientation.packed])
    legs = []
    for leg in robot.LEG_NAMES:
        reference = refs.legs.get(leg)
        if reference is None:
            legs.append(np.zeros(_LEG_HEADER))
            continue
        kp, kd = reference.foot_gains if reference.foot_gains is not None else (0.0, 0.0)
        calf = reference.calf_rotation
        packed = reference.trajectory.packed
        legs += [
            [reference.mode, kp, kd, calf is not None],
            np.zeros(3) if calf is None else calf,
            [packed.size],
            packed,
        ]
    press = refs.press
    if press is None or press["frozen_at"] is not None:
        legs.append(np.zeros(_PRESS_SIZE))
    else:
        if not press["ramp"] > 0.0:
            raise PediError(f"speed ramp must be > 0 s, got {press['ramp']!r}")
        leg = robot.LEG_NAMES.index(press["leg"])
        legs += [[1.0, leg, press["t0"], press["ramp"], press["speed"]], press["start"], press["direction"]]
    return ReferenceTable(body, _read_only(legs))


@kernel
def body_reference_into(body, t, x) -> None:
    """Fills `x`, the `body_reference` vector (19), with the packed body references at `t` [s]."""
    split = int(body[0])
    # Layout: p [0:3], quaternion [3:7], v [7:10], a [10:13], w [13:16], alpha [16:19].
    sample_vector_into(body[1:split], t, x[0:3], x[7:10], x[10:13])
    R = np.empty((3, 3))
    sample_rotation_into(body[split:], t, R, x[3:7], x[13:16], x[16:19])


@kernel
def leg_reference_into(legs, t, x) -> None:
    """Fills `x`, the `leg_reference` vector (48), with the packed leg references at `t` [s]."""
    x[:] = 0.0
    i = 0
    for leg in range(4):
        k = leg * LEG_BLOCK
        size = int(legs[i + 7])
        if size > 0:
            x[k] = legs[i]
            sample_vector_into(legs[i + 8 : i + 8 + size], t, x[k + 1 : k + 4], x[k + 4 : k + 7], x[k + 7 : k + 10])
            if legs[i + 3] > 0.5:
                # The held foot pose's calf rotation in the acceleration's place.
                x[k + 7 : k + 10] = legs[i + 4 : i + 7]
            x[k + 10] = legs[i + 1]
            x[k + 11] = legs[i + 2]
        i += _LEG_HEADER + size
    if legs[i] > 0.5:
        # The press drives its foot from `start` along `direction` at `speed`, reached smoothly.
        k = int(legs[i + 1]) * LEG_BLOCK
        s, sd, sdd = smooth_start_kernel(t, legs[i + 2], legs[i + 3])
        speed = legs[i + 4]
        x[k] = LEG_MODE_FOOT
        for j in range(3):
            direction = legs[i + 8 + j]
            x[k + 1 + j] = legs[i + 5 + j] + speed * s * direction
            x[k + 4 + j] = speed * sd * direction
            x[k + 7 + j] = speed * sdd * direction


@kernel
def references_into(body, legs, t, x) -> None:
    """Fills `x` (REFERENCES_SIZE) with `body_reference` then `leg_reference` at `t` [s]."""
    body_reference_into(body, t, x[:BODY_REFERENCE_SIZE])
    leg_reference_into(legs, t, x[BODY_REFERENCE_SIZE:])


def warm_up(refs: References) -> None:
    """Compiles (or loads) the kernels a tick runs, outside any tick: the outputs' and, for the
    phases, the trajectories' own `sample` (`refs` has a position and an orientation)."""
    table = reference_table(refs)
    references_into(table.body, table.legs, 0.0, np.zeros(REFERENCES_SIZE))
    body_reference_into(table.body, 0.0, np.zeros(BODY_REFERENCE_SIZE))
    leg_reference_into(table.legs, 0.0, np.zeros(LEG_REFERENCE_SIZE))
    refs.body_position.sample(0.0)
    refs.body_orientation.sample(0.0)
