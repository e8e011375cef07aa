"""ProjectedImpedanceController: paper 002's whole-body controller as a Drake LeafSystem.

The maths (projector, constrained dynamics, prioritised impedance, contact-force QP, force
estimate: Eqs. 2 to 11 of paper 002) is in `compiled_projected_dynamics.py`; every `period` [s]
this adapter hands the controller's ports and state to one compiled call
(`projected_impedance_tick.py`), which stores the next `go1.command` in the Context. It has
exactly the ports of `WholeBodyController`, so missions, the estimator and the LCM driver use it
unchanged. tests/reference_projected_impedance_tick.py is the same tick in numpy on Drake's
dynamics, the oracle tests/test_projected_impedance_tick.py runs beside it on paper 002's missions.

Tasks at one instant (world frame):
    constraint Jacobian: the feet and prong tips in the contact set, or still ramping out;
    first priority (impedance, Eq. 10): every lifted leg with a reference. A world foot
    reference (leg mode 1, or mode 3 with the calf's roll and pitch: the 5-D task) is used as is:
    the foot is held in the world and the trunk yields to it. A joint reference (mode 2, the
    mission's IK answer in the trunk frame) is turned into the foot position it means on the
    trunk as estimated now, so it moves with the trunk (a trunk tracking error, such as the
    deliberate one of a trunk pressed onto its prongs, does not become a foot error). A lifted
    leg without a reference is a joint impedance towards the nominal posture;
    second priority: the trunk pose, in the feet's dynamically consistent null space: its position
    first, then its attitude in the position's null space (`torso_position_first`; else the six
    rows together). When the feet leave the trunk fewer than six directions (a 5-D foot task
    on three stance legs leaves four), the trunk keeps its path and gives up attitude. On loaded
    prongs the order turns round: a prong tip pins the trunk's position, and its attitude (the
    turn about the tip) is what is left to control;
    last priority: the joint posture, in the null space of all the above;
    constrained space: the contact-force QP (Eq. 7), tau = tau_m + tau_c (Eq. 8). Where no forces
    within the friction pyramids and torque limits give the planned acceleration's wrench balance
    (a swing's reaction on three stance feet), the nearest balance they allow is taken and the
    tick reports status 3 (contacts relaxed), as the HQP does for its own fallback.
The `safety_polygon` input is read for the capture-point diagnostic only: paper 002's law has
no balance task, the mission keeps the centre of mass over the support.

Commands: tau_ff is the total torque; q_des, qd_des integrate the planned joint accelerations
(kept near the measurement) under the configured joint PD (no stiffness by default, so the foot
stiffness is the commanded one). A failed QP or a non-finite input never emits NaN: the last good
command is held with zero velocity target and `failure_kd` damping, and reported.

Diagnostics: the layout of `WholeBodyController` (same names and places, so the run's judging
reads either; `solve_time` is the compiled call's), then `force_estimate` (12: Eq. 11 per leg,
world frame [N], zero for legs without a foot impedance) and `constraint_rank` (rank of the held
contacts' Jacobian).
"""

import time

import numpy as np
from pydrake.systems.framework import Context, DiscreteValues

from pedi_drake import robot
from pedi_drake.control import projected_impedance_tick, references
from pedi_drake.control.config import ProjectedImpedanceConfig
from pedi_drake.control.controller_ports import declare_controller_ports
from pedi_drake.control.robot_model import ControllerModel
from pedi_drake.control.tick_steps import STATUS_CONTACTS_RELAXED, STATUS_OK
from pedi_drake.control.whole_body_controller import diagnostics_layout
from pedi_drake.exceptions import ConfigError
from pedi_drake.leaf_system import LeafSystemWithoutWitnesses
from pedi_drake.prongs import ProngDesign
from pedi_drake.terrain import terrain_map

# Force-estimate filter state: per leg, the last impedance error rate (3), the filtered error
# acceleration (3), and whether the leg had a foot impedance at the last tick (1).
_ESTIMATE_STATE_SIZE = 4 * 7


def projected_diagnostics_layout(num_contacts: int) -> dict[str, slice]:
    """WholeBodyController's diagnostics layout, then force_estimate (12) and constraint_rank (1)."""
    layout = diagnostics_layout(num_contacts)
    start = layout["contact_ramp"].stop
    layout["force_estimate"] = slice(start, start + 12)  # [N], world, per leg FR, FL, RR, RL
    layout["constraint_rank"] = slice(start + 12, start + 13)
    return layout


class ProjectedImpedanceController(LeafSystemWithoutWitnesses):
    """Paper 002's projected-inverse-dynamics impedance controller for the Go1 (and its prongs)."""

    def __init__(
        self, config: ProjectedImpedanceConfig, prongs: ProngDesign | None = None, terrain: np.ndarray | None = None
    ) -> None:
        """`terrain`: the map of the ground (`pedi_drake.terrain.terrain_table`), under which each
        held contact's friction pyramid stands on the terrain's normal; None: flat ground."""
        super().__init__()
        problems = config.validate()
        if problems:
            raise ConfigError("; ".join(problems))
        self.config = config
        self.terrain = terrain_map(terrain)
        self.model = ControllerModel(prongs, com_bias=False)
        nc = self.model.num_contacts
        self.num_contacts = nc
        nv = self.model.nv
        self.v_index = np.asarray(self.model.plant_map.v_index)
        self.diag = projected_diagnostics_layout(nc)
        self.default_contact_set = references.contact_set_vector(num_prongs=nc - 4)
        # The compiled tick's stand-ins for unconnected inputs. Writeable like a port's value: numba
        # types a read-only array apart, and a tick must not meet a type it was not compiled for.
        self._default_inputs = {
            "body": np.zeros(references.BODY_REFERENCE_SIZE),  # the tick fills in the held pose
            "leg": np.zeros(references.LEG_REFERENCE_SIZE),
            "polygon": np.zeros(references.SAFETY_POLYGON_SIZE),
            "friction": np.array([config.friction]),
            "trunk_wrench": np.zeros(6),
        }

        shared_states = declare_controller_ports(self, nc, config.failure_kd)
        self.estimate_state = self.DeclareDiscreteState(_ESTIMATE_STATE_SIZE)
        self.diagnostics_state = self.DeclareDiscreteState(self.diag["constraint_rank"].stop)
        # The discrete states in the compiled tick's argument order, and their group numbers.
        self._state_indices = (*shared_states, self.estimate_state, self.diagnostics_state)
        self._state_groups = tuple(int(index) for index in self._state_indices)
        # The optional inputs in the compiled tick's argument order (the body reference aside).
        self._optional_ports = (
            self.contact_set_port,
            self.leg_reference_port,
            self.safety_polygon_port,
            self.friction_port,
            self.trunk_wrench_port,
        )
        self._solve_time_entry = self.diag["solve_time"].start
        self._tick_time_entry = self.diag["tick_time"].start
        self.DeclarePeriodicDiscreteUpdateEvent(config.period, 0.0, self._update)
        # The same tick on demand (CalcForcedDiscreteVariableUpdate): tests and the benchmark.
        self.DeclareForcedDiscreteUpdateEvent(self._update)
        self.command_port = self.DeclareStateOutputPort("command", self.command_state)
        self.diagnostics_port = self.DeclareStateOutputPort("diagnostics", self.diagnostics_state)

        self._tick_params = projected_impedance_tick.tick_params(
            config, self.v_index, nv, nc, self.model.total_mass, self.diag
        )
        self._snapshot = self.model.dynamics.new_output()
        self._warm_up()

    def _warm_up(self) -> None:
        """Compiles (or loads from numba's cache) the compiled tick for the argument types a tick
        passes, by running ticks on a scratch context: never inside a control tick. The types are
        the same whichever inputs are connected (the stand-ins of unconnected ones are writeable
        float arrays like a port's value), so one signature serves every tick."""
        context = self.CreateDefaultContext()
        X_WB = np.array([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3])
        self.base_state_port.FixValue(context, np.concatenate([X_WB, np.zeros(6)]))
        self.position_port.FixValue(context, robot.STANDING_Q)
        self.velocity_port.FixValue(context, np.zeros(12))
        values = self.AllocateDiscreteVariables()
        self._update(context, values)
        # And with every optional input connected (the same signature, the other branches).
        self.body_reference_port.FixValue(context, np.concatenate([X_WB[4:], X_WB[:4], np.zeros(12)]))
        self.leg_reference_port.FixValue(context, np.zeros(references.LEG_REFERENCE_SIZE))
        self.contact_set_port.FixValue(context, self.default_contact_set)
        self.safety_polygon_port.FixValue(context, np.zeros(references.SAFETY_POLYGON_SIZE))
        self.friction_port.FixValue(context, np.array([self.config.friction]))
        self._update(context, values)

    def _update(self, context: Context, discrete_state: DiscreteValues) -> None:
        """The tick as one compiled call (projected_impedance_tick). The inputs go in as the ports' own float
        arrays and the states as views by group number: at these sizes every numpy or pydrake call
        saved is a microsecond."""
        start = time.perf_counter()
        defaults = self._default_inputs
        has_body = self.body_reference_port.HasValue(context)
        ports = self._optional_ports
        last = context.get_discrete_state()
        states = [last.value(group) for group in self._state_groups]
        outputs = [discrete_state.get_mutable_value(group) for group in self._state_groups]
        solve_start = time.perf_counter()
        inputs = (
            self.base_state_port.Eval(context),
            self.position_port.Eval(context),
            self.velocity_port.Eval(context),
            ports[0].Eval(context) if ports[0].HasValue(context) else self.default_contact_set,
            self.body_reference_port.Eval(context) if has_body else defaults["body"],
            has_body,
            ports[1].Eval(context) if ports[1].HasValue(context) else defaults["leg"],
            ports[2].Eval(context) if ports[2].HasValue(context) else defaults["polygon"],
            ports[3].Eval(context) if ports[3].HasValue(context) else defaults["friction"],
            ports[4].Eval(context) if ports[4].HasValue(context) else defaults["trunk_wrench"],
        )
        status = projected_impedance_tick.projected_impedance_tick(
            self._tick_params, self.model.dynamics.model_record, self._snapshot, inputs, self.terrain, *states, *outputs
        )
        diag = outputs[-1]
        now = time.perf_counter()
        if status in (STATUS_OK, STATUS_CONTACTS_RELAXED):
            diag[self._solve_time_entry] = now - solve_start
        diag[self._tick_time_entry] = now - start
