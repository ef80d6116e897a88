"""The muscle problems' IPOPT settings (gaitcli/muscles/solver.py)."""

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.muscles.eid import solve_eid
from gaitcli.muscles.problem import Models, build_problem
from gaitcli.muscles.solver import SolverSettings


def test_limited_memory_hessian_reaches_the_exact_hessians_eid_optimum(gait):
    """Two ways to the same optimum: EID (Crowninshield–Brand cost, 11 nodes of the synthetic cycle) with
    CasADi's exact second derivatives and with IPOPT's L-BFGS approximation end at the same forces."""
    motion, limb = gait
    problem = build_problem(motion, Models.build(limb), nodes=11)
    exact = solve_eid(problem, SolverSettings(hessian="exact"), objective="crowninshield_brand")
    lbfgs = solve_eid(problem, SolverSettings(hessian="limited-memory"), objective="crowninshield_brand")
    assert exact.outcome.converged and lbfgs.outcome.converged
    assert lbfgs.outcome.objective == pytest.approx(exact.outcome.objective, rel=1e-6)
    assert np.sqrt(np.mean((lbfgs.force_N - exact.force_N) ** 2)) < 0.05  # N; the forces reach ~960 N
    assert exact.force_N.max() > 500


def test_an_unknown_hessian_is_refused(gait):
    motion, limb = gait
    problem = build_problem(motion, Models.build(limb), nodes=11)
    with pytest.raises(InputError, match="hessian"):
        solve_eid(problem, SolverSettings(hessian="bfgs"), objective="crowninshield_brand")
