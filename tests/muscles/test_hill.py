"""Muscle model (2.17–2.25, A.1–A.21): known values, sign conventions and forward ↔ inverse round trips."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.core.numerics import finite_difference_matrix
from gaitcli.errors import InputError
from gaitcli.muscles import MUSCLE_NAMES, MuscleModel, table_a1

IDX = {name: i for i, name in enumerate(MUSCLE_NAMES)}


@pytest.fixture(scope="module")
def model():
    return MuscleModel()


def test_table_a1_and_time_constants(model):
    p = model.params
    assert p.max_isometric_force_N[IDX["vasti"]] == 7403
    assert p.tendon_slack_length_m[IDX["soleus"]] == pytest.approx(0.245)
    # (A.1)–(A.2), docs/model_constants.md §7: τ_act / τ_deact in ms for Ilio RF Glu Ham Vas Gas TA Sol
    np.testing.assert_allclose(p.activation_time_s * 1000, [56.5, 49.45, 58.85, 63.55, 56.5, 56.5, 68.25, 70.6])
    np.testing.assert_allclose(p.deactivation_time_s * 1000, [62.0, 53.6, 64.8, 70.4, 62.0, 62.0, 76.0, 78.8])


def test_activation_dynamics_limits(model):
    """Decision 1: ȧ = (1 − a)/τ_act at u = 1 and −a/τ_deact at u = 0."""
    p = model.params
    a = np.linspace(0.1, 0.9, 8)
    np.testing.assert_allclose(model.evaluate("activation_rate", np.ones(8), a), (1 - a) / p.activation_time_s)
    np.testing.assert_allclose(model.evaluate("activation_rate", np.zeros(8), a), -a / p.deactivation_time_s)


def test_excitation_root_rule(model):
    """(4.19): the chosen root reproduces ȧ, lies in [0, 1] and is the one nearest to a."""
    rng = np.random.default_rng(1)
    u = rng.uniform(0, 1, (50, 8))
    a = rng.uniform(0, 1, (50, 8))
    adot = model.evaluate("activation_rate", u, a)
    np.testing.assert_allclose(model.evaluate("excitation", a, adot), u, atol=1e-12)
    # the other root of t1·u² + (t2 − t1·a)·u − (t2·a + ȧ) = 0 is far below 0
    t1, t2 = model.params.activation_t1_per_s, model.params.activation_t2_per_s
    other = -(t2 - t1 * a) / t1 - u
    assert np.all(other < -5)


def test_the_slowest_activation_rate_keeps_the_excitation_root_real(model):
    """At the floor the discriminant is 1 % of (t2 − t1·a)², so the root is u = −0.45·(t2 − t1·a)/t1 exactly,
    and (2.17) of that u gives the floor back; 1 % further down the root does not exist (NaN)."""
    a = np.linspace(0.0, 1.0, 8)
    t1, t2 = model.params.activation_t1_per_s, model.params.activation_t2_per_s
    floor = model.evaluate("slowest_activation_rate", a)
    assert np.all(floor < -t2 * a)  # below every feasible rate (u ≥ 0)
    u = model.evaluate("excitation", a, floor)
    np.testing.assert_allclose(u, -0.45 * (t2 - t1 * a) / t1, rtol=1e-12)
    np.testing.assert_allclose(model.evaluate("activation_rate", u, a), floor, rtol=1e-12)
    beyond = floor - 0.02 * (t2 - t1 * a) ** 2 / (4 * t1)
    assert np.all(np.isnan(model.evaluate("excitation", a, beyond)))


def test_force_length(model):
    p = model.params
    lopt, w = p.optimal_fibre_length_m, p.width
    np.testing.assert_allclose(model.evaluate("force_length", lopt), 1.0)
    np.testing.assert_allclose(model.evaluate("force_length", lopt * (1 + 0.5 * w)), 0.75)  # 1 − 0.5²
    np.testing.assert_allclose(model.evaluate("force_length", lopt * (1 + 1.2 * w)), 0.0)  # clipped
    np.testing.assert_allclose(model.evaluate("force_length", lopt * (1 - w)), 0.0, atol=1e-12)


def test_force_velocity(model):
    """(A.3), (A.5): f_iso at ṽ = 0, equal slopes there (slope factor 1), asymptote f_asympt·f_iso."""
    p = model.params
    lopt = p.optimal_fibre_length_m
    one = np.ones(8)
    np.testing.assert_allclose(model.evaluate("flv", lopt, 0 * one), 1.0)
    h = 1e-6
    slope_con = (1.0 - model.evaluate("flv", lopt, -h * lopt)) / h
    slope_ecc = (model.evaluate("flv", lopt, h * lopt) - 1.0) / h
    np.testing.assert_allclose(slope_con, (p.fv_a_rel + 1) / p.fv_b_rel_per_s, rtol=1e-4)  # (A_r + f_iso)/B_r
    np.testing.assert_allclose(slope_ecc, slope_con, rtol=1e-4)
    np.testing.assert_allclose(model.evaluate("flv", lopt, 1e7 * lopt), 1.5, rtol=1e-5)
    # concentric value by hand: ṽ = −2, f_iso = 1: (5.2·1 + 0.41·(−2))/(5.2 + 2)
    np.testing.assert_allclose(model.evaluate("flv", lopt, -2 * lopt), (5.2 - 0.82) / 7.2)
    # zero force at ṽ = −B_r·f_iso/A_r
    np.testing.assert_allclose(model.evaluate("flv", lopt, -5.2 / 0.41 * lopt), 0.0, atol=1e-12)


def test_tendon(model):
    """(2.19): F = F_max at 4 % strain; inverse and normalised-stretch forms agree."""
    p = model.params
    ls = p.tendon_slack_length_m
    np.testing.assert_allclose(model.evaluate("tendon_force", ls * 1.04), p.max_isometric_force_N)
    np.testing.assert_allclose(model.evaluate("tendon_force", ls * 0.99), 0.0)
    force = np.linspace(1.0, 5000.0, 8)
    np.testing.assert_allclose(model.evaluate("tendon_force", model.evaluate("tendon_length", force)), force,
                               rtol=1e-12)
    s_norm = np.linspace(0.0, 1.2, 8)
    f_s, l_s = model.evaluate("stretch_tendon", s_norm)
    np.testing.assert_allclose(model.evaluate("tendon_force", l_s), f_s, rtol=1e-12, atol=1e-9)


def test_path_neutral_lengths_and_arms(model):
    """Decision 4: neutral Gas/Sol lengths 0.487/0.284 m; r = −∂l/∂q by finite differences."""
    q0 = np.zeros(3)
    lm = model.evaluate("length", q0)
    assert lm[IDX["gastrocnemius"]] == pytest.approx(0.404 + 0.053 * np.pi / 2)
    assert lm[IDX["gastrocnemius"]] == pytest.approx(0.487, abs=1e-3)
    assert lm[IDX["soleus"]] == pytest.approx(0.284, abs=1e-3)
    q = np.array([0.3, 0.5, -0.1])
    arms = model.evaluate("moment_arms", q)
    h = 1e-6
    for k in range(3):
        dq = np.zeros(3)
        dq[k] = h
        fd = -(model.evaluate("length", q + dq) - model.evaluate("length", q - dq)) / (2 * h)
        np.testing.assert_allclose(arms[k], fd, atol=1e-9)
    qd = np.array([1.0, -2.0, 0.5])
    np.testing.assert_allclose(model.evaluate("velocity", q, qd), -(arms.T @ qd), atol=1e-12)


@pytest.mark.parametrize("muscle, joint, sign", [
    ("hamstrings", "knee", +1), ("hamstrings", "hip", -1), ("vasti", "knee", -1), ("soleus", "ankle", -1),
    ("tibialis_anterior", "ankle", +1), ("rectus_femoris", "knee", -1), ("rectus_femoris", "hip", +1),
    ("iliopsoas", "hip", +1), ("glutei", "hip", -1), ("gastrocnemius", "ankle", -1),
    ("gastrocnemius", "knee", +1),
])
def test_moment_arm_directions(model, muscle, joint, sign):
    """Generalized moments are positive for hip flexion, knee flexion, ankle dorsiflexion."""
    k = {"hip": 0, "knee": 1, "ankle": 2}[joint]
    arms = model.evaluate("moment_arms", np.array([0.2, 0.4, 0.05]))
    assert np.sign(arms[k, IDX[muscle]]) == sign


def test_single_joint_muscles_span_one_joint(model):
    arms = model.evaluate("moment_arms", np.array([0.2, 0.4, 0.05]))
    for name, joint in [("iliopsoas", 0), ("glutei", 0), ("vasti", 1), ("tibialis_anterior", 2), ("soleus", 2)]:
        others = [k for k in range(3) if k != joint]
        assert np.all(arms[others, IDX[name]] == 0)


def test_contraction_round_trip_pointwise(model):
    """Forward (2.25) then inverse (4.13–4.18) returns the activation; forces to 1e-6 relative.

    States are drawn so that the CE force lies between 0.2 and 1.45 times its isometric value
    (inside the force–velocity curve, where the forward dynamics has a finite solution).
    """
    rng = np.random.default_rng(2)
    p = model.params
    lm = model.evaluate("length", np.array([0.2, 0.5, 0.05]))
    for _ in range(20):
        s = p.tendon_slack_length_m * p.tendon_strain_at_max_force * rng.uniform(0.2, 0.7, 8)
        vm = rng.uniform(-0.3, 0.3, 8)
        force = model.evaluate("tendon_force", p.tendon_slack_length_m + s)
        l_ce = (lm - p.tendon_slack_length_m - s) / np.cos(p.pennation_rad)
        ratio = rng.uniform(0.2, 1.45, 8)  # f_ce/(a·F_max·f_iso)
        a = force / np.cos(p.pennation_rad) / (p.max_isometric_force_N * model.evaluate("force_length", l_ce) * ratio)
        sdot, force_out, l_ce_out, v_ce = model.evaluate("contraction_rate", a, s, lm, vm)
        np.testing.assert_allclose(force_out, force, rtol=1e-12)
        np.testing.assert_allclose(l_ce_out, l_ce, rtol=1e-12)
        f_ce = model.evaluate("fibre_force", a, l_ce_out, v_ce)
        np.testing.assert_allclose(f_ce * np.cos(p.pennation_rad), force, rtol=1e-6)
        np.testing.assert_allclose(model.evaluate("activation_from_force", force, sdot, lm, vm), a, rtol=1e-9)
        s_norm = s / (p.tendon_slack_length_m * p.tendon_strain_at_max_force)
        np.testing.assert_allclose(model.evaluate("activation_from_stretch", s_norm, sdot, lm, vm), a, rtol=1e-9)
        # the same through the force derivative: v_se = Ḟ/(dF/dl_se) (2.21)
        fdot = 2 * np.sqrt(p.tendon_stiffness_N_per_m2 * force) * sdot
        np.testing.assert_allclose(model.evaluate("tendon_velocity", force, fdot), sdot, rtol=1e-9, atol=1e-15)


def test_activation_from_stretch_differentiable_at_slack_tendon(model):
    """At ŝ = 0 (F = 0) ∂a/∂ŝ is finite, 0 (a ∝ ŝ²), where a(F) through √(F/k_T) has no derivative: the
    predictive NLP's starting points may put a tendon exactly there (its lower bound)."""
    s, v_se, l_m, v_m = (ca.SX.sym(k, 8) for k in ("s", "v_se", "l_m", "v_m"))
    a = model.activation_from_stretch(s, v_se, l_m, v_m)
    grad = ca.Function("g", [s, v_se, l_m, v_m], [ca.jacobian(a, s)])
    lm = model.evaluate("length", np.array([0.2, 0.5, 0.05]))
    value = np.array(grad(np.zeros(8), np.zeros(8), lm, np.zeros(8)))
    assert np.all(np.isfinite(value)) and np.allclose(value, 0.0)
    force = ca.SX.sym("F", 8)
    via_force = ca.jacobian(model.activation_from_force(force, v_se, l_m, v_m), force)
    assert not np.all(np.isfinite(np.array(ca.Function("h", [force, v_se, l_m, v_m], [via_force])(
        np.zeros(8), np.zeros(8), lm, np.zeros(8)))))


def test_fibre_force_round_trip(model):
    """a → f_ce (2.18) → a (4.18) at random fibre states."""
    rng = np.random.default_rng(4)
    p = model.params
    a = rng.uniform(0.01, 1, (40, 8))
    l_ce = p.optimal_fibre_length_m * rng.uniform(0.7, 1.3, (40, 8))
    v_ce = p.optimal_fibre_length_m * rng.uniform(-4, 4, (40, 8))
    f_ce = model.evaluate("fibre_force", a, l_ce, v_ce)
    g = model.evaluate("flv", l_ce, v_ce)
    np.testing.assert_allclose(f_ce / (p.max_isometric_force_N * g), a, rtol=1e-12)


def test_time_series_round_trip():
    """u(t) → a(t), F(t) by integration (2.17, 2.25) → finite-difference inversion → u(t) (4.10–4.19).

    Smooth sinusoidal excitations and muscle lengths; integrated by CVODES with the same CasADi
    Functions, sampled at 1 kHz. Central differences are O(Δt²) except within a few ms of the
    instants where v_ce changes sign (the force–velocity curve has a second-derivative jump
    there), which are left out of the 1e-4 check.
    """
    model = MuscleModel()
    p, m = model.params, model.m
    t = ca.SX.sym("t")
    x = ca.SX.sym("x", 2 * m)
    phase = ca.DM(np.arange(m) * 0.7)
    u = 0.35 + 0.25 * ca.sin(2 * np.pi * t + phase)
    lopt, ls = ca.DM(p.optimal_fibre_length_m), ca.DM(p.tendon_slack_length_m)
    lm = 1.02 * ls + lopt + 0.3 * lopt * ca.sin(2 * np.pi * t + 2 * phase)
    vm = ca.jacobian(lm, t)
    ode = ca.vertcat(model.activation_rate(u, x[:m]), model.contraction_rate(x[:m], x[m:], lm, vm)[0])
    dt = 1e-3
    ts = np.arange(0.0, 1.2 + 1e-12, dt)
    integ = ca.integrator("round_trip", "cvodes", {"x": x, "t": t, "ode": ode}, 0.0, ts,
                          {"abstol": 1e-13, "reltol": 1e-11})
    a0 = np.array(ca.evalf(ca.substitute(u, t, 0))).ravel()
    xs = np.array(integ(x0=np.concatenate([a0, 0.02 * p.tendon_slack_length_m]))["xf"]).T
    inputs = ca.Function("inputs", [t], [u, lm, vm]).map(ts.size)
    u_true, l_m, v_m = (np.array(v).T for v in inputs(ts))
    force = p.tendon_stiffness_N_per_m2 * np.maximum(xs[:, m:], 0) ** 2
    inv = model.invert_forces(force, l_m, v_m, dt, "central")
    keep = slice(200, -2)  # after the start-up transient, away from the one-sided end differences
    np.testing.assert_allclose(inv["a"][keep], xs[keep, :m], atol=1e-5)
    err = np.abs(inv["u"] - u_true)[keep]
    sign_change = np.abs(np.diff(np.sign(inv["v_ce"]), axis=0)) > 0
    near = np.zeros_like(inv["u"], dtype=bool)
    for k in range(-8, 9):
        near[np.clip(np.arange(ts.size - 1) + k, 0, ts.size - 1)] |= sign_change
    assert err[~near[keep]].max() < 1e-4
    assert np.median(err) < 1e-6
    assert err.max() < 1e-3


def test_finite_difference_matrices():
    n, dt = 40, 0.025
    t = np.arange(n) * dt
    x = np.sin(2 * np.pi * t / (n * dt))
    exact = 2 * np.pi / (n * dt) * np.cos(2 * np.pi * t / (n * dt))
    per = finite_difference_matrix(n, dt, "periodic") @ x
    assert np.abs(per - exact).max() < 2 * (2 * np.pi / (n * dt)) ** 3 * dt ** 2 / 6
    back = finite_difference_matrix(n, dt, "backward") @ t ** 2
    np.testing.assert_allclose(back[1:], (t[1:] ** 2 - t[:-1] ** 2) / dt)
    cen = finite_difference_matrix(n, dt, "central") @ t ** 2
    np.testing.assert_allclose(cen[1:-1], 2 * t[1:-1])


def test_finite_difference_bad_requests():
    """A misspelt scheme or too few nodes is a user error with a hint, not a ValueError."""
    with pytest.raises(InputError, match="scheme: got 'periodc'.*did you mean 'periodic'"):
        finite_difference_matrix(10, 0.01, "periodc")
    with pytest.raises(InputError, match="nodes: got 2"):
        finite_difference_matrix(2, 0.01, "periodic")
    assert finite_difference_matrix(2, 0.01, "central").shape == (2, 2)


# ------------------------------------------------------------------- energetics (A.12–A.21)
def _ilio(model):
    p = model.params
    i = IDX["iliopsoas"]
    return i, p.optimal_fibre_length_m[i], p.muscle_mass_kg[i]


def _rate(model, i, u, a, l_ce, v_ce, f_ce):
    """Evaluate the model with the chosen muscle's values (others at rest) and return muscle i."""
    p = model.params
    args = [np.full(8, 0.0), np.full(8, 0.0), p.optimal_fibre_length_m.copy(), np.zeros(8), np.zeros(8)]
    for arr, val in zip(args, (u, a, l_ce, v_ce, f_ce)):
        arr[i] = val
    return model.evaluate("metabolic_rate", *args)[i]


def test_metabolic_rate_hand_computed_shortening(model):
    """Ilio (ft 50 %), u = 0.6 > a = 0.4, l_ce = 0.9·l_opt, ṽ = −1 l_opt/s, f_ce = 300 N."""
    i, lopt, mass = _ilio(model)
    assert mass == pytest.approx(1059.7 * 0.102 * 821 / 0.25e6)
    a_m = 0.6  # (A.17)
    h_am = 1.28 * 50 + 25  # (A.18)
    maintenance = h_am * a_m ** 0.6 * 1.5
    alpha_st, alpha_ft = 250 / 12, 153 / 12
    shortening = (alpha_st * 1.0 * 0.5 + alpha_ft * 1.0 * 0.5) * a_m ** 2 * 1.5
    work = -300.0 * (-1.0 * lopt)
    expected = work + mass * (maintenance + shortening)
    assert expected == pytest.approx(68.70, abs=0.01)
    assert _rate(model, i, 0.6, 0.4, 0.9 * lopt, -1.0 * lopt, 300.0) == pytest.approx(expected, rel=1e-12)


def test_metabolic_rate_long_fibres_lengthening(model):
    """l_ce > l_opt (A.16): f_iso factors; u ≤ a: a_m = (u + a)/2; ṽ = +2 (α_L = 4·α_ST)."""
    i, lopt, mass = _ilio(model)
    f_iso = 1 - (0.2 / model.params.width[i]) ** 2
    a_m = (0.2 + 0.5) / 2
    heat = (0.4 + 0.6 * f_iso) * 89 * a_m ** 0.6 * 1.5 + 4 * 250 / 12 * 2.0 * f_iso * a_m * 1.5
    expected = -100.0 * 2.0 * lopt + mass * heat
    assert _rate(model, i, 0.2, 0.5, 1.2 * lopt, 2.0 * lopt, 100.0) == pytest.approx(expected, rel=1e-12)


def test_metabolic_cap_and_floor(model):
    """Decision 6: −α_ST·ṽ capped at 100 W/kg before the ST weighting; total heat ≥ 1 W/kg."""
    i, lopt, mass = _ilio(model)
    heat = 89 * 1.0 * 1.5 + (100.0 * 0.5 + 153 / 12 * 10 * 0.5) * 1.0 * 1.5
    expected = -200.0 * (-10 * lopt) + mass * heat
    assert _rate(model, i, 1.0, 1.0, lopt, -10 * lopt, 200.0) == pytest.approx(expected, rel=1e-12)
    assert _rate(model, i, 0.0, 0.0, lopt, 0.0, 0.0) == pytest.approx(mass * 1.0)


def test_metabolic_umberger2010_variant():
    """α_L = 0.3·α_ST and no negative work (Umberger 2010)."""
    model = MuscleModel(table_a1(metabolic_model="umberger2010"))
    i, lopt, mass = _ilio(model)
    a_m = 0.5
    heat = 89 * a_m ** 0.6 * 1.5 + 0.3 * 250 / 12 * 1.0 * a_m * 1.5
    assert _rate(model, i, 0.5, 0.5, lopt, 1.0 * lopt, 400.0) == pytest.approx(mass * heat, rel=1e-12)


def test_smoothed_metabolic_rate_converges_to_exact(model):
    rng = np.random.default_rng(3)
    p = model.params
    args = (rng.uniform(0, 1, (30, 8)), rng.uniform(0, 1, (30, 8)),
            p.optimal_fibre_length_m * rng.uniform(0.6, 1.4, (30, 8)),
            p.optimal_fibre_length_m * rng.uniform(-3, 3, (30, 8)), rng.uniform(0, 2000, (30, 8)))
    exact = model.evaluate("metabolic_rate", *args)
    smooth = np.asarray(model.smoothed_metabolic_rate(1e-6)(*[a.T for a in args])).T
    np.testing.assert_allclose(smooth, exact, rtol=1e-3, atol=1e-3)
