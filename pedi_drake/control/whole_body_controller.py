"""WholeBodyController: the task-priority QP controller as a Drake LeafSystem.

Every `period` [s] a discrete update reads the state estimate, the measured joints and the task
references, computes the dynamics terms (`go1_dynamics.py`), builds the configured stack
(`compiled_stack.py`), solves it with the hierarchical QP (`compiled_hqp.py`) and stores the next
`go1.command` in the Context, all in one compiled call (`whole_body_tick.py`); the `command`
output is that state (a zero-order hold).

Inputs (all numeric vectors; reference layouts in `pedi_drake.control.references`):
    base_state (13)         floating-base estimate [quat wxyz, p_WB, w_WB, v_WB], world frame
    position_measured (12)  joint angles [rad], Unitree order
    velocity_measured (12)  joint rates [rad/s], Unitree order
    body_reference (19)     trunk pose trajectory sample; unconnected: hold the first-tick pose
    leg_reference (48)      per-leg foot / joint references; unconnected: no leg task
    contact_set (4 + prongs) loaded contacts 0/1; unconnected: the four feet
    safety_polygon (20)     capture-point polygon (vertices in its frame); unconnected or n = 0:
                            the support polygon of the loaded contacts shrunk by `safety_margin`
    friction (1)            ground friction coefficient; unconnected: `config.friction`
Outputs:
    command (60)            go1.command: q_des, qd_des, kp, kd, tau_ff (Unitree order)
    diagnostics             see DIAGNOSTICS_LAYOUT

Discrete state (nothing that changes lives in Python members): the command, the integrated
joint reference (q, qd), the contact ramps, the held trunk pose, the diagnostics.

Commands: tau_ff is the QP's torque (tau = M_a vdot + h_a - J_a^T f); q_des, qd_des integrate the
QP's joint accelerations (kept near the measurement) under low PD gains, so the motor PD only
corrects what the feed-forward misses. A failed QP or a non-finite input never emits NaN: the
last good command is held with zero velocity target and `failure_kd` damping, and reported.
"""

import time

import numpy as np
from pydrake.systems.framework import Context, DiscreteValues

from pedi_drake import robot
from pedi_drake.control import compiled_stack, references, whole_body_tick
from pedi_drake.control.compiled_hqp import HqpSettings
from pedi_drake.control.config import HQP_MODES, STACKS, WholeBodyControllerConfig
from pedi_drake.control.controller_ports import declare_controller_ports
from pedi_drake.control.robot_model import ControllerModel
from pedi_drake.exceptions import ConfigError
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.prongs import ProngDesign
from pedi_drake.runtime.jit import new_record
from pedi_drake.terrain import terrain_map

MAX_LEVELS = 5


def diagnostics_layout(num_contacts: int) -> dict[str, slice]:
    """Named slices of the diagnostics vector."""
    sizes = [
        ("status", 1),  # 0 ok, 1 QP failed (last command held), 2 non-finite input, 3 contacts relaxed
        ("solve_time", 1),  # wall time of the HQP solve [s]
        ("tick_time", 1),  # wall time of the whole update [s]
        ("consecutive_failures", 1),
        ("total_failures", 1),
        ("capture_point", 2),  # [m], world xy
        ("trunk_position_error", 3),  # p_ref - p [m]
        ("trunk_orientation_error", 3),  # rotation vector of R_ref R^T [rad]
        ("foot_errors", 4),  # |p_ref - p_foot| of legs in foot mode, else 0 [m]
        ("level_residuals", MAX_LEVELS),  # equality residual per level (padded)
        ("contact_forces", 3 * num_contacts),  # [N], world frame
        ("tau_ff", 12),  # [N m]
        ("contact_ramp", num_contacts),  # [-]
    ]
    layout, start = {}, 0
    for name, size in sizes:
        layout[name] = slice(start, start + size)
        start += size
    return layout


class WholeBodyController(LeafSystemWithoutWitnesses):
    """Hierarchical whole-body QP controller for the Go1 (and its prongs)."""

    def __init__(
        self, config: WholeBodyControllerConfig, prongs: ProngDesign | None = None, terrain: np.ndarray | None = None
    ) -> None:
        """`terrain`: the map of the ground (`pedi_drake.terrain.terrain_table`), under which each
        contact's friction pyramid stands on the terrain's normal; None: flat ground."""
        super().__init__()
        if config.stack not in STACKS:
            raise ConfigError(f"whole_body.stack: must be one of {STACKS}, got {config.stack!r}")
        if config.hqp_mode not in HQP_MODES:
            raise ConfigError(f"whole_body.hqp_mode: must be one of {HQP_MODES}, got {config.hqp_mode!r}")
        if not config.period > 0.0:
            raise ConfigError(f"whole_body.period: must be > 0 s, got {config.period!r}")
        self.config = config
        # Constant after construction: the model (its scratch context is rewritten every tick).
        self.model = ControllerModel(prongs, com_bias=config.balance_com_bias)
        nc = self.model.num_contacts
        self.num_contacts = nc
        self.hqp_settings = HqpSettings()
        levels = compiled_stack.num_levels(config.stack)
        if config.level_weights and len(config.level_weights) != levels:
            raise ConfigError(
                f"whole_body.level_weights: the {config.stack} stack has {levels} levels, "
                f"got {len(config.level_weights)} weights"
            )
        self.diag = diagnostics_layout(nc)
        self.default_contact_set = references.contact_set_vector(num_prongs=nc - 4)
        self._compiled_records()
        # What an unconnected optional input reads as in the compiled tick, which only reads them
        # (writable all the same: a read-only array is another argument type, another compilation).
        self._no_body = np.zeros(references.BODY_REFERENCE_SIZE)
        self._no_leg_reference = np.zeros(references.LEG_REFERENCE_SIZE)
        self._no_safety_polygon = np.zeros(references.SAFETY_POLYGON_SIZE)
        self._default_friction = np.array([config.friction])
        self._no_trunk_wrench = np.zeros(6)
        self.terrain = terrain_map(terrain)

        shared_states = declare_controller_ports(self, nc, config.failure_kd)
        self.diagnostics_state = self.DeclareDiscreteState(self.diag["contact_ramp"].stop)
        # The discrete states in the compiled tick's argument order.
        self._state_indices = (*shared_states, self.diagnostics_state)
        self.DeclarePeriodicDiscreteUpdateEvent(config.period, 0.0, self._update)
        # The same tick on demand (CalcForcedDiscreteVariableUpdate): tests and the benchmark.
        self.DeclareForcedDiscreteUpdateEvent(self._update)
        self.command_port = self.DeclareStateOutputPort("command", self.command_state)
        self.diagnostics_port = self.DeclareStateOutputPort("diagnostics", self.diagnostics_state)
        self._warm_up()

    def _warm_up(self) -> None:
        """Compiles (or loads from numba's cache) the compiled tick for the argument types of a
        real tick, by running one on a scratch context: never inside a control tick."""
        context = self.CreateDefaultContext()
        standing = np.array(
            [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, robot.trunk_height_for(robot.STANDING_Q[1], robot.STANDING_Q[2])] + [0.0] * 6
        )
        self.base_state_port.FixValue(context, standing)
        self.position_port.FixValue(context, robot.STANDING_Q)
        self.velocity_port.FixValue(context, np.zeros(12))
        self._update(context, self.AllocateDiscreteVariables())

    def _compiled_records(self) -> None:
        """The compiled tick's constant records and its workspaces (a snapshot, a row table)."""
        nv, nc = self.model.nv, self.num_contacts
        self._stack_params = compiled_stack.stack_params(
            self.config, self.model.plant_map.v_index, nv, nc, self.model.total_mass
        )
        self._tick_params = whole_body_tick.tick_params(self.config, self.hqp_settings, self.diag, MAX_LEVELS)
        self._snapshot = self.model.dynamics.new_output()
        self._table = new_record(compiled_stack.table_dtype(nv, nc))

    def _update(self, context: Context, discrete_state: DiscreteValues) -> None:
        start = time.perf_counter()
        # A vector port's Eval is already a contiguous float64 array (no np.asarray a tick).
        base = self.base_state_port.Eval(context)
        q = self.position_port.Eval(context)
        qd = self.velocity_port.Eval(context)
        has_body = self.body_reference_port.HasValue(context)
        body = self.body_reference_port.Eval(context) if has_body else self._no_body
        contact_set = self._evaluated(self.contact_set_port, context, self.default_contact_set)
        leg_x = self._evaluated(self.leg_reference_port, context, self._no_leg_reference)
        polygon_x = self._evaluated(self.safety_polygon_port, context, self._no_safety_polygon)
        mu_x = self._evaluated(self.friction_port, context, self._default_friction)
        trunk_wrench = self._evaluated(self.trunk_wrench_port, context, self._no_trunk_wrench)
        # The framework hands the update the current state: the tick updates it in place.
        get = discrete_state.get_mutable_value
        state = [get(index) for index in self._state_indices]
        solve_start = time.perf_counter()
        whole_body_tick.whole_body_tick(
            self._tick_params,
            self._stack_params,
            self.model.dynamics.model_record,
            self._snapshot,
            (base, q, qd, contact_set, body, has_body, leg_x, polygon_x, mu_x, trunk_wrench),
            self.terrain,
            self._table,
            *state,
        )
        diag = state[-1]
        now = time.perf_counter()
        diag[self.diag["solve_time"]] = now - solve_start
        diag[self.diag["tick_time"]] = now - start

    @staticmethod
    def _evaluated(port, context: Context, default: np.ndarray) -> np.ndarray:
        """The port's value, or `default`."""
        return port.Eval(context) if port.HasValue(context) else default
