"""The muscle stage: SO | MSO | EID on a sagittal motion, as one pure function (Diss. ch. 4).

``run_muscles(motion, limb, method=...)`` returns a :class:`MuscleResult` with
forces, activations, excitations, metabolic rates and cost, the moment
residuals and the solver's report; the CLI writes it and maps
``converged=False`` to exit code 3.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from gaitcli.core.events import SIDES, Events
from gaitcli.core.validate import one_of, parameter
from gaitcli.dynamics.sagittal import SagittalExport, SagittalMotion
from gaitcli.emg.comparison import EmgAgreement
from gaitcli.errors import InputError

from .eid import JOINT_NAMES, OBJECTIVES, moment_shortfall, quadrature_weights, solve_eid
from .forward import ValidationResult, validate_forward
from .interval import prepare_leg
from .limb import LimbParameters, MotionInterpolant
from .mso import solve_mso
from .parameters import JointParameters, MuscleParameters, table_a1
from .problem import Models, Problem, build_problem
from .so import solve_so
from .solver import SolverSettings

METHODS = ("so", "mso", "eid")
PHASES = ("cycle", "swing")
#: J per (thermochemical) calorie, for Ralston's (4.4)–(4.5)
JOULE_PER_CAL = 4.184


@dataclass(frozen=True)
class MusclesConfig:
    """Parameters of ``gait muscles`` (ch. 4)."""

    method: str = parameter("eid", choices=METHODS, help="Static optimization, modified SO or extended inverse "
                                                         "dynamics (default: eid).")
    side: str = parameter("r", choices=SIDES, help="Which leg (default: r).")
    nodes: int = parameter(50, low=4, high=2000, help="EID nodes over the interval (default 50).")
    validate: bool = parameter(False, help="Integrate the forward model with the EID excitations and compare "
                                           "(4.5.4).")
    objective: str = parameter("metabolic", choices=OBJECTIVES,
                               help="EID cost: total metabolic energy (4.29) or Crowninshield–Brand Σ(F/Fmax)³ "
                                    "(4.3) (default: metabolic).")
    phase: str = parameter("cycle", choices=PHASES, help="A stride recorded on the plates (periodic) or a swing "
                                                         "phase (default: cycle).")

    @property
    def variant(self) -> str:
        """The output folder's name below ``muscles/``: the method, then ``_l`` for the left leg, ``_swing`` for a
        swing phase and ``_cb`` for the Crowninshield–Brand objective, so that no variant replaces another's
        results (the default, right leg over a stride with the metabolic objective, is the method alone)."""
        return (self.method + ("_l" if self.side == "l" else "") + ("_swing" if self.phase == "swing" else "")
                + ("_cb" if self.objective == "crowninshield_brand" else ""))


@dataclass(frozen=True)
class MuscleOptions:
    """Settings of the muscle stage (all have the dissertation's values as defaults).

    ``muscles``/``joints``: model parameters (Table A.1; passive moments and
    damping). ``solver``: IPOPT settings. ``objective``: EID cost, "metabolic"
    (4.29) or "crowninshield_brand" ((4.3) integrated over time).
    ``smoothing``: width of the smoothed kinks of the heat rate the EID
    optimiser sees (0 = exact; reported costs always use the exact model).
    ``eid_nodes``: default number of EID nodes (4.5.2: 50). ``extra_nodes``:
    nodes added before and after a non-periodic interval (4.3.6).
    ``mso_penalty``: L1 weight of the excitation-bound slacks in MSO.
    ``bound_tolerance``: how far u or a may leave [0, 1] before a frame counts
    as infeasible (and before SO's metabolic cost is declared invalid).
    ``validation_restart_at_nodes``: the forward validation restarts every
    inter-node interval from the EID state instead of one integration from
    the first node (4.5.4); ``None`` restarts on a periodic cycle, whose stance
    an open-loop integration with prescribed ground reactions cannot follow,
    and integrates once over a swing phase, as the dissertation does.
    """

    muscles: MuscleParameters = field(default_factory=table_a1)
    joints: JointParameters = field(default_factory=JointParameters)
    solver: SolverSettings = field(default_factory=SolverSettings)
    objective: str = "metabolic"
    smoothing: float = 1e-2
    eid_nodes: int = 50
    extra_nodes: int = 2
    mso_penalty: float = 1e4
    bound_tolerance: float = 1e-6
    validation_restart_at_nodes: bool | None = None


@dataclass(frozen=True)
class MuscleResult:
    """Result of one muscle-stage run over the interval of interest (n nodes, m muscles).

    Arrays (n, m): ``forces_N``, ``activations``, ``excitations``,
    ``fibre_length_m``, ``fibre_velocity_m_s``, ``metabolic_rate_W`` (per
    muscle, (A.12)). Arrays (n, 3) in the limb's generalized coordinates (hip
    flexion, knee flexion, ankle dorsiflexion positive): ``joint_moments_Nm``
    (inverse dynamics), ``passive_moments_Nm``, ``damping_moments_Nm``,
    ``muscle_moments_Nm`` and ``moment_error_Nm`` = muscle + passive + damping −
    inverse dynamics (4.20). ``metabolic_cost_J`` is one leg over the interval
    (NaN when the excitations or activations leave [0, 1], where the energetics
    model does not apply — SO in Table 4.2); ``cost_of_transport_J_per_m`` =
    2 × one leg / distance (4.5.2); ``metabolic_energy_J`` (m,) its share per
    muscle; ``ralston_J_per_m`` the empirical (4.5) at the same speed.
    ``infeasible_frames`` (indices into ``time_s``) and ``infeasibility`` (how
    far u left [0, 1] there) — MSO only. ``moment_shortfall_Nm`` (n, 3) and
    ``diagnosis`` — an unconverged EID only: required minus achievable moment
    where the muscles cannot produce it (:func:`muscles.eid.moment_shortfall`).
    """

    method: str
    objective: str
    side: str
    time_s: np.ndarray
    muscle_names: tuple[str, ...]
    forces_N: np.ndarray
    activations: np.ndarray
    excitations: np.ndarray
    fibre_length_m: np.ndarray
    fibre_velocity_m_s: np.ndarray
    metabolic_rate_W: np.ndarray
    metabolic_cost_J: float
    metabolic_energy_J: np.ndarray
    cost_of_transport_J_per_m: float
    ralston_J_per_m: float
    distance_m: float
    speed_m_s: float
    duration_s: float
    joint_moments_Nm: np.ndarray
    passive_moments_Nm: np.ndarray
    damping_moments_Nm: np.ndarray
    muscle_moments_Nm: np.ndarray
    moment_error_Nm: np.ndarray
    converged: bool
    status: str
    iterations: int
    solve_time_s: float
    min_excitation: float
    max_excitation: float
    infeasible_frames: tuple[int, ...]
    infeasibility: tuple[float, ...]
    periodic: bool
    nodes: int
    notes: tuple[str, ...] = ()
    validation: ValidationResult | None = None
    moment_shortfall_Nm: np.ndarray | None = None
    diagnosis: str = ""
    phase: str = "cycle"
    interval_s: tuple[float, ...] = ()
    events: Events | None = None  # the analysed side's events
    history: tuple[str, ...] = ()  # the processing steps that made it
    emg: EmgAgreement | None = None  # the activations against the trial's EMG, where it has some (4.5.4)

    @property
    def max_moment_error_Nm(self) -> float:
        return float(np.max(np.abs(self.moment_error_Nm)))

    def summary(self) -> dict:
        """The stage's key scalars for ``summary.json``; the keys are fixed (tests, ``gait batch`` and
        ``gait compare`` read them)."""
        def num(x):
            return None if x is None or not np.isfinite(x) else float(x)
        out = {"method": self.method, "nodes": int(self.nodes), "solve_time_s": float(self.solve_time_s),
               "converged": bool(self.converged), "metabolic_cost_J": num(self.metabolic_cost_J),
               "cost_of_transport_J_per_m": num(self.cost_of_transport_J_per_m),
               "min_excitation": num(self.min_excitation), "max_excitation": num(self.max_excitation),
               "max_moment_error_Nm": num(self.max_moment_error_Nm)}
        if self.validation is not None:
            out["validation_rms_deg"] = num(self.validation.rms_total_deg)
            out["validation_metabolic_cost_J"] = num(self.validation.metabolic_cost_forward_J)
            out["validation_restarted_at_nodes"] = bool(self.validation.restarted_at_nodes)
        if self.moment_shortfall_Nm is not None:
            out["max_moment_shortfall_Nm"] = dict(zip(JOINT_NAMES,
                                                      np.abs(self.moment_shortfall_Nm).max(axis=0).tolist()))
            out["diagnosis"] = self.diagnosis
        if self.emg is not None:
            out["emg"] = {name: {"channel": channel, "correlation": num(r), "lag_s": num(lag),
                                 "lagged_correlation": num(r_lag), "on_off_agreement_pct": num(agree)}
                          for name, channel, r, lag, r_lag, agree in zip(
                              self.emg.muscles, self.emg.channels, self.emg.correlation, self.emg.lag_s,
                              self.emg.lagged_correlation, self.emg.on_off_agreement_pct)}
        return out


def run_muscles_stage(export: SagittalExport, cfg: MusclesConfig, *, stature_m: float, sex: str,
                      source=None, options: MuscleOptions | None = None) -> MuscleResult:
    """The muscle stage on one leg of the idyn stage's export: interval, limb, then :func:`run_muscles`."""
    leg = prepare_leg(export, cfg.side, cfg.phase, stature_m=stature_m, sex=sex, source=source)
    options = replace(options or MuscleOptions(), objective=cfg.objective)
    result = run_muscles(leg.motion, leg.limb, method=cfg.method, nodes=cfg.nodes if cfg.method == "eid" else None,
                         interval=leg.interval_s, periodic=leg.periodic, options=options, validate=cfg.validate)
    start, end = leg.interval_s
    step = (f"muscles: {cfg.method.upper()} ({result.objective}) on the {cfg.side} leg, {cfg.phase} "
            f"{start:.3f}–{end:.3f} s, {result.nodes} nodes, {result.status}")
    return replace(result, phase=cfg.phase, interval_s=(float(start), float(end)),
                   events=export.events.of(side=cfg.side), history=export.history + (step,))


def ralston_cost_of_transport(speed_m_s: float, body_mass_kg: float) -> float:
    """Ralston's E_w^t = 32/v + 0.0050·v cal/kg/m with v in m/min (4.5), in J/m for the whole body."""
    v = speed_m_s * 60.0
    return (32.0 / v + 0.0050 * v) * body_mass_kg * JOULE_PER_CAL


def run_muscles(motion: SagittalMotion, limb: LimbParameters, *, method: str, nodes: int | None = None,
                interval: tuple[float, float] | None = None, periodic: bool | None = None,
                options: MuscleOptions | None = None, validate: bool = False) -> MuscleResult:
    """Solve the force-sharing problem of one leg with SO, MSO or EID (Diss. 4.1.1, 4.4, 4.3).

    Parameters
    ----------
    motion : SagittalMotion
        The leg's sagittal motion and ground reaction (SI, rad).
    limb : LimbParameters
        Its segments.
    method : str
        ``"so"``, ``"mso"`` or ``"eid"``.
    nodes : int, optional
        Analysis nodes: default one per frame (SO, MSO) or ``options.eid_nodes`` (EID).
    interval : (float, float), optional
        (start, end), s: default the first heel-strike-to-heel-strike cycle, else the whole table.
    periodic : bool, optional
        Default: True for a heel-strike-to-heel-strike cycle.
    options : MuscleOptions, optional
        Model parameters and solver settings (default: the dissertation's).
    validate : bool
        EID only: integrate the forward model with the EID excitations (4.5.4).

    Returns
    -------
    MuscleResult
        ``converged`` False when the solver did not converge (the CLI's exit 3).
    """
    one_of(method, METHODS, where="method")
    opts = options or MuscleOptions()
    one_of(opts.objective, OBJECTIVES, where="objective")
    if validate and method != "eid":
        raise InputError(None, "validate", "forward validation needs the EID excitations (--method eid)")
    if method == "eid" and nodes is None:
        nodes = opts.eid_nodes
    start = time.perf_counter()
    models = Models.build(limb, opts.muscles, opts.joints)
    problem = build_problem(motion, models, nodes=nodes, interval=interval, periodic=periodic,
                            extra_nodes=opts.extra_nodes)
    muscle = models.muscle
    notes = []
    infeasible, violation = (), ()
    scheme = problem.scheme
    activation = excitation = None
    shortfall, diagnosis = None, ""
    if method == "so":
        force, out = solve_so(problem, opts.solver)
        converged, status, iterations = out.converged, out.status, out.iterations
        objective = "crowninshield_brand"
    elif method == "mso":
        sol = solve_mso(problem, opts.solver, penalty=opts.mso_penalty)
        force, scheme, objective = sol.force_N, "backward", "crowninshield_brand"
        activation, excitation = sol.activation, sol.excitation
        iterations = sol.so_outcome.iterations + sum(o.iterations for o in sol.outcomes)
        failed = [j + 1 for j, o in enumerate(sol.outcomes) if not o.converged]
        bad = np.flatnonzero(sol.violation > opts.bound_tolerance)
        bad = bad[(bad >= problem.interval.start) & (bad < problem.interval.stop)]  # not the extra nodes
        infeasible, violation = tuple(int(j) for j in bad), tuple(float(sol.violation[j]) for j in bad)
        converged = sol.so_outcome.converged and not failed and not bad.size
        status = "Solve_Succeeded" if not failed else f"{len(failed)} frame solves failed (frames {failed[:10]})"
        if bad.size:
            status += f"; {bad.size} infeasible frames (u outside [0, 1] by up to {sol.violation[bad].max():.3g})"
            notes.append("MSO infeasible frames keep the least-violating forces (4.4); their excitations "
                         "are reported as computed, not clipped")
        notes.append("MSO first frame: SO forces, activation by forward difference (4.4); its excitation "
                     "is not constrained (4.30 holds for j ≥ 2)")
    else:
        sol = solve_eid(problem, opts.solver, objective=opts.objective, smoothing=opts.smoothing)
        force, out, objective = sol.force_N, sol.outcome, opts.objective
        converged, status, iterations = out.converged, out.status, out.iterations
        activation, excitation = sol.activation, sol.excitation
        if out.outside:
            notes.append(f"EID start (SO's forces and the states they need) outside the bounds, clipped: "
                         f"{out.outside.describe()}")
        if not converged:  # where can the muscles not produce the moments? (one more, always feasible, NLP)
            shortfall = moment_shortfall(problem, SolverSettings(print_level=opts.solver.print_level),
                                         warm_start_force_N=sol.warm_start_force_N)
            if shortfall.outcome.converged:
                diagnosis = shortfall.describe(problem.time_s)
                notes.append(f"EID diagnosis (moment equations relaxed, L1 penalty): {diagnosis}")
            else:
                notes.append(f"EID diagnosis (moment equations relaxed) ended {shortfall.outcome.status}")
                shortfall = None
        if opts.objective == "metabolic" and opts.smoothing > 0:
            notes.append(f"EID objective: heat rate with kinks smoothed over {opts.smoothing:g}; "
                         f"optimiser objective {out.objective:.2f} J, reported cost uses the exact model")
    inv = muscle.invert_forces(force, problem.l_m, problem.v_m, problem.dt_s, scheme)
    if method == "eid":
        mismatch = max(np.nanmax(np.abs(inv["a"] - activation)), np.nanmax(np.abs(inv["u"] - excitation)))
        notes.append(f"EID activations/excitations re-derived from the forces by (4.10–4.19); "
                     f"largest difference to the NLP's values {mismatch:.2g}")
    elif method == "mso":
        # frame 0 is the SO estimate (4.4); the later frames are the per-frame NLP values,
        # which the backward-difference inversion (4.31–4.34) reproduces
        mismatch = max(np.nanmax(np.abs(inv["a"][2:] - activation[2:])),
                       np.nanmax(np.abs(inv["u"][2:] - excitation[2:])))
        notes.append(f"MSO activations/excitations re-derived by (4.31–4.34) from frame 2 on differ from the "
                     f"per-frame NLP values by at most {mismatch:.2g}")
        inv["a"], inv["u"] = activation, excitation
        inv["l_ce"][0], inv["v_ce"][0] = sol.first_frame["l_ce"], sol.first_frame["v_ce"]
    solve_time = time.perf_counter() - start
    result = _result(method, objective, problem, motion, force, inv, converged, status, iterations, solve_time,
                     infeasible, violation, notes, opts, validate, sol if method == "eid" else None)
    if shortfall is not None:
        result = replace(result, moment_shortfall_Nm=shortfall.shortfall_Nm[problem.interval], diagnosis=diagnosis)
    return result


def _result(method, objective, problem: Problem, motion, force, inv, converged, status, iterations, solve_time,
            infeasible, violation, notes, opts: MuscleOptions, validate, eid_solution) -> MuscleResult:
    muscle = problem.models.muscle
    sl = problem.interval
    u_all, a_all = inv["u"], inv["a"]
    rate = muscle.evaluate("metabolic_rate", u_all, a_all, inv["l_ce"], inv["v_ce"], inv["f_ce"])
    u, a = u_all[sl], a_all[sl]
    tol = opts.bound_tolerance
    # MSO's first frame is an SO estimate whose excitation (4.30) does not constrain (j ≥ 2)
    uc, ac = (u[1:], a[1:]) if method == "mso" and sl.start == 0 else (u, a)
    out_of_bounds = (not np.all(np.isfinite(uc)) or not np.all(np.isfinite(ac)) or np.min(uc) < -tol
                     or np.max(uc) > 1 + tol or np.min(ac) < -tol or np.max(ac) > 1 + tol)
    weights = quadrature_weights(sl.stop - sl.start, problem.periodic)
    energy = problem.dt_s * weights @ rate[sl]  # per muscle, the same quadrature as (4.29)
    cost = float(energy.sum())
    if out_of_bounds:
        notes = list(notes) + ["metabolic cost not given: excitations or activations outside [0, 1], where "
                               "the energetics model does not apply (Table 4.2)"]
        cost = float("nan")
        energy = np.full_like(energy, np.nan)
    duration = problem.dt_s * (sl.stop - sl.start) if problem.periodic else problem.t_end_s - problem.t_start_s
    distance = problem.distance_m
    speed = distance / duration if duration > 0 else float("nan")
    cot = 2.0 * cost / distance if distance > 0 else float("nan")  # both legs (4.5.2)
    ralston = ralston_cost_of_transport(speed, problem.body_mass_kg) if speed > 0 else float("nan")
    validation = None
    if validate:
        interp = MotionInterpolant(motion, problem.time_s[0], problem.time_s[-1])
        restart = problem.periodic if opts.validation_restart_at_nodes is None else opts.validation_restart_at_nodes
        validation = validate_forward(problem, interp, force, eid_solution.activation, eid_solution.excitation,
                                      cost, restart_at_nodes=restart)
        if restart:
            notes = list(notes) + ["forward validation restarted from the EID state at every node (4.5.4's "
                                   "variant): an open-loop integration with prescribed ground reactions cannot "
                                   "follow a stance phase; --phase swing integrates once, as the dissertation"]
        elif problem.periodic:
            notes = list(notes) + ["forward validation over a whole cycle in one integration: open-loop with "
                                   "prescribed ground reactions, it drifts in stance"]
    finite_u = u[np.isfinite(u)]
    return MuscleResult(
        method=method, objective=objective, side=motion.side, time_s=problem.time_s[sl],
        muscle_names=muscle.names, forces_N=force[sl], activations=a, excitations=u,
        fibre_length_m=inv["l_ce"][sl], fibre_velocity_m_s=inv["v_ce"][sl], metabolic_rate_W=rate[sl],
        metabolic_cost_J=cost, metabolic_energy_J=energy, cost_of_transport_J_per_m=cot, ralston_J_per_m=ralston,
        distance_m=distance,
        speed_m_s=speed, duration_s=duration, joint_moments_Nm=problem.tau_id[sl],
        passive_moments_Nm=problem.tau_passive[sl], damping_moments_Nm=problem.tau_damping[sl],
        muscle_moments_Nm=problem.muscle_moments(force)[sl], moment_error_Nm=problem.moment_error(force)[sl],
        converged=bool(converged), status=str(status), iterations=int(iterations), solve_time_s=float(solve_time),
        min_excitation=float(finite_u.min()) if finite_u.size else float("nan"),
        max_excitation=float(finite_u.max()) if finite_u.size else float("nan"),
        infeasible_frames=tuple(int(j) - sl.start for j in infeasible if sl.start <= j < sl.stop),
        infeasibility=tuple(v for j, v in zip(infeasible, violation) if sl.start <= j < sl.stop),
        periodic=problem.periodic, nodes=sl.stop - sl.start, notes=tuple(notes), validation=validation)
