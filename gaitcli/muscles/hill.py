"""Hill-type muscle model of the 2-D lower limb, written once in CasADi (2.17–2.25, A.1–A.21).

Every formula is built once as a CasADi expression and wrapped in a
``casadi.Function``; the optimisation problems call these Functions
symbolically and outputs/tests evaluate the very same Functions numerically
(``evaluate``). All Functions take column vectors with one entry per muscle;
called with ``m × n`` matrices they evaluate ``n`` samples at once.

The muscle path takes the sagittal joint angles ``ψ = (hip flexion relative to
the pelvis/HAT, knee flexion, ankle dorsiflexion)`` in rad, whatever model
supplies them (the limb of ``limb.py``, with an upright trunk, has ψ = q); the
conversion to the angles of the muscle path (A.9) happens only in
:func:`gaitcli.kinematics.conventions.muscle_path_angles`. Moment arms are
joint moments per newton, conjugate to ψ.

Where the printed formulas are ambiguous or mistyped — t1 of (2.17), the force–length
clip, fac and slope factor 1, v_ce under constant pennation (4.15), the Umberger heat
rate's cap and floor — the readings and their reasons are docs/model_constants.md §7–§9.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gaitcli.core.numerics import finite_difference_matrix
from gaitcli.kinematics.conventions import muscle_path_angles

from .evaluation import evaluate
from .parameters import MuscleParameters, table_a1

#: number of sagittal joint angles the muscles span (hip, knee, ankle)
NQ = 3


def path_angles(joint_angles):
    """Joint angles ψ = (hip flexion, knee flexion, ankle dorsiflexion) → (α, β, γ) of the muscle path (A.9).

    α hip extension, β knee flexion, γ ankle plantarflexion (docs/model_constants.md §6), through
    :func:`gaitcli.kinematics.conventions.muscle_path_angles`.
    """
    return muscle_path_angles(joint_angles[0], joint_angles[1], joint_angles[2])


def _smooth_max(x, y, width: float):
    """max(x, y); for width > 0 the smooth ½(x + y + √((x − y)² + width²))."""
    if width == 0:
        return ca.fmax(x, y)
    return 0.5 * (x + y + ca.sqrt((x - y) ** 2 + width ** 2))


def _smooth_min(x, y, width: float):
    """min(x, y); for width > 0 the smooth ½(x + y − √((x − y)² + width²))."""
    if width == 0:
        return ca.fmin(x, y)
    return 0.5 * (x + y - ca.sqrt((x - y) ** 2 + width ** 2))


def _step(x, width: float):
    """1 for x > 0 else 0; for width > 0 the smooth ½(1 + tanh(x/width))."""
    if width == 0:
        return ca.if_else(x > 0, 1, 0)
    return 0.5 * (1 + ca.tanh(x / width))


def _col(values) -> ca.DM:
    return ca.DM(np.asarray(values, dtype=float).reshape(-1, 1))


class MuscleModel:
    """The compiled CasADi Functions of the muscle model for one parameter set.

    Functions (vectors have one entry per muscle; ``q``/``qd`` are the 3 joint angles
    ψ = (hip flexion, knee flexion, ankle dorsiflexion) and their rates, see the module doc):

    - ``activation_rate(u, a) → ȧ`` (2.17)
    - ``excitation(a, ȧ) → u`` root rule of 4.3.3 (4.19)
    - ``force_length(l_ce) → f_iso`` (A.4), l_ce in m
    - ``flv(l_ce, v_ce) → g`` = f_ce/(a·F_max) (A.3–A.8)
    - ``fibre_force(a, l_ce, v_ce) → f_ce`` [N] (2.18)
    - ``tendon_force(l_se) → F`` (2.19); ``tendon_length(F) → l_se`` (2.20);
      ``tendon_velocity(F, Ḟ) → v_se`` (2.21); ``stretch_tendon(ŝ) → (F, l_se)``
      (2.19) in terms of the normalised tendon stretch, the force variable of the optimisations
    - ``length(q) → l_m`` (A.9); ``moment_arms(q) → R`` (3 × m, A.11: generalized
      moment per newton, positive in the direction of ψ); ``velocity(q, qd) → v_m``
    - ``fibre_kinematics(l_se, v_se, l_m, v_m) → (l_ce, v_ce)`` (4.15, 4.17)
    - ``activation_from_force(F, v_se, l_m, v_m) → a`` (4.13–4.18); ``activation_from_stretch(ŝ, v_se, l_m,
      v_m) → a`` the same with the tendon from ŝ, whose derivatives exist at F = 0 (√(F/k_T) has none)
    - ``contraction_rate(a, s, l_m, v_m) → (ṡ, F, l_ce, v_ce)`` forward
      contraction dynamics (2.20–2.25) with the tendon stretch s = l_se − l_slack as state
    - ``metabolic_rate(u, a, l_ce, v_ce, f_ce) → Ė`` [W] (A.12–A.21), and
      ``heat_rate`` [W/kg], ``work_rate`` [W] of the same formulas
    """

    #: the forward contraction dynamics needs a > 0; smaller activations are
    #: treated as this value there (numerical guard, forward direction only)
    FORWARD_MIN_ACTIVATION = 1e-6
    #: the forward contraction dynamics limits the normalised CE force to
    #: f_iso·(f_asympt − this) so that the lengthening velocity stays finite
    FORWARD_ASYMPTOTE_MARGIN = 0.01

    def __init__(self, params: MuscleParameters | None = None):
        self.params = p = params if params is not None else table_a1()
        self.names = tuple(p.names)
        m = self.m = p.count
        self._l_opt = _col(p.optimal_fibre_length_m)
        self._width = _col(p.width)
        self._f_max = _col(p.max_isometric_force_N)
        self._l_slack = _col(p.tendon_slack_length_m)
        self._cos_pen = _col(np.cos(p.pennation_rad))
        self._k_t = _col(p.tendon_stiffness_N_per_m2)
        self._t1 = _col(p.activation_t1_per_s)
        self._t2 = _col(p.activation_t2_per_s)
        self._ft = _col(p.fast_twitch_pct)
        self._mass = _col(p.muscle_mass_kg)
        self._smoothed = {}

        sym = ca.SX.sym
        u, a, adot = sym("u", m), sym("a", m), sym("adot", m)
        l_ce, v_ce, f_ce = sym("l_ce", m), sym("v_ce", m), sym("f_ce", m)
        l_se, v_se, force, force_dot = sym("l_se", m), sym("v_se", m), sym("F", m), sym("Fdot", m)
        l_m, v_m, stretch = sym("l_m", m), sym("v_m", m), sym("s", m)
        q, qd = sym("q", NQ), sym("qd", NQ)

        F = ca.Function
        self.activation_rate = F("activation_rate", [u, a], [self._activation_rate(u, a)],
                                 ["u", "a"], ["adot"])
        self.excitation = F("excitation", [a, adot], [self._excitation(a, adot)], ["a", "adot"], ["u"])
        self.slowest_activation_rate = F("slowest_activation_rate", [a], [self._slowest_activation_rate(a)],
                                         ["a"], ["adot"])
        self.force_length = F("force_length", [l_ce], [self._force_length(l_ce)], ["l_ce"], ["f_iso"])
        self.flv = F("flv", [l_ce, v_ce], [self._flv(l_ce, v_ce)], ["l_ce", "v_ce"], ["g"])
        self.fibre_force = F("fibre_force", [a, l_ce, v_ce], [a * self._f_max * self._flv(l_ce, v_ce)],
                             ["a", "l_ce", "v_ce"], ["f_ce"])
        self.tendon_force = F("tendon_force", [l_se], [self._tendon_force(l_se)], ["l_se"], ["F"])
        self.tendon_length = F("tendon_length", [force], [self._tendon_length(force)], ["F"], ["l_se"])
        self.stretch_tendon = F("stretch_tendon", [stretch], list(self._stretch_tendon(stretch)),
                                ["s_norm"], ["F", "l_se"])
        self.tendon_velocity = F("tendon_velocity", [force, force_dot],
                                 [force_dot / (2 * ca.sqrt(self._k_t * force))], ["F", "Fdot"], ["v_se"])
        lm_expr = self._length(q)
        arms = -ca.jacobian(lm_expr, q).T  # (A.11)
        self.length = F("length", [q], [lm_expr], ["q"], ["l_m"])
        self.moment_arms = F("moment_arms", [q], [arms], ["q"], ["R"])
        self.velocity = F("velocity", [q, qd], [ca.jtimes(lm_expr, q, qd)], ["q", "qd"], ["v_m"])
        lce_expr, vce_expr = self._fibre_kinematics(l_se, v_se, l_m, v_m)
        self.fibre_kinematics = F("fibre_kinematics", [l_se, v_se, l_m, v_m], [lce_expr, vce_expr],
                                  ["l_se", "v_se", "l_m", "v_m"], ["l_ce", "v_ce"])
        lce_f, vce_f = self._fibre_kinematics(self._tendon_length(force), v_se, l_m, v_m)
        a_expr = (force / self._cos_pen) / (self._f_max * self._flv(lce_f, vce_f))  # (4.16), (4.18)
        self.activation_from_force = F("activation_from_force", [force, v_se, l_m, v_m], [a_expr],
                                       ["F", "v_se", "l_m", "v_m"], ["a"])
        stretch_force, stretch_length = self._stretch_tendon(stretch)
        lce_s, vce_s = self._fibre_kinematics(stretch_length, v_se, l_m, v_m)
        self.activation_from_stretch = F(
            "activation_from_stretch", [stretch, v_se, l_m, v_m],
            [(stretch_force / self._cos_pen) / (self._f_max * self._flv(lce_s, vce_s))],
            ["s_norm", "v_se", "l_m", "v_m"], ["a"])
        self.contraction_rate = F("contraction_rate", [a, stretch, l_m, v_m],
                                  list(self._contraction_rate(a, stretch, l_m, v_m)),
                                  ["a", "s", "l_m", "v_m"], ["sdot", "F", "l_ce", "v_ce"])
        heat, work = self._heat_rate(u, a, l_ce, v_ce), self._work_rate(v_ce, f_ce)
        self.heat_rate = F("heat_rate", [u, a, l_ce, v_ce], [heat], ["u", "a", "l_ce", "v_ce"], ["hdot"])
        self.work_rate = F("work_rate", [v_ce, f_ce], [work], ["v_ce", "f_ce"], ["wdot"])
        self.metabolic_rate = F("metabolic_rate", [u, a, l_ce, v_ce, f_ce], [work + self._mass * heat],
                                ["u", "a", "l_ce", "v_ce", "f_ce"], ["edot"])

    # ----------------------------------------------------------------- formulas
    def _activation_rate(self, u, a):
        """ȧ = (u − a)(t1·u + t2) (2.17; t1, t2 as docs/model_constants.md §7), 1/s."""
        return (u - a) * (self._t1 * u + self._t2)

    def _excitation(self, a, adot):
        """Root of t1·u² + (t2 − t1·a)·u − (t2·a + ȧ) = 0 nearest to a (4.3.3).

        ȧ(u) rises monotonically for u > (a − t2/t1)/2 (t2/t1 ≈ 10), so the larger
        root is the one in [0, 1] whenever one is, and the one nearest to a
        otherwise (the other root lies near −t2/t1). Written as 2c/(b + √D) to
        avoid cancellation; NaN where no real root exists.
        """
        b = self._t2 - self._t1 * a
        c = self._t2 * a + adot
        return 2 * c / (b + ca.sqrt(b * b + 4 * self._t1 * c))

    def _slowest_activation_rate(self, a):
        """ȧ 99 % of the way from u = 0 (ȧ = −t2·a) to where 4.3.3 has no real root any more (its discriminant
        (t2 − t1·a)² + 4·t1·(t2·a + ȧ) = 0, at u = −(t2 − t1·a)/(2·t1) ≈ −5), 1/s: a floor on ȧ that keeps
        :meth:`_excitation` real and smooth on and near the feasible ȧ ≥ −t2·a (a floor at −t2·a itself
        would put a kink on the bound u ≥ 0)."""
        return -self._t2 * a - 0.99 * (self._t2 - self._t1 * a) ** 2 / (4 * self._t1)

    def _force_length(self, l_ce):
        """f_iso = −(l/l_opt)²/w² + 2(l/l_opt)/w² − 1/w² + 1, clipped at ≥ 0 (A.4)."""
        x = l_ce / self._l_opt
        w2 = self._width ** 2
        return ca.fmax(-x * x / w2 + 2 * x / w2 - 1 / w2 + 1, 0)

    def _fv(self, f_iso, v_norm):
        """f_ce/(a·F_max) from f_iso and ṽ = v_ce/l_opt (A.3, A.5–A.8)."""
        p = self.params
        ar, br, fac, sf = p.fv_a_rel, p.fv_b_rel_per_s, p.fv_fac, p.slope_factor
        w = br - v_norm / fac
        concentric = (br * (f_iso + ar) - ar * w) / w  # (A.3) / a
        b2 = -f_iso * p.eccentric_asymptote  # (A.6)
        b1 = fac * br * (f_iso + b2) ** 2 / ((f_iso + ar) * sf)  # (A.7)
        b3 = fac * br * (f_iso + b2) / ((f_iso + ar) * sf)  # (A.8) = b1/(f_iso + b2)
        eccentric = ca.if_else(f_iso > 0, (b1 - b2 * (b3 - v_norm)) / (b3 - v_norm), 0)  # (A.5) / a
        return ca.if_else(v_norm < 0, concentric, eccentric)

    def _flv(self, l_ce, v_ce):
        return self._fv(self._force_length(l_ce), v_ce / self._l_opt)

    def _tendon_force(self, l_se):
        """F = k_T·(l_se − l_slack)² for l_se ≥ l_slack, else 0 (2.19)."""
        return self._k_t * ca.fmax(l_se - self._l_slack, 0) ** 2

    def _tendon_length(self, force):
        """l_se = l_slack + √(F/k_T), the inverse of (2.19) for F ≥ 0 (2.20, 4.13)."""
        return self._l_slack + ca.sqrt(force / self._k_t)

    def _stretch_tendon(self, s_norm):
        """(2.19) in terms of the normalised stretch ŝ = (l_se − l_slack)/(ε0·l_slack) ≥ 0.

        F = F_max·ŝ² and l_se = l_slack·(1 + ε0·ŝ). The optimisations use ŝ as the
        force variable: the map is one-to-one for F ≥ 0 and, unlike l_se(F) =
        l_slack + √(F/k_T), smooth at F = 0.
        """
        eps0 = self.params.tendon_strain_at_max_force
        return self._f_max * s_norm ** 2, self._l_slack * (1 + eps0 * s_norm)

    def _length(self, q):
        """l_m = l_m0 + r_a(π/2 − γ) + r_k·β − r_h·α (A.9), angles from :func:`path_angles`."""
        p = self.params
        alpha, beta, gamma = path_angles(q)
        return (_col(p.neutral_length_m) + _col(p.ankle_arm_m) * (np.pi / 2 - gamma)
                + _col(p.knee_arm_m) * beta - _col(p.hip_arm_m) * alpha)

    def _fibre_kinematics(self, l_se, v_se, l_m, v_m):
        """l_ce = (l_m − l_se)/cos α_p (4.17); v_ce its time derivative (4.15, see module doc)."""
        return (l_m - l_se) / self._cos_pen, (v_m - v_se) / self._cos_pen

    def _contraction_rate(self, a, stretch, l_m, v_m):
        """Forward contraction dynamics ṡ = v_se(a, s, l_m, v_m) (2.20–2.25).

        s = l_se − l_slack (negative when the tendon is slack). The CE velocity
        solves f_ce = a·F_max·g(l_ce, v_ce) for v_ce (the hyperbolas (A.3), (A.5)
        inverted in closed form). Guards: a is floored at
        ``FORWARD_MIN_ACTIVATION`` and the normalised force at
        f_iso·(f_asympt − ``FORWARD_ASYMPTOTE_MARGIN``), beyond which (A.5) has
        no finite solution.
        """
        p = self.params
        ar, br, fac, sf = p.fv_a_rel, p.fv_b_rel_per_s, p.fv_fac, p.slope_factor
        force = self._tendon_force(self._l_slack + stretch)
        l_ce = (l_m - self._l_slack - stretch) / self._cos_pen  # (4.17)
        f_ce = force / self._cos_pen  # (4.16)
        f_iso = self._force_length(l_ce)
        h = f_ce / (self._f_max * ca.fmax(a, self.FORWARD_MIN_ACTIVATION))
        h = ca.fmin(h, f_iso * (p.eccentric_asymptote - self.FORWARD_ASYMPTOTE_MARGIN))
        v_con = fac * br * (h - f_iso) / (h + ar)  # (A.3) solved for ṽ
        b2 = -f_iso * p.eccentric_asymptote
        b1 = fac * br * (f_iso + b2) ** 2 / ((f_iso + ar) * sf)
        b3 = fac * br * (f_iso + b2) / ((f_iso + ar) * sf)
        v_ecc = ca.if_else(f_iso > 0, b3 - b1 / (h + b2), 0)  # (A.5) solved for ṽ
        v_ce = ca.if_else(h <= f_iso, v_con, v_ecc) * self._l_opt
        v_se = v_m - v_ce * self._cos_pen  # (2.22) with v_ce = (v_m − v_se)/cos α_p
        return v_se, force, l_ce, v_ce

    def _heat_rate(self, u, a, l_ce, v_ce, smoothing: float = 0.0):
        """Specific heat rate ḣ [W/kg] of Umberger et al. (2003) (A.14–A.21; docs/model_constants.md §9).

        ``smoothing`` = 0 gives the exact model. A positive ε replaces each of
        its kinks (the u > a switch (A.17), l_ce ≷ l_opt (A.15/A.16), ṽ ≷ 0, the
        100 W/kg cap and the 1 W/kg floor) by a smooth blend of width ε
        (activation, l_ce/l_opt − 1 and ṽ in l_opt/s) or 10·ε W/kg (cap, floor);
        used only as the optimiser's objective (see ``eid.py``).
        """
        p = self.params
        eps = float(smoothing)
        s = p.heat_scale
        ft = self._ft / 100.0
        v_norm = v_ce / self._l_opt
        f_iso = self._force_length(l_ce)
        a_m = (u + a) / 2 + _smooth_max(u - a, 0, eps) / 2  # (A.17): u if u > a else (u + a)/2
        h_am = 1.28 * self._ft + 25.0  # (A.18)
        alpha_st = 250.0 / p.max_fast_twitch_velocity  # (A.19)
        alpha_ft = 153.0 / p.max_fast_twitch_velocity  # (A.20)
        alpha_l = (4.0 if p.metabolic_model == "umberger2003" else 0.3) * alpha_st  # (A.21) / 2010
        longer = _step(l_ce / self._l_opt - 1, eps)
        scale = longer * f_iso + (1 - longer)  # f_iso factors of (A.16)
        # a_m^0.6 has an infinite slope at 0: evaluated at max(a_m, 1e-8) where a_m > 0 (values within
        # 2e-5·h_am·S W/kg of the formula's below a_m = 1e-8, slope ≤ 950) and 0 below, so that its derivative
        # is finite at a_m = 0 too (if_else differentiates both branches)
        a_m_06 = ca.if_else(a_m > 0, ca.fmax(a_m, 1e-8) ** 0.6, 0)
        maintenance = (longer * (0.4 + 0.6 * f_iso) + (1 - longer)) * h_am * a_m_06 * s
        shortening = (_smooth_min(-alpha_st * v_norm * scale, p.shortening_heat_cap_W_per_kg, 10 * eps)
                      * (1 - ft) - alpha_ft * v_norm * scale * ft) * a_m ** 2 * s
        lengthening = alpha_l * v_norm * scale * a_m * s
        lengthens = _step(v_norm, eps)
        total = maintenance + (1 - lengthens) * shortening + lengthens * lengthening  # (A.15), (A.16)
        return _smooth_max(total, p.heat_floor_W_per_kg, 10 * eps)

    def _work_rate(self, v_ce, f_ce, smoothing: float = 0.0):
        """CE power Ẇ = −f_ce·v_ce (2.26); 2010 variant: negative work excluded."""
        work = -f_ce * v_ce
        if self.params.metabolic_model == "umberger2003":
            return work
        return _smooth_max(work, 0, 10 * float(smoothing))

    def smoothed_metabolic_rate(self, smoothing: float) -> ca.Function:
        """``metabolic_rate`` with the kinks smoothed over ``smoothing`` (0: exact), cached."""
        if smoothing == 0:
            return self.metabolic_rate
        cache = self._smoothed
        if smoothing not in cache:
            m = self.m
            u, a, l_ce, v_ce, f_ce = (ca.SX.sym(n, m) for n in ("u", "a", "l_ce", "v_ce", "f_ce"))
            rate = (self._work_rate(v_ce, f_ce, smoothing)
                    + self._mass * self._heat_rate(u, a, l_ce, v_ce, smoothing))
            cache[smoothing] = ca.Function("metabolic_rate_smooth", [u, a, l_ce, v_ce, f_ce], [rate],
                                           ["u", "a", "l_ce", "v_ce", "f_ce"], ["edot"])
        return cache[smoothing]

    # ------------------------------------------------------------ evaluation
    def evaluate(self, name: str, *args) -> np.ndarray | tuple:
        """Evaluate Function ``name`` on arrays shaped (n, k) or (k,) (see ``evaluation.evaluate``).

        ``moment_arms`` returns (n, 3, m).
        """
        return evaluate(getattr(self, name), *args)

    def invert_forces(self, force_N, l_m, v_m, dt: float, scheme: str) -> dict:
        """Force history → fibre state → activation → excitation (4.10–4.19, 4.31–4.34).

        ``force_N``, ``l_m``, ``v_m`` shaped (n, m). The tendon velocity is the
        finite difference (``scheme``, see :func:`finite_difference_matrix`) of
        the tendon length l_se(F) (4.13), which equals v_se(Ḟ) (4.14) up to the
        truncation error without dividing by the tendon stiffness, which vanishes
        at F = 0. Forces below zero (an optimiser's bound tolerance) count as 0.
        Returns a dict of (n, m) arrays: l_se, v_se, l_ce, v_ce, f_ce, a, adot, u.
        """
        force = np.maximum(np.asarray(force_N, float), 0.0)
        d = finite_difference_matrix(force.shape[0], dt, scheme)
        l_se = self.evaluate("tendon_length", force)
        v_se = d @ l_se
        l_ce, v_ce = self.evaluate("fibre_kinematics", l_se, v_se, l_m, v_m)
        a = self.evaluate("activation_from_force", force, v_se, l_m, v_m)
        adot = d @ a
        u = self.evaluate("excitation", a, adot)
        f_ce = force / np.cos(self.params.pennation_rad)
        return {"l_se": l_se, "v_se": v_se, "l_ce": l_ce, "v_ce": v_ce, "f_ce": f_ce,
                "a": a, "adot": adot, "u": u}
