#!/usr/bin/env bash
# Regenerates the Python Go1 LCM types from the .lcm files in this folder.
# lcm-gen ships with the `lcm` PyPI wheel (1.5.3). The types have no package line, so each
# becomes a top-level module <type>.py here; __init__.py (hand-written) re-exports them.
set -euo pipefail
cd "$(dirname "$0")"
lcm-gen -p --ppath . pd_tau_targets_lcmt.lcm leg_control_data_lcmt.lcm state_estimator_lcmt.lcm rc_command_lcmt.lcm foot_command_lcmt.lcm foot_feedback_lcmt.lcm
