"""The predictive-gait NLP (gaitcli/predict/nlp.py and its parts): the constraint groups' sizes follow the grid
and the phase table; the lifted variables of a design vector solve the NLP's own defining equations (two
implementations of the same quantities agree); the symmetric model's gait is symmetric to round-off; windows
move only where a solution presses on them."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.predict.contact import PHASE_TABLE
from gaitcli.predict.guess import initial_guess
from gaitcli.predict.layout import box_bounds
from gaitcli.predict.nlp import build_nlp
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import read_reference
from gaitcli.predict.settings import PredictSettings
from gaitcli.predict.solve import moved_windows
from gaitcli.resources import bundled_reference

DEFINING = ("splines", "dynamics", "paths", "activation", "reactions")


@pytest.fixture(scope="module")
def transcriber():
    return Transcriber(18)


@pytest.fixture(scope="module")
def reference():
    return read_reference(bundled_reference())


@pytest.fixture(scope="module", params=[False, True], ids=["full", "symmetric"])
def built(request, transcriber, reference):
    symmetric = request.param
    return symmetric, build_nlp(transcriber, reference, symmetric=symmetric)


def test_group_sizes(transcriber, built):
    symmetric, nlp = built
    grid = transcriber.grid
    share = 2 if symmetric else 1  # the symmetric model states the first half cycle only
    points = range(grid.points // share)
    phases = [int(grid.phase[j]) + 1 for j in points]
    rows = [len(PHASE_TABLE[p - 1].rows) for p in phases]
    widths = [len(transcriber.contact.reaction_names[p]) for p in phases]
    sizes = {k: v.stop - v.start for k, v in nlp.groups.items()}
    muscles = 16 // share
    assert sizes["dynamics"] == 9 * grid.instants // share
    assert sizes["paths"] == 2 * muscles * grid.instants and sizes["activation"] == muscles * grid.instants
    assert sizes["reactions"] == sum(widths)  # one normal equation per reaction and point
    assert sizes["moment"] == 6 * len(points)  # 720 full
    assert sizes["contact"] == sum(rows)
    assert sizes["unilateral"] == sum(sum(1 for _, axis, _ in PHASE_TABLE[p - 1].rows if axis == "z") for p in phases)
    assert sizes["mtp"] == sum(1 for p in phases if PHASE_TABLE[p - 1].mtp_moment_side)
    assert sizes["excitation"] == 2 * muscles * grid.instants  # the two ȧ bounds per muscle and instant
    # the 4 shape bounds (5.45–5.48) and each heel rocker stated (PredictSettings.foot_flat_min_pct)
    assert sizes["speed"] == 1 and sizes["shape"] == 4 + (1 if symmetric else 2)
    assert nlp.constraints.size1() == len(nlp.lbg) == len(nlp.ubg) == sum(sizes.values())
    assert nlp.layout.size == (219 if symmetric else 438)


def test_the_variables_are_laid_out_as_documented(built):
    # variables.py's table at nn = 18 on the default grid: each block's size, in order, filling w
    symmetric, nlp = built
    expected = ({"C_t": 9 * 3, "C_y": 17 * 3, "C_s": 17 * 8, "T": 4, "L": 1, "Q": 112 * 41, "P": 56 * 18,
                 "Λ": 218} if symmetric else
                {"C_t": 18 * 3, "C_y": 17 * 6, "C_s": 17 * 16, "T": 8, "L": 2, "Q": 112 * 100, "Λ": 436})
    assert [(k, s.stop - s.start) for k, s in nlp.blocks.items()] == list(expected.items())
    assert nlp.w.size1() == nlp.lbw.size == sum(expected.values()) == (6037 if symmetric else 12074)


def test_lifted_start_solves_the_defining_equations(transcriber, reference, built):
    # w from the numeric transcription of χ (problem.py, λ by the pseudoinverse) satisfies the lifted NLP's own
    # equations, and its moment errors are the transcription's
    symmetric, nlp = built
    x0 = np.clip(initial_guess(transcriber, reference, symmetric=symmetric), *box_bounds(nlp.layout))
    w0 = nlp.start(x0)
    np.testing.assert_allclose(nlp.design(w0), x0, atol=1e-12)  # χ → w → χ
    g = nlp.constraint_values(w0)
    for name in DEFINING:
        assert np.abs(g[nlp.groups[name]]).max() < 1e-9, name
    t = transcriber.at(*nlp.gait(w0))
    half = transcriber.grid.points // 2 if symmetric else transcriber.grid.points
    np.testing.assert_allclose(g[nlp.groups["moment"]], np.concatenate(t.moment_error_Nm[:half]), atol=1e-9)
    assert np.all(w0 >= nlp.lbw) and np.all(w0 <= nlp.ubw)
    cost, et, jdev = nlp.cost_parts(w0)
    assert np.isfinite(cost) and 100 < et < 2000 and jdev > 0  # J/m: a walking order of magnitude at 10 % F_max
    assert abs(g[nlp.groups["speed"]][0]) < 1e-12  # the guess walks at the set speed: T = (L_r + L_l)/v


def test_symmetric_gait_is_symmetric_to_round_off(transcriber, reference):
    # the full transcription of a symmetric design: the second half cycle is the first with the legs swapped,
    # so every contact-dependent quantity of phase p + 4 equals phase p's mirrored
    nlp = build_nlp(transcriber, reference, symmetric=True)
    rng = np.random.default_rng(0)
    x = initial_guess(transcriber, reference, symmetric=True)
    x = np.clip(x + 0.01 * rng.normal(size=x.size), *box_bounds(nlp.layout))
    t = transcriber.at(*nlp.gait(nlp.start(x)))
    half = transcriber.grid.points // 2
    for j in range(half):
        first, second = t.moment_error_Nm[j], t.moment_error_Nm[j + half]
        np.testing.assert_allclose(second, np.concatenate([first[3:], first[:3]]), atol=1e-9)
        np.testing.assert_allclose(np.sort(t.reactions[j + half]), np.sort(t.reactions[j]), atol=1e-6)
    instants = transcriber.grid.instants // 2
    np.testing.assert_allclose(t.metabolic_rate_W[instants:, 8:], t.metabolic_rate_W[:instants, :8], rtol=1e-9)


def test_windows_move_only_where_a_solution_presses_on_them(built):
    _, nlp = built
    lam_g = np.zeros(nlp.constraints.size1())
    assert moved_windows(nlp, lam_g) is None
    rows = nlp.groups["windows"]
    lam_g[rows.start + 3], lam_g[rows.start + 5] = 1e-3, -1e-3  # instant 3 presses forward, instant 5 back
    moved = moved_windows(nlp, lam_g)
    before = nlp.segments["cycle"]
    assert moved["cycle"][3] == before[3] + 1 and moved["cycle"][5] == max(before[5] - 1, 0)
    assert np.array_equal(np.delete(moved["cycle"], [3, 5]), np.delete(before, [3, 5]))


@pytest.fixture(scope="module")
def prosthetic(reference):
    """The symmetric NLP with SACH prostheses (5.3.3): the device's coefficients D are variables."""
    from gaitcli.predict.muscles import WalkerMuscles
    from gaitcli.predict.prosthesis import COMMERCIAL_FEET

    transcriber = Transcriber(18, muscles=WalkerMuscles(prosthesis=COMMERCIAL_FEET["sach"], strength_scale=1.5))
    return transcriber, build_nlp(transcriber, reference, symmetric=True)


def test_prosthetic_nlp_removes_two_muscles_and_its_start_solves_the_defining_equations(prosthetic, reference):
    from gaitcli.predict.cubic_ankle import ProsthesisCurve

    DEVICE_SCALE = ProsthesisCurve.SCALE

    transcriber, nlp = prosthetic
    grid = transcriber.grid
    sizes = {k: v.stop - v.start for k, v in nlp.groups.items()}
    assert sizes["activation"] == 6 * grid.instants and sizes["paths"] == 12 * grid.instants
    assert sizes["excitation"] == 12 * grid.instants
    x0 = initial_guess(transcriber, reference, symmetric=True)
    w0 = nlp.start(x0)
    lbw, ubw = nlp.bounds()  # the optimal device: D free
    assert w0.size == lbw.size == nlp.w.size1() and nlp.device_size == 6
    np.testing.assert_allclose(nlp.device(w0), transcriber.muscles.prosthesis.coefficients())
    np.testing.assert_allclose(w0[-6:] * DEVICE_SCALE, transcriber.muscles.prosthesis.coefficients())
    g = nlp.constraint_values(w0)
    for name in DEFINING:
        assert np.abs(g[nlp.groups[name]]).max() < 1e-9, name
    # Sol and TA: every variable of theirs fixed at 0 (spline coefficients and lifted ŝ, l_m, v_m, a)
    fixed = (nlp.lbw == 0) & (nlp.ubw == 0)
    per_instant = 4 * 2 * grid.instants  # ŝ, l_m, v_m, a of 2 muscles at every instant
    coefficients = 2 * (transcriber.layout.nodes - 1)  # their cubic B-splines' coefficients
    assert fixed.sum() == per_instant + coefficients
    # the moment error uses the prostheses' moment: the transcription (problem.py) with SACH's curve agrees
    t = transcriber.at(*nlp.gait(w0))
    np.testing.assert_allclose(g[nlp.groups["moment"]], np.concatenate(t.moment_error_Nm[:grid.points // 2]),
                               atol=1e-9)


def test_monotonicity_rows_accept_the_commercial_feet_and_refuse_a_rising_curve(prosthetic, reference):
    from gaitcli.predict.cubic_ankle import ProsthesisCurve
    from gaitcli.predict.prosthesis import COMMERCIAL_FEET

    DEVICE_SCALE = ProsthesisCurve.SCALE

    transcriber, nlp = prosthetic
    w0 = nlp.start(initial_guess(transcriber, reference, symmetric=True))
    for foot in COMMERCIAL_FEET.values():  # Table A.7's feet decrease over −25° … +10°
        w0[-6:] = foot.coefficients() / DEVICE_SCALE
        assert nlp.constraint_values(w0)[nlp.groups["monotone"]].max() <= 0, foot.name
    rising = ProsthesisCurve("rising", 0.0, 0.0, -50.0, 0.0, -2000.0, 1.0)  # slope −50 − 4000·y > 0 for y < −1.4°
    w0[-6:] = rising.coefficients() / DEVICE_SCALE
    monotone = nlp.constraint_values(w0)[nlp.groups["monotone"]]
    angles = np.linspace(np.radians(-25), np.radians(10), monotone.size)
    np.testing.assert_allclose(monotone * DEVICE_SCALE[2], -50.0 - 4000.0 * np.minimum(angles, 0.0) *
                               (angles <= 0), atol=1e-9)
    assert not rising.is_monotone(np.radians(-25), np.radians(10))


def test_speed_and_weights_are_parameters(built, transcriber, reference):
    # one built problem serves every speed and weight set: T − ΔS/v and J = w1·Et/100 + w2·Jdev at p
    symmetric, nlp = built
    w0 = nlp.start(initial_guess(transcriber, reference, symmetric=symmetric))
    durations, steps_r, steps_l, _ = nlp.gait(w0)
    for speed, weights in ((1.0, (1.0, 1.0)), (1.33, (20 / 11, 2 / 11))):
        settings = PredictSettings(speed_m_s=speed, weights=weights)
        g = nlp.constraint_values(w0, settings)
        assert g[nlp.groups["speed"]][0] == pytest.approx(durations.sum() - (steps_r + steps_l) / speed, abs=1e-12)
        cost, et, jdev = nlp.cost_parts(w0, settings)
        assert cost == pytest.approx(weights[0] * et / 100 + weights[1] * jdev, rel=1e-12)


def test_steady_trunk_and_centre_of_pressure_terms_add_their_integrals(built, transcriber, reference):
    # Jdev with trunk_rate_sd_deg_s and cop_sd_m = the dissertation's Jdev + ∫(ẏ3/σ)² + ∫(c − ĉ)²/σ², the
    # integrands recomputed here from the numeric transcription (λ by the pseudoinverse) and closed periodically
    symmetric, nlp = built
    settings = PredictSettings(trunk_rate_sd_deg_s=10.0, cop_sd_m=0.02)
    extended = build_nlp(transcriber, reference, settings, symmetric=symmetric, segments=nlp.segments)
    x = initial_guess(transcriber, reference, symmetric=symmetric)
    x = np.clip(x + 0.01 * np.random.default_rng(1).normal(size=x.size), *box_bounds(nlp.layout))  # a rocking trunk
    w0 = nlp.start(x)
    jdev, jdev_extended = nlp.cost_parts(w0)[2], extended.cost_parts(w0, settings)[2]
    gait = nlp.gait(w0)
    t, durations = transcriber.at(*gait), gait[0]
    grid, names = transcriber.grid, transcriber.contact.reaction_names
    strikes, stance, delta = ({"r": 0.0, "l": durations[:4].sum()}, durations[:6].sum(),
                              transcriber.contact.heel_to_mtp_m)
    trunk, cop = [], []
    for i, j in enumerate(grid.instant_points):
        trunk.append(np.degrees(t.yd[j, 2]) / 10.0)
        phase, row = int(grid.phase[j]) + 1, 0.0
        reactions = dict(zip(names[phase], t.reactions[j]))
        for side, rolling in (("r", (2, 3, 4)), ("l", (6, 7, 8))):
            if phase in rolling:
                heel, mtp = reactions.get(f"heel_{side}_fz_N", 0.0), reactions[f"mtp_{side}_fz_N"]
                target = (heel + mtp) * delta * (t.instant_times_s[i] - strikes[side]) / (0.85 * stance)
                row = (mtp * delta - target) / (transcriber.model.total_mass_kg * 9.81) / 0.02
        cop.append(row)
    closed = np.append(t.instant_times_s, t.instant_times_s[0] + t.period_s)

    def integral(values):
        v = np.append(values, values[0]) ** 2
        return float(np.sum((v[1:] + v[:-1]) / 2 * np.diff(closed)))

    assert integral(cop) > 1.0 and integral(trunk) > 0.1  # neither steady nor rolling
    assert jdev_extended == pytest.approx(jdev + integral(trunk) + integral(cop), rel=1e-9)


def test_the_hip_bounds_hold_the_hip_moments(built, transcriber, reference):
    # the opt-in hip_bound rows are what the muscles and tissues give each thigh, recomputed here from its
    # equation of motion: (M ÿ + k − g)_thigh − rhs_thigh, at every instant (the symmetric model: the right leg's,
    # its left leg being the same half a cycle later), within ± bound × body mass, the swing's bound in swing
    symmetric, nlp = built
    settings = PredictSettings(swing_hip_moment_Nm_per_kg=0.3, hip_moment_Nm_per_kg=0.9)
    bounded = build_nlp(transcriber, reference, settings, symmetric=symmetric, segments=nlp.segments)
    assert "hip_bound" not in nlp.groups  # off by default
    w0 = bounded.start(initial_guess(transcriber, reference, symmetric=symmetric))
    rows = bounded.constraint_values(w0, settings)[bounded.groups["hip_bound"]]
    t, model, grid = transcriber.at(*bounded.gait(w0)), transcriber.model, transcriber.grid
    expected, bounds = [], []
    for j in grid.instant_points:
        for thigh, swing in (((3, (7, 8)),) if symmetric else ((3, (7, 8)), (6, (3, 4)))):
            y, yd, ydd = t.y[j], t.yd[j], t.ydd[j]
            net = (np.array(model.mass_matrix(y)) @ ydd + np.array(model.bias(y, yd)).ravel()
                   - np.array(model.gravity(y)).ravel())
            expected.append(net[thigh] - np.array(t.generalized_forces[j], float).ravel()[thigh])
            bounds.append((0.3 if int(grid.phase[j]) + 1 in swing else 0.9) * model.total_mass_kg)
    assert len(expected) == len(grid.instant_points) * (1 if symmetric else 2) and len(set(bounds)) == 2
    np.testing.assert_allclose(rows, expected, rtol=1e-9, atol=1e-6)
    np.testing.assert_array_equal(bounded.lbg[bounded.groups["hip_bound"]], -np.array(bounds))
    np.testing.assert_array_equal(bounded.ubg[bounded.groups["hip_bound"]], bounds)


def test_the_cost_stays_finite_where_an_activation_falls_faster_than_any_excitation_allows(transcriber, reference,
                                                                                            built):
    # a start whose activation drops 1 → 0.02 in one instant (an unconverged neighbour's solution did): no real
    # excitation root (4.3.3) there; Et and its gradient stay finite (IPOPT stopped at iteration 0 on a NaN)
    import casadi as ca

    symmetric, nlp = built
    w0 = nlp.start(initial_guess(transcriber, reference, symmetric=symmetric))
    head = nlp.spline_size
    columns = [name for name, cols in nlp.lifted[0][2] for _ in range(cols)]
    n_i = transcriber.grid.instants
    a = head + columns.index("a") * n_i  # the first muscle's activations, instant by instant (column-major)
    w = w0.copy()
    w[a + 40], w[a + 41] = 1.0, 0.02
    cost = ca.Function("cost", [nlp.w, nlp.parameters], [nlp.cost, ca.gradient(nlp.cost, nlp.w)])
    p = nlp.parameter_values(PredictSettings())
    value, gradient = (np.array(v).ravel() for v in cost(w, p))
    assert np.isfinite(value).all() and np.isfinite(gradient).all()
    assert nlp.constraint_values(w)[nlp.groups["excitation"]].min() < 0  # the point is outside the bounds


def test_the_constraint_jacobian_is_banded_in_the_spline_coefficients(reference):
    # with B-spline coefficients an instant's y, ẏ, ÿ, ŝ read the 2·reach + 1 segments of its window, each
    # d + 1 coefficients wide: 2·reach + 1 + d per spline column, whatever the node count; no row of the
    # Jacobian grows with nn
    import casadi as ca

    from gaitcli.predict.grid import control_grid

    reach, widest = 1, {}
    for nodes in (14, 22):
        transcriber = Transcriber(nodes, grid=control_grid((2,) * 8))
        nlp = build_nlp(transcriber, reference, symmetric=False, reach=reach)
        jacobian = ca.jacobian(nlp.constraints, nlp.w).sparsity()
        counts = np.diff(np.array(jacobian.get_crs()[0]))  # non-zeros per row
        widest[nodes] = counts.max()
        splines = nlp.groups["splines"]
        coefficients = nlp.blocks["C_y"].stop  # the quartic coordinates' columns, 9 × N
        rows = ca.jacobian(nlp.constraints[splines], nlp.w[:coefficients]).sparsity()
        per_row = np.diff(np.array(rows.get_crs()[0]))
        assert per_row.max() == 2 * reach + 1 + 4, nodes  # one coordinate's value: its own spline only
    assert widest[14] == widest[22]
