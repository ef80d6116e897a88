"""Contact phases and ground reactions (gaitcli/predict/contact.py): the phase table against the
dissertation's lists (5.6–5.9, 5.33–5.40), constraints and their Jacobians, the pseudoinverse (5.30) on
consistent states, and the rank gap of phases 4 and 8 that the MTP moment closes (docs/prediction.md,
"MTP moment")."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.predict.contact import PHASE_TABLE, PHASES, ContactModel, foot_rotation, ground_reactions, joint_moment_map
from gaitcli.predict.model import WalkingModel

RNG = np.random.default_rng(11)
G = 9.81


@pytest.fixture(scope="module")
def contact() -> ContactModel:
    return ContactModel(WalkingModel())


def test_rows_per_phase():
    assert [len(p.rows) for p in PHASE_TABLE] == [4, 5, 3, 2, 4, 5, 3, 2]
    assert [p.number for p in PHASE_TABLE] == list(PHASES)


# (5.37–5.40) with their printed phases, and (5.33–5.36) with theirs: the complement
IN_CONTACT = {"heel_r": {1, 2, 3}, "mtp_r": {2, 3, 4, 5, 6}, "heel_l": {5, 6, 7}, "mtp_l": {1, 2, 6, 7, 8}}
CLEARANCE = {"heel_r": {4, 5, 6, 7, 8}, "mtp_r": {1, 7, 8}, "heel_l": {1, 2, 3, 4, 8}, "mtp_l": {3, 4, 5}}


@pytest.mark.parametrize("point", list(IN_CONTACT))
def test_contact_and_clearance_phases_are_the_notes_lists(point):
    touching = {p.number for p in PHASE_TABLE if point in p.points()}
    assert touching == IN_CONTACT[point]
    assert set(PHASES) - touching == CLEARANCE[point]


def test_the_mtp_moment_is_a_reaction_where_a_foot_stands_on_its_mtp_alone():
    assert {p.number: p.mtp_moment_side for p in PHASE_TABLE if p.mtp_moment_side} == {1: "l", 4: "r", 5: "r", 8: "l"}


def flat_right_foot_posture(contact, L_r=0.65, x0=0.0):
    """y with the right foot flat, its heel where phase 3 pins it; the left leg anywhere in the air."""
    model = contact.model
    y = np.array([0.0, 0.0, 0.05, -0.2, 0.3, 0.0, 0.4, 0.9, 0.2])
    y[5] = -(y[3] + y[4])  # foot angle thigh + knee + ankle = 0: flat
    heel = model.point("heel_r", y)
    y[0] += (x0 + L_r - contact.heel_to_mtp_m) - heel[0]
    y[1] -= heel[1]
    return y, L_r, x0


def test_constraints_vanish_on_a_consistent_posture_and_their_jacobian_is_exact(contact):
    y, L_r, x0 = flat_right_foot_posture(contact)
    np.testing.assert_allclose(np.array(contact.constraint[3](y, L_r, 0.6, x0)).ravel(), 0.0, atol=1e-12)
    assert abs(float(contact.model.point("mtp_r", y)[1])) < 1e-12  # flat: B on the floor too
    assert float(contact.model.point("mtp_l", y)[1]) > 0.02  # the left foot clears the floor
    h = 1e-6
    for n in PHASES:
        C = np.array(contact.jacobian[n](y))
        fd = np.column_stack([(np.array(contact.constraint[n](y + h * e, L_r, 0.6, x0)).ravel()
                               - np.array(contact.constraint[n](y - h * e, L_r, 0.6, x0)).ravel()) / (2 * h)
                              for e in np.eye(9)])
        np.testing.assert_allclose(C, fd, atol=1e-7, err_msg=f"phase {n}")


@pytest.mark.parametrize("phase", PHASES)
def test_pseudoinverse_returns_the_reactions_of_a_consistent_state(contact, phase):
    # ÿ from chosen reactions λ and joint moments τ: M ÿ + k − g − B τ = G λ exactly; (5.30) must give λ back
    model = contact.model
    y = np.concatenate([[0.1, 0.9], RNG.uniform(-0.5, 0.5, 7)])
    yd = RNG.normal(size=9)
    Gm = np.array(contact.reaction_matrix[phase](y))
    lam = RNG.normal(scale=300.0, size=Gm.shape[1])
    if contact.phase(phase).mtp_moment_side:
        lam[-1] = -6.0  # within 5.2.2's −10 … 0 N·m
    tau = RNG.normal(scale=50.0, size=6)
    B = joint_moment_map()
    M = np.array(model.mass_matrix(y))
    k, g = np.array(model.bias(y, yd)).ravel(), np.array(model.gravity(y)).ravel()
    ydd = np.linalg.solve(M, Gm @ lam + B @ tau + g - k)
    rhs = M @ ydd + k - g - B @ tau
    got, e = ground_reactions(Gm, rhs)
    np.testing.assert_allclose(got, lam, rtol=1e-9, atol=1e-7)
    assert np.abs(e).max() < 1e-8
    # the same on CasADi expressions (what the NLP will use)
    import casadi as ca

    got_ca, e_ca = ground_reactions(ca.DM(Gm), ca.DM(rhs))
    np.testing.assert_allclose(np.array(got_ca).ravel(), lam, rtol=1e-9, atol=1e-7)
    assert np.abs(np.array(e_ca)).max() < 1e-8


@pytest.mark.parametrize("phase", [4, 8])
def test_the_mtp_moment_closes_the_rank_gap_of_phases_4_and_8(contact, phase):
    # with only the MTP pin (2 reactions) and 6 joint moments, 8 < 9 unknowns: some e ≠ 0 gives e_m = 0;
    # the MTP moment makes the system square and regular
    y = np.concatenate([[0.3, 0.95], RNG.uniform(-0.5, 0.5, 7)])
    B = joint_moment_map()
    C = np.array(contact.jacobian[phase](y))
    assert np.linalg.matrix_rank(np.column_stack([C.T, B])) == 8
    full = np.column_stack([np.array(contact.reaction_matrix[phase](y)), B])
    assert full.shape == (9, 9) and np.linalg.matrix_rank(full) == 9
    # the gap, constructed: a generalized force orthogonal to every column is left unexplained (e = that force)
    gap = np.linalg.svd(np.column_stack([C.T, B]).T)[2][-1]
    lam, e = ground_reactions(C.T, gap)
    assert np.linalg.norm(e) == pytest.approx(1.0, abs=1e-9) and np.abs(np.linalg.pinv(B) @ e).max() < 1e-9


def test_static_double_stance_carries_the_body_weight(contact):
    # standing still (ẏ = ÿ = 0) in phase 2: the contact forces and the joint moments balance gravity; whatever
    # the joint moments, the ground carries m·g vertically and nothing horizontally
    model = contact.model
    y, _, _ = flat_right_foot_posture(contact)
    Gm = np.array(contact.reaction_matrix[2](y))
    g = np.array(model.gravity(y)).ravel()
    solution = np.linalg.lstsq(np.column_stack([Gm, joint_moment_map()]), -g, rcond=None)[0]
    lam = solution[:Gm.shape[1]]
    names = contact.reaction_names[2]
    fz = sum(v for v, n in zip(lam, names) if n.endswith("_fz_N"))
    fx = sum(v for v, n in zip(lam, names) if n.endswith("_fx_N"))
    assert fz == pytest.approx(model.total_mass_kg * G, rel=1e-12)
    assert fx == pytest.approx(0.0, abs=1e-9)


def test_foot_rotation_is_the_rate_of_the_foot_angle(contact):
    # the generalized force of a pure moment is ∂φ/∂y; φ from the heel–MTP line of the model
    model = contact.model
    y = np.concatenate([[0.0, 1.0], RNG.uniform(-0.4, 0.4, 7)])
    h = 1e-6

    def foot_angle(yy, side):  # clockwise angle of the sole line heel → MTP from the forward horizontal
        d = model.point(f"mtp_{side}", yy) - model.point(f"heel_{side}", yy)
        return -np.arctan2(d[1], d[0])

    for side in ("r", "l"):
        fd = np.array([(foot_angle(y + h * e, side) - foot_angle(y - h * e, side)) / (2 * h) for e in np.eye(9)])
        np.testing.assert_allclose(foot_rotation(side), fd, atol=1e-8)
