"""The linear programs over the RFP, built once per problem and re-solved with new coefficients.

`RfpLinearProgram(problem)` holds one MathematicalProgram over x = [F; lambda] with the problem's
equalities and inequalities, and answers three questions by updating coefficients only:

* `support(n)`: max n . F over the RFP (the support function; the exact projection's step);
* `ray(d)`: the largest f with f d in the RFP (the single-direction and Fibonacci methods);
* `feasible(F)`: whether F is rejectable.

LP solvers: "clp" (Drake's CLP: a dual simplex, about half Clarabel's time per small LP here) or
"clarabel" (interior point); the SOCP/SDP methods take "clarabel", "scs" or "csdp".
"""

import numpy as np
from pydrake.solvers import ClarabelSolver, ClpSolver, CsdpSolver, MathematicalProgram, ScsSolver, SolutionResult

from pedi_drake.exceptions import SufError
from pedi_drake.suf.problem import RejectableForceProblem

SOLVERS = {"clp": ClpSolver, "clarabel": ClarabelSolver, "scs": ScsSolver, "csdp": CsdpSolver}
# A ray is capped at this force [N] so that an unbounded direction (a body-ground contact
# carrying any push into the ground) gives a finite, recognisable answer.
RAY_CAP = 1e5


def make_solver(name: str):
    """The Drake solver object for `name` (one of SOLVERS); raises SufError naming the choices."""
    if name not in SOLVERS:
        raise SufError(f"solver: must be one of {sorted(SOLVERS)}, got {name!r}")
    solver = SOLVERS[name]()
    if not solver.available() or not solver.enabled():
        raise SufError(f"solver: {name!r} is not available in this Drake build")
    return solver


class RfpLinearProgram:
    """LPs over the RFP of one problem (see the module docstring)."""

    def __init__(self, problem: RejectableForceProblem, solver: str = "clp"):
        self.problem = problem
        self.solver = make_solver(solver)
        p = problem
        prog = MathematicalProgram()
        self.F = prog.NewContinuousVariables(3, "F")
        self.lam = prog.NewContinuousVariables(3 * p.num_contacts, "lambda")
        self.f = prog.NewContinuousVariables(1, "f")
        x = np.concatenate([self.F, self.lam])
        prog.AddLinearEqualityConstraint(p.A_eq, p.b_eq, x)
        prog.AddLinearConstraint(p.A_in, np.full(len(p.b_in), -np.inf), p.b_in, x)
        # F - f d = 0 (ray mode) or F free (support mode: d = 0 and f free but costless).
        self._ray = prog.AddLinearEqualityConstraint(
            np.hstack([np.eye(3), np.zeros((3, 1))]), np.zeros(3), [*self.F, *self.f]
        )
        self._bounds = prog.AddBoundingBoxConstraint(np.full(3, -RAY_CAP), np.full(3, RAY_CAP), self.F)
        self._f_bounds = prog.AddBoundingBoxConstraint(0.0, RAY_CAP, self.f)
        self._cost = prog.AddLinearCost(np.zeros(4), 0.0, [*self.F, *self.f])
        self.prog = prog

    def _solve(self):
        result = self.solver.Solve(self.prog)
        return result

    def _set_mode(self, d: np.ndarray | None, cost: np.ndarray, F_box: tuple[np.ndarray, np.ndarray]) -> None:
        if d is None:
            # Support / feasibility mode: F unconstrained by the ray, f pinned at 0.
            self._ray.evaluator().UpdateCoefficients(np.hstack([np.zeros((3, 3)), np.zeros((3, 1))]), np.zeros(3))
        else:
            self._ray.evaluator().UpdateCoefficients(np.hstack([np.eye(3), -d.reshape(3, 1)]), np.zeros(3))
        self._bounds.evaluator().set_bounds(*F_box)
        self._cost.evaluator().UpdateCoefficients(cost, 0.0)

    def support(self, n: np.ndarray) -> tuple[float, np.ndarray]:
        """(max n . F, the maximiser F) over the RFP; raises SufError when infeasible."""
        n = np.asarray(n, dtype=float)
        self._set_mode(None, np.concatenate([-n, [0.0]]), (np.full(3, -RAY_CAP), np.full(3, RAY_CAP)))
        self._f_bounds.evaluator().set_bounds([0.0], [0.0])
        result = self._solve()
        if not result.is_success():
            raise SufError(f"support LP in direction {n.tolist()}: {result.get_solution_result()}")
        F = result.GetSolution(self.F)
        return float(n @ F), F

    def ray(self, d: np.ndarray) -> float:
        """The largest f >= 0 with f d rejectable [N] (RAY_CAP if unbounded); raises SufError
        when not even F = 0 is rejectable."""
        d = np.asarray(d, dtype=float)
        self._set_mode(d, np.array([0.0, 0.0, 0.0, -1.0]), (np.full(3, -RAY_CAP), np.full(3, RAY_CAP)))
        self._f_bounds.evaluator().set_bounds([0.0], [RAY_CAP])
        result = self._solve()
        if not result.is_success():
            raise SufError(
                "the nominal motion is not feasible (no torques and contact forces within the limits "
                f"hold it even without a disturbance): {result.get_solution_result()}"
            )
        return float(result.GetSolution(self.f)[0])

    def feasible(self, F: np.ndarray, tol: float = 1e-7) -> bool:
        """Whether the force F [N] is rejectable (to the LP's tolerance)."""
        F = np.asarray(F, dtype=float)
        self._set_mode(None, np.zeros(4), (F - tol, F + tol))
        self._f_bounds.evaluator().set_bounds([0.0], [0.0])
        result = self._solve()
        return result.get_solution_result() == SolutionResult.kSolutionFound
