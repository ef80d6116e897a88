"""The predict stage: a predictive simulation of one gait cycle by state dynamic optimization (Diss. 5.2–5.3).

``run_predict(cfg, params=…, reference=…)`` builds the lifted NLP (``nlp.py``) for the subject's
walking model, solves it (``solve.py``) from the default initial guess (or a warm start) and returns a
:class:`PredictResult`: the gait transcribed from the solution's design vector by the independent
numeric transcription (``problem.py``; λ by the pseudoinverse (5.30), the exact heat-rate model),
its cost parts and every constraint group's largest violation. The CLI writes it and maps
``converged=False`` to exit code 3.
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.core.validate import number_pair, parameter
from gaitcli.errors import InputError
from gaitcli.kinematics.conventions import (
    walker_moments_to_clinical,
    walker_to_clinical,
)
from gaitcli.predict.ankle_law import ProsthesisLaw
from gaitcli.predict.checks import gait_checks
from gaitcli.predict.cost import check_weights, cost_of_transport, deviation, objective
from gaitcli.predict.grid import DEFAULT_CONTROL_POINTS, control_grid, instant_times
from gaitcli.predict.guess import STARTS, initial_guess, shipped_walk
from gaitcli.predict.layout import STEP_RANGE_M, DesignLayout, full_from_symmetric
from gaitcli.predict.model import WalkerParameters, WalkingModel
from gaitcli.predict.muscles import WalkerMuscles
from gaitcli.predict.nlp import build_nlp, instant_segments
from gaitcli.predict.problem import Transcriber, gait_at
from gaitcli.predict.prosthesis import CHOICES, COEFFICIENTS, curve_for
from gaitcli.predict.reference import VARIABLES, reference_curves
from gaitcli.predict.settings import PredictSettings
from gaitcli.predict.solve import NlpCache, PredictSolution, WarmStart, solve_windowed
from gaitcli.signal.bands import Band

#: phases with the right foot on the floor (HSr … TOr) and with both feet down (Fig. 5.3)
RIGHT_STANCE_PHASES = (1, 2, 3, 4, 5, 6)
DOUBLE_SUPPORT_PHASES = (1, 2, 5, 6)
#: how far a constraint group may leave its bounds at a converged solution (IPOPT's tolerance, scaled)
FEASIBILITY_TOLERANCE = 1e-5
#: the windows' reach (segments either side of an instant's own) of the full model's solve from the symmetric
#: solution, near its own: a sparser KKT matrix to factorise, 0.37 s an iteration against 0.55 s at the
#: default ±3 (nn = 18: 173 iterations in 64 s against 172 in 96 s, to the same J; benchmarks/README.md)
SOLUTION_WINDOW_REACH = 1
#: how many times finer than the control points the reported fine-grid costs are evaluated
FINE_GRID_REFINEMENT = 4
JOINTS = ("hip_r", "knee_r", "ankle_r", "hip_l", "knee_l", "ankle_l")


WEIGHTS_EXPECTED = "two weights W1,W2 ≥ 0 that sum to 2, (5.29); e.g. 4/3,2/3"
PROSTHESIS_EXPECTED = f"{', '.join(CHOICES)} or a .yaml file of {', '.join(COEFFICIENTS)}"


def weight_pair(value) -> tuple[float, float]:
    """(w1, w2) of "W1,W2" or a pair, each a number or a fraction read exactly ("4/3": 4/3 and 2/3 written as
    decimals differ from the default weights in the last bit, and the optimizer's path is sensitive to that);
    ≥ 0 and summing to 2 (5.29). ValueError otherwise."""
    try:
        return check_weights(number_pair(value, fractions=True))
    except InputError:
        raise ValueError(WEIGHTS_EXPECTED) from None


def angle_range_deg(value) -> tuple[float, float]:
    """(low, high) in degrees of "LOW,HIGH" or a pair, −60 ≤ low < high ≤ 60. ValueError otherwise."""
    low, high = number_pair(value)
    if not -60 <= low < high <= 60:
        raise ValueError("an increasing range")
    return low, high


def foot_position_m(value) -> tuple[float, float] | None:
    """(forward, down) in m of "FORWARD,DOWN" or a pair, each within ±0.3; None (or "") for the foot's CoM."""
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    forward, down = number_pair(value)
    if abs(forward) > 0.3 or abs(down) > 0.3:
        raise ValueError("a position near the ankle")
    return forward, down


def stride_range_m(value) -> tuple[float, float] | None:
    """(low, high) in m of "LOW,HIGH" or a pair, 0.4 ≤ low < high ≤ 2.4 (each step within the box's 0.2–1.2 m);
    None (or "") for the default (:attr:`PredictConfig.stride_range_m`)."""
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    low, high = number_pair(value)
    if not 2 * STEP_RANGE_M[0] <= low < high <= 2 * STEP_RANGE_M[1]:
        raise ValueError("an increasing range")
    return low, high


def even_nodes(nodes: int) -> int:
    """``nodes`` when even (5.2.4: with an odd number the periodic quartic spline is singular)."""
    if nodes % 2:
        raise ValueError("an even number")
    return nodes


def prosthesis_name(value) -> str:
    """One of :data:`~gaitcli.predict.prosthesis.CHOICES` (any case), or the path of an existing .yaml file of
    the curve's coefficients (read, and checked against the monotone range, when the stage runs)."""
    if not isinstance(value, str):
        raise ValueError(PROSTHESIS_EXPECTED)
    if value.lower().endswith((".yaml", ".yml")):
        if not Path(value).is_file():
            raise InputError(value, None, f"file not found (expected a YAML file of {', '.join(COEFFICIENTS)})")
        return value
    if value.lower() not in CHOICES:
        raise ValueError(PROSTHESIS_EXPECTED)
    return value.lower()


#: the optimal prosthesis's monotone range by default: the NLP's, in degrees (PredictSettings.monotone_range_rad)
MONOTONE_RANGE_DEG = tuple(round(float(np.degrees(v)), 9) for v in PredictSettings.monotone_range_rad)


@dataclass(frozen=True)
class PredictConfig:
    """Parameters of ``gait predict`` (5.2.10, 5.3.1): numbers and pairs of numbers, parsed where they are given
    (the command line, a pipeline file's ``predict:`` section, a study file) by :func:`core.validate.check_parameter`.
    The defaults of the problem's settings are :class:`~gaitcli.predict.settings.PredictSettings`'s."""

    speed_m_s: float = parameter(PredictSettings.speed_m_s, low=0.0, high=3.0, low_open=True,
                                 help="Mean walking speed, m/s (5.43).")
    weights: tuple[float, float] = parameter(PredictSettings.weights, parse=weight_pair, expected=WEIGHTS_EXPECTED,
                                             metavar="W1,W2", help="W1,W2 of J = W1·Et/100 + W2·Jdev (5.29), ≥ 0 "
                                                                   "and summing to 2; fractions such as 4/3 are exact.")
    nodes: int = parameter(18, low=6, high=40, parse=even_nodes,
                           expected="an even number of nodes: with an odd number the periodic quartic spline is "
                                    "singular, 5.2.4",
                           help="Spline nodes over the cycle, even (5.2.4).")
    symmetric: bool = parameter(True, help="Left leg = right leg half a cycle later (5.3.1).")
    max_iterations: int = parameter(PredictSettings.max_iterations, low=1, high=100000,
                                    help="IPOPT's iteration limit.")
    time_limit_s: float = parameter(0.0, low=0.0, high=1e6,
                                    help="Wall-clock budget of the solves, s: past it IPOPT stops and the result "
                                         "is marked unconverged (0: none).")
    foot_mass_kg: float = parameter(0.0, low=0.0, high=20.0, help="Mass added to each foot, kg (5.3.2: 2).")
    foot_mass_at: tuple[float, float] | None = parameter(
        None, parse=foot_position_m, metavar="FORWARD,DOWN",
        expected="FORWARD,DOWN in m from the ankle in the foot frame, each within ±0.3",
        help="Where the added foot mass sits: FORWARD,DOWN m from the ankle in the foot frame, as a band with "
             "Table A.2's inertia (default: at the foot's CoM, inertia unchanged).")
    prosthesis: str = parameter("none", parse=prosthesis_name, expected=PROSTHESIS_EXPECTED,
                                metavar="|".join(CHOICES[1:]) + "|FILE",
                                help="Bilateral transtibial prostheses (5.3.3): a commercial foot of Table A.7, the "
                                     "optimal device, or a YAML file of a_p, b_p, c0, a_n, b_n, d_prosth "
                                     "(N·m/rad³, /rad², /rad, N·m·s/rad; or `law:` and another law's "
                                     "coefficients).")
    strength_scale: float = parameter(0.0, low=0.0, high=5.0,
                                      help="Every F_max times this (5.3.3: 1.5; default 0 = 1.5 with a "
                                           "prosthesis, 1 without).")
    monotone_range_deg: tuple[float, float] = parameter(
        MONOTONE_RANGE_DEG, parse=angle_range_deg, metavar="LOW,HIGH",
        expected="LOW,HIGH in degrees, −60 ≤ LOW < HIGH ≤ 60",
        help="Ankle angles (deg, negative = dorsiflexion) over which a prosthesis's spring moment must decrease.")
    foot_flat_min_pct: float = parameter(
        PredictSettings.foot_flat_min_pct, low=0.0, high=30.0,
        help="Each heel rocker (heel strike to the forefoot's contact) lasts at least this % of the cycle (7: the "
             "earliest of 9 real stances; 0: free, as in the dissertation).")
    stride_range_m: tuple[float, float] | None = parameter(
        None, parse=stride_range_m, metavar="LOW,HIGH", expected="LOW,HIGH in m, 0.4 ≤ LOW < HIGH ≤ 2.4",
        help="Bounds on the stride, m (5.44's reasonable step lengths; each step half of it). Default: the stride of "
             "the speed's reference group ± 1 SD where the prediction tracks the shipped per-speed reference, "
             "else 0.4–2.4.")
    start: str = parameter("walk", choices=STARTS,
                           help="Where IPOPT starts without --init: walk (the shipped walk of the nearest speed on "
                                "these nodes, retimed to the speed) or guess (5.2.10's initial guess from the "
                                "reference).")
    starts: int = parameter(1, low=1, high=100,
                            help="Solve from this many starts (the default start and seeded perturbations of "
                                 "5.2.10's guess) in parallel and keep the best; every start in starts.csv.")
    seed: int = parameter(0, low=0, help="Seed of the perturbed starts.")

    @property
    def prosthetic(self) -> bool:
        return self.prosthesis != "none"

    def strength(self) -> float:
        """The F_max scale: ``strength_scale``, or 1.5 with a prosthesis and 1 without when it is 0."""
        return float(self.strength_scale) if self.strength_scale else (1.5 if self.prosthetic else 1.0)

    def monotone_range_rad(self) -> tuple[float, float]:
        """``monotone_range_deg`` in rad."""
        low, high = self.monotone_range_deg
        return float(np.radians(low)), float(np.radians(high))

    def walker_parameters(self, params: WalkerParameters | None) -> WalkerParameters:
        """The subject's model parameters with this case's added foot mass."""
        params = params if params is not None else WalkerParameters.subject_1()
        return params.with_foot_mass(self.foot_mass_kg, self.foot_mass_at) if self.foot_mass_kg else params


@dataclass(frozen=True)
class PredictResult:
    """One predicted gait cycle (SI units; angles in the model's clockwise signs unless named clinical).

    At the I distinct instants (``time_s``, ``cycle_pct``): ``coordinates`` (I, 9) y1…y9,
    ``clinical_angles_deg`` (I, 6) hip/knee flexion and ankle dorsiflexion right then left,
    ``muscle_forces_N``, ``activations``, ``excitations``, ``metabolic_rate_W`` (I, 16). At the P
    control points (``point_time_s``, ``point_phase`` 1–8): ``grf_N`` (P, 4) right f_x, f_z, left f_x, f_z;
    ``joint_moments_Nm`` (P, 6) from inverse dynamics with the ground reactions λ and
    ``muscle_moments_Nm`` (P, 6) from muscles and passive structures (5.49–5.51), joint senses of
    ``clinical_angles_deg``; ``moment_error_Nm`` (P, 6) B⁺e; ``contact_error_m`` (P,) the largest |c_ph|.
    ``points_m`` (I, n, 2): x, z of the model's ``point_names`` (hip, HAT CoM, knees, ankles, heels, MTPs);
    ``reference_mean``/``reference_sd`` (101, 10): the reference the deviation was measured against.
    """

    speed_m_s: float
    weights: tuple[float, float]
    nodes: int
    symmetric: bool
    time_s: np.ndarray
    cycle_pct: np.ndarray
    coordinates: np.ndarray
    clinical_angles_deg: np.ndarray
    muscle_names: tuple[str, ...]
    muscle_forces_N: np.ndarray
    activations: np.ndarray
    excitations: np.ndarray
    metabolic_rate_W: np.ndarray
    point_time_s: np.ndarray
    point_phase: np.ndarray
    grf_N: np.ndarray
    joint_moments_Nm: np.ndarray
    muscle_moments_Nm: np.ndarray
    moment_error_Nm: np.ndarray
    contact_error_m: np.ndarray
    residual_norm_by_phase: np.ndarray
    phase_durations_s: np.ndarray
    step_lengths_m: np.ndarray
    body_mass_kg: float
    point_names: tuple[str, ...]
    points_m: np.ndarray
    reference_mean: np.ndarray
    reference_sd: np.ndarray
    ankle_moment_Nm: np.ndarray  # (I, 2) the prostheses' moments (5.59) right, left, in the sense of y6/y9
    cost_of_transport_J_per_m: float
    deviation: float
    objective: float
    violations: dict = field(default_factory=dict)
    fine_grid: dict = field(default_factory=dict)
    design: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: the last NLP's variables w (χ and the lifted values) and IPOPT's multipliers of g and of w's bounds: what
    #: a warm start from this result (``--init``) continues from
    nlp_variables: np.ndarray = field(default_factory=lambda: np.zeros(0))
    constraint_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))
    bound_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))
    converged: bool = False
    status: str = ""
    iterations: int = 0
    rounds: int = 0
    solve_time_s: float = 0.0
    history: tuple[str, ...] = ()
    prosthesis: ProsthesisLaw | None = None  # the curve of a prosthetic run (the optimal one when optimal)
    foot_mass_kg: float = 0.0
    strength_scale: float = 1.0

    @property
    def period_s(self) -> float:
        return float(self.phase_durations_s.sum())

    @property
    def stride_m(self) -> float:
        """The two steps' sum, m."""
        return float(np.sum(self.step_lengths_m))

    @property
    def cadence_steps_per_min(self) -> float:
        return 120.0 / self.period_s

    def summary(self) -> dict:
        """summary.json: the predict keys of README.md's outputs table ("A tour of the CLI"): costs, durations, steps,
        stance, double support, ‖e‖ per phase, violations, checks."""
        d, T = self.phase_durations_s, self.period_s
        return {
            "speed_m_s": float(self.speed_m_s), "cost_of_transport_J_per_m": float(self.cost_of_transport_J_per_m),
            "deviation": float(self.deviation), "objective": float(self.objective), "weights": list(self.weights),
            "max_moment_error_Nm": float(np.abs(self.moment_error_Nm).max()),
            "max_contact_error_m": float(self.contact_error_m.max()),
            "min_excitation": float(self.excitations.min()), "max_excitation": float(self.excitations.max()),
            "converged": bool(self.converged), "iterations": int(self.iterations),
            "solve_time_s": float(self.solve_time_s), "status": self.status, "nodes": int(self.nodes),
            "symmetric": bool(self.symmetric), "period_s": T,
            "phase_durations_s": [float(v) for v in d], "step_lengths_m": [float(v) for v in self.step_lengths_m],
            "stance_pct": 100 * float(sum(d[p - 1] for p in RIGHT_STANCE_PHASES)) / T,
            "double_support_pct": 100 * float(sum(d[p - 1] for p in DOUBLE_SUPPORT_PHASES)) / T,
            "max_residual_norm_by_phase": [float(v) for v in self.residual_norm_by_phase],
            "violations": {k: float(v) for k, v in self.violations.items()},
            "fine_grid": dict(self.fine_grid),
            "foot_mass_kg": float(self.foot_mass_kg), "strength_scale": float(self.strength_scale),
            "prosthesis": (None if self.prosthesis is None else
                           {"name": self.prosthesis.name, **self.prosthesis.named()}),
            "gait_checks": self.gait_checks(),
            "vertical_impulse_ratio": self.vertical_impulse_ratio(),
        }

    def vertical_impulse_ratio(self) -> float:
        """∫ΣF_z dt / (m·g·T) over the cycle, trapezoid over the control points: 1 for a periodic motion that
        obeys Newton's second law (the centre of mass's vertical momentum returns to its start)."""
        from scipy.integrate import trapezoid

        t, fz = self.point_time_s, self.grf_N[:, 1] + self.grf_N[:, 3]
        return float(trapezoid(fz, t) / (self.body_mass_kg * GRAVITY_M_S2 * self.period_s))

    def gait_checks(self) -> dict:
        """Whether the right leg walks as people do (``checks.py``)."""
        d, T = self.phase_durations_s, self.period_s
        grf_pct = 100 * self.point_time_s / T
        return gait_checks(self.cycle_pct, self.clinical_angles_deg[:, 1], self.grf_N[:, 1] / self.body_mass_kg,
                           grf_pct, self.joint_moments_Nm[:, 2], grf_pct,
                           stance_pct=100 * float(sum(d[p - 1] for p in RIGHT_STANCE_PHASES)) / T,
                           double_support_pct=100 * float(sum(d[p - 1] for p in DOUBLE_SUPPORT_PHASES)) / T)


def violated_groups(violations: dict, tolerance: float = FEASIBILITY_TOLERANCE) -> dict:
    """The constraint groups whose largest violation exceeds ``tolerance``."""
    return {k: v for k, v in violations.items() if v > tolerance}


def settings_of(cfg: PredictConfig) -> PredictSettings:
    """The NLP's settings for ``cfg``."""
    return PredictSettings(speed_m_s=cfg.speed_m_s, weights=cfg.weights, max_iterations=cfg.max_iterations,
                           monotone_range_rad=cfg.monotone_range_rad(), foot_flat_min_pct=cfg.foot_flat_min_pct,
                           step_range_m=(None if cfg.stride_range_m is None
                                         else (cfg.stride_range_m[0] / 2, cfg.stride_range_m[1] / 2)))


def walker_muscles(cfg: PredictConfig, device: ProsthesisLaw | None) -> WalkerMuscles:
    """The muscles of ``cfg``: intact, or with prostheses of curve ``device`` (the optimal run's start), F_max
    scaled by ``cfg.strength()``."""
    if cfg.prosthetic and device is None:
        raise InputError(None, "--prosthesis", f"{cfg.prosthesis}: no curve given (expected a foot, a file's "
                                               "curve, or the optimal run's start)")
    return WalkerMuscles(prosthesis=device if cfg.prosthetic else None, strength_scale=cfg.strength())


def run_predict(cfg: PredictConfig, *, params: WalkerParameters | None = None, reference: Band,
                init: np.ndarray | None = None, warm: WarmStart | None = None, report=None,
                device: ProsthesisLaw | None = None,
                cache: NlpCache | None = None, settings: PredictSettings | None = None) -> PredictResult:
    """Predict one gait cycle (module docstring).

    Parameters
    ----------
    cfg : PredictConfig
        The problem and its settings (speed, weights, nodes, prosthesis, foot mass, F_max scale, …).
    params : WalkerParameters, optional
        The subject (default: the dissertation's subject 1); ``cfg``'s foot mass is added here.
    reference : Reference
        What Jdev (5.28) tracks.
    init : array, optional
        A design vector χ of the same layout to start from (default: the default initial guess).
    warm : WarmStart, optional
        With ``init``: the variables and multipliers it was solved with, continued where they fit the problem.
    report : callable, optional
        ``report(iteration, objective, violation)`` after every IPOPT iteration, counted over all solves.
    device : ProsthesisLaw, optional
        The prostheses' curve (a commercial foot's or a file's; for ``prosthesis: optimal`` the start of the
        free coefficients); default the commercial foot ``cfg.prosthesis`` names.
    cache : NlpCache, optional
        The runner's built problems and compiled solvers (default: one for this call; a runner that solves
        many cases keeps one per process and passes it to each).
    settings : PredictSettings, optional
        The problem's settings (default ``settings_of(cfg)``; e.g. with an opt-in tracking term).

    Returns
    -------
    PredictResult
        The transcribed solution, its costs and violations; ``converged`` False when IPOPT did not converge
        or a constraint group is violated.
    """
    weights = cfg.weights
    settings = settings if settings is not None else settings_of(cfg)
    device = device if device is not None else curve_for(cfg.prosthesis)
    optimal = cfg.prosthesis == "optimal"
    model = WalkingModel(cfg.walker_parameters(params))
    transcriber = Transcriber(cfg.nodes, model=model, muscles=walker_muscles(cfg, device))
    layout = DesignLayout.build(cfg.nodes, symmetric=cfg.symmetric)  # the parity check, before anything runs
    if init is not None and np.size(init) != layout.size:
        raise InputError(None, "--init", f"holds {np.size(init)} design variables (expected {layout.size} for "
                                         f"{cfg.nodes} nodes, {'symmetric' if cfg.symmetric else 'full'} model)")
    start, history, iterations, rounds = time.perf_counter(), [], 0, 0
    deadline = start + cfg.time_limit_s if cfg.time_limit_s > 0 else None
    if report is not None:  # one count over every solve (each IPOPT run counts from 0)
        calls, each = itertools.count(), report
        report = lambda k, objective, violation: each(next(calls), objective, violation)  # noqa: E731
    label = (f"{cfg.nodes} nodes, {cfg.speed_m_s:g} m/s, weights {weights[0]:.4g},{weights[1]:.4g}"
             + (f", prosthesis {cfg.prosthesis}" if cfg.prosthetic else "")
             + (f", +{cfg.foot_mass_kg:g} kg per foot" if cfg.foot_mass_kg else "")
             + (f", F_max ×{cfg.strength():g}" if cfg.strength() != 1 else ""))
    cache = cache if cache is not None else NlpCache()
    solve_options = {"device": device, "optimal_device": optimal, "deadline": deadline, "cache": cache}
    if init is not None:
        # a start from a solution (of a neighbouring case) keeps the default windows: ±1 segment, though cheaper
        # to factorise, made IPOPT creep from another case's gait on the default grid (benchmarks/README.md,
        # "Twenty points"); a window that binds is moved and the problem solved again (solve_windowed)
        x0 = init
    elif cfg.symmetric:
        x0 = default_start(cfg, transcriber, reference, settings, symmetric=True)
    else:
        # the full model starts from the symmetric model's solution (from the default start): on the full
        # model's grid that gait is exactly a point (layout.full_from_symmetric), feasible, so IPOPT starts there
        # with the feasible start's push (solve.FEASIBLE_START_OPTIONS) and the narrow windows of a solution
        first = solve_windowed(transcriber, reference, default_start(cfg, transcriber, reference, settings,
                                                                     symmetric=True),
                               settings, symmetric=True, report=report, **solve_options)
        iterations, rounds = first.outcome.iterations, first.rounds
        history += _solve_notes(first, f"symmetric model (the full model's start), {label}")
        if first.outcome.converged:
            x0 = full_from_symmetric(cfg.nodes, first.x)
            settings = replace(settings, window_reach=min(settings.window_reach, SOLUTION_WINDOW_REACH))
        else:
            x0 = default_start(cfg, transcriber, reference, settings, symmetric=False)
        if optimal and first.outcome.converged:
            solve_options["device"] = device.with_values("optimal", first.device)
    solved = solve_windowed(transcriber, reference, x0, settings, symmetric=cfg.symmetric, report=report,
                            warm=warm if init is not None else None, **solve_options)
    solve_time = time.perf_counter() - start
    final = (device.with_values("optimal", solved.device) if optimal else device) if cfg.prosthetic else None
    muscles = walker_muscles(cfg, final)
    result, violations = describe(cfg, solved.nlp, solved.outcome.x, reference, model, muscles)
    converged = solved.outcome.converged and solved.windows_hold and not violated_groups(violations)
    history += _solve_notes(solved, f"{'symmetric' if cfg.symmetric else 'full'} model, {label}")
    result["fine_grid"] = fine_grid(cfg, solved.x, reference, model, muscles)
    return PredictResult(**result, design=np.asarray(solved.x, float), nlp_variables=solved.outcome.x,
                         constraint_multipliers=solved.outcome.lam_g, bound_multipliers=solved.outcome.lam_x,
                         converged=bool(converged),
                         status=solved.outcome.status, iterations=iterations + solved.outcome.iterations,
                         rounds=rounds + solved.rounds, solve_time_s=solve_time, history=tuple(history),
                         prosthesis=final, foot_mass_kg=cfg.foot_mass_kg, strength_scale=cfg.strength())


def default_start(cfg: PredictConfig, transcriber: Transcriber, reference: Band, settings: PredictSettings, *,
                  symmetric: bool) -> np.ndarray:
    """χ to start from without ``--init``: ``cfg.start``'s (``guess.py``)."""
    if cfg.start == "guess":
        return initial_guess(transcriber, reference, settings, symmetric=symmetric)
    return shipped_walk(cfg.nodes, settings, symmetric=symmetric)


def _solve_notes(solved: PredictSolution, label: str) -> list[str]:
    """The history lines of one windowed solve: what its start had outside the bounds (clipped), its end."""
    notes = []
    if solved.outcome.outside:
        notes.append(f"predict: {label}: the start lay outside its bounds, clipped into them: "
                     f"{solved.outcome.outside.describe()}")
    return notes + [f"predict: {label}: {solved.outcome.status} after {solved.outcome.iterations} iterations"]


def describe(cfg: PredictConfig, nlp, w: np.ndarray, reference: Band, model: WalkingModel,
             muscles: WalkerMuscles) -> tuple[dict, dict]:
    """The fields of a :class:`PredictResult` for the NLP's variables ``w`` (the gait transcribed anew with the
    exact heat-rate model and ``muscles``, whose device is the solution's) and every constraint group's largest
    violation there."""
    g = nlp.constraint_values(w, settings_of(cfg))
    violations = {name: float(np.max(np.maximum(nlp.lbg[sl] - g[sl], 0) + np.maximum(g[sl] - nlp.ubg[sl], 0)))
                  for name, sl in nlp.groups.items()}
    durations, steps_r, steps_l, values = nlp.gait(w)
    exact = Transcriber(cfg.nodes, model=model, muscles=muscles, smoothing=0.0)
    t = exact.at(durations, steps_r, steps_l, values)
    fields = _result(cfg, cfg.weights, exact, t, durations, (steps_r, steps_l), reference, violations)
    return fields, violations


def evaluate_design(cfg: PredictConfig, x: np.ndarray, *, reference: Band,
                    params: WalkerParameters | None = None, device: ProsthesisLaw | None = None) -> PredictResult:
    """The :class:`PredictResult` of a given design vector χ, without solving.

    Parameters
    ----------
    cfg : PredictConfig
        The problem χ belongs to (its layout, model and settings).
    x : array
        χ, e.g. a stored solution.
    reference : Reference
        What Jdev (5.28) is evaluated against.
    params : WalkerParameters, optional
        The subject (default: subject 1).
    device : ProsthesisLaw, optional
        The prostheses' curve (default the commercial foot ``cfg.prosthesis`` names).

    Returns
    -------
    PredictResult
        ``converged`` says whether every constraint group holds at χ; no iterations.
    """
    device = device if device is not None else curve_for(cfg.prosthesis)
    model = WalkingModel(cfg.walker_parameters(params))
    muscles = walker_muscles(cfg, device)
    transcriber = Transcriber(cfg.nodes, model=model, muscles=muscles)
    layout = DesignLayout.build(cfg.nodes, symmetric=cfg.symmetric)
    nlp = build_nlp(transcriber, reference, settings_of(cfg), symmetric=cfg.symmetric,
                    segments=instant_segments(transcriber, layout, x))
    fields, violations = describe(cfg, nlp, nlp.start(x, device), reference, model, muscles)
    fields["fine_grid"] = fine_grid(cfg, x, reference, model, muscles)
    return PredictResult(**fields, design=np.asarray(x, float), converged=not violated_groups(violations),
                         status="evaluated", history=("predict: a given design vector, evaluated",),
                         prosthesis=device if cfg.prosthetic else None, foot_mass_kg=cfg.foot_mass_kg,
                         strength_scale=cfg.strength())


def _ground_forces(tr: Transcriber, t) -> np.ndarray:
    """(P, 4) right f_x, f_z, left f_x, f_z at the control points from the transcription's λ, N."""
    grid, contact = tr.grid, tr.contact
    grf = np.zeros((grid.points, 4))
    for j in range(grid.points):
        names = contact.reaction_names[int(grid.phase[j]) + 1]
        for k, suffix in enumerate(("_r_fx_N", "_r_fz_N", "_l_fx_N", "_l_fz_N")):
            grf[j, k] = sum(v for v, n in zip(t.reactions[j], names) if n.endswith(suffix))
    return grf


def _costs(tr: Transcriber, t, period: float, stride: float, reference: Band,
           grf: np.ndarray | None = None) -> tuple[float, float]:
    """Et (5.27, J/m) and Jdev (5.28) of a transcription on its grid's instants (``grf``: its
    :func:`_ground_forces`, where the caller has them)."""
    opening = tr.grid.instant_points
    times = np.asarray(t.instant_times_s, float).ravel()
    pct = 100 * times / period
    grf = _ground_forces(tr, t) if grf is None else grf
    values = np.column_stack([walker_to_clinical(t.y[opening]), grf[opening] / tr.model.total_mass_kg])
    mean_at, sd_at = reference_curves(reference)
    means, sds = np.array(mean_at(pct[None, :])).T, np.array(sd_at(pct[None, :])).T
    return (float(cost_of_transport(t.metabolic_rate_W, times, period, stride)),
            float(deviation(values, means, sds, times, period)))


def fine_grid(cfg: PredictConfig, x: np.ndarray, reference: Band, model: WalkingModel,
              muscles: WalkerMuscles | None = None, refinement: int = FINE_GRID_REFINEMENT) -> dict:
    """The design χ ``x`` on a grid ``refinement`` times finer than the control points': how far the optimum,
    which sees the control points only, holds between them.

    Each phase's intervals are split alike; the heat rates are the exact model's. ``model`` and ``muscles``
    are the case's (default muscles: Table A.1's, intact).

    Returns
    -------
    dict
        ``refinement``, Et (``cost_of_transport_J_per_m``), Jdev (``deviation``), J (``objective``), the
        largest moment error (N·m) and contact error (m), and the excitation range there.
    """
    counts = tuple(refinement * (c - 1) + 1 for c in DEFAULT_CONTROL_POINTS)
    fine = Transcriber(cfg.nodes, model=model, muscles=muscles, grid=control_grid(counts), smoothing=0.0)
    layout = DesignLayout.build(cfg.nodes, symmetric=cfg.symmetric)
    durations = layout.phase_durations(x)
    times = np.asarray(instant_times(fine.grid, durations), float).ravel()
    t = fine.at(*gait_at(layout, x, times))
    et, jdev = _costs(fine, t, float(np.sum(durations)), sum(layout.step_lengths(x)), reference)
    u = np.asarray(t.muscle_state["u"], float)[:, fine.muscles.present]
    return {"refinement": refinement, "cost_of_transport_J_per_m": et, "deviation": jdev,
            "objective": float(objective(et, jdev, cfg.weights)),
            "max_moment_error_Nm": float(max(np.abs(fine.joint_map_pinv @ np.asarray(e, float)).max()
                                             for e in t.residual)),
            "max_contact_error_m": float(max(np.abs(c).max() for c in t.contact_error_m)),
            "min_excitation": float(np.nanmin(u)), "max_excitation": float(np.nanmax(u))}


def _result(cfg, weights, tr: Transcriber, t, durations, steps, reference: Band, violations) -> dict:
    grid = tr.grid
    opening = grid.instant_points
    period, stride = float(np.sum(durations)), float(sum(steps))
    times = np.asarray(t.instant_times_s, float).ravel()
    mass = tr.model.total_mass_kg
    grf = _ground_forces(tr, t)
    angles = walker_to_clinical(t.y[opening])
    pct = 100 * times / period
    et, jdev = _costs(tr, t, period, stride, reference, grf)
    present = tr.muscles.present  # a prosthetic run's outputs leave out the removed muscles
    ankle = np.zeros((len(opening), 2))
    if tr.muscles.prosthetic:  # the prostheses' moments (5.59) on y6, y9
        c = tr.muscles.prosthesis.coefficients()
        ankle = np.array([np.ravel(np.array(tr.muscles.device(y, yd, c)))[[5, 8]]
                          for y, yd in zip(t.y[opening], t.yd[opening])])
    # joint moments: muscles (and passive structures) vs what the motion and λ require (5.49–5.51)
    B_pinv = tr.joint_map_pinv
    muscle, required, error = [], [], []
    for j in range(grid.points):
        e = np.asarray(t.residual[j], float)
        yj = t.y[j]
        f = t.forces_N[j]
        tau_m = B_pinv @ (np.array(tr.muscles.moment_arms(yj)) @ f + np.array(tr.muscles.passive(yj, t.yd[j])).ravel())
        muscle.append(walker_moments_to_clinical(tau_m))
        required.append(walker_moments_to_clinical(tau_m + B_pinv @ e))  # τ* = B⁺(M ÿ + k − g − G λ) = τm + B⁺e
        error.append(B_pinv @ e)
    residual_by_phase = np.array([max(np.linalg.norm(t.residual[j]) for j in range(grid.points)
                                      if int(grid.phase[j]) == p) for p in range(8)])
    reference_mean, reference_sd = reference.arrays(VARIABLES)
    return dict(speed_m_s=cfg.speed_m_s, weights=weights, nodes=cfg.nodes, symmetric=cfg.symmetric,
                time_s=times, cycle_pct=pct, coordinates=t.y[opening], clinical_angles_deg=angles,
                muscle_names=tuple(np.array(tr.muscles.names)[present]),
                muscle_forces_N=np.asarray(t.forces_N)[opening][:, present],
                activations=t.muscle_state["a"][:, present], excitations=t.muscle_state["u"][:, present],
                metabolic_rate_W=t.metabolic_rate_W[:, present],
                point_time_s=np.asarray(t.point_times_s, float).ravel(),
                point_phase=grid.phase + 1, grf_N=grf, joint_moments_Nm=np.array(required),
                muscle_moments_Nm=np.array(muscle), moment_error_Nm=np.array(error),
                contact_error_m=np.array([np.abs(c).max() for c in t.contact_error_m]),
                residual_norm_by_phase=residual_by_phase, phase_durations_s=np.asarray(durations, float),
                step_lengths_m=np.asarray(steps, float), body_mass_kg=mass, point_names=tuple(tr.model.point_names),
                points_m=np.array([np.column_stack([np.ravel(np.array(v)) for v in tr.model.points(y)]).T
                                   for y in t.y[opening]]),
                reference_mean=reference_mean, reference_sd=reference_sd, ankle_moment_Nm=ankle,
                cost_of_transport_J_per_m=float(et),
                deviation=float(jdev), objective=float(objective(et, jdev, weights)), violations=violations)

