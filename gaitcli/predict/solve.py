"""Solving the predictive-gait NLP: IPOPT through ``core/ipopt.py``, the runner's cache, the window strategy.

:func:`solve` runs IPOPT with exact derivatives (Hessian included) on one built problem: the start χ is
checked against its box bounds and the start w against w's bounds, what lies outside is reported in the
:class:`~gaitcli.core.ipopt.Outcome` (``outside``) and clipped. :func:`solve_windowed` places the spline
windows where the start puts the instants and, while a solution presses on a window's edge, moves that window
and solves again from the last solution (warm, with its multipliers).

:class:`NlpCache` holds the built problems (one per structure, :func:`gaitcli.predict.nlp.nlp_key`) and
their compiled IPOPT solvers (one per problem and option set, all taking the problem's derivative functions,
``NLP.derivatives``, built once): the speed and the weights are parameters, so a study's
cases reuse them. The runner owns the cache and passes it in; a hit is returned as stored, never changed.
"""

from __future__ import annotations

import dataclasses
import time
from collections import OrderedDict
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.core import ipopt
from gaitcli.core.ipopt import Outcome, outside_bounds
from gaitcli.predict.layout import DesignLayout, box_bounds
from gaitcli.predict.nlp import NLP, build_nlp, instant_segments, nlp_key
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.settings import TIME_LIMIT_STATUS, PredictSettings
from gaitcli.signal.bands import Band

#: how many built problems a cache keeps: a study alternates between at most two structures (intact,
#: prosthetic)
BUILT_NLPS_KEPT = 3


class IterationReport(ca.Callback):
    """IPOPT's iteration callback: ``report(iteration, objective, constraint_violation)`` after each iteration
    (the violation is the largest distance of g from its bounds); past ``deadline`` (time.perf_counter's clock)
    it stops IPOPT, which then returns ``User_Requested_Stop`` (:data:`TIME_LIMIT_STATUS` in the result).
    The compiled solver keeps its callback: :meth:`start` points it at one solve's caller."""

    def __init__(self, nlp: NLP, report=None):
        ca.Callback.__init__(self)
        self.report, self.lbg, self.ubg, self.iteration, self.deadline = report, nlp.lbg, nlp.ubg, 0, None
        self.sizes = {"x": nlp.w.size1(), "g": nlp.constraints.size1()}
        self.construct("iteration_report", {"enable_fd": False})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        if name in ("f",):
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.sizes["x"])
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.sizes["g"])
        return ca.Sparsity(0, 0)

    def start(self, report, deadline: float | None = None) -> None:
        """Report to ``report`` (or nobody) from iteration 0, and stop past ``deadline``."""
        self.report, self.iteration, self.deadline = report, 0, deadline

    def eval(self, arg):
        stop = int(self.deadline is not None and time.perf_counter() > self.deadline)
        if self.report is None:
            return [stop]
        g = np.array(arg[ca.nlpsol_out().index("g")]).ravel()
        violation = float(np.max(np.maximum(self.lbg - g, 0) + np.maximum(g - self.ubg, 0))) if g.size else 0.0
        self.report(self.iteration, float(arg[ca.nlpsol_out().index("f")]), violation)
        self.iteration += 1
        return [stop]


def ipopt_options(settings: PredictSettings, warm: bool) -> dict:
    """IPOPT's options for ``settings`` (a warm start's when ``warm``): MUMPS with METIS ordering, without its
    own row/column scaling and with a pivot tolerance of 1e-8 (IPOPT raises it where a factorisation looks
    inaccurate), the fastest measured on this KKT system (``benchmarks/README.md``)."""
    s = settings
    opts = ipopt.options(tol=s.tolerance, max_iter=s.max_iterations, print_level=s.print_level,
                         **{"ipopt.mumps_pivot_order": 5, "ipopt.mumps_permuting_scaling": 0,
                            "ipopt.mumps_pivtol": 1e-8, "ipopt.mumps_scaling": 0,
                            "ipopt.acceptable_tol": s.acceptable_tolerance,
                            "ipopt.acceptable_iter": s.acceptable_iterations,
                            "ipopt.acceptable_obj_change_tol": s.acceptable_objective_change})
    if warm:
        opts.update({"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-6,
                     "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9})
    return opts


@dataclass
class _Built:
    """One cached problem, its compiled solvers by their options, and its derivative functions once built."""

    nlp: NLP
    solvers: dict = field(default_factory=dict)
    derivatives: dict = field(default_factory=dict)


class NlpCache:
    """The built problems of one runner and their compiled IPOPT solvers (module docstring); the
    ``kept`` most recently used problems stay, with their solvers. ``builds`` counts the problems built and
    ``build_s`` the seconds spent building them and their solvers, since the cache was made."""

    def __init__(self, kept: int = BUILT_NLPS_KEPT):
        self.kept = kept
        self._built: OrderedDict[tuple, _Built] = OrderedDict()
        self.builds, self.build_s = 0, 0.0

    def __len__(self) -> int:
        return len(self._built)

    def _entry(self, key: tuple, make) -> _Built:
        if key in self._built:
            self._built.move_to_end(key)
        else:
            self._built[key] = _Built(make())
            while len(self._built) > self.kept:
                self._built.popitem(last=False)
        return self._built[key]

    def nlp(self, transcriber: Transcriber, reference: Band, settings: PredictSettings | None = None, *,
            symmetric: bool = False, segments: dict, reach: int | None = None) -> NLP:
        """:func:`build_nlp`'s problem, built once per structure (:func:`gaitcli.predict.nlp.nlp_key`)."""
        s = settings or PredictSettings()
        reach = s.window_reach if reach is None else reach
        key = nlp_key(transcriber, reference, s, symmetric=symmetric, segments=segments, reach=reach)

        def make() -> NLP:
            began = time.perf_counter()
            built = build_nlp(transcriber, reference, s, symmetric=symmetric, segments=segments, reach=reach)
            self.builds += 1
            self.build_s += time.perf_counter() - began
            return built

        return self._entry(key, make).nlp

    def solvers(self, nlp: NLP) -> dict:
        """The compiled solvers of ``nlp`` so far, by their options' key (a copy)."""
        return dict(self._entry(nlp.key, lambda: nlp).solvers)

    def derivatives(self, nlp: NLP) -> dict:
        """∇J, the Jacobian of g and the Hessian of the Lagrangian of ``nlp`` (empty before its first solver)."""
        return dict(self._entry(nlp.key, lambda: nlp).derivatives)

    def constraint_values(self, nlp: NLP, w: np.ndarray, p: np.ndarray) -> np.ndarray:
        """g(w, p) of ``nlp`` by the derivative functions its solvers use (built here once if not yet)."""
        entry = self._entry(nlp.key, lambda: nlp)
        if not entry.derivatives:
            entry.derivatives.update(nlp.derivatives())
        return np.asarray(entry.derivatives["jac_g"](w, p)[0]).ravel()

    def solver(self, nlp: NLP, opts: dict) -> tuple[ca.Function, IterationReport]:
        """IPOPT for ``nlp`` with the options ``opts``, compiled once per problem and option set.
        Returns (solver, its iteration callback)."""
        entry = self._entry(nlp.key, lambda: nlp)
        key = repr(sorted(opts.items()))
        if key not in entry.solvers:
            began = time.perf_counter()
            callback = IterationReport(nlp)
            problem = {"x": nlp.w, "f": nlp.cost, "g": nlp.constraints, "p": nlp.parameters}
            if not entry.derivatives:
                entry.derivatives.update(nlp.derivatives())
            derivatives = dict(entry.derivatives)
            if opts.get("ipopt.hessian_approximation", "exact") != "exact":
                derivatives.pop("hess_lag")
            # no nlpsol-made gradient of the Lagrangian (for multipliers of p, unused): 0.8 s of construction
            solver = ipopt.build_solver("predict", problem, {**opts, **derivatives, "iteration_callback": callback,
                                                             "no_nlp_grad": True, "calc_lam_p": False})
            entry.solvers[key] = (solver, callback)
            self.build_s += time.perf_counter() - began
        return entry.solvers[key]


def checked_design(transcriber: Transcriber, layout: DesignLayout, x) -> tuple[np.ndarray, ipopt.OutsideBounds]:
    """χ ``x`` clipped into its box bounds (``layout.box_bounds``) and what lay outside them, per χ block
    (in its own units: m, rad, s; the tendon stretch dimensionless)."""
    low, high = box_bounds(layout, transcriber.muscles.present)
    blocks = {name: slice(start, start + rows * cols) for name, (start, rows, cols) in layout.blocks.items()}
    return np.clip(x, low, high), outside_bounds(x, low, high, blocks)


def solve(nlp: NLP, x0: np.ndarray, settings: PredictSettings | None = None, *, w0: np.ndarray | None = None,
          multipliers: tuple[np.ndarray, np.ndarray] | None = None, options: dict | None = None, report=None,
          device=None, optimal_device: bool = False, deadline: float | None = None, cache: NlpCache | None = None,
          transcriber: Transcriber | None = None) -> Outcome:
    """IPOPT with exact derivatives (Hessian included) on one built problem.

    Parameters
    ----------
    nlp : NLP
        The problem (:func:`~gaitcli.predict.nlp.build_nlp`, or the cache's).
    x0 : array
        The start χ: checked against its box bounds, clipped, and transcribed into w (unless ``w0``).
    settings : PredictSettings, optional
        The parameters p (speed, weights) and IPOPT's stopping rules.
    w0 : array, optional
        The whole start w (an earlier solution of a problem of the same structure).
    multipliers : (array, array), optional
        (lam_g, lam_x) of an earlier solve: a warm start.
    options : dict, optional
        Further IPOPT/CasADi options.
    report : callable, optional
        ``report(iteration, objective, violation)`` after every IPOPT iteration.
    device : ProsthesisLaw, optional
        Prosthetic models: where D starts and, unless ``optimal_device``, stays (default the transcriber's).
    optimal_device : bool
        D free within its law's BOUNDS.
    deadline : float, optional
        On time.perf_counter's clock: past it IPOPT stops with status :data:`TIME_LIMIT_STATUS`, unconverged.
    cache : NlpCache, optional
        The runner's (default: one for this call).
    transcriber : Transcriber, optional
        The case's (default the NLP's: a problem serves every transcriber of its key; this one's prosthesis
        starts D).

    Returns
    -------
    Outcome
        Its ``x`` is w; ``outside`` what the start had outside the bounds of χ (per χ block, in SI units) or
        of w (per w block, scaled), clipped before IPOPT ran.
    """
    s = settings or PredictSettings()
    transcriber = transcriber or nlp.transcriber
    cache = cache or NlpCache()
    opts = {**ipopt_options(s, warm=multipliers is not None), **(options or {})}
    outside = ipopt.OutsideBounds()
    if w0 is None:
        x, outside = checked_design(transcriber, nlp.layout, x0)
        start = nlp.lifted_start(x, device, transcriber)
    else:
        start = w0
        if nlp.device_size and device is not None:  # D starts at the given device
            start = np.concatenate([start[:start.size - nlp.device_size], device.scaled()])
    lbw, ubw = nlp.bounds(None if optimal_device else (device or transcriber.muscles.prosthesis))
    lam_g0, lam_x0 = multipliers if multipliers is not None else (None, None)
    p = nlp.parameter_values(s)
    if multipliers is None and "ipopt.bound_push" not in opts and _feasible(cache.constraint_values(nlp, start, p),
                                                                           nlp):
        opts.update(FEASIBLE_START_OPTIONS)
    solver, callback = cache.solver(nlp, opts)
    callback.start(report, deadline)
    out = ipopt.solve(solver, start, lbw, ubw, nlp.lbg, nlp.ubg, p, lam_g0=lam_g0, lam_x0=lam_x0, blocks=nlp.blocks)
    status = out.status
    if status == "User_Requested_Stop" and deadline is not None and time.perf_counter() > deadline:
        status = TIME_LIMIT_STATUS
    return dataclasses.replace(out, status=status, outside=outside.merged(out.outside))


#: IPOPT's push of a start off its bounds when the start already satisfies every constraint (a solution of
#: this problem, as the default prediction's shipped walk is): IPOPT's default 1e-2 moves the many variables on
#: a bound so far that it needs 100 iterations back to where it started, 60 with 1e-3 (benchmarks/README.md)
FEASIBLE_START_OPTIONS = {"ipopt.bound_push": 1e-3, "ipopt.bound_frac": 1e-3}
#: the largest constraint violation of a start that counts as feasible (scaled constraints)
FEASIBLE_START_TOLERANCE = 1e-6


def _feasible(g: np.ndarray, nlp: NLP) -> bool:
    """Whether the constraint values ``g`` lie within ``nlp``'s bounds to :data:`FEASIBLE_START_TOLERANCE`."""
    lbg, ubg = np.broadcast_to(nlp.lbg, g.shape), np.broadcast_to(nlp.ubg, g.shape)
    violation = np.maximum(lbg - g, 0) + np.maximum(g - ubg, 0)
    return bool(g.size) and float(np.max(violation)) < FEASIBLE_START_TOLERANCE


def moved_windows(nlp: NLP, lam_g: np.ndarray, threshold: float = 1e-8) -> dict | None:
    """The segments with every window whose edge an instant presses on (a non-zero multiplier ``lam_g`` of its
    ``windows`` row) moved one segment that way; ``None`` when no window binds (a solution of the problem
    without windows)."""
    lam = lam_g[nlp.groups["windows"]]
    moved, start, changed = {}, 0, False
    for key in sorted(nlp.segments):  # windows_rows' order
        k = np.asarray(nlp.segments[key], int)
        step = np.where(lam[start:start + k.size] > threshold, 1, np.where(lam[start:start + k.size] < -threshold,
                                                                              -1, 0))
        moved[key] = np.clip(k + step, 0, nlp.intervals[key] - 1)
        changed |= bool(np.any(moved[key] != k))
        start += k.size
    return moved if changed else None


@dataclass(frozen=True)
class WarmStart:
    """An earlier solve's last point: the NLP's variables ``w`` and IPOPT's multipliers of g and of w's bounds.
    It continues a problem of the same sizes (the same nodes and model), whatever its speed or weights."""

    w: np.ndarray
    lam_g: np.ndarray
    lam_x: np.ndarray

    def fits(self, nlp: NLP) -> bool:
        """Whether it has the sizes of ``nlp``'s w and g."""
        return self.w.size == self.lam_x.size == nlp.w.numel() and self.lam_g.size == nlp.constraints.numel()


@dataclass(frozen=True)
class PredictSolution:
    """A windowed solve: ``outcome`` the last solve's (iterations and time summed over the rounds; ``x`` is w,
    ``outside`` what the first start had outside the bounds), ``x`` χ of the solution, ``device`` its device
    coefficients (empty without one), ``nlp`` the last problem, ``rounds`` the solves, ``windows_hold`` whether
    no window binds (a solution of the problem without windows)."""

    outcome: Outcome
    x: np.ndarray
    device: np.ndarray
    nlp: NLP
    rounds: int
    windows_hold: bool


def solve_windowed(transcriber: Transcriber, reference: Band, x0: np.ndarray,
                   settings: PredictSettings | None = None, *, symmetric: bool = False, rounds: int = 6,
                   options: dict | None = None, report=None, w0: np.ndarray | None = None, device=None,
                   optimal_device: bool = False, deadline: float | None = None,
                   cache: NlpCache | None = None, warm: WarmStart | None = None) -> PredictSolution:
    """:func:`solve` with the spline windows placed where the start puts the instants, moved while a solution
    presses on one.

    Parameters
    ----------
    transcriber : Transcriber
        The case's model, muscles, node count and grid.
    reference : Band
        What Jdev tracks.
    x0 : array
        The start χ (clipped into its box bounds first; what lay outside is reported).
    settings : PredictSettings, optional
        As :func:`solve`; ``window_reach`` the windows' reach.
    symmetric : bool
        The symmetric model or the full one.
    rounds : int
        At most this many solves: after each, the windows an instant presses on move one segment and the
        problem is solved again from the last solution (warm, with its multipliers).
    options, report, w0, device, optimal_device, deadline
        As :func:`solve` (``w0`` the first round's).
    cache : NlpCache, optional
        The runner's built problems and compiled solvers (default: one for this call).
    warm : WarmStart, optional
        An earlier solve's variables and multipliers: the first round starts from them (IPOPT's warm start)
        where they fit its problem (:meth:`WarmStart.fits`; else from ``x0`` alone).

    Returns
    -------
    PredictSolution
        The last solve's outcome (iterations and time over all rounds; ``outside``: the first start's), χ,
        the device coefficients, the last problem, the rounds and whether no window binds.
    """
    cache = cache if cache is not None else NlpCache()
    layout = DesignLayout.build(transcriber.layout.nodes, symmetric=symmetric)
    x, outside = checked_design(transcriber, layout, x0)
    segments = instant_segments(transcriber, layout, x)
    w, multipliers, iterations, seconds = w0, None, 0, 0.0
    for k in range(1, rounds + 1):
        nlp = cache.nlp(transcriber, reference, settings, symmetric=symmetric, segments=segments)
        if k == 1 and warm is not None and warm.fits(nlp):
            w, multipliers = warm.w, (warm.lam_g, warm.lam_x)
        out = solve(nlp, x, settings, w0=w, multipliers=multipliers, options=options, report=report, device=device,
                    optimal_device=optimal_device, deadline=deadline, cache=cache, transcriber=transcriber)
        if k == 1:
            outside = outside.merged(out.outside)
        iterations, seconds = iterations + out.iterations, seconds + out.time_s
        x, w = nlp.design(out.x), out.x
        segments = moved_windows(nlp, out.lam_g)
        lam_g = out.lam_g.copy()
        lam_g[nlp.groups["windows"]] = 0.0  # the moved windows no longer bind
        multipliers = (lam_g, out.lam_x)
        if segments is None or not out.converged:
            break
    outcome = dataclasses.replace(out, iterations=iterations, time_s=seconds, outside=outside)
    return PredictSolution(outcome=outcome, x=x, device=nlp.device(out.x), nlp=nlp, rounds=k,
                           windows_hold=segments is None)

