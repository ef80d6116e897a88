"""Per-point functions: their derivatives scattered into the problem's equal CasADi's of the whole expression
(two implementations), and each function's Jacobian equals finite differences."""

import casadi as ca
import numpy as np
import pytest

from gaitcli.predict.pointwise import Placement, PointFunction, affine, derivatives


def _reference_derivatives(w, p, cost, g) -> dict:
    """CasADi's own ∇f, Jacobian of g and Hessian of the Lagrangian of the whole expressions."""
    solver = ca.nlpsol("reference", "ipopt", {"x": w, "p": p, "f": cost, "g": g})
    return {"grad_f": solver.get_function("nlp_grad_f"), "jac_g": solver.get_function("nlp_jac_g"),
            "hess_lag": solver.get_function("nlp_hess_l")}


def _assert_same(ours: dict, theirs: dict, x, p, lam_f, lam_g, rtol=1e-10) -> None:
    for name in ("grad_f", "jac_g", "hess_lag"):
        args = [x, p] + ([lam_f, lam_g] if name == "hess_lag" else [])
        a, b = ours[name].call(args), theirs[name].call(args)
        for k, (va, vb) in enumerate(zip(a, b)):
            va, vb = np.array(ca.densify(va)), np.array(ca.densify(vb))
            scale = max(1.0, np.abs(vb).max())
            np.testing.assert_allclose(va, vb, rtol=0, atol=rtol * scale, err_msg=f"{name} output {k}")


def test_a_toy_problem_has_casadis_derivatives():
    # instant i reads its own and the next instant's variables (a variable shared by two inputs of one instant:
    # the Hessian's mirrored terms meet on the diagonal), scaled sums and a constant; a cost-only function; rows
    # of g around them that are no point function's
    n = 7
    w, p, z = ca.SX.sym("w", 3 * n + 2), ca.SX.sym("p", 2), ca.SX.sym("z", 4)
    rows = ca.Function("rows", [z], [ca.vertcat(ca.sin(z[0]) * z[1] ** 2, z[2] * z[3] + z[0] ** 3),
                                     ca.exp(z[1] * z[3]) + z[2] ** 2 * z[0]], ["z"], ["rows", "cost"])
    only_cost = ca.Function("only_cost", [z], [ca.cos(z[0] * z[1]) + z[2] * z[3] ** 3], ["z"], ["cost"])
    inputs = [ca.vertcat(2 * w[3 * i], w[3 * i + 1] + w[3 * ((i + 1) % n) + 2], w[-1] - w[-2] + 0.5,
                         0.3 * w[3 * ((i + 1) % n)] + 1) for i in range(n)]
    first = PointFunction("first", rows, ca.horzcat(*inputs), weight=2 * p[0])
    second = PointFunction("second", only_cost, ca.horzcat(*inputs[::-1]), weight=p[1] ** 2)
    rest_cost = p[1] * w[3] ** 2 * w[4]
    g = ca.vertcat(w[0] * w[5], ca.vec(first.outputs["rows"]), ca.cos(w[2] + w[-1]))
    cost = first.cost + second.cost + rest_cost
    ours = derivatives(w, p, g, cost, rest_cost, [first, second], [Placement(first, "rows", 1)])
    rng = np.random.default_rng(0)
    _assert_same(ours, _reference_derivatives(w, p, cost, g), rng.normal(size=w.numel()), rng.normal(size=2), 0.7,
                 rng.normal(size=g.numel()))


def test_inputs_must_be_affine_in_w_and_free_of_the_parameters():
    w, p = ca.SX.sym("w", 3), ca.SX.sym("p")
    a, b = affine(ca.horzcat(ca.vertcat(2 * w[0] + 1, w[1] - w[2]), ca.vertcat(w[2], 3.0)), w, p)
    np.testing.assert_array_equal(a.toarray(), [[2, 0, 0], [0, 1, -1], [0, 0, 1], [0, 0, 0]])
    np.testing.assert_array_equal(b, [1, 0, 0, 3])
    with pytest.raises(ValueError, match="affine"):
        affine(ca.vertcat(w[0] * w[1]), w, p)
    with pytest.raises(ValueError, match="parameters"):
        affine(ca.vertcat(w[0] * p), w, p)


@pytest.fixture(scope="module", params=[True, False], ids=["symmetric", "full"])
def tiny_nlp(request):
    """The NLP on the tiniest grid (2 control points per phase, 6 nodes) with the opt-in terms on, and its
    start from 5.2.10's guess."""
    from gaitcli.predict.grid import control_grid
    from gaitcli.predict.guess import initial_guess
    from gaitcli.predict.layout import box_bounds
    from gaitcli.predict.nlp import build_nlp
    from gaitcli.predict.problem import Transcriber
    from gaitcli.predict.reference import read_reference
    from gaitcli.predict.settings import PredictSettings
    from gaitcli.resources import bundled_reference

    transcriber = Transcriber(6, grid=control_grid((2,) * 8))
    reference = read_reference(bundled_reference())
    settings = PredictSettings(cop_sd_m=0.01, trunk_rate_sd_deg_s=50.0, hip_moment_Nm_per_kg=1.0)
    nlp = build_nlp(transcriber, reference, settings, symmetric=request.param)
    x = np.clip(initial_guess(transcriber, reference, settings, symmetric=request.param), *box_bounds(nlp.layout))
    return nlp, nlp.start(x)


def test_the_problems_derivatives_are_casadis_of_the_whole_expressions(tiny_nlp):
    nlp, w0 = tiny_nlp
    theirs = _reference_derivatives(nlp.w, nlp.parameters, nlp.cost, nlp.constraints)
    rng = np.random.default_rng(1)
    lam_g = rng.normal(size=nlp.constraints.numel())
    p = np.array([1.2, 1.3, 0.7])  # v, w1, w2
    _assert_same(nlp.derivatives(), theirs, w0 * (1 + 0.01 * rng.normal(size=w0.size)), p, 0.8, lam_g, rtol=1e-9)
    names = {pf.name for pf in nlp.point_functions}
    assert {"dynamics", "muscles", "deviation", "splines_stretch"} <= names


def test_each_point_functions_jacobian_equals_finite_differences(tiny_nlp):
    nlp, w0 = tiny_nlp
    for pf in nlp.point_functions:
        inputs = np.array(ca.Function("inputs", [nlp.w], [pf.inputs])(w0))
        f, z_sym = pf.function, pf.function.mx_in(0)
        outputs = ca.vertcat(*[ca.vec(o) for o in f.call([z_sym])])
        jac = ca.Function("exact_jacobian", [z_sym], [ca.jacobian(outputs, z_sym)])
        rng = np.random.default_rng(2)
        for i in range(0, pf.instants, max(1, pf.instants // 3)):
            # off the reference's 1 %-knots and the window edges, where one-sided slopes differ
            z = inputs[:, i] * (1 + 1e-3 * rng.uniform(-1, 1, inputs.shape[0]))
            exact = np.array(jac(z))
            step = 1e-6 * np.maximum(1.0, np.abs(z))
            numeric = np.zeros_like(exact)
            for k in range(z.size):
                up, down = z.copy(), z.copy()
                up[k] += step[k]
                down[k] -= step[k]
                numeric[:, k] = (np.concatenate([np.array(v).ravel() for v in f.call([up])])
                                 - np.concatenate([np.array(v).ravel() for v in f.call([down])])) / (2 * step[k])
            scale = np.maximum(1.0, np.abs(exact))
            assert np.max(np.abs(numeric - exact) / scale) < 1e-5, (pf.name, i)
