"""EID's positive semi-definite objective curvature (gaitcli/muscles/hessian.py) and the convex-then-exact solve."""

import casadi as ca
import numpy as np
import pytest

from gaitcli.muscles import eid
from gaitcli.muscles.hessian import ConvexObjectiveCurvature, convex_hessian
from gaitcli.muscles.problem import Models, build_problem
from gaitcli.muscles.solver import SolverSettings


def _start(problem):
    """A start inside the bounds away from them: SO's forces and the activations they need."""
    from gaitcli.muscles.so import solve_so

    x0, lbx, ubx, _ = eid._bounds_and_start(problem, solve_so(problem)[0], 0)
    return 0.9 * np.clip(x0, lbx, ubx) + 0.05


def _assembled(curvature: ConvexObjectiveCurvature, x) -> np.ndarray:
    """The blocks' sum placed into the full (symmetric) matrix, each block at its variables: a second assembly
    beside the callback's."""
    m, n = curvature._m, curvature._n
    size = m * n
    blocks = curvature.blocks(x) * curvature._scale[:, :, None, None]
    full = np.zeros((3 * size, 3 * size))
    for i in range(m):
        for j in range(n):
            stretch = [j * m + i, curvature._others[j, 0] * m + i, curvature._others[j, 1] * m + i]
            at = np.array(stretch + [size + j * m + i, 2 * size + j * m + i])
            np.add.at(full, (at[:, None], at[None, :]), blocks[i, j])
    return full


@pytest.mark.parametrize("periodic", [True, False])
def test_the_blocks_add_up_to_the_exact_objective_hessian(gait, periodic):
    """CasADi's Hessian of the whole metabolic cost equals the sum of the per-muscle, per-node 5 × 5 blocks, on a
    periodic grid and on an interval with one-sided differences at its ends (4.11, 4.12)."""
    motion, limb = gait
    problem = build_problem(motion, Models.build(limb), nodes=9, **({} if periodic else {"interval": (0.682, 1.1)}))
    x, cost, _ = eid._eid_nlp(problem, "metabolic", 1e-2, None)
    x0 = _start(problem)
    exact = np.array(ca.Function("hessian", [x], [ca.hessian(cost, x)[0]])(x0))
    curvature = ConvexObjectiveCurvature(problem, 1e-2, eid.quadrature_weights(problem.n, problem.periodic))
    np.testing.assert_allclose(_assembled(curvature, x0), exact, atol=1e-9 * np.abs(exact).max())
    assert np.linalg.eigvalsh(exact).min() < -1e-3 * np.abs(exact).max()  # the exact one is indefinite


def test_ipopts_hessian_is_the_constraints_exact_curvature_plus_a_semi_definite_objective_part(gait):
    """hess_lag(x, σ, λ) − hess_lag(x, 0, λ) (the objective's part, σ·[∇²f]₊) is positive semi-definite and has
    the exact part's positive eigen-directions inside each block; hess_lag(x, 0, λ) is λᵀ∇²g exactly."""
    motion, limb = gait
    problem = build_problem(motion, Models.build(limb), nodes=9)
    x, cost, g = eid._eid_nlp(problem, "metabolic", 1e-2, None)
    x0, lam = _start(problem), np.random.default_rng(1).normal(size=g.shape[0])
    hess, curvature = convex_hessian(problem, 1e-2, np.ones(9), x, cost, g)

    def full(sigma):
        upper = np.array(ca.densify(hess(x0, [], sigma, lam)))
        assert not np.tril(upper, -1).any()  # IPOPT takes the upper triangle
        return upper + np.triu(upper, 1).T

    constraints = np.array(ca.Function("h", [x], [ca.hessian(ca.dot(ca.DM(lam), g), x)[0]])(x0))
    np.testing.assert_allclose(full(0.0), constraints, atol=1e-9 * np.abs(constraints).max())
    objective = full(2.0) - full(0.0)
    assert np.linalg.eigvalsh(objective).min() > -1e-9 * np.abs(objective).max()
    # block by block: each block's eigenvalues are kept where positive, reflected at half their size where negative
    blocks = 2.0 * curvature.blocks(x0) * curvature._scale[:, :, None, None]
    values = np.linalg.eigvalsh(blocks)
    assert (values < 0).any()
    expected = np.sort(np.where(values < 0, -0.5 * values, values), axis=-1)
    inner = np.abs(objective).max()
    for i, j in ((0, 0), (3, 4), (7, 8)):
        _, vectors = np.linalg.eigh(blocks[i, j])
        at = [j * 8 + i, curvature._others[j, 0] * 8 + i, curvature._others[j, 1] * 8 + i, 72 + j * 8 + i,
              144 + j * 8 + i]
        rebuilt = (vectors * expected[i, j]) @ vectors.T
        np.testing.assert_allclose(np.sort(np.linalg.eigvalsh(rebuilt)), expected[i, j], atol=1e-9 * inner)
        assert len(set(at)) == 5


def test_convex_then_exact_ends_at_a_kkt_point_of_the_same_nlp(gait):
    """EID with hessian="convex" (20 nodes of the synthetic cycle) ends where the exact NLP's first-order
    conditions hold with its multipliers, computed here from CasADi's gradient and Jacobian: ∇f + Jᵀλ_g + λ_x = 0,
    g = 0, bounds kept, λ_x of the sign of the active bound; and at a cost within the spread of EID's local optima
    (benchmarks/README.md: 2.1 % at 100 nodes) of the exact Hessian's."""
    motion, limb = gait
    problem = build_problem(motion, Models.build(limb), nodes=20)
    convex = eid.solve_eid(problem, SolverSettings(hessian="convex"))
    exact = eid.solve_eid(problem, SolverSettings(hessian="exact"), warm_start=(convex.warm_start_force_N,
                                                                                  convex.warm_start_outcome))
    out = convex.outcome
    assert out.converged and exact.outcome.converged
    x, cost, g = eid._eid_nlp(problem, "metabolic", 1e-2, None)
    grad = np.array(ca.Function("gradient", [x], [ca.gradient(cost, x)])(out.x)).ravel()
    jac = np.array(ca.Function("constraint_jacobian", [x], [ca.jacobian(g, x)])(out.x))
    stationarity = grad + jac.T @ out.lam_g + out.lam_x
    assert np.abs(stationarity).max() < 1e-6 * max(1.0, np.abs(grad).max())
    assert np.abs(np.array(ca.Function("g", [x], [g])(out.x))).max() < 1e-8
    _, lbx, ubx, _ = eid._bounds_and_start(problem, convex.warm_start_force_N, 0)
    assert np.all(out.x >= lbx - 1e-8) and np.all(out.x <= ubx + 1e-8)
    # complementarity: a bound's multiplier (CasADi's sign: < 0 at a lower, > 0 at an upper bound) times the
    # distance from it vanishes (to IPOPT's barrier parameter at the end, 1e-9 here)
    assert np.max((out.x - lbx) * np.maximum(-out.lam_x, 0)) < 1e-8
    assert np.max((ubx - out.x) * np.maximum(out.lam_x, 0)) < 1e-8
    assert np.count_nonzero(out.lam_x < -1e-3) > 10  # activations and excitations at 0 (benchmarks/README.md)
    assert abs(out.objective / exact.outcome.objective - 1) < 0.021
