"""The walking model's dynamics and the muscles' inversion as expressions of the NLP's variables (Diss. 5.2.6–5.2.8).

At every instant i of the cycle (``variables.Variables.values``):

    F   = F_max·ŝ²                                                  muscle forces, N             (2.19)
    Φ   = M(y) ÿ + k(y, ẏ) − g(y) − Q_t(y, ẏ) − Q_d(y, ẏ; D) − R(y) F  the generalized forces the
                                                                    ground must balance, N, N·m  (5.1)
    l_m, v_m                                                        the muscles' paths, m, m/s   (A.9)

and per leg, over the I instants (the unequal-step derivative of ``grid.py``): the tendon length
l_se = l_slack·(1 + ε0·ŝ) and its rate, fibre length and velocity (4.15, 4.17), ȧ, the excitation u of (2.17)
(the root of 4.3.3), the fibre's force balance a·F_max·g(l_ce, v_ce) − f_ce (2.18, 4.18) and the heat rate
Ė (A.12, its kinks smoothed). At every stated control point j: y (one stride on at the cycle's closing
point), the contact Jacobian G_ph (5.30), λ_j and the residual e = rhs − G_ph λ_j, the feet's summed forces.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitcli.predict.grid import periodic_derivative, step_derivative
from gaitcli.predict.pointwise import PointFunction
from gaitcli.predict.variables import LIFTED_SCALE, Variables, instant_steps


def tendon_force(stretch, max_isometric_force_N):
    """F = F_max·ŝ² (2.19), N, of the tendon stretches ``stretch`` (16: both legs, or 8: one leg's;
    ``max_isometric_force_N`` one leg's 8)."""
    f_max = np.asarray(max_isometric_force_N, float)
    return ca.DM(np.tile(f_max, stretch.numel() // f_max.size)) * stretch ** 2


def muscle_forces(v: Variables, max_isometric_force_N) -> list:
    """F (2.19), N, at every instant (16 each; :func:`tendon_force`)."""
    return [tendon_force(v.values["stretch"][i], max_isometric_force_N) for i in range(v.n_i)]


def dynamics_function(v: Variables, model, muscles) -> PointFunction:
    """(rhs − Φ)/100 N (5.1) at every stated instant, a point function of z = (y, ẏ, ÿ (9 each), ŝ (16),
    rhs (9), the device's coefficients): rhs the lifted generalized forces, Φ from the model."""
    n_d = v.coefficients.numel()
    z = ca.SX.sym("z", 52 + n_d)
    y, yd, ydd, stretch, rhs, device = z[0:9], z[9:18], z[18:27], z[27:43], z[43:52], z[52:]
    forces = tendon_force(stretch, muscles.muscle.params.max_isometric_force_N)
    physics = (model.mass_matrix(y) @ ydd + model.bias(y, yd) - model.gravity(y) - muscles.tissue(y, yd)
               - muscles.device(y, yd, device) - muscles.moment_arms(y) @ forces)
    function = ca.Function("dynamics", [z], [(rhs - physics) / LIFTED_SCALE["rhs"]], ["z"], ["dynamics"])
    columns = [ca.vertcat(v.values["y"][i], v.values["yd"][i], v.values["ydd"][i], v.values["stretch"][i],
                          v.generalized_forces[i], v.coefficients) for i in v.dynamics_instants]
    return PointFunction("dynamics", function, ca.horzcat(*columns))


def path_residuals(v: Variables, muscles) -> list:
    """(l_m − l_m(y), v_m − v_m(y, ẏ)) of the modelled muscles at every instant (A.9), m and m/s."""
    out = []
    for i in range(v.n_i):
        y, yd = v.values["y"][i], v.values["yd"][i]
        out.append((v.values["l_m"][i][v.columns] - muscles.lengths(y)[v.columns],
                    v.values["v_m"][i][v.columns] - muscles.velocities(y, yd)[v.columns]))
    return out


def muscle_function(v: Variables, transcriber, weight) -> PointFunction:
    """The muscles' inversion (5.25–5.26, as EID's 4.10–4.19) of one leg at one instant, a point function:

        z = (ŝ_{i−1}, ŝ_i, ŝ_{i+1}, a_{i−1}, a_i, a_{i+1}, l_m, v_m (8 each), h1, h2, ΔS)
        balance = (a·F_max·g(l_ce, v_ce) − f_ce)/F_max             the fibre's force balance (2.18, 4.18)
        cost    = Σ_m Ė_m·(h1 + h2)/2 / ΔS                         instant i's share of Et (5.27), J/m

    of the modelled muscles, with l_se = l_slack·(1 + ε0·ŝ), its rate and ȧ by the unequal-step derivative
    (``grid.step_derivative``), l_ce, v_ce (4.15, 4.17), u of (2.17) (the root of 4.3.3) and Ė (A.12, kinks
    smoothed); stated at every (leg, instant), the symmetric model's right leg only (its Et counted twice).
    ``weight`` (of p) multiplies Σ cost in J."""
    muscle = transcriber.muscles.muscle
    params = muscle.params
    z = ca.SX.sym("z", 8 * 8 + 3)
    stretch, a = [z[8 * k:8 * k + 8] for k in range(3)], [z[8 * k:8 * k + 8] for k in range(3, 6)]
    l_m, v_m = z[48:56], z[56:64]
    h1, h2, stride = z[64], z[65], z[66]
    slack, eps0 = ca.DM(params.tendon_slack_length_m), params.tendon_strain_at_max_force
    f_max = ca.DM(params.max_isometric_force_N)
    l_se = [slack * (1 + eps0 * s) for s in stretch]
    v_se, adot = step_derivative(*l_se, h1, h2), step_derivative(*a, h1, h2)
    l_ce, v_ce = muscle.fibre_kinematics(l_se[1], v_se, l_m, v_m)
    # the root of 4.3.3 is real only above a slowest ȧ, below the feasible ȧ ≥ −t2·a (u ≥ 0, the first
    # excitation bound); a start beyond it (a neighbouring case's unconverged solution) would make Et NaN
    # and stop IPOPT at iteration 0, so ȧ is raised to that floor (MuscleModel.slowest_activation_rate):
    # u exact and smooth on the feasible set and near it, finite everywhere
    u = muscle.excitation(a[1], ca.fmax(adot, muscle.slowest_activation_rate(a[1])))
    f_ce = tendon_force(stretch[1], params.max_isometric_force_N) / ca.DM(np.cos(params.pennation_rad))
    # the activation that makes F, as the fibre's force balance a·F_max·g(l_ce, v_ce) = f_ce (2.18) per
    # F_max: a = f_ce/(F_max·g) (4.18) itself has slopes ∝ 1/g², unbounded where g is small
    balance = (muscle.fibre_force(a[1], l_ce, v_ce) - f_ce) / f_max
    rate = transcriber.metabolic(u, a[1], l_ce, v_ce, f_ce)
    cost = v.energy_factor * ca.sum1(rate[v.kept]) * (h1 + h2) / 2 / stride
    function = ca.Function("muscles", [z], [balance[v.kept], cost], ["z"], ["activation", "cost"])
    h1s, h2s = instant_steps(v)
    columns = []
    for k in range(v.muscle_columns.stop // 8):
        c = slice(8 * k, 8 * k + 8)
        for i in range(v.n_i):
            near = [(i - 1) % v.n_i, i, (i + 1) % v.n_i]
            columns.append(ca.vertcat(*[v.values["stretch"][j][c] for j in near], *[v.values["a"][j][c] for j in near],
                                      v.values["l_m"][i][c], v.values["v_m"][i][c], h1s[i], h2s[i], v.stride))
    return PointFunction("muscles", function, ca.horzcat(*columns), weight)


@dataclass
class LegActivation:
    """One leg's activations ``a`` and their rates ``adot`` (I × 8, 1/s; the unequal-step derivative) with the
    activation rate constants ``t1``, ``t2`` (I × 8), 1/s: what the excitation bounds (5.32) read."""

    a: ca.SX
    adot: ca.SX
    t1: ca.SX
    t2: ca.SX


def leg_activations(v: Variables, params) -> list[LegActivation]:
    """:class:`LegActivation` of each stated leg."""
    a_m = ca.horzcat(*v.values["a"]).T  # (I × 16)
    adot = periodic_derivative(a_m, v.times, v.period)
    t1 = np.tile(np.asarray(params.activation_t1_per_s), 2)
    t2 = np.tile(np.asarray(params.activation_t2_per_s), 2)
    legs = []
    for k in range(v.muscle_columns.stop // 8):
        c = slice(8 * k, 8 * k + 8)
        legs.append(LegActivation(a=a_m[:, c], adot=adot[:, c], t1=ca.repmat(ca.DM(t1[c]).T, v.n_i, 1),
                                  t2=ca.repmat(ca.DM(t2[c]).T, v.n_i, 1)))
    return legs


@dataclass
class ContactPoint:
    """The ground at one stated control point j (phase 1–8, instant i): ``y`` its coordinates, ``G`` G_ph(y),
    ``lam`` λ_j (N, N·m), ``residual`` e = rhs − G λ (5.30), ``names`` the phase's reaction names, ``feet``
    side → (f_x, f_z) summed per foot and ``split`` side → (heel f_z, MTP f_z), N."""

    j: int
    phase: int
    i: int
    y: ca.SX
    G: ca.SX
    lam: ca.SX
    residual: ca.SX
    names: tuple
    feet: dict
    split: dict


def contact_points(v: Variables, contact) -> list[ContactPoint]:
    """The :class:`ContactPoint` of every stated control point, in grid order."""
    grid, out = v.grid, []
    for j in v.points:
        phase, i = v.phases[j], int(grid.instant[j])
        y = v.values["y"][i] + (ca.DM([1.0] + [0.0] * 8) * v.stride if grid.wraps[j] else 0)
        G = contact.reaction_matrix[phase](y)
        lam = v.reactions[j]
        names = contact.reaction_names[phase]
        feet = {}
        for side in ("r", "l"):
            fx = sum((lam[k] for k, name in enumerate(names) if name.endswith(f"_{side}_fx_N")), ca.SX(0))
            fz = sum((lam[k] for k, name in enumerate(names) if name.endswith(f"_{side}_fz_N")), ca.SX(0))
            feet[side] = (fx, fz)
        split = {side: tuple(sum((lam[k] for k, name in enumerate(names) if name == f"{point}_{side}_fz_N"),
                                 ca.SX(0)) for point in ("heel", "mtp")) for side in ("r", "l")}
        out.append(ContactPoint(j=j, phase=phase, i=i, y=y, G=G, lam=lam, residual=v.generalized_forces[i] - G @ lam,
                                names=tuple(names), feet=feet, split=split))
    return out
