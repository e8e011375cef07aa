"""The compiled whole-body tick against its oracle (reference_whole_body_tick), tick for tick.

A shadow run: a mission simulated with the oracle's tick driving the robot, and at every tick the
compiled tick also runs on the same context into scratch state. Both must write the same command,
reference, ramps, held pose and diagnostics. Both solve their QPs with DAQP at the same settings
(the oracle through its Python module, the compiled tick through its C library), so the two agree
to rounding.
"""

import dataclasses

import numpy as np
import pytest
from reference_whole_body_tick import ReferenceTick
from test_whole_body_controller import standing_controller, tick

from pedi_drake.control import whole_body_tick
from pedi_drake.control.tick_steps import STATUS_BAD_INPUT
from pedi_drake.control.whole_body_controller import WholeBodyController
from pedi_drake.run import simulate
from pedi_drake.runtime import jit
from pedi_drake.scenario import load_scenario

# Largest difference allowed per command block [rad, rad/s, N m/rad, N m s/rad, N m], for the
# integrated reference [rad, rad/s] and the contact forces [N]: far below anything the motors
# resolve, far above the solvers' tolerance.
COMMAND_TOLERANCE = (1e-9, 1e-6, 0.0, 0.0, 1e-5)
STATE_TOLERANCE = 1e-9
FORCE_TOLERANCE = 1e-4
# The weighted mode's single QP weighs its levels 1e6 to 1 (100^(L-1-k)): its Hessian spans twelve
# decades, and DAQP's proximal iterations stop at its automatic tolerance there (a tighter one is
# not met within the iteration limit). The oracle and the compiled tick, whose QPs differ by
# rounding, stop at points up to 2.3e-6 rad, 1.2e-3 rad/s, 0.034 N m and 0.17 N apart (measured
# over the 1001 ticks of this run): a few times that, still far below what the motors resolve.
WEIGHTED_COMMAND_TOLERANCE = (1e-5, 5e-3, 0.0, 0.0, 0.1)
WEIGHTED_STATE_TOLERANCE = 5e-3  # the joint reference holds qd_ref too
WEIGHTED_FORCE_TOLERANCE = 0.5


@dataclasses.dataclass
class ShadowStats:
    ticks: int = 0
    worst_command: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(5))
    worst_force: float = 0.0
    status_mismatches: int = 0
    statuses: set = dataclasses.field(default_factory=set)


def shadow_run(monkeypatch, mission: str, duration: float, state_tolerance: float, **whole_body) -> ShadowStats:
    """Simulates `mission` for `duration` [s] on the oracle's tick, the compiled one beside it."""
    stats = ShadowStats()
    compiled_update = WholeBodyController._update

    def shadow(self, context, discrete_state):
        if not hasattr(self, "_oracle"):
            self._oracle = ReferenceTick(self)
        self._oracle.update(context, discrete_state)
        scratch = self.AllocateDiscreteVariables()
        scratch.SetFrom(context.get_discrete_state())  # as the framework hands it to an update
        compiled_update(self, context, scratch)
        expected = discrete_state.get_vector(self.command_state).value()
        actual = scratch.get_vector(self.command_state).value()
        for k in range(5):
            error = np.abs(expected[12 * k : 12 * k + 12] - actual[12 * k : 12 * k + 12]).max()
            stats.worst_command[k] = max(stats.worst_command[k], error)
        for state in (self.reference_state, self.ramp_state, self.hold_state):
            np.testing.assert_allclose(
                scratch.get_vector(state).value(),
                discrete_state.get_vector(state).value(),
                rtol=0,
                atol=state_tolerance,
            )
        expected_diag = discrete_state.get_vector(self.diagnostics_state).value()
        actual_diag = scratch.get_vector(self.diagnostics_state).value()
        forces = self.diag["contact_forces"]
        stats.worst_force = max(stats.worst_force, np.abs(expected_diag[forces] - actual_diag[forces]).max())
        status = self.diag["status"].start
        stats.status_mismatches += int(expected_diag[status] != actual_diag[status])
        stats.statuses.add(float(expected_diag[status]))
        stats.ticks += 1

    monkeypatch.setattr(WholeBodyController, "_update", shadow)
    scenario = load_scenario()
    scenario.mission = mission
    scenario.simulation_duration = duration
    scenario.whole_body = dataclasses.replace(scenario.whole_body, **whole_body)
    simulate(scenario=scenario, name=mission, quiet=True, replay=False)
    return stats


def assert_same_ticks(stats: ShadowStats, command_tolerance, force_tolerance) -> None:
    assert stats.ticks > 100
    assert stats.status_mismatches == 0
    for k, name in enumerate(("q_des", "qd_des", "kp", "kd", "tau_ff")):
        assert stats.worst_command[k] <= command_tolerance[k], f"{name}: {stats.worst_command[k]:.3g}"
    assert stats.worst_force <= force_tolerance


@pytest.mark.parametrize(
    "mission, duration",
    [
        ("hit_target_front", 8.0),  # stand, lift FR, reach: the paper000 stack on three feet
        ("prong_push_box", 9.0),  # on the prongs, paper003's stack, both front feet lifted
        ("evaluations/shank_hold", 6.8),  # FL's shank held in 6-D (from 5.8 s) as the trunk starts to move
    ],
)
def test_compiled_tick_equals_the_reference_tick(monkeypatch, mission, duration):
    stats = shadow_run(monkeypatch, mission, duration, STATE_TOLERANCE)
    assert_same_ticks(stats, COMMAND_TOLERANCE, FORCE_TOLERANCE)


def test_compiled_weighted_tick_equals_the_reference_tick(monkeypatch):
    stats = shadow_run(monkeypatch, "hit_target_front", 2.0, WEIGHTED_STATE_TOLERANCE, hqp_mode="weighted")
    assert_same_ticks(stats, WEIGHTED_COMMAND_TOLERANCE, WEIGHTED_FORCE_TOLERANCE)


@pytest.mark.parametrize("bad", ["nan_base", "zero_quaternion", "nan_joint"])
def test_bad_input_holds_the_last_command_and_damps(bad):
    controller, context = standing_controller(load_scenario().whole_body)
    good, _ = tick(controller, context, 3)
    base = controller.base_state_port.Eval(context).copy()
    q = controller.position_port.Eval(context).copy()
    if bad == "nan_base":
        base[5] = np.nan
    elif bad == "zero_quaternion":
        base[0:4] = 0.0
    else:
        q[4] = np.nan
    controller.base_state_port.FixValue(context, base)
    controller.position_port.FixValue(context, q)
    command, diag = tick(controller, context)
    assert diag[controller.diag["status"]][0] == STATUS_BAD_INPUT
    assert np.all(np.isfinite(command))
    np.testing.assert_array_equal(command[12:24], 0.0)  # no velocity target
    assert np.all(command[36:48] >= controller.config.failure_kd)
    np.testing.assert_array_equal(command[48:60], good[48:60])  # the last good torques, held


@pytest.mark.skipif(not jit.ENABLED, reason="PEDI_DRAKE_JIT=0")
def test_the_compiled_tick_releases_python():
    # The driver's receive thread must run while a tick computes: the kernel holds no GIL.
    assert whole_body_tick.whole_body_tick.targetoptions.get("nogil") is True


@pytest.mark.skipif(not jit.ENABLED, reason="PEDI_DRAKE_JIT=0")
def test_no_tick_compiles_code(monkeypatch):
    # The constructor compiles the tick for the argument types of a connected diagram's ticks: a
    # compilation inside a tick would stall it for seconds (the driver's guard would damp).
    scenario = load_scenario()
    scenario.mission = "hit_target_front"
    scenario.simulation_duration = 0.1
    signatures = []
    constructor = WholeBodyController.__init__

    def construct(self, *args, **kwargs):
        constructor(self, *args, **kwargs)
        signatures.append(list(whole_body_tick.whole_body_tick.signatures))

    monkeypatch.setattr(WholeBodyController, "__init__", construct)
    simulate(scenario=scenario, name="signatures", quiet=True, replay=False)
    assert signatures and list(whole_body_tick.whole_body_tick.signatures) == signatures[0]
