"""Go1 LCM message types (wire-compatible with the walk-these-ways `lcm_position` bridge), and
the project's own operator messages (`foot_command_lcmt` and its answer `foot_feedback_lcmt`,
not part of the bridge).

The `.lcm` files here have no `package` line, as on the robot, so `lcm-gen -p` writes one
top-level module per type and no `__init__.py`; this file makes them importable as
`pedi_drake.go1_driver.lcmtypes.<type>`. The generated modules import only the standard library.
Regenerate with ./regenerate.sh (lcm-gen from the `lcm` 1.5.3 wheel).
"""

from pedi_drake.go1_driver.lcmtypes.foot_command_lcmt import foot_command_lcmt
from pedi_drake.go1_driver.lcmtypes.foot_feedback_lcmt import foot_feedback_lcmt
from pedi_drake.go1_driver.lcmtypes.leg_control_data_lcmt import leg_control_data_lcmt
from pedi_drake.go1_driver.lcmtypes.pd_tau_targets_lcmt import pd_tau_targets_lcmt
from pedi_drake.go1_driver.lcmtypes.rc_command_lcmt import rc_command_lcmt
from pedi_drake.go1_driver.lcmtypes.state_estimator_lcmt import state_estimator_lcmt

__all__ = [
    "foot_command_lcmt", "foot_feedback_lcmt",
    "leg_control_data_lcmt", "pd_tau_targets_lcmt", "rc_command_lcmt", "state_estimator_lcmt",
]
