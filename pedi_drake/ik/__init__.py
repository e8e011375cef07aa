"""Leg inverse kinematics: constrained FABRIK (the solver), a closed-form reference, LegIkSystem."""

from pedi_drake.ik.analytic import leg_ik_solutions, solve_leg_ik_analytic
from pedi_drake.ik.fabrik import LegIkResult, extended_leg_q, solve_leg_ik
from pedi_drake.ik.leg_ik_system import LegIkSystem

__all__ = [
    "LegIkResult",
    "LegIkSystem",
    "extended_leg_q",
    "leg_ik_solutions",
    "solve_leg_ik",
    "solve_leg_ik_analytic",
]
