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

from gaitcli.predict.grid import periodic_derivative
from gaitcli.predict.variables import Variables


def muscle_forces(v: Variables, max_isometric_force_N) -> list:
    """F = F_max·ŝ² (2.19), N, at every instant (16 each; ``max_isometric_force_N`` one leg's 8)."""
    f_max = np.tile(np.asarray(max_isometric_force_N), 2)
    return [ca.DM(f_max) * v.values["stretch"][i] ** 2 for i in range(v.n_i)]


def dynamics_residuals(v: Variables, model, muscles, forces: list) -> list:
    """rhs − Φ (5.1) at every stated instant: rhs the lifted generalized forces, Φ from the model."""
    out = []
    for i in v.dynamics_instants:
        y, yd, ydd = v.values["y"][i], v.values["yd"][i], v.values["ydd"][i]
        physics = (model.mass_matrix(y) @ ydd + model.bias(y, yd) - model.gravity(y) - muscles.tissue(y, yd)
                   - muscles.device(y, yd, v.coefficients) - muscles.moment_arms(y) @ forces[i])
        out.append(v.generalized_forces[i] - physics)
    return out


def path_residuals(v: Variables, muscles) -> list:
    """(l_m − l_m(y), v_m − v_m(y, ẏ)) of the modelled muscles at every instant (A.9), m and m/s."""
    out = []
    for i in range(v.n_i):
        y, yd = v.values["y"][i], v.values["yd"][i]
        out.append((v.values["l_m"][i][v.columns] - muscles.lengths(y)[v.columns],
                    v.values["v_m"][i][v.columns] - muscles.velocities(y, yd)[v.columns]))
    return out


@dataclass
class LegInversion:
    """One leg's inverted muscle states (8 × I each): ``balance`` the fibre's force balance per F_max (2.18),
    ``rate`` the heat rate Ė, W (I × 8), ``adot`` ȧ and ``a`` (I × 8), ``t1``, ``t2`` the activation rate
    constants (I × 8), 1/s."""

    balance: ca.SX
    rate: ca.SX
    a: ca.SX
    adot: ca.SX
    t1: ca.SX
    t2: ca.SX


def invert_muscles(v: Variables, transcriber, forces: list) -> list[LegInversion]:
    """The muscles' inversion (5.25–5.26, as EID's 4.10–4.19) for each stated leg (module docstring)."""
    muscle = transcriber.muscles.muscle
    params = muscle.params

    def matrix(name):
        return ca.horzcat(*v.values[name]).T  # (I × 16)

    stretch_m, a_m = matrix("stretch"), matrix("a")
    force_m = ca.horzcat(*forces).T
    slack = np.tile(np.asarray(params.tendon_slack_length_m), 2)
    f_max_n = np.tile(np.asarray(params.max_isometric_force_N), 2)
    l_se = ca.repmat(ca.DM(slack).T, v.n_i, 1) * (1 + params.tendon_strain_at_max_force * stretch_m)
    v_se = periodic_derivative(l_se, v.times, v.period)
    adot = periodic_derivative(a_m, v.times, v.period)
    t1 = np.tile(np.asarray(params.activation_t1_per_s), 2)
    t2 = np.tile(np.asarray(params.activation_t2_per_s), 2)
    legs = []
    for k in range(v.muscle_columns.stop // 8):
        c = slice(8 * k, 8 * k + 8)
        l_ce, v_ce = muscle.fibre_kinematics(l_se[:, c].T, v_se[:, c].T, matrix("l_m")[:, c].T, matrix("v_m")[:, c].T)
        # the root of 4.3.3 is real only above a slowest ȧ, below the feasible ȧ ≥ −t2·a (u ≥ 0, the first
        # excitation bound); a start beyond it (a neighbouring case's unconverged solution) would make Et NaN
        # and stop IPOPT at iteration 0, so ȧ is raised to that floor (MuscleModel.slowest_activation_rate):
        # u exact and smooth on the feasible set and near it, finite everywhere
        a_rows = a_m[:, c].T
        u = muscle.excitation(a_rows, ca.fmax(adot[:, c].T, muscle.slowest_activation_rate(a_rows)))
        f_ce = force_m[:, c].T / ca.repmat(ca.DM(np.cos(params.pennation_rad)), 1, v.n_i)
        # the activation that makes F, as the fibre's force balance a·F_max·g(l_ce, v_ce) = f_ce (2.18) per
        # F_max: a = f_ce/(F_max·g) (4.18) itself has slopes ∝ 1/g², unbounded where g is small
        f_max = ca.repmat(ca.DM(f_max_n[c]), 1, v.n_i)
        balance = (muscle.fibre_force(a_m[:, c].T, l_ce, v_ce) - f_ce) / f_max
        rate = transcriber.metabolic(u, a_m[:, c].T, l_ce, v_ce, f_ce).T
        legs.append(LegInversion(balance=balance, rate=rate, a=a_m[:, c], adot=adot[:, c],
                                 t1=ca.repmat(ca.DM(t1[c]).T, v.n_i, 1), t2=ca.repmat(ca.DM(t2[c]).T, v.n_i, 1)))
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
