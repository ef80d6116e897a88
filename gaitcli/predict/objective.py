"""The cost terms of the predictive-gait NLP as expressions of its variables (Diss. 5.2.7, (5.27)–(5.29)).

    Et    = (1/ΔS) Σ_m ∫ Ė_m dt                                    J/m   (5.27)
    Jdev  = Σ_k ∫ (x_k − x̂_k)²/σ_k² dt                             s     (5.28)
            x: hip and knee flexion, ankle dorsiflexion (deg) and f_x, f_z per body mass (N/kg) of both
            sides at the I instants, against the reference's mean x̂ and SD σ at the same cycle percentage;
            plus, opt-in (``PredictSettings``), a steady trunk (ẏ3 against 0, deg/s) and each foot's
            centre of pressure (against a heel-to-MTP progression, per body weight)
    J     = w1·Et/100 + w2·Jdev                                           (5.29)

with the integrals by the periodic trapezoid rule (``cost.py``), the heat rates' kinks smoothed for the
optimiser as in EID (reported costs use the exact model) and (w1, w2) parameters of the NLP. Et's and Jdev's
shares of each instant are point functions (``pointwise.py``; Et's with the muscles' inversion,
``dynamics.muscle_function``). The symmetric model's Et counts its right leg's muscles twice; its second half
cycle's ground forces are the first half's, sides swapped.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gaitcli.kinematics.conventions import walker_joint_angles
from gaitcli.predict.cost import deviation
from gaitcli.predict.dynamics import ContactPoint
from gaitcli.predict.pointwise import PointFunction
from gaitcli.predict.reference import reference_curves
from gaitcli.predict.variables import Variables, instant_steps
from gaitcli.signal.bands import Band

#: the fraction of its stance over which a foot's centre of pressure is tracked from heel to MTP
COP_PROGRESSION_STANCE = 0.85


def _per_side(v: Variables, table: dict, i: int) -> dict:
    """``table[point]`` (side → value) at instant i; the symmetric model's second half: the first half's,
    sides swapped."""
    j = int(v.grid.instant_points[i])
    if j in table:
        return table[j]
    mirrored = table[int(v.grid.instant_points[i - v.half])]
    return {"r": mirrored["l"], "l": mirrored["r"]}


def deviation_function(v: Variables, reference: Band, points: list[ContactPoint], mass_kg: float,
                       weight) -> PointFunction:
    """The dissertation's Jdev (5.28), joint angles and ground forces against ``reference``, as instant i's
    share, a point function of z = (y (9), the feet's f_x, f_z right then left (4), N, t_i, T, h1, h2, s):

        cost = Σ_k ((x_k − x̂_k)/σ_k)²·(h1 + h2)/2   at the cycle percentage 100·t_i/T

    (the periodic trapezoid rule); ``weight`` (of p) multiplies Σ cost in J."""
    z = ca.SX.sym("z", 17)
    y, ground, t, period, h1, h2 = z[0:9], z[9:13], z[13], z[14], z[15], z[16]
    angles = [*walker_joint_angles(y[2], y[3], y[4], y[5]), *walker_joint_angles(y[2], y[6], y[7], y[8])]
    x = ca.vertcat(*[angle * 180 / np.pi for angle in angles], ground / mass_kg)
    mean_at, sd_at = reference_curves(reference)
    pct = 100 * t / period
    means, sds = mean_at(pct), sd_at(pct)
    function = ca.Function("deviation", [z], [ca.sumsqr((x - means) / sds) * (h1 + h2) / 2], ["z"], ["cost"])
    feet_at = {p.j: p.feet for p in points}
    h1s, h2s = instant_steps(v)
    columns = []
    for i in range(len(v.grid.instant_points)):
        feet = _per_side(v, feet_at, i)
        columns.append(ca.vertcat(v.values["y"][i], feet["r"][0], feet["r"][1], feet["l"][0], feet["l"][1],
                                  v.times[i], v.period, h1s[i], h2s[i]))
    return PointFunction("deviation", function, ca.horzcat(*columns), weight)


def centre_of_pressure(v: Variables, points: list[ContactPoint], heel_to_mtp_m: float, weight_N: float,
                       sd_m: float) -> ca.SX:
    """∫(c − ĉ)²/σ² dt: from foot flat to the other foot's heel strike each foot's centre of pressure
    (its heel and MTP forces, the MTP moment not counted) against a progression from heel to MTP linear over
    :data:`COP_PROGRESSION_STANCE` of its stance; c, ĉ as moments per body weight ``weight_N``, m."""
    split_at = {p.j: p.split for p in points}
    strikes = {"r": 0.0, "l": ca.sum1(v.durations[:4])}
    stance = ca.sum1(v.durations[:6])
    rows = []
    for i, j in enumerate(v.grid.instant_points):
        phase, split = v.phases[int(j)], _per_side(v, split_at, i)
        row = ca.SX(0)
        for side, rolling in (("r", (2, 3, 4)), ("l", (6, 7, 8))):
            if phase in rolling:
                heel, mtp = split[side]  # heel 0 once it is off (phases 4, 8)
                progress = (v.times[i] - strikes[side]) / (COP_PROGRESSION_STANCE * stance)
                row = (mtp * heel_to_mtp_m - (heel + mtp) * heel_to_mtp_m * progress) / weight_N
        rows.append(row)
    return deviation(ca.vertcat(*rows), ca.DM.zeros(v.n_i, 1), ca.DM.ones(v.n_i, 1) * sd_m, v.times, v.period)


def trunk_rate(v: Variables, sd_deg_s: float) -> ca.SX:
    """∫(ẏ3/σ)² dt: the HAT's pitch rate (deg/s) against 0, a steady trunk."""
    rate = ca.vertcat(*[v.values["yd"][i][2] * 180 / np.pi for i in range(v.n_i)])
    return deviation(rate, ca.DM.zeros(v.n_i, 1), ca.DM.ones(v.n_i, 1) * sd_deg_s, v.times, v.period)


def tracking_extras(v: Variables, points: list[ContactPoint], settings, transcriber) -> ca.SX:
    """The opt-in tracking terms of ``settings`` (module docstring), added to Jdev."""
    model = transcriber.model
    extras = ca.SX(0)
    if settings.cop_sd_m > 0:
        extras += centre_of_pressure(v, points, transcriber.contact.heel_to_mtp_m,
                                     model.total_mass_kg * model.gravity_m_s2, settings.cop_sd_m)
    if settings.trunk_rate_sd_deg_s > 0:
        extras += trunk_rate(v, settings.trunk_rate_sd_deg_s)
    return extras


def cost_weights(v: Variables) -> tuple:
    """(w1/100, w2) of (5.29): the weights of Et and Jdev in J, with (w1, w2) the NLP's parameters."""
    return v.parameters[1] / 100.0, v.parameters[2]

