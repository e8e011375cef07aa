"""The ports and discrete states both whole-body controllers declare, in one place: missions, the
estimator, the controller switch and the LCM driver wire either controller alike."""

from pedi_drake.control import references
from pedi_drake.estimation.base_state import BASE_STATE_SIZE
from pedi_drake.go1_command import initial_command


def declare_controller_ports(system, num_contacts: int, failure_kd: float) -> tuple:
    """Declares on the LeafSystem `system`, as attributes, the controllers' inputs and the discrete
    states they share:

    inputs  base_state_port (13), position_port (12), velocity_port (12), body_reference_port,
            leg_reference_port, contact_set_port (num_contacts), safety_polygon_port,
            friction_port (1), trunk_wrench_port (6: an external wrench on the trunk the model
            lacks, [torque; force] at the trunk origin, world [N m, N], a carried load from
            pedi_drake.control.trunk_load_compensation; zero unconnected);
    states  command_state (60, go1.command, damping only until the first tick [N m s/rad]:
            `failure_kd`), reference_state (24: q_ref, qd_ref), ramp_state (num_contacts),
            hold_state (8: initialised flag, p_WB, quaternion).
    Returns the four states' indices, in that order (the compiled ticks' argument order).
    """
    system.base_state_port = system.DeclareVectorInputPort("base_state", BASE_STATE_SIZE)
    system.position_port = system.DeclareVectorInputPort("position_measured", 12)
    system.velocity_port = system.DeclareVectorInputPort("velocity_measured", 12)
    system.body_reference_port = system.DeclareVectorInputPort("body_reference", references.BODY_REFERENCE_SIZE)
    system.leg_reference_port = system.DeclareVectorInputPort("leg_reference", references.LEG_REFERENCE_SIZE)
    system.contact_set_port = system.DeclareVectorInputPort("contact_set", num_contacts)
    system.safety_polygon_port = system.DeclareVectorInputPort("safety_polygon", references.SAFETY_POLYGON_SIZE)
    system.friction_port = system.DeclareVectorInputPort("friction", 1)
    system.trunk_wrench_port = system.DeclareVectorInputPort("trunk_external_wrench", 6)
    system.command_state = system.DeclareDiscreteState(initial_command(failure_kd))
    system.reference_state = system.DeclareDiscreteState(24)
    system.ramp_state = system.DeclareDiscreteState(num_contacts)
    system.hold_state = system.DeclareDiscreteState(8)
    return system.command_state, system.reference_state, system.ramp_state, system.hold_state
