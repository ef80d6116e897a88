"""The settings of one prediction: what shapes the problem (tolerances, opt-in terms) and how IPOPT solves it."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from gaitcli.predict.cost import DEFAULT_WEIGHTS

#: the status of a solve stopped by its time limit (PredictConfig.time_limit_s)
TIME_LIMIT_STATUS = "Time_Limit_Reached"


@dataclass(frozen=True)
class PredictSettings:
    """The settings of one prediction (defaults: the dissertation's 5.2.10 and 5.3.1, and our stated choices)."""

    speed_m_s: float = 1.1275
    weights: tuple[float, float] = DEFAULT_WEIGHTS
    moment_tolerance_Nm: float = 2.0
    contact_tolerance_m: float = 0.002
    friction_coefficient: float = 0.8
    clearance_m: float = 0.0
    mtp_moment_Nm: tuple[float, float] = (-10.0, 0.0)
    smoothing: float = 1e-2
    max_iterations: int = 3000
    window_reach: int = 3  # segments either side of its own that an instant may move to within one solve
    tolerance: float = 1e-6
    # IPOPT's "acceptable" stop (acceptable_tol, acceptable_obj_change_tol, acceptable_iter): without it the full
    # model's tail creeps on at relative changes of J far below what the outputs show
    acceptable_tolerance: float = 1e-4
    acceptable_objective_change: float = 1e-6
    acceptable_iterations: int = 10
    print_level: int = 0
    #: the ankle angles y (rad; y < 0 dorsiflexion) over which the optimal prosthesis's τ_s must decrease,
    #: sampled at ``monotone_samples`` angles: −25° … +10° (Table A.8's 1.68 m/s c, d turn beyond +10°)
    monotone_range_rad: tuple[float, float] = (float(np.radians(-25.0)), float(np.radians(10.0)))
    monotone_samples: int = 71
    #: > 0: every step this long, m (a walk at a chosen stride, e.g. the synthetic trials'); 0: free in STEP_RANGE_M
    step_m: float = 0.0
    #: (low, high): each step within these, m (5.44's "reasonable step lengths": the speed's reference group's
    #: stride ± 1 SD, halved; ``speed_reference.py``); None: the box's ``layout.STEP_RANGE_M``
    step_range_m: tuple[float, float] | None = None
    #: > 0: Jdev (5.28) also tracks the HAT's pitch rate ẏ3 against 0 with this SD, deg/s (a steady trunk, e.g.
    #: the synthetic walk's); 0: the dissertation's Jdev
    trunk_rate_sd_deg_s: float = 0.0
    #: > 0: Jdev (5.28) also tracks, from foot flat to the other foot's heel strike, each foot's centre of
    #: pressure (from its heel and MTP forces; the MTP moment not counted) against a heel-to-MTP progression
    #: linear over 85 % of its stance, with this SD, m; 0: the dissertation's Jdev
    cop_sd_m: float = 0.0
    #: > 0: the hip moment of a leg in swing (phases 7–8 right, 3–4 left) stays within ± this, N·m/kg, at every
    #: instant (a typical adult's swing, e.g. the synthetic walk's); 0: unbounded, as in the dissertation
    swing_hip_moment_Nm_per_kg: float = 0.0
    #: > 0: the hip moments stay within ± this, N·m/kg, at every instant; 0: unbounded, as in the dissertation
    hip_moment_Nm_per_kg: float = 0.0
    #: each foot's heel rocker (heel strike to the forefoot's contact, HS→TC) lasts at least this % of the cycle;
    #: 0: free, as in the dissertation (whose durations are all free). 7 %: the earliest foot flat of 9 stances
    #: of 5 real level-walking trials (mean 9.2 ± 1.8 %, benchmarks/survey_foot_events.py); free, the optimum
    #: lands the forefoot at 4.7 % and carries the body on it (no knee extensor moment, vasti silent)
    foot_flat_min_pct: float = 7.0

    def parameter_values(self) -> np.ndarray:
        """p = (v, w1, w2): the NLP's parameters (the speed (5.43) and the weights (5.29))."""
        return np.array([self.speed_m_s, *self.weights], float)

    def structure(self) -> PredictSettings:
        """These settings without what does not shape the NLP: the parameters (speed, weights) and IPOPT's
        stopping rules. Two settings of one structure build the same problem (the NLP cache's key)."""
        return dataclasses.replace(self, speed_m_s=PredictSettings.speed_m_s, weights=PredictSettings.weights,
                                   max_iterations=0, tolerance=0.0, acceptable_tolerance=0.0,
                                   acceptable_objective_change=0.0, acceptable_iterations=0, print_level=0)
