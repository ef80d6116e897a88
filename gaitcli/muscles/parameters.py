"""Muscle and joint parameters of the 2-D lower-limb model (Diss. Table A.1, 4.5.1).

All numbers come from the dissertation's Appendix A.1 or from the literature it
cites without printing the values; docs/model_constants.md §5–§11 gives each
source and the readings of the printed formulas.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from gaitcli.core.validate import one_of

#: the eight muscle groups of Fig. 4.5a, in Table A.1 order
MUSCLE_NAMES = ("iliopsoas", "rectus_femoris", "glutei", "hamstrings", "vasti",
                "gastrocnemius", "tibialis_anterior", "soleus")
MUSCLE_ABBREVIATIONS = ("Ilio", "RF", "Glu", "Ham", "Vas", "Gas", "TA", "Sol")

#: Diss. Table A.1: ft [%], l_opt [m], width, F_max [N], l_slack [m], alpha_p [deg],
#: l_m0 [m], r_a [m], r_k [m], r_h [m]
_TABLE_A1 = np.array([
    # ft   l_opt  width  F_max  l_slack alpha_p l_m0   r_a     r_k     r_h
    [50, 0.102, 1.298, 821, 0.142, 7.5, 0.248, 0.0, 0.0, -0.050],   # Ilio
    [65, 0.081, 1.443, 663, 0.398, 5.0, 0.474, 0.0, 0.050, -0.034],  # RF
    [45, 0.200, 0.625, 1705, 0.157, 3.0, 0.271, 0.0, 0.0, 0.062],    # Glu
    [35, 0.104, 1.197, 1770, 0.334, 7.5, 0.383, 0.0, -0.034, 0.072],  # Ham
    [50, 0.093, 0.627, 7403, 0.223, 4.4, 0.271, 0.0, 0.043, 0.0],    # Vas
    [50, 0.055, 0.888, 1639, 0.420, 14.3, 0.404, 0.053, -0.020, 0.0],  # Gas
    [25, 0.082, 0.442, 1528, 0.317, 6.0, 0.464, -0.037, 0.0, 0.0],   # TA
    [20, 0.055, 1.039, 3883, 0.245, 23.6, 0.201, 0.053, 0.0, 0.0],   # Sol
])

METABOLIC_MODELS = ("umberger2003", "umberger2010")


@dataclass(frozen=True)
class MuscleParameters:
    """Hill-type muscle parameters, one array entry per muscle group (SI units).

    Per muscle (Table A.1): ``fast_twitch_pct`` ft, ``optimal_fibre_length_m``
    l_opt, ``width`` of the force–length parabola, ``max_isometric_force_N``,
    ``tendon_slack_length_m``, ``pennation_rad`` α_p and the path constants of
    (A.9) ``neutral_length_m`` l_m0, ``ankle_arm_m`` r_a, ``knee_arm_m`` r_k,
    ``hip_arm_m`` r_h (signs as in Table A.1, read as docs/model_constants.md §6).

    Model constants: tendon strain at F_max ε0 (2.19), force–velocity A_r,
    B_r [l_opt/s], f_asympt, fac and slope factor (A.3–A.8, §8), the
    activation time constants (A.1–A.2), the energetics constants (A.12–A.21,
    §9) and ``metabolic_model`` ("umberger2003" or "umberger2010").
    """

    names: tuple
    fast_twitch_pct: np.ndarray
    optimal_fibre_length_m: np.ndarray
    width: np.ndarray
    max_isometric_force_N: np.ndarray
    tendon_slack_length_m: np.ndarray
    pennation_rad: np.ndarray
    neutral_length_m: np.ndarray
    ankle_arm_m: np.ndarray
    knee_arm_m: np.ndarray
    hip_arm_m: np.ndarray
    tendon_strain_at_max_force: float = 0.04  # ε0 (2.19)
    fv_a_rel: float = 0.41  # A_r (A.3)
    fv_b_rel_per_s: float = 5.2  # B_r in l_opt/s (A.3)
    eccentric_asymptote: float = 1.5  # f_asympt (A.6)
    fv_fac: float = 1.0  # fac (A.3, A.7), the dissertation sets fac = 1
    slope_factor: float = 1.0  # (A.7), the dissertation sets 1 instead of 2
    activation_ms: tuple = (80.0, 0.47)  # A_a1, A_a2 (A.1): τ_act = A_a1 − A_a2·ft
    deactivation_ms: tuple = (90.0, 0.56)  # A_d1, A_d2 (A.2)
    density_kg_m3: float = 1059.7  # ρ (A.13)
    specific_tension_Pa: float = 0.25e6  # σ (A.13)
    heat_scale: float = 1.5  # S (A.15): 1.5 aerobic
    max_fast_twitch_velocity: float = 12.0  # ṽ_max,FT in l_opt/s (A.19)
    heat_floor_W_per_kg: float = 1.0  # floor of the total specific heat rate
    shortening_heat_cap_W_per_kg: float = 100.0  # cap of −α_ST·ṽ (docs/model_constants.md §9)
    metabolic_model: str = "umberger2003"
    notes: tuple = field(default=())

    def __post_init__(self):
        one_of(self.metabolic_model, METABOLIC_MODELS, where="metabolic_model")

    @property
    def count(self) -> int:
        return len(self.names)

    @property
    def activation_time_s(self) -> np.ndarray:
        """τ_act = A_a1 − A_a2·ft (A.1), in s."""
        return (self.activation_ms[0] - self.activation_ms[1] * self.fast_twitch_pct) / 1000.0

    @property
    def deactivation_time_s(self) -> np.ndarray:
        """τ_deact = A_d1 − A_d2·ft (A.2), in s."""
        return (self.deactivation_ms[0] - self.deactivation_ms[1] * self.fast_twitch_pct) / 1000.0

    @property
    def activation_t1_per_s(self) -> np.ndarray:
        """t1 = 1/τ_act − 1/τ_deact of (2.17), 1/s (the printed 1/(ta − t2) is a typo: docs/model_constants.md §7)."""
        return 1.0 / self.activation_time_s - 1.0 / self.deactivation_time_s

    @property
    def activation_t2_per_s(self) -> np.ndarray:
        """t2 = 1/τ_deact of (2.17)."""
        return 1.0 / self.deactivation_time_s

    @property
    def pcsa_m2(self) -> np.ndarray:
        """Physiological cross-sectional area F_max/σ (A.13), in m²."""
        return self.max_isometric_force_N / self.specific_tension_Pa

    @property
    def muscle_mass_kg(self) -> np.ndarray:
        """m = ρ·l_opt·F_max/σ (A.13)."""
        return self.density_kg_m3 * self.optimal_fibre_length_m * self.pcsa_m2

    @property
    def tendon_stiffness_N_per_m2(self) -> np.ndarray:
        """k_T = F_max/(ε0·l_slack)² of (2.19)."""
        return self.max_isometric_force_N / (self.tendon_strain_at_max_force * self.tendon_slack_length_m) ** 2

    def with_options(self, **changes) -> "MuscleParameters":
        """A copy with some constants changed (e.g. ``metabolic_model="umberger2010"``)."""
        return replace(self, **changes)


def table_a1(**changes) -> MuscleParameters:
    """The dissertation's Table A.1 with the constants of A.1 (docs/model_constants.md §5–§9)."""
    t = _TABLE_A1
    params = MuscleParameters(
        names=MUSCLE_NAMES,
        fast_twitch_pct=t[:, 0].copy(),
        optimal_fibre_length_m=t[:, 1].copy(),
        width=t[:, 2].copy(),
        max_isometric_force_N=t[:, 3].copy(),
        tendon_slack_length_m=t[:, 4].copy(),
        pennation_rad=np.deg2rad(t[:, 5]),
        neutral_length_m=t[:, 6].copy(),
        ankle_arm_m=t[:, 7].copy(),
        knee_arm_m=t[:, 8].copy(),
        hip_arm_m=t[:, 9].copy(),
        notes=("Table A.1 (Gerritsen et al. 1998, Menegaldo et al.); readings of docs/model_constants.md §6–§9",),
    )
    return params.with_options(**changes) if changes else params


@dataclass(frozen=True)
class JointParameters:
    """Passive joint properties of the limb model (4.5.1).

    ``hip_damping_Nms_per_rad`` and ``knee_damping_Nms_per_rad`` are the linear
    viscous dampings the dissertation takes from Stein et al. (1996) without
    printing them; the default 0.01 N·m·s/rad is the gait2d model family's joint
    damping (docs/model_constants.md §11). Set the pendulum-test values here when
    they are known. ``passive_moments`` switches the Riener & Edrich (1999) moments
    on or off; ``prosthetic_ankle`` removes what spans the intact ankle (5.3.3): no
    ankle moment M_A, and the knee moment M_K evaluated at a neutral ankle
    (docs/model_constants.md §10).
    """

    hip_damping_Nms_per_rad: float = 0.01
    knee_damping_Nms_per_rad: float = 0.01
    passive_moments: bool = True
    prosthetic_ankle: bool = False
