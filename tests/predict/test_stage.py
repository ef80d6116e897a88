"""The predict stage (gaitcli/predict/stage.py) on a small problem stopped early: IPOPT's iteration callback
reports every iteration with the violation the result then states, the result's parts agree with each other
(J from Et and Jdev, the stance from the durations), and a warm start must match the layout."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.predict.cost import objective
from gaitcli.predict.reference import read_reference
from gaitcli.predict.stage import PredictConfig, run_predict
from gaitcli.resources import bundled_reference, stored_solution


@pytest.fixture(scope="module")
def stopped():
    seen = []
    cfg = PredictConfig(nodes=6, max_iterations=2)
    result = run_predict(cfg, reference=read_reference(bundled_reference()),
                         report=lambda k, f, v: seen.append((k, f, v)))
    return result, seen


def test_every_iteration_is_reported_with_the_stated_violation(stopped):
    result, seen = stopped
    assert [k for k, _, _ in seen] == list(range(result.iterations + 1))
    assert not result.converged and result.status == "Maximum_Iterations_Exceeded"
    assert seen[-1][2] == pytest.approx(max(result.violations.values()), rel=1e-6)


def test_the_result_parts_agree(stopped):
    result, _ = stopped
    assert result.objective == pytest.approx(objective(result.cost_of_transport_J_per_m, result.deviation,
                                                       result.weights), rel=1e-12)
    d = result.phase_durations_s
    assert np.allclose(d[:4], d[4:])  # the symmetric model's mirrored phases
    summary = result.summary()
    assert summary["stance_pct"] == pytest.approx(100 * d[:6].sum() / d.sum())
    assert summary["converged"] is False and set(summary["gait_checks"]) >= {"stance_pct", "vertical_grf"}
    assert result.excitations.shape == (80, 16) and result.grf_N.shape == (88, 4)


def test_a_second_solver_of_one_nlp_takes_the_first_ones_derivatives(stopped):
    """Another IPOPT option set builds another solver from the first one's ∇J, Jacobian and Hessian of the
    Lagrangian (not derived anew): from the same start both take the same iterates, as if each had derived
    its own (a mismatch of CasADi's conventions for them — a triangle, the sign of λ — would show here). The
    NLP is the stopped prediction's, from this process's cache (its first solver derived them)."""
    from gaitcli.predict.layout import DesignLayout
    from gaitcli.predict.model import WalkingModel
    from gaitcli.predict.nlp import cached_nlp, initial_guess, instant_segments, solve
    from gaitcli.predict.problem import Transcriber
    from gaitcli.predict.stage import settings_of, walker_muscles

    cfg = PredictConfig(nodes=6, max_iterations=2)
    reference, settings = read_reference(bundled_reference()), settings_of(cfg)
    transcriber = Transcriber(6, model=WalkingModel(cfg.walker_parameters(None)), muscles=walker_muscles(cfg, None))
    x0 = initial_guess(transcriber, reference, settings, symmetric=True)
    nlp = cached_nlp(transcriber, reference, settings, symmetric=True,
                     segments=instant_segments(transcriber, DesignLayout.build(6, symmetric=True), x0))
    first = solve(nlp, x0, settings)
    assert set(nlp.derivatives) == {"grad_f", "jac_g", "hess_lag"}
    solvers = len(nlp.solvers)
    again = solve(nlp, x0, settings, options={"ipopt.print_frequency_iter": 2})
    assert len(nlp.solvers) == solvers + 1 and again["iterations"] == first["iterations"] == 2
    np.testing.assert_array_equal(again["w"], first["w"])


def test_a_warm_start_of_another_layout_is_refused():
    with pytest.raises(InputError, match="--init"):
        run_predict(PredictConfig(nodes=6), reference=read_reference(bundled_reference()), init=np.zeros(10))


def test_a_full_model_result_is_written_with_its_layout(tmp_path):
    """The full model's result through the predict writer (the CLI test runs the symmetric one): its 435
    design values and ``symmetric: false`` in predict.h5 and summary.json, every table with 80 instants."""
    import json

    import h5py

    from gaitcli.predict.layout import full_from_symmetric
    from gaitcli.predict.stage import evaluate_design
    from gaitcli.predict.outputs import write_predict_outputs

    stored = stored_solution(18, symmetric=True)
    x = full_from_symmetric(18, np.loadtxt(stored))
    result = evaluate_design(PredictConfig(symmetric=False), x, reference=read_reference(bundled_reference()))
    summary = write_predict_outputs(tmp_path, result, {"converged": int(result.converged)})
    assert summary["symmetric"] is False and len(summary["phase_durations_s"]) == 8
    with h5py.File(tmp_path / "predict.h5", "r") as h5:
        assert np.asarray(h5["result/design"][()]).size == 435
    for name in ("motion.csv", "muscles.csv"):
        assert len((tmp_path / name).read_text().splitlines()) == 81  # header + 80 instants
    assert json.loads(json.dumps(summary, default=float))["fine_grid"]["refinement"] == 4


def test_a_solve_past_its_time_limit_stops_unconverged_and_says_why():
    """The limit counts from the start of the prediction: 1 µs is spent before IPOPT's first iteration, so the
    iteration callback stops it there (not the 50-iteration limit)."""
    from gaitcli.predict.nlp import TIME_LIMIT_STATUS

    result = run_predict(PredictConfig(nodes=6, max_iterations=50, time_limit_s=1e-6),
                         reference=read_reference(bundled_reference()))
    assert result.status == TIME_LIMIT_STATUS and result.iterations == 0 and not result.converged
