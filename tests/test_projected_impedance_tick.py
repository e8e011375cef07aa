"""The compiled tick of paper 002's controller against its oracle (reference_projected_impedance_tick,
built on reference_projected_dynamics).

* Shadow runs: short simulations of paper 002's missions driven by the oracle's tick, in which
  every tick the compiled tick also runs on the same context; the two must give the same status
  and the same next state (command, joint reference, ramps, held pose, Eq. 11 filter state,
  diagnostics but the timings) within ATOL + RTOL |reference|. The bound allows rounding (the
  two differ by 1e-12 to 1e-8 in these runs: the pseudo-inverses amplify rounding by the tasks'
  conditioning) and the contact QP solvers' tolerances (1e-9), and nothing of the size of a
  control effect.
* Standalone ticks: non-finite and invalid inputs, an infeasible contact QP, the first tick.
* The kernels against their plain-Python source (`.py_func`) and against reference_projected_dynamics
  on random inputs.
"""

import dataclasses
import functools

import numpy as np
import pytest
import reference_projected_dynamics as pd
from pydrake.systems.analysis import Simulator
from reference_projected_impedance_tick import ReferenceTick
from standing_context import standing_context

from pedi_drake import robot
from pedi_drake.control import compiled_projected_dynamics as cpd
from pedi_drake.control import projected_impedance_tick, references
from pedi_drake.control.compiled_projected_dynamics import lu_solve, symmetric_eigen, symmetric_pseudo_inverse
from pedi_drake.control.config import ProjectedImpedanceConfig
from pedi_drake.control.projected_impedance_controller import ProjectedImpedanceController
from pedi_drake.control.tick_steps import STATUS_BAD_INPUT, STATUS_OK, STATUS_QP_FAILED
from pedi_drake.diagram import MakePedipulationDiagram
from pedi_drake.exceptions import QpInfeasible
from pedi_drake.friction import UP
from pedi_drake.mission.spec import missions_dir
from pedi_drake.runtime import jit
from pedi_drake.scenario import RobotConfig, load_scenario
from pedi_drake.station.initial_state import initial_trunk_pose

# Agreement of the compiled tick with the reference, per state entry [SI units: rad, rad/s, N m, N, m].
ATOL = 1e-7
RTOL = 1e-7
_TIMINGS = ("solve_time", "tick_time")


# ------------------------------------------------------------------------------------------------
# Shadow runs.


@dataclasses.dataclass
class ShadowTick:
    """One tick of a shadow run: both statuses, the worst disagreement over the next state (in
    units of the tolerance: at most 1 passes), and what the tick was asked to do."""

    time: float  # [s]
    status_compiled: float
    status_reference: float
    worst: float  # max over entries of |compiled - reference| / (ATOL + RTOL |reference|)
    worst_state: str  # the state holding that entry
    leg_modes: np.ndarray  # (4,) leg reference modes
    contact_set: np.ndarray  # (nc,)
    force_estimate: np.ndarray  # (4,) |Eq. 11 estimate| per leg, the reference's [N]


def shadow_run(scenario_text: str, duration: float) -> list[ShadowTick]:
    """Simulates `duration` [s] of the scenario with the oracle's tick driving the robot and the
    compiled tick shadowing it on the same context, tick for tick."""
    scenario = load_scenario(scenario_text=scenario_text)
    scenario.simulation_duration = duration
    compiled_update = ProjectedImpedanceController._update
    shadowed: dict[int, object] = {}

    def dispatch(self, context, discrete_state) -> None:
        # The periodic event holds the class's update as it was when the controller was built.
        shadowed.get(id(self), functools.partial(compiled_update, self))(context, discrete_state)

    ProjectedImpedanceController._update = dispatch
    try:
        built = MakePedipulationDiagram(scenario)
    finally:
        ProjectedImpedanceController._update = compiled_update
    controller = built.diagram.GetSubsystemByName("controller")
    assert isinstance(controller, ProjectedImpedanceController)
    reference_update = ReferenceTick(controller).update
    shadow = controller.AllocateDiscreteVariables()
    names = ("command", "reference", "ramp", "hold", "estimate", "diagnostics")
    ticks = []

    def update(context, discrete_state) -> None:
        shadow.SetFrom(context.get_discrete_state())  # as the framework hands it to an update
        compiled_update(controller, context, shadow)
        reference_update(context, discrete_state)
        worst, worst_state = 0.0, ""
        for name, index in zip(names, controller._state_indices, strict=True):
            compiled = shadow.get_vector(index).value().copy()
            reference = discrete_state.get_vector(index).value().copy()
            if name == "diagnostics":
                for field in _TIMINGS:
                    compiled[controller.diag[field]] = reference[controller.diag[field]] = 0.0
                status_compiled = compiled[controller.diag["status"]][0]
                status_reference = reference[controller.diag["status"]][0]
                estimate = reference[controller.diag["force_estimate"]].reshape(4, 3)
            ratio = float(np.max(np.abs(compiled - reference) / (ATOL + RTOL * np.abs(reference))))
            if not ratio <= worst:
                worst, worst_state = ratio, name
        ticks.append(
            ShadowTick(
                time=context.get_time(),
                status_compiled=status_compiled,
                status_reference=status_reference,
                worst=worst,
                worst_state=worst_state,
                leg_modes=np.round(controller.leg_reference_port.Eval(context)[0::12]).astype(int),
                contact_set=controller.contact_set_port.Eval(context).copy(),
                force_estimate=np.linalg.norm(estimate, axis=1),
            )
        )

    shadowed[id(controller)] = update
    Simulator(built.diagram).AdvanceTo(duration)
    return ticks


# (mission, scenario fields, simulated duration [s]); each long enough to reach what it checks
# (see test_shadow_run_covers_its_mission).
SHADOW_RUNS = {
    # IV-A: FL lifted (a joint impedance while its ramp runs out, then the joint reference, then
    # the 5-D foot pose) and the first second of the torso circle.
    "iv_a": (str(missions_dir() / "quick" / "torso_circle_one_lap.yaml"), "robot: {initial_pose: standing}", 5.0),
    # IV-B: the trunk on one prong, both front feet lifted and held, the first rotation.
    "iv_b": (str(missions_dir() / "quick" / "pivot_rotations_once.yaml"), "robot: {initial_pose: standing}", 12.0),
    # obstacle_sensing: stand-up, FR lifted, both presses (the impedance estimate stops them).
    "obstacle_sensing": ("obstacle_sensing", "force_estimate: impedance", 13.0),
}


@pytest.fixture(scope="module", params=sorted(SHADOW_RUNS))
def shadow(request) -> tuple[str, list[ShadowTick]]:
    mission, fields, duration = SHADOW_RUNS[request.param]
    text = f"{{mission: {mission}, controller: projected_impedance, {fields}}}"
    return request.param, shadow_run(text, duration)


def test_compiled_tick_has_the_reference_status_every_tick(shadow):
    _, ticks = shadow
    different = [
        (t.time, t.status_compiled, t.status_reference) for t in ticks if t.status_compiled != t.status_reference
    ]
    assert not different


def test_compiled_tick_gives_the_reference_state_every_tick(shadow):
    _, ticks = shadow
    worst = max(ticks, key=lambda t: t.worst)
    assert worst.worst <= 1.0, f"{worst.worst_state} off by {worst.worst} tolerances at t = {worst.time} s"


def test_shadow_run_covers_its_mission(shadow):
    name, ticks = shadow
    modes = np.array([t.leg_modes for t in ticks])
    contact = np.array([t.contact_set for t in ticks])
    estimate = np.array([t.force_estimate for t in ticks])
    assert np.mean([t.status_reference == STATUS_OK for t in ticks]) > 0.99
    if name == "iv_a":
        assert np.any((modes[:, 1] == 0) & (contact[:, 1] == 0.0))  # FL's idle joint impedance
        assert np.count_nonzero(modes[:, 1] == references.LEG_MODE_FOOT_POSE) > 500  # > 1 s of the 5-D task
    elif name == "iv_b":
        on_prong = contact[:, 4] == 1.0
        front_feet_held = (modes[:, 0] == references.LEG_MODE_FOOT) & (modes[:, 1] == references.LEG_MODE_FOOT)
        assert np.count_nonzero(on_prong & front_feet_held) > 500
    else:
        pressing = modes[:, 0] != 0
        assert np.any(modes[:, 0] == references.LEG_MODE_JOINTS) and np.any(modes[:, 0] == references.LEG_MODE_FOOT)
        assert np.max(estimate[pressing, 0]) > 8.0  # the presses pushed (12 N commanded)
        assert np.all(contact[-1] == 1.0)  # FR back on the ground


# ------------------------------------------------------------------------------------------------
# Standalone ticks of both paths.


def standing_controller(config: ProjectedImpedanceConfig | None = None):
    controller = ProjectedImpedanceController(config or ProjectedImpedanceConfig())
    context = standing_context(controller)
    return controller, context


def next_states(controller, context, update) -> dict[str, np.ndarray]:
    values = controller.AllocateDiscreteVariables()
    values.SetFrom(context.get_discrete_state())
    update(context, values)
    states = {index: values.get_vector(index).value().copy() for index in controller._state_indices}
    diag = states[controller.diagnostics_state]
    for field in _TIMINGS:
        diag[controller.diag[field]] = 0.0
    return states, values


def assert_paths_agree(controller, context) -> dict[str, np.ndarray]:
    """Ticks both paths on `context` (the compiled one first) and checks they agree; advances the
    context with the reference's states and returns them."""
    compiled, _ = next_states(controller, context, controller._update)
    reference, values = next_states(controller, context, ReferenceTick(controller).update)
    for index in controller._state_indices:
        np.testing.assert_allclose(compiled[index], reference[index], rtol=RTOL, atol=ATOL)
    context.SetDiscreteState(values)
    return reference


def status_of(controller, states) -> float:
    return states[controller.diagnostics_state][controller.diag["status"]][0]


@pytest.fixture(scope="module")
def standing() -> ProjectedImpedanceController:
    """A controller on the compiled path (so both paths are ready to tick), standing on four feet."""
    controller, _ = standing_controller()
    return controller


def _fresh_context(controller):
    """A standing context on which both paths have ticked three times alike."""
    context = standing_context(controller)
    for _ in range(3):
        assert status_of(controller, assert_paths_agree(controller, context)) == STATUS_OK
    return context


NON_FINITE_INPUTS = [
    ("base_state", 2, np.nan),
    ("base_state", 11, np.inf),
    ("position_measured", 4, np.nan),
    ("velocity_measured", 7, -np.inf),
    ("contact_set", 1, np.nan),
    ("body_reference", 0, np.nan),
    ("leg_reference", 1, np.nan),
    ("safety_polygon", 5, np.inf),
    ("friction", 0, np.nan),
]


@pytest.mark.parametrize(("port", "entry", "value"), NON_FINITE_INPUTS)
def test_non_finite_input_holds_the_last_command_on_both_paths(standing, port, entry, value):
    controller = standing
    context = _fresh_context(controller)
    good = context.get_discrete_state(controller.command_state).value().copy()
    system_port = controller.GetInputPort(port)
    x = (
        system_port.Eval(context).copy()
        if system_port.HasValue(context)
        else {
            "body_reference": np.concatenate(
                [context.get_discrete_state(controller.hold_state).value()[1:8], np.zeros(12)]
            ),
            "leg_reference": np.zeros(references.LEG_REFERENCE_SIZE),
            "contact_set": controller.default_contact_set.copy(),
            "safety_polygon": np.zeros(references.SAFETY_POLYGON_SIZE),
            "friction": np.array([controller.config.friction]),
        }[port]
    )
    x[entry] = value
    system_port.FixValue(context, x)
    states = assert_paths_agree(controller, context)
    assert status_of(controller, states) == STATUS_BAD_INPUT
    command = states[controller.command_state]
    assert np.all(np.isfinite(command))
    np.testing.assert_array_equal(command[48:60], good[48:60])
    np.testing.assert_array_equal(command[12:24], 0.0)


def test_friction_that_is_not_positive_is_a_bad_input_on_both_paths(standing):
    controller = standing
    context = _fresh_context(controller)
    controller.friction_port.FixValue(context, np.array([0.0]))
    assert status_of(controller, assert_paths_agree(controller, context)) == STATUS_BAD_INPUT


def test_zero_quaternion_fails_without_nan_on_both_paths(standing):
    controller = standing
    context = _fresh_context(controller)
    base = controller.base_state_port.Eval(context).copy()
    base[0:4] = 0.0
    controller.base_state_port.FixValue(context, base)
    states = assert_paths_agree(controller, context)
    assert status_of(controller, states) == STATUS_QP_FAILED
    assert np.all(np.isfinite(states[controller.command_state]))


def test_infeasible_contact_qp_fails_and_recovers_alike_on_both_paths():
    # 200 N minimum per loaded foot: four feet cannot balance a 13 kg robot, and a tenth of the
    # effort limits cannot press them that hard (no relaxed balance either).
    config = ProjectedImpedanceConfig(min_normal_force=200.0, torque_limit_scale=0.1, contact_ramp_time=0.02)
    controller, context = standing_controller(config)
    controller.contact_set_port.FixValue(context, np.zeros(4))
    statuses = []
    for _ in range(2):
        statuses.append(status_of(controller, assert_paths_agree(controller, context)))
    controller.contact_set_port.FixValue(context, np.ones(4))
    for _ in range(15):
        statuses.append(status_of(controller, assert_paths_agree(controller, context)))
    controller.contact_set_port.FixValue(context, np.zeros(4))
    for _ in range(15):
        statuses.append(status_of(controller, assert_paths_agree(controller, context)))
    assert STATUS_QP_FAILED in statuses
    assert statuses[0] == statuses[-1] == STATUS_OK


@pytest.mark.parametrize("mode", [references.LEG_MODE_FOOT_POSE, references.LEG_MODE_SHANK_POSE])
def test_lifting_a_foot_to_a_world_pose_agrees_on_both_paths(mode):
    # Standing, then FR's load ramped out (in 10 ticks) and the leg moving: the idle joint
    # impedance, then FR's foot held 5 cm up with its calf pitched (the 5-D task, or the 6-D shank
    # task with the calf's yaw held too) with the force estimate's filter running. The inputs stay
    # fixed, so the centre of mass stays on the FL-RR diagonal; a trunk reference 2 cm towards FR
    # asks for an acceleration that way, which moves the centre of pressure into the FL-RR-RL
    # triangle and keeps the contact QP feasible.
    controller, context = standing_controller(ProjectedImpedanceConfig(contact_ramp_time=0.02))
    base = controller.base_state_port.Eval(context)
    s = controller.model.update(base, robot.STANDING_Q, np.zeros(12))
    X = initial_trunk_pose(RobotConfig(initial_pose="standing"))
    towards_FR = references.body_reference_vector(X.translation() + np.array([0.02, -0.02, 0.0]), X.rotation())
    controller.body_reference_port.FixValue(context, towards_FR)
    for _ in range(3):
        assert_paths_agree(controller, context)
    controller.contact_set_port.FixValue(context, references.contact_set_vector(("FL", "RR", "RL")))
    controller.velocity_port.FixValue(context, np.linspace(-0.2, 0.2, 12))
    target = s.p_contacts[0] + np.array([0.0, 0.0, 0.05])
    calf_pitch = np.array([0.0, 0.1, 0.0])  # the calf's reference orientation, a rotation vector [rad]
    legs = references.leg_reference_vector({"FR": (mode, target, np.zeros(3), calf_pitch)})
    foot_task_ticks = 0
    for k in range(60):
        if k == 30:
            controller.leg_reference_port.FixValue(context, legs)
        states = assert_paths_agree(controller, context)
        diag = states[controller.diagnostics_state]
        if status_of(controller, states) == STATUS_OK and diag[controller.diag["foot_errors"]][0] > 0.0:
            foot_task_ticks += 1
    assert foot_task_ticks > 20
    assert states[controller.ramp_state][0] == 0.0


def test_no_tick_compiles_whichever_inputs_are_connected():
    if not jit.ENABLED:
        pytest.skip("PEDI_DRAKE_JIT=0: nothing is compiled")
    controller, context = standing_controller()
    compiled_signatures = len(projected_impedance_tick.projected_impedance_tick.signatures)
    X = initial_trunk_pose(RobotConfig(initial_pose="standing"))
    optional = {
        controller.body_reference_port: references.body_reference_vector(X.translation(), X.rotation()),
        controller.leg_reference_port: np.zeros(references.LEG_REFERENCE_SIZE),
        controller.contact_set_port: np.ones(4),
        controller.safety_polygon_port: np.zeros(references.SAFETY_POLYGON_SIZE),
        controller.friction_port: np.array([0.8]),
    }
    for port, value in optional.items():
        port.FixValue(context, value)
        next_states(controller, context, controller._update)
        fresh = controller.CreateDefaultContext()  # this input alone among the optional ones
        for required in (controller.base_state_port, controller.position_port, controller.velocity_port):
            required.FixValue(fresh, required.Eval(context))
        port.FixValue(fresh, value)
        next_states(controller, fresh, controller._update)
    assert len(projected_impedance_tick.projected_impedance_tick.signatures) == compiled_signatures


# ------------------------------------------------------------------------------------------------
# Kernels against their Python source and against projected_dynamics.py.

RNG_SEED = 20261202


def random_tick_inputs(controller, rng) -> list:
    """Arguments of projected_impedance_tick at a random standing-like state, contact set and leg
    references (every leg mode among them), on the controller's records."""
    X = initial_trunk_pose(RobotConfig(initial_pose="standing"))
    quaternion = X.rotation().ToQuaternion().wxyz() + rng.normal(0, 0.02, 4)
    base = np.concatenate([quaternion, X.translation() + rng.normal(0, 0.01, 3), rng.normal(0, 0.1, 6)])
    q = robot.STANDING_Q + rng.normal(0, 0.05, 12)
    qd = rng.normal(0, 0.5, 12)
    nc = controller.num_contacts
    contact_set = (rng.uniform(size=nc) > 0.3).astype(float)
    contact_set[2:4] = 1.0  # the hind feet keep the QP feasible most of the time
    s = controller.model.update(base, q, qd)
    legs = {}
    for i, leg in enumerate(robot.LEG_NAMES):
        mode = int(rng.integers(0, 4))
        if contact_set[i] or mode == 0:
            continue
        if mode == references.LEG_MODE_JOINTS:
            legs[leg] = (
                mode,
                q[3 * i : 3 * i + 3] + rng.normal(0, 0.05, 3),
                rng.normal(0, 0.3, 3),
                rng.normal(0, 1, 3),
            )
        else:
            legs[leg] = (mode, s.p_contacts[i] + rng.normal(0, 0.02, 3), rng.normal(0, 0.1, 3), rng.normal(0, 0.2, 3))
    body = np.concatenate([X.translation(), X.rotation().ToQuaternion().wxyz(), rng.normal(0, 0.1, 12)])
    last_ramp = np.clip(contact_set + rng.uniform(-0.5, 0.5, nc), 0.0, 1.0)
    last_hold = np.concatenate([[1.0], X.translation(), X.rotation().ToQuaternion().wxyz()])
    last_estimate = np.zeros(28)
    last_estimate[6::7] = rng.integers(0, 2, 4)
    last_estimate[np.arange(28) % 7 != 6] = rng.normal(0, 0.1, 24)
    last_diag = np.zeros(controller.diagnostics_port.size())
    last_command = np.concatenate([q, qd, np.zeros(24), rng.normal(0, 3, 12)])
    inputs = [
        base,
        q,
        qd,
        contact_set,
        body,
        True,
        references.leg_reference_vector(legs),
        np.zeros(references.SAFETY_POLYGON_SIZE),
        np.array([0.6]),
        rng.normal(0, [0.5, 0.5, 0.5, 5.0, 5.0, 20.0]),  # a load on the trunk [N m, N]
        last_command,
        np.concatenate([q, qd]),
        last_ramp,
        last_hold,
        last_estimate,
        last_diag,
    ]
    outputs = [
        np.zeros(60),
        np.zeros(24),
        np.zeros(nc),
        np.zeros(8),
        np.zeros(28),
        np.zeros(controller.diagnostics_port.size()),
    ]
    return inputs, outputs


def test_tick_kernel_equals_its_python_source(standing):
    if not jit.ENABLED:
        pytest.skip("PEDI_DRAKE_JIT=0: the kernel is its Python source")
    controller = standing
    rng = np.random.default_rng(RNG_SEED)
    statuses = set()
    for _ in range(40):
        inputs, outputs = random_tick_inputs(controller, rng)
        python_outputs = [x.copy() for x in outputs]
        status = projected_impedance_tick.projected_impedance_tick(
            controller._tick_params,
            controller.model.dynamics.model_record,
            controller.model.dynamics.new_output(),
            tuple(inputs[:10]),
            controller.terrain,
            *inputs[10:],
            *outputs,
        )
        python_status = projected_impedance_tick.projected_impedance_tick.py_func(
            jit.python_records(controller._tick_params),
            jit.python_records(controller.model.dynamics.model_record),
            jit.python_records(controller.model.dynamics.new_output()),
            tuple(inputs[:10]),
            controller.terrain,
            *inputs[10:],
            *python_outputs,
        )
        assert status == python_status
        statuses.add(status)
        for compiled, python in zip(outputs, python_outputs, strict=True):
            np.testing.assert_allclose(compiled, python, rtol=1e-9, atol=1e-9)
    assert STATUS_OK in statuses


def _random_contact_jacobian(rng, rows: int, nv: int = 18, dependent: bool = False) -> np.ndarray:
    Jc = rng.normal(size=(rows, nv))
    if dependent and rows >= 6:
        Jc[-3:] = Jc[:3] + 1e-12 * rng.normal(size=(3, nv))  # two prong tips on one rigid body
    return Jc


def _random_inertia(rng, nv: int = 18) -> np.ndarray:
    X = rng.normal(size=(nv, nv))
    return X @ X.T + 0.1 * np.eye(nv)


def test_symmetric_eigen_decomposes_like_lapack(rng):
    for n in (1, 2, 3, 5, 9, 12, 18):
        for rank in sorted({0, 1, n // 2, n}):
            X = rng.normal(size=(n, rank)) * 10.0 ** rng.uniform(-3, 3)
            A = X @ X.T - (0.5 * np.eye(n) if rank == n else 0.0)  # an indefinite one too
            w, W = np.empty(n), np.empty((n, n))
            assert symmetric_eigen(A, w, W)
            scale = max(np.abs(A).max(), 1e-300)
            np.testing.assert_allclose(w, np.linalg.eigvalsh(A), rtol=0, atol=1e-13 * scale)
            np.testing.assert_allclose(W @ W.T, np.eye(n), rtol=0, atol=1e-13)
            np.testing.assert_allclose(W.T @ np.diag(w) @ W, A, rtol=0, atol=1e-13 * scale)


def test_symmetric_pseudo_inverse_keeps_the_reference_rank_and_value(rng):
    for n in (2, 3, 5, 9, 12, 18):
        for rank in range(n + 1):
            X = rng.normal(size=(n, rank))
            A = X @ X.T
            out = np.empty((n, n))
            for scale in (None, float(np.linalg.norm(A)) * 10.0):
                expected, expected_rank = pd.symmetric_pseudo_inverse(A, 1e-6, scale)
                got = symmetric_pseudo_inverse(A, 1e-6, -1.0 if scale is None else scale, out)
                assert got == expected_rank
                np.testing.assert_allclose(out, expected, rtol=0, atol=1e-9 * max(1.0, np.abs(expected).max()))


def test_decompositions_fail_on_non_finite_or_singular_input_without_raising():
    n = 4
    bad = np.eye(n)
    bad[1, 2] = bad[2, 1] = np.nan
    assert not symmetric_eigen(bad, np.empty(n), np.empty((n, n)))
    assert symmetric_pseudo_inverse(bad, 1e-6, -1.0, np.empty((n, n))) == -1
    assert not lu_solve(bad.copy(), np.ones((n, 1)))
    assert not lu_solve(np.zeros((n, n)), np.ones((n, 1)))


def test_lu_solve_solves_like_numpy(rng):
    for n in (1, 3, 18):
        A = rng.normal(size=(n, n)) + n * np.eye(n)
        B = rng.normal(size=(n, n + 1))
        X = B.copy()
        assert lu_solve(A.copy(), X)
        np.testing.assert_allclose(X, np.linalg.solve(A, B), rtol=0, atol=1e-12)


def _reference_dynamics(rng, rows, dependent=False):
    nv = 18
    M = _random_inertia(rng)
    h = rng.normal(size=nv)
    Jc = _random_contact_jacobian(rng, rows, dependent=dependent)
    Jcdot_v = rng.normal(size=rows)
    v = rng.normal(size=nv)
    return M, h, Jc, Jcdot_v, v


@pytest.mark.parametrize(("rows", "dependent"), [(0, False), (9, False), (12, False), (18, True)])
def test_constrained_dynamics_kernel_equals_projected_dynamics(rng, rows, dependent):
    M, h, Jc, Jcdot_v, v = _reference_dynamics(rng, rows, dependent)
    expected = pd.constrained_dynamics(M, h, Jc, Jcdot_v, v, 10.0, 1e-6)
    P, A, vdot_0 = np.empty((18, 18)), np.empty((18, 18)), np.empty(18)
    rank = cpd.constrained_dynamics(M, h, Jc, Jcdot_v, v, 10.0, 1e-6, P, A, vdot_0)
    assert rank == expected.projection.rank
    np.testing.assert_allclose(P, expected.projection.P, rtol=0, atol=1e-10)
    np.testing.assert_allclose(A, expected.A, rtol=0, atol=1e-10 * np.abs(expected.A).max())
    np.testing.assert_allclose(vdot_0, expected.vdot_0, rtol=0, atol=1e-9 * np.abs(expected.vdot_0).max())


def test_prioritized_force_and_torques_equal_projected_dynamics(rng):
    nv = 18
    for trial in range(20):
        rows = int(rng.choice([6, 9, 12]))
        M, h, Jc, Jcdot_v, v = _reference_dynamics(rng, rows)
        dynamics = pd.constrained_dynamics(M, h, Jc, Jcdot_v, v, 10.0, 1e-6)
        m = int(rng.choice([0, 3, 5, 8]))
        impedance = pd.ImpedanceTask(
            "feet",
            rng.normal(size=(m, nv)),
            *(rng.normal(size=m) for _ in range(4)),
            rng.uniform(10, 600, m),
            rng.uniform(0, 30, m),
        )
        S = np.eye(nv)[6:]
        sizes = [3, 3, 12] if trial % 2 else [6, 12]
        lower = [
            pd.AccelerationTask(
                f"task{k}",
                rng.normal(size=(size, nv)) if size < 12 else S,
                rng.normal(size=size),
                rng.normal(size=size),
            )
            for k, size in enumerate(sizes)
        ]
        expected = pd.prioritized_force(dynamics, v, impedance, lower, 1e-6)
        u, F, Lambda, residuals = np.empty(nv), np.empty(m), np.empty((m, m)), np.zeros(5)
        count = cpd.prioritized_force(
            dynamics.A,
            dynamics.vdot_0,
            dynamics.projection.P,
            nv - dynamics.projection.rank,
            impedance.J,
            impedance.Jdot_v,
            impedance.error,
            impedance.error_rate,
            impedance.acceleration_ref,
            impedance.stiffness,
            impedance.damping,
            np.vstack([t.J for t in lower]),
            np.concatenate([t.Jdot_v for t in lower]),
            np.concatenate([t.desired for t in lower]),
            np.cumsum([0, *sizes]),
            1e-6,
            u,
            F,
            Lambda,
            residuals,
        )
        assert count == len(expected.residuals)
        scale = max(1.0, np.abs(expected.u).max())
        np.testing.assert_allclose(u, expected.u, rtol=0, atol=1e-8 * scale)
        np.testing.assert_allclose(F, expected.impedance_force, rtol=0, atol=1e-8 * scale)
        np.testing.assert_allclose(
            Lambda, expected.impedance_inertia, rtol=0, atol=1e-8 * max(1.0, np.max(np.abs(Lambda), initial=0.0))
        )
        np.testing.assert_allclose(residuals[:count], expected.residuals, rtol=0, atol=1e-8 * scale)
        free = pd.constraint_free_torque(dynamics, expected.u, S, 1e-6)
        tau_m, vdot = np.empty(12), np.empty(nv)
        assert cpd.constraint_free_torque(
            dynamics.A, dynamics.vdot_0, dynamics.projection.P, expected.u, np.arange(6, 18), 1e-6, tau_m, vdot
        )
        np.testing.assert_allclose(tau_m, free.tau_m, rtol=0, atol=1e-8 * max(1.0, np.abs(free.tau_m).max()))
        np.testing.assert_allclose(vdot, free.vdot, rtol=0, atol=1e-8 * max(1.0, np.abs(free.vdot).max()))


def test_contact_forces_kernel_solves_the_reference_qp(standing):
    controller = standing
    oracle = ReferenceTick(controller)
    rng = np.random.default_rng(RNG_SEED)
    outcomes = {cpd.CONTACT_FORCES_OK: 0, cpd.CONTACT_FORCES_RELAXED: 0}
    for _ in range(30):
        inputs, _ = random_tick_inputs(controller, rng)
        s = controller.model.update(inputs[0], inputs[1], inputs[2])
        held = np.flatnonzero(inputs[3] > 0.5)
        rows = (3 * held[:, None] + np.arange(3)).ravel()
        Jc = s.J_contacts[rows]
        ramp = rng.uniform(0.2, 1.0, len(held))
        share = np.zeros(3 * len(held))
        share[2::3] = ramp * oracle.total_weight / ramp.sum()
        vdot = rng.normal(0, 0.5, 18)
        problem = pd.ContactForceProblem(
            Jc=Jc,
            r=s.M @ vdot + s.h,
            unactuated=oracle.unactuated,
            actuated=controller.v_index,
            ramp=ramp,
            friction=0.6 / np.sqrt(2.0),
            f_min=5.0,
            f_max=250.0,
            torque_limit=0.9 * robot.EFFORT_LIMIT,
            force_share=share,
            torque_weight=1.0,
            force_weight=0.1,
        )
        try:
            expected = pd.solve_contact_forces(problem)
        except QpInfeasible:
            expected = None
        lam, tau, residual = np.empty(len(rows)), np.empty(12), np.zeros(1)
        status = cpd.contact_forces(
            Jc,
            problem.r,
            controller._tick_params[0]["unactuated"],
            controller._tick_params[0]["v_joints"],
            ramp,
            problem.friction,
            np.tile(UP, (len(ramp), 1)),
            5.0,
            250.0,
            problem.torque_limit,
            share,
            1.0,
            0.1,
            1e-6,
            projected_impedance_tick.CONTACT_QP_PROXIMAL_WEIGHT,
            lam,
            tau,
            residual,
        )
        if expected is None:
            assert status == cpd.CONTACT_FORCES_INFEASIBLE
            continue
        assert status == (cpd.CONTACT_FORCES_RELAXED if expected.relaxed else cpd.CONTACT_FORCES_OK)
        outcomes[status] += 1
        np.testing.assert_allclose(lam, expected.lam, rtol=RTOL, atol=ATOL)
        np.testing.assert_allclose(tau, expected.tau, rtol=RTOL, atol=ATOL)
        assert residual[0] == pytest.approx(expected.equality_residual, abs=1e-6 if expected.relaxed else 1e-9)
    # Both the exact balance and the relaxed one met, several times each.
    assert outcomes[cpd.CONTACT_FORCES_OK] > 5 and outcomes[cpd.CONTACT_FORCES_RELAXED] > 2, outcomes
