"""The predict stage: a predictive simulation of one gait cycle by state dynamic optimization (Diss. 5.2–5.3).

``run_predict(cfg, params=…, reference=…)`` builds the lifted NLP (``nlp.py``) for the subject's
walking model, solves it from the default initial guess (or a warm start) and returns a
:class:`PredictResult`: the gait transcribed from the solution's design vector by the independent
numeric transcription (``problem.py``; λ by the pseudoinverse (5.30), the exact heat-rate model),
its cost parts and every constraint group's largest violation. The CLI writes it and maps
``converged=False`` to exit code 3.
"""

from __future__ import annotations

import dataclasses
import itertools
import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.core.validate import parameter
from gaitcli.errors import InputError, shown
from gaitcli.kinematics.conventions import walker_moments_to_clinical, walker_to_clinical
from gaitcli.predict.checks import gait_checks
from gaitcli.predict.cost import check_weights, cost_of_transport, deviation, objective
from gaitcli.predict.layout import DesignLayout, full_from_symmetric
from gaitcli.predict.model import GRAVITY_M_S2, WalkerParameters, WalkingModel
from gaitcli.predict.nlp import PredictSettings, build_nlp, initial_guess, instant_segments, solve_windowed
from gaitcli.predict.grid import DEFAULT_CONTROL_POINTS, control_grid, instant_times
from gaitcli.predict.problem import Transcriber, gait_at
from gaitcli.predict.reference import CYCLE_PCT, VARIABLES, Reference

#: phases with the right foot on the floor (HSr … TOr) and with both feet down (Fig. 5.3)
RIGHT_STANCE_PHASES = (1, 2, 3, 4, 5, 6)
DOUBLE_SUPPORT_PHASES = (1, 2, 5, 6)
#: how far a constraint group may leave its bounds at a converged solution (IPOPT's tolerance, scaled)
FEASIBILITY_TOLERANCE = 1e-5
#: how many times finer than the control points the reported fine-grid costs are evaluated
FINE_GRID_REFINEMENT = 4
JOINTS = ("hip_r", "knee_r", "ankle_r", "hip_l", "knee_l", "ankle_l")


@dataclass(frozen=True)
class PredictConfig:
    """Parameters of ``gait predict`` (5.2.10, 5.3.1)."""

    speed_m_s: float = parameter(1.1275, low=0.0, high=3.0, low_open=True,
                                 help="Mean walking speed, m/s (5.43; default 1.1275, the dissertation's).")
    weights: str = parameter("4/3,2/3",
                             help="W1,W2 of J = W1·Et/100 + W2·Jdev (5.29), ≥ 0 and summing to 2 (default 4/3,2/3).")
    nodes: int = parameter(18, low=6, high=40, help="Spline nodes over the cycle, even (5.2.4; default 18).")
    symmetric: bool = parameter(True, help="Left leg = right leg half a cycle later (5.3.1; default on).")
    max_iterations: int = parameter(3000, low=1, high=100000, help="IPOPT's iteration limit (default 3000).")

    def weight_pair(self) -> tuple[float, float]:
        """(w1, w2) of ``weights`` "W1,W2" (an InputError naming ``--weights`` otherwise)."""
        parts = str(self.weights).split(",")
        if len(parts) != 2:
            raise InputError(None, "--weights", f"got {shown(self.weights)} (expected two numbers W1,W2 that sum to 2)")
        return check_weights(parts)


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
    cost_of_transport_J_per_m: float
    deviation: float
    objective: float
    violations: dict = field(default_factory=dict)
    fine_grid: dict = field(default_factory=dict)
    design: np.ndarray = field(default_factory=lambda: np.zeros(0))
    converged: bool = False
    status: str = ""
    iterations: int = 0
    rounds: int = 0
    solve_time_s: float = 0.0
    history: tuple[str, ...] = ()

    @property
    def period_s(self) -> float:
        return float(self.phase_durations_s.sum())

    def summary(self) -> dict:
        """DESIGN.md's predict keys plus durations, steps, stance, double support, ‖e‖ per phase, violations."""
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


def run_predict(cfg: PredictConfig, *, params: WalkerParameters | None = None, reference: Reference,
                init: np.ndarray | None = None, report=None) -> PredictResult:
    """Predict one gait cycle (module docstring). ``init``: a design vector χ of the same layout to start from;
    ``report(iteration, objective, violation)`` after every IPOPT iteration."""
    weights = cfg.weight_pair()
    settings = PredictSettings(speed_m_s=cfg.speed_m_s, weights=weights, max_iterations=cfg.max_iterations)
    model = WalkingModel(params)
    transcriber = Transcriber(cfg.nodes, model=model)
    layout = DesignLayout.build(cfg.nodes, symmetric=cfg.symmetric)  # the parity check, before anything runs
    if init is not None and np.size(init) != layout.size:
        raise InputError(None, "--init", f"holds {np.size(init)} design variables (expected {layout.size} for "
                                         f"{cfg.nodes} nodes, {'symmetric' if cfg.symmetric else 'full'} model)")
    start, history, iterations, rounds = time.perf_counter(), [], 0, 0
    if report is not None:  # one count over every solve (each IPOPT run counts from 0)
        calls, each = itertools.count(), report
        report = lambda k, objective, violation: each(next(calls), objective, violation)  # noqa: E731
    label = (f"{cfg.nodes} nodes, {cfg.speed_m_s:g} m/s, weights {weights[0]:.4g},{weights[1]:.4g}")
    if init is not None:
        x0 = init
    elif cfg.symmetric:
        x0 = initial_guess(transcriber, reference, settings, symmetric=True)
    else:
        # the full model starts from the symmetric model's solution (from its default guess): a gait that
        # already walks, to which the full model's splines are fitted (layout.full_from_symmetric)
        first = solve_windowed(transcriber, reference, initial_guess(transcriber, reference, settings,
                                                                     symmetric=True),
                               settings, symmetric=True, report=report)
        iterations, rounds = first["iterations"], first["rounds"]
        history.append(f"predict: symmetric model (the full model's start), {label}: {first['status']} after "
                       f"{first['iterations']} iterations")
        x0 = (full_from_symmetric(cfg.nodes, first["x"]) if first["success"]
              else initial_guess(transcriber, reference, settings, symmetric=False))
        if first["success"]:  # near a solution: windows of ±1 segment (a third of the factorisation's cost)
            settings = dataclasses.replace(settings, window_reach=1)
    solved = solve_windowed(transcriber, reference, x0, settings, symmetric=cfg.symmetric, report=report)
    solve_time = time.perf_counter() - start
    result, violations = describe(cfg, solved["nlp"], solved["w"], reference, model)
    converged = solved["success"] and solved["windows_hold"] and not violated_groups(violations)
    history.append(f"predict: {'symmetric' if cfg.symmetric else 'full'} model, {label}: {solved['status']} after "
                   f"{solved['iterations']} iterations")
    result["fine_grid"] = fine_grid(cfg, solved["x"], reference, model)
    return PredictResult(**result, design=np.asarray(solved["x"], float), converged=bool(converged),
                         status=solved["status"], iterations=iterations + solved["iterations"],
                         rounds=rounds + solved["rounds"], solve_time_s=solve_time, history=tuple(history))


def describe(cfg: PredictConfig, nlp, w: np.ndarray, reference: Reference, model: WalkingModel) -> tuple[dict, dict]:
    """The fields of a :class:`PredictResult` for the NLP's variables ``w`` (the gait transcribed anew with the
    exact heat-rate model) and every constraint group's largest violation there."""
    g = np.array(ca.Function("g", [nlp.w], [nlp.constraints])(w)).ravel()
    violations = {name: float(np.max(np.maximum(nlp.lbg[sl] - g[sl], 0) + np.maximum(g[sl] - nlp.ubg[sl], 0)))
                  for name, sl in nlp.groups.items()}
    durations, steps_r, steps_l, values = nlp.gait(w)
    exact = Transcriber(cfg.nodes, model=model, smoothing=0.0)
    t = exact.at(durations, steps_r, steps_l, values)
    fields = _result(cfg, cfg.weight_pair(), exact, t, durations, (steps_r, steps_l), reference, violations)
    return fields, violations


def evaluate_design(cfg: PredictConfig, x: np.ndarray, *, reference: Reference,
                    params: WalkerParameters | None = None) -> PredictResult:
    """The :class:`PredictResult` of a given design vector χ ``x`` (e.g. a stored solution), without solving;
    ``converged`` says whether every constraint group holds there."""
    model = WalkingModel(params)
    transcriber = Transcriber(cfg.nodes, model=model)
    settings = PredictSettings(speed_m_s=cfg.speed_m_s, weights=cfg.weight_pair())
    layout = DesignLayout.build(cfg.nodes, symmetric=cfg.symmetric)
    nlp = build_nlp(transcriber, reference, settings, symmetric=cfg.symmetric,
                    segments=instant_segments(transcriber, layout, x))
    fields, violations = describe(cfg, nlp, nlp.start(x), reference, model)
    fields["fine_grid"] = fine_grid(cfg, x, reference, model)
    return PredictResult(**fields, design=np.asarray(x, float), converged=not violated_groups(violations),
                         status="evaluated", history=("predict: a given design vector, evaluated",))


def _ground_forces(tr: Transcriber, t) -> np.ndarray:
    """(P, 4) right f_x, f_z, left f_x, f_z at the control points from the transcription's λ, N."""
    grid, contact = tr.grid, tr.contact
    grf = np.zeros((grid.points, 4))
    for j in range(grid.points):
        names = contact.reaction_names[int(grid.phase[j]) + 1]
        for k, suffix in enumerate(("_r_fx_N", "_r_fz_N", "_l_fx_N", "_l_fz_N")):
            grf[j, k] = sum(v for v, n in zip(t.reactions[j], names) if n.endswith(suffix))
    return grf


def _costs(tr: Transcriber, t, period: float, stride: float, reference: Reference,
           grf: np.ndarray | None = None) -> tuple[float, float]:
    """Et (5.27, J/m) and Jdev (5.28) of a transcription on its grid's instants (``grf``: its
    :func:`_ground_forces`, where the caller has them)."""
    opening = tr.grid.instant_points
    times = np.asarray(t.instant_times_s, float).ravel()
    pct = 100 * times / period
    grf = _ground_forces(tr, t) if grf is None else grf
    values = np.column_stack([walker_to_clinical(t.y[opening]), grf[opening] / tr.model.total_mass_kg])
    means = np.column_stack([np.interp(pct, CYCLE_PCT, reference.mean[:, k]) for k in range(len(VARIABLES))])
    sds = np.column_stack([np.interp(pct, CYCLE_PCT, reference.sd[:, k]) for k in range(len(VARIABLES))])
    return (float(cost_of_transport(t.metabolic_rate_W, times, period, stride)),
            float(deviation(values, means, sds, times, period)))


def fine_grid(cfg: PredictConfig, x: np.ndarray, reference: Reference, model: WalkingModel,
              refinement: int = FINE_GRID_REFINEMENT) -> dict:
    """The design χ ``x`` on a grid ``refinement`` times finer than the control points' (each phase's
    intervals split alike; exact heat-rate model): Et, Jdev, J and the largest moment error, contact error and
    excitation range there — how far the optimum, which sees the control points only, holds between them."""
    counts = tuple(refinement * (c - 1) + 1 for c in DEFAULT_CONTROL_POINTS)
    fine = Transcriber(cfg.nodes, model=model, grid=control_grid(counts), smoothing=0.0)
    layout = DesignLayout.build(cfg.nodes, symmetric=cfg.symmetric)
    durations = layout.phase_durations(x)
    times = np.asarray(instant_times(fine.grid, durations), float).ravel()
    t = fine.at(*gait_at(layout, x, times))
    et, jdev = _costs(fine, t, float(np.sum(durations)), sum(layout.step_lengths(x)), reference)
    u = np.asarray(t.muscle_state["u"], float)
    return {"refinement": refinement, "cost_of_transport_J_per_m": et, "deviation": jdev,
            "objective": float(objective(et, jdev, cfg.weight_pair())),
            "max_moment_error_Nm": float(max(np.abs(fine.joint_map_pinv @ np.asarray(e, float)).max()
                                             for e in t.residual)),
            "max_contact_error_m": float(max(np.abs(c).max() for c in t.contact_error_m)),
            "min_excitation": float(np.nanmin(u)), "max_excitation": float(np.nanmax(u))}


def _result(cfg, weights, tr: Transcriber, t, durations, steps, reference: Reference, violations) -> dict:
    grid = tr.grid
    opening = grid.instant_points
    period, stride = float(np.sum(durations)), float(sum(steps))
    times = np.asarray(t.instant_times_s, float).ravel()
    mass = tr.model.total_mass_kg
    grf = _ground_forces(tr, t)
    angles = walker_to_clinical(t.y[opening])
    pct = 100 * times / period
    et, jdev = _costs(tr, t, period, stride, reference, grf)
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
    return dict(speed_m_s=cfg.speed_m_s, weights=weights, nodes=cfg.nodes, symmetric=cfg.symmetric,
                time_s=times, cycle_pct=pct, coordinates=t.y[opening], clinical_angles_deg=angles,
                muscle_names=tr.muscles.names, muscle_forces_N=np.asarray(t.forces_N)[opening],
                activations=t.muscle_state["a"], excitations=t.muscle_state["u"],
                metabolic_rate_W=t.metabolic_rate_W, point_time_s=np.asarray(t.point_times_s, float).ravel(),
                point_phase=grid.phase + 1, grf_N=grf, joint_moments_Nm=np.array(required),
                muscle_moments_Nm=np.array(muscle), moment_error_Nm=np.array(error),
                contact_error_m=np.array([np.abs(c).max() for c in t.contact_error_m]),
                residual_norm_by_phase=residual_by_phase, phase_durations_s=np.asarray(durations, float),
                step_lengths_m=np.asarray(steps, float), body_mass_kg=mass, point_names=tuple(tr.model.point_names),
                points_m=np.array([np.column_stack([np.ravel(np.array(v)) for v in tr.model.points(y)]).T
                                   for y in t.y[opening]]),
                reference_mean=reference.mean, reference_sd=reference.sd, cost_of_transport_J_per_m=float(et),
                deviation=float(jdev), objective=float(objective(et, jdev, weights)), violations=violations)

