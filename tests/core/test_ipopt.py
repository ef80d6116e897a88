"""The one IPOPT interface (gaitcli/core/ipopt.py): a start outside its bounds is reported per block and by how
much, then clipped — which changes nothing IPOPT would not do itself — and every run returns one Outcome."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.core import ipopt


def test_outside_bounds_counts_per_block_beyond_ipopts_own_relaxation():
    low, high = np.zeros(6), np.array([1.0, 1.0, 1.0, 10.0, 10.0, 10.0])
    x = np.array([-0.5, 0.5, 1.0 + 1e-10, 12.0, np.nan, 10.0 + 1e-8])  # 1e-10, 1e-8 within 1e-8·max(1, |b|)
    report = ipopt.outside_bounds(x, low, high, {"a": slice(0, 3), "b": slice(3, 6)})
    assert report.blocks == {"a": (1, 3, 0.5), "b": (2, 3, np.inf)}
    assert report.count == 3 and bool(report)
    assert report.describe() == "a 1 of 3 by up to 0.5; b 2 of 3 by up to inf"
    inside = ipopt.outside_bounds(np.clip(np.nan_to_num(x), low, high), low, high)
    assert not inside and inside.describe() == "" and inside.count == 0
    assert ipopt.outside_bounds(x[:2], 0.0, 1.0).blocks == {"x": (1, 2, 0.5)}  # scalar bounds, one block


def _problem():
    """min (x0 − 2)² + (x1 + 1)² + x2² s.t. x0 + x1 + x2 = 0.5, 0 ≤ x ≤ 1: x* = (0.5, 0, 0), f* = 3.25, the
    lower bounds of x1 and x2 active."""
    x = ca.SX.sym("x", 3)
    problem = {"x": x, "f": (x[0] - 2) ** 2 + (x[1] + 1) ** 2 + x[2] ** 2, "g": x[0] + x[1] + x[2]}
    return ipopt.build_solver("test", problem, ipopt.options(tol=1e-10, max_iter=100))


def test_a_start_outside_is_reported_clipped_and_solved_as_from_inside():
    solver = _problem()
    outside = np.array([-3.0, 5.0, 0.2])
    out = ipopt.solve(solver, outside, np.zeros(3), np.ones(3), 0.5, 0.5, blocks={"y": slice(0, 2), "z": slice(2, 3)})
    assert isinstance(out, ipopt.Outcome) and out.converged and out.status == "Solve_Succeeded"
    assert out.outside.blocks == {"y": (2, 2, 4.0)}
    np.testing.assert_allclose(out.x, [0.5, 0.0, 0.0], atol=1e-6)  # IPOPT relaxes bounds by 1e-8
    assert out.objective == pytest.approx(3.25, abs=1e-6) and out.iterations > 0 and out.time_s > 0
    assert out.lam_g.shape == (1,) and out.lam_x.shape == (3,)
    # IPOPT moves every start component inside its bounds itself: from the clipped start, the same run
    inside = ipopt.solve(solver, np.clip(outside, 0, 1), np.zeros(3), np.ones(3), 0.5, 0.5)
    assert not inside.outside and inside.iterations == out.iterations
    np.testing.assert_array_equal(inside.x, out.x)


class _SignalAt(ca.Callback):
    """An iteration callback that sends this process SIGINT at iteration ``at`` (as Ctrl-C would)."""

    def __init__(self, at: int):
        ca.Callback.__init__(self)
        self.at, self.iteration = at, 0
        self.construct("signal_at", {"enable_fd": False})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        return {"f": ca.Sparsity.scalar(), "x": ca.Sparsity.dense(3), "lam_x": ca.Sparsity.dense(3),
                "g": ca.Sparsity.dense(1), "lam_g": ca.Sparsity.dense(1)}.get(name, ca.Sparsity(0, 0))

    def eval(self, arg):
        import os
        import signal

        if self.iteration == self.at:
            os.kill(os.getpid(), signal.SIGINT)
        self.iteration += 1
        return [0]


def test_an_interrupt_during_ipopt_is_raised_not_returned_as_a_failure():
    # CasADi stops IPOPT on a KeyboardInterrupt and returns its iterate as an ordinary failure; the one solve
    # every problem goes through raises it instead (core/interrupts.py)
    x = ca.SX.sym("x", 3)
    callback = _SignalAt(1)
    solver = ipopt.build_solver("interrupted", {"x": x, "f": ca.sumsqr(x - 2), "g": ca.sum1(x)},
                                {**ipopt.options(tol=1e-12, max_iter=50), "iteration_callback": callback})
    with pytest.raises(KeyboardInterrupt):
        ipopt.solve(solver, np.zeros(3), -10.0, 10.0, 0.5, 0.5)
    assert callback.iteration == 1  # stopped where the signal came (the handler raised in the callback)
