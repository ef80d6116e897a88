"""The predict stage (gaitcli/predict/stage.py) on a small problem stopped early: IPOPT's iteration callback
reports every iteration with the violation the result then states, the result's parts agree with each other
(J from Et and Jdev, the stance from the durations), and a warm start must match the layout."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.predict.cost import objective
from gaitcli.predict.reference import read_reference
from gaitcli.predict.solve import NlpCache
from gaitcli.predict.stage import PredictConfig, run_predict
from gaitcli.resources import bundled_reference


@pytest.fixture(scope="module")
def cache():
    """One NlpCache for the module, as a runner keeps one per process: the 6-node problem (10 s to build, most
    of it the Hessian) is built once for every test here."""
    return NlpCache()


@pytest.fixture(scope="module")
def stopped(cache):
    seen = []
    cfg = PredictConfig(nodes=6, max_iterations=2)
    result = run_predict(cfg, reference=read_reference(bundled_reference()),
                         report=lambda k, f, v: seen.append((k, f, v)), cache=cache)
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
    assert result.excitations.shape == (112, 16) and result.grf_N.shape == (120, 4)


def test_a_second_solver_of_one_nlp_takes_the_first_ones_derivatives(cache):
    """Another IPOPT option set builds another solver from the first one's ∇J, Jacobian and Hessian of the
    Lagrangian (not derived anew): from the same start both take the same iterates, as if each had derived
    its own (a mismatch of CasADi's conventions for them — a triangle, the sign of λ — would show here). Both
    solves return the shared IPOPT outcome; the cache hands back the problem it built, unchanged."""
    from gaitcli.core.ipopt import Outcome
    from gaitcli.predict.guess import shipped_walk
    from gaitcli.predict.layout import DesignLayout
    from gaitcli.predict.model import WalkingModel
    from gaitcli.predict.nlp import instant_segments
    from gaitcli.predict.problem import Transcriber
    from gaitcli.predict.solve import solve
    from gaitcli.predict.stage import settings_of, walker_muscles

    cfg = PredictConfig(nodes=6, max_iterations=2)
    reference, settings = read_reference(bundled_reference()), settings_of(cfg)
    transcriber = Transcriber(6, model=WalkingModel(cfg.walker_parameters(None)), muscles=walker_muscles(cfg, None))
    x0 = shipped_walk(6, settings, symmetric=True)  # run_predict's default start: the same windows
    segments = instant_segments(transcriber, DesignLayout.build(6, symmetric=True), x0)
    problems, builds = len(cache), cache.builds
    nlp = cache.nlp(transcriber, reference, settings, symmetric=True, segments=segments)
    first = solve(nlp, x0, settings, cache=cache)
    assert set(cache.derivatives(nlp)) == {"grad_f", "jac_g", "hess_lag"}
    solvers = len(cache.solvers(nlp))
    again = solve(nlp, x0, settings, options={"ipopt.print_frequency_iter": 2}, cache=cache)
    assert len(cache.solvers(nlp)) == solvers + 1 and again.iterations == first.iterations == 2
    np.testing.assert_array_equal(again.x, first.x)
    assert isinstance(first, Outcome) and not first.converged and first.status == "Maximum_Iterations_Exceeded"
    faster = dataclasses.replace(settings, speed_m_s=1.3, max_iterations=5)  # a parameter, not the structure
    assert cache.nlp(transcriber, reference, faster, symmetric=True, segments=segments) is nlp
    assert len(cache) == problems + (problems == 0)  # this problem, built here or by the tests before
    assert cache.builds == builds + (problems == 0) and cache.build_s > 0  # a hit is no build

    # a start with the right knee hyperextended beyond its bound (0 rad): reported per block of χ, then clipped
    start, rows, _ = DesignLayout.build(6, symmetric=True).blocks["right_leg"]
    bent = x0.copy()
    knee = slice(start + rows, start + 2 * rows)  # right_leg's columns: thigh, knee, ankle
    bent[knee] -= 0.3
    outside = bent[knee] < 0
    assert outside.any()
    out = solve(nlp, bent, settings, cache=cache)
    count, size, distance = out.outside.blocks["right_leg"]
    assert (count, size) == (outside.sum(), 3 * rows) and distance == pytest.approx(-bent[knee].min(), rel=1e-12)
    assert "right_leg" not in first.outside.blocks and len(cache.solvers(nlp)) == solvers + 1


def test_a_start_outside_its_bounds_is_a_line_of_the_history():
    from gaitcli.core.ipopt import Outcome, OutsideBounds
    from gaitcli.predict.solve import PredictSolution
    from gaitcli.predict.stage import _solve_notes

    outcome = Outcome(x=np.zeros(1), objective=1.0, converged=True, status="Solve_Succeeded", iterations=7,
                      time_s=1.0, outside=OutsideBounds({"right_leg": (2, 15, 0.035), "Q": (4, 328, 0.5)}))
    solved = PredictSolution(outcome=outcome, x=np.zeros(1), device=np.zeros(0), nlp=None, rounds=1,
                             windows_hold=True)
    assert _solve_notes(solved, "symmetric model") == [
        "predict: symmetric model: the start lay outside its bounds, clipped into them: right_leg 2 of 15 by up to "
        "0.035; Q 4 of 328 by up to 0.5", "predict: symmetric model: Solve_Succeeded after 7 iterations"]
    inside = dataclasses.replace(solved, outcome=dataclasses.replace(outcome, outside=OutsideBounds()))
    assert _solve_notes(inside, "full model") == ["predict: full model: Solve_Succeeded after 7 iterations"]


def test_a_warm_start_of_another_layout_is_refused():
    with pytest.raises(InputError, match="--init"):
        run_predict(PredictConfig(nodes=6), reference=read_reference(bundled_reference()), init=np.zeros(10))


def test_a_full_model_result_is_written_with_its_layout(tmp_path):
    """The full model's result through the predict writer (the CLI test runs the symmetric one): its 438
    design values and ``symmetric: false`` in predict.h5 and summary.json, every table with 112 instants."""
    import json

    import h5py

    from gaitcli.predict.guess import SHIPPED_WALK
    from gaitcli.predict.layout import full_from_symmetric
    from gaitcli.predict.outputs import write_predict_outputs
    from gaitcli.predict.stage import evaluate_design

    x = full_from_symmetric(18, np.loadtxt(SHIPPED_WALK))
    result = evaluate_design(PredictConfig(symmetric=False), x, reference=read_reference(bundled_reference()))
    summary = write_predict_outputs(tmp_path, result, {"converged": int(result.converged)})
    assert summary["symmetric"] is False and len(summary["phase_durations_s"]) == 8
    with h5py.File(tmp_path / "predict.h5", "r") as h5:
        assert np.asarray(h5["result/design"][()]).size == 438
    for name in ("motion.csv", "muscles.csv"):
        assert len((tmp_path / name).read_text().splitlines()) == 113  # header + 112 instants
    # trunk lean: forward positive, as the HAT's centre of mass ahead of the hip says
    import pandas as pd

    from gaitcli.predict.model import WalkingModel

    lean = pd.read_csv(tmp_path / "motion.csv").trunk_lean_deg.to_numpy()
    model = WalkingModel()
    ahead = np.array([model.point("hat_com", y)[0] - model.point("hip", y)[0] for y in result.coordinates])
    assert np.all(np.sign(lean) == np.sign(ahead)) and np.abs(lean).max() > 1.0
    assert json.loads(json.dumps(summary, default=float))["fine_grid"]["refinement"] == 4


def test_a_solve_past_its_time_limit_stops_unconverged_and_says_why(cache):
    """The limit counts from the start of the prediction: 1 µs is spent before IPOPT's first iteration, so the
    iteration callback stops it there (not the 50-iteration limit)."""
    from gaitcli.predict.settings import TIME_LIMIT_STATUS

    result = run_predict(PredictConfig(nodes=6, max_iterations=50, time_limit_s=1e-6),
                         reference=read_reference(bundled_reference()), cache=cache)
    assert result.status == TIME_LIMIT_STATUS and result.iterations == 0 and not result.converged


def test_a_warm_start_continues_from_the_stored_variables_where_they_fit(stopped, cache):
    """A result keeps the last NLP's variables and multipliers; a start from them (``--init`` of its
    predict.h5) begins at exactly those variables, while a start from χ alone recomputes the lifted values. A
    warm start of other sizes (another node count, an older formulation) is not used."""
    from gaitcli.predict.problem import Transcriber
    from gaitcli.predict.solve import WarmStart, solve_windowed
    from gaitcli.predict.stage import settings_of

    result, _ = stopped
    warm = WarmStart(result.nlp_variables, result.constraint_multipliers, result.bound_multipliers)
    assert warm.w.size == warm.lam_x.size > result.design.size and warm.lam_g.size > 0
    cfg = PredictConfig(nodes=6, max_iterations=0)  # IPOPT evaluates the start and stops there
    reference, transcriber = read_reference(bundled_reference()), Transcriber(6)

    def first_point(start):
        return solve_windowed(transcriber, reference, result.design, settings_of(cfg), symmetric=True, warm=start,
                              cache=cache).outcome.x

    from_design = first_point(None)
    assert np.array_equal(first_point(warm), warm.w)
    assert not np.allclose(from_design, warm.w, rtol=0, atol=1e-9)
    other = WarmStart(warm.w[:-1], warm.lam_g, warm.lam_x[:-1])
    assert np.array_equal(first_point(other), from_design)
    # a predict.h5 of the nodal-value formulation (segment coefficients and continuity rows: at 6 nodes 216 more
    # variables, 216 continuity rows for 64 nodal ones) starts from its χ, which both formulations share
    extra, rows = 216, 216 - 64
    old = WarmStart(np.zeros(warm.w.size + extra), np.zeros(warm.lam_g.size + rows), np.zeros(warm.lam_x.size + extra))
    assert np.array_equal(first_point(old), from_design)


def test_a_start_is_feasible_only_within_every_constraints_bounds():
    """``solve`` pushes a start that satisfies every constraint to 1e-6 only 0.1 % off its bounds (IPOPT's 1 %
    breaks a solution's constraints by 1e-2: 100 iterations back for the default prediction, 60 with it)."""
    from types import SimpleNamespace

    from gaitcli.predict.solve import FEASIBLE_START_OPTIONS, FEASIBLE_START_TOLERANCE, _feasible

    nlp = SimpleNamespace(lbg=np.array([0.0, -1.0, 2.0]), ubg=np.array([0.0, 1.0, np.inf]))
    assert _feasible(np.array([0.0, 1.0, 2.0]), nlp)
    assert _feasible(np.array([0.5 * FEASIBLE_START_TOLERANCE, -1.0, 5.0]), nlp)
    assert not _feasible(np.array([2 * FEASIBLE_START_TOLERANCE, 0.0, 3.0]), nlp)
    assert not _feasible(np.array([0.0, 0.0, 2.0 - 1e-3]), nlp)
    assert not _feasible(np.array([0.0, np.nan, 2.0]), nlp)
    assert FEASIBLE_START_OPTIONS == {"ipopt.bound_push": 1e-3, "ipopt.bound_frac": 1e-3}
