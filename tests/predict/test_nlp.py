"""The predictive-gait NLP (gaitcli/predict/nlp.py): the constraint groups' sizes follow the grid and the phase
table, the default initial guess lies inside the box bounds, and the cost parts evaluate to finite values."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.predict.contact import PHASE_TABLE
from gaitcli.predict.nlp import LIFTED_COLUMNS, build_nlp, initial_guess
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import read_reference
from gaitcli.resources import bundled_reference


@pytest.fixture(scope="module")
def built():
    transcriber = Transcriber(18)
    reference = read_reference(bundled_reference())
    return transcriber, reference, build_nlp(transcriber, reference)


def test_group_sizes(built):
    transcriber, _, nlp = built
    grid = transcriber.grid
    phases = [int(p) + 1 for p in grid.phase]
    rows = [len(PHASE_TABLE[p - 1].rows) for p in phases]
    widths = [len(transcriber.contact.reaction_names[p]) for p in phases]
    sizes = {k: v.stop - v.start for k, v in nlp.groups.items()}
    assert sizes["splines"] == (27 + 16) * grid.instants
    assert sizes["dynamics"] == 9 * grid.instants
    assert sizes["paths"] == 32 * grid.instants and sizes["activation"] == 16 * grid.instants
    assert sizes["reactions"] == sum(widths)  # one normal equation per reaction and point
    assert sizes["moment"] == 6 * grid.points  # 480
    assert sizes["contact"] == sum(rows)
    assert sizes["unilateral"] == sum(sum(1 for _, axis, _ in PHASE_TABLE[p - 1].rows if axis == "z") for p in phases)
    assert sizes["mtp"] == sum(1 for p in phases if PHASE_TABLE[p - 1].mtp_moment_side)
    assert sizes["excitation"] == 2 * 16 * grid.instants  # the two ȧ bounds per muscle and instant
    assert sizes["speed"] == 1 and sizes["shape"] == 4
    assert nlp.constraints.size1() == len(nlp.lbg) == len(nlp.ubg) == sum(sizes.values())
    assert nlp.w.size1() == (5 * 9 + 4 * 16) * 17 + 10 + LIFTED_COLUMNS * grid.instants + sum(widths)
    assert sizes["continuity"] == (4 * 9 + 3 * 16) * 17


def test_lifted_start_solves_the_defining_equations(built):
    # w from the transcription of χ (problem.py, λ by the pseudoinverse) satisfies the lifted NLP's own
    # equations: two implementations of the same quantities agree
    transcriber, reference, nlp = built
    x0 = initial_guess(transcriber, reference)
    w0 = nlp.start(x0)
    g = np.array(ca.Function("g", [nlp.w], [nlp.constraints])(w0)).ravel()
    for name in ("continuity", "splines", "dynamics", "paths", "activation", "reactions"):
        assert np.abs(g[nlp.groups[name]]).max() < 1e-9, name
    t = transcriber(x0)
    np.testing.assert_allclose(g[nlp.groups["moment"]], np.concatenate(t.moment_error_Nm), atol=1e-9)


def test_initial_guess_is_inside_the_box_and_evaluates(built):
    transcriber, reference, nlp = built
    x0 = initial_guess(transcriber, reference)
    w0 = nlp.start(x0)
    assert np.all(w0 >= nlp.lbw) and np.all(w0 <= nlp.ubw)
    f = ca.Function("f", [nlp.w], [nlp.cost, nlp.parts["Et"], nlp.parts["Jdev"], nlp.constraints])
    cost, et, jdev, g = (np.array(v).ravel() for v in f(w0))
    assert np.isfinite(cost).all() and np.isfinite(g).all()
    assert 100 < et.item() < 2000  # J/m: a walking order of magnitude from 10 % F_max everywhere
    assert jdev.item() > 0
    speed = np.array(g)[nlp.groups["speed"]]
    assert abs(float(speed[0])) < 1e-12  # the guess walks at the set speed: T = (L_r + L_l)/v
