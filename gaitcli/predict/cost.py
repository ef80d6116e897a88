"""Muscle-state inversion on the control grid and the cost of a predicted gait (Diss. 5.2.6–5.2.7).

Inversion (5.25–5.26; as EID, 4.10–4.19): at the cycle's distinct control
instants (times t_j, s; the grid of ``grid.py``) the muscle forces F (N) give
the tendon length l_se(F) (2.20), its rate by the unequal-step differences of
the grid (5.2.6), fibre length and velocity (4.15, 4.17), the activation
from the force–length–velocity relation (4.18), its rate by the same
differences, and the excitation from (2.17) (the root of 4.3.3). Everything is
the muscle stage's one compiled model (:class:`gaitcli.muscles.hill.MuscleModel`),
called on numpy or CasADi arrays alike.

Cost (5.27–5.29), integrals by the trapezoid rule over the instants of one
periodic cycle (the last interval closes the cycle back to t_1 + T):

    Et   = (1/ΔS) Σ_i ∫ Ė_i dt                      J/m,  ΔS = L_r + L_l    (5.27)
    Jdev = Σ_k ∫ (x_k − x̂_k)² / σ_k² dt             s                      (5.28)
    J    = w1·Et/100 + w2·Jdev,  w1 + w2 = 2                               (5.29)
"""

from __future__ import annotations

from fractions import Fraction

import casadi as ca
import numpy as np

from gaitcli.errors import InputError, shown
from gaitcli.muscles.hill import MuscleModel
from gaitcli.predict.grid import periodic_derivative
from gaitcli.predict.splines import is_casadi

#: (5.29) weight set b) of 5.3.1, "realistic"
DEFAULT_WEIGHTS = (4.0 / 3.0, 2.0 / 3.0)


def check_weights(weights) -> tuple[float, float]:
    """(w1, w2) with w1 + w2 = 2 and both ≥ 0 (5.29), else an InputError naming ``--weights``. Each may be a
    fraction ("4/3"): 4/3 and 2/3 written as decimals differ from DEFAULT_WEIGHTS in the last bit, and the
    optimizer's path (and local optimum) is sensitive to that."""
    try:
        w1, w2 = (float(Fraction(w.strip())) if isinstance(w, str) else float(w) for w in weights)
    except (TypeError, ValueError, ZeroDivisionError):
        raise InputError(None, "--weights", f"got {shown(weights)} (expected two numbers W1,W2)") from None
    if not (np.isfinite(w1) and np.isfinite(w2) and w1 >= 0 and w2 >= 0 and abs(w1 + w2 - 2.0) < 1e-9):
        raise InputError(None, "--weights", f"got {w1:g},{w2:g} (expected two weights ≥ 0 that sum to 2, (5.29); "
                                            "e.g. 4/3,2/3)")
    return w1, w2


def trapezoid_periodic(values, times, period):
    """∫ over one cycle of samples ``values`` (I,) or (I, n) at the periodic ``times`` (I,), trapezoid rule."""
    if is_casadi(values, times, period):
        x = values if is_casadi(values) else ca.DM(np.asarray(values, float))
        t = times if is_casadi(times) else ca.DM(np.asarray(times, float))
        t = ca.vec(t)
        steps = ca.vertcat(t[1:] - t[:-1], t[0] + period - t[-1])
        nxt = ca.vertcat(x[1:, :], x[0, :])
        return ca.sum1(ca.repmat(steps, 1, x.shape[1]) * (x + nxt) / 2)
    x = np.asarray(values, float)
    t = np.asarray(times, float).ravel()
    steps = np.append(np.diff(t), t[0] + period - t[-1])
    nxt = np.roll(x, -1, axis=0)
    return np.tensordot(steps, (x + nxt) / 2, axes=(0, 0))


def invert_muscles(muscle: MuscleModel, force_N, length_m, velocity_m_s, times, period, *,
                   tendon_length_m=None) -> dict:
    """Activations and excitations from muscle forces on the periodic control instants (5.25–5.26).

    ``force_N``, ``length_m`` (l_m), ``velocity_m_s`` (v_m): (I, m) arrays (numpy or CasADi) at ``times``
    (I,); ``tendon_length_m`` l_se where known (from the tendon stretch: smooth where F = 0), else
    l_se(F) (2.20). Returns (I, m) arrays: ``l_se``, ``v_se``, ``l_ce``, ``v_ce``, ``f_ce``, ``a``,
    ``adot``, ``u``.
    """
    symbolic = is_casadi(force_N, length_m, velocity_m_s, times, period)

    def per_sample(function, *arrays):
        if not symbolic:
            return muscle.evaluate(function, *arrays)
        out = getattr(muscle, function)(*(a.T for a in arrays))
        return [o.T for o in out] if isinstance(out, (list, tuple)) else out.T

    force = force_N if symbolic else np.asarray(force_N, float)
    l_se = per_sample("tendon_length", force) if tendon_length_m is None else tendon_length_m
    v_se = periodic_derivative(l_se, times, period)
    l_ce, v_ce = per_sample("fibre_kinematics", l_se, v_se, length_m, velocity_m_s)
    a = per_sample("activation_from_force", force, v_se, length_m, velocity_m_s)
    adot = periodic_derivative(a, times, period)
    u = per_sample("excitation", a, adot)
    cos_pen = np.cos(muscle.params.pennation_rad)
    f_ce = force / (ca.repmat(ca.DM(cos_pen).T, force.shape[0], 1) if symbolic else cos_pen)
    return {"l_se": l_se, "v_se": v_se, "l_ce": l_ce, "v_ce": v_ce, "f_ce": f_ce, "a": a, "adot": adot, "u": u}


def cost_of_transport(metabolic_rate_W, times, period, stride_m):
    """Et (5.27), J/m: the cycle's metabolic energy of all muscles (``metabolic_rate_W`` (I, m)) per ΔS."""
    energy = trapezoid_periodic(metabolic_rate_W, times, period)
    return (ca.sum2(energy) if is_casadi(energy) else float(np.sum(energy))) / stride_m


def deviation(values, reference_mean, reference_sd, times, period):
    """Jdev (5.28), s: Σ_k ∫ (x_k − x̂_k)²/σ_k² dt of the (I, n_d) ``values`` against the reference's mean
    and SD at the same instants (SD > 0)."""
    if not is_casadi(reference_sd) and np.any(np.asarray(reference_sd) <= 0):
        raise InputError(None, "reference", "standard deviations must be > 0 (Jdev divides by them, 5.28)")
    squared = ((values - reference_mean) / reference_sd) ** 2
    total = trapezoid_periodic(squared, times, period)
    return ca.sum2(total) if is_casadi(total) else float(np.sum(total))


def objective(cost_of_transport_J_per_m, deviation_s, weights=DEFAULT_WEIGHTS):
    """J_SDO (5.29) = w1·Et/100 + w2·Jdev."""
    w1, w2 = check_weights(weights)
    return w1 * cost_of_transport_J_per_m / 100.0 + w2 * deviation_s
