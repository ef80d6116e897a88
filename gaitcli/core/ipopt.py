"""IPOPT (bundled with CasADi) with exact derivatives: one interface for every optimisation problem of gaitcli.

The muscle problems (SO, MSO, EID) and the predictive gait build their ``nlpsol`` with :func:`build_solver`
and run it with :func:`solve`, which checks the start against the bounds (:func:`outside_bounds`), clips it
into them, runs IPOPT with interrupts raised (``core/interrupts.py``) and returns one :class:`Outcome`.

Clipping the start changes nothing IPOPT would not do itself (it moves every start component at least
``bound_push`` inside its bounds); it is done here so that the start's distance from the bounds is measured
and reported, not silently absorbed.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.core.interrupts import interrupts_raised
from gaitcli.core.native import prepare_solvers

#: a start component counts as outside its bounds beyond this fraction of max(1, |bound|): IPOPT's own
#: relaxation of the bounds (``bound_relax_factor``), within which its solutions (warm starts) may lie
BOUND_TOLERANCE = 1e-8


@dataclass(frozen=True)
class OutsideBounds:
    """The components of a start outside their bounds, per named block of the variable vector.

    ``blocks``: name → (components outside, components in the block, largest distance outside), in the
    block's own units; only blocks with a component outside are listed.
    """

    blocks: dict[str, tuple[int, int, float]] = field(default_factory=dict)

    def __bool__(self) -> bool:
        return bool(self.blocks)

    @property
    def count(self) -> int:
        """How many components lie outside their bounds."""
        return sum(outside for outside, _, _ in self.blocks.values())

    def merged(self, other: OutsideBounds) -> OutsideBounds:
        """Both reports in one (block names are assumed distinct)."""
        return OutsideBounds({**self.blocks, **other.blocks})

    def describe(self) -> str:
        """One line: "trunk 2 of 27 by up to 0.035; Q 14 of 3280 by up to 0.2" (empty when none)."""
        return "; ".join(f"{name} {outside} of {size} by up to {distance:.3g}"
                         for name, (outside, size, distance) in self.blocks.items())


def outside_bounds(x, low, high, blocks: dict[str, slice] | None = None,
                   tolerance: float = BOUND_TOLERANCE) -> OutsideBounds:
    """Which components of a start lie outside their bounds.

    Parameters
    ----------
    x : array (n,)
        The start.
    low, high : array (n,) or float
        Its bounds (±inf where there is none).
    blocks : dict of str to slice, optional
        The named blocks of ``x`` to report on (default one block, "x").
    tolerance : float
        A component counts as outside beyond ``tolerance``·max(1, |bound|) (:data:`BOUND_TOLERANCE`).

    Returns
    -------
    OutsideBounds
        Per block with a component outside: how many, of how many, and the largest distance (NaN counts as
        outside, at an infinite distance).
    """
    x, low, high = (np.broadcast_to(np.asarray(v, float), np.shape(x)) for v in (x, low, high))
    with np.errstate(invalid="ignore"):
        below = np.where(x < low - tolerance * np.maximum(1.0, np.abs(low)), low - x, 0.0)
        above = np.where(x > high + tolerance * np.maximum(1.0, np.abs(high)), x - high, 0.0)
    distance = np.where(np.isnan(x), np.inf, np.maximum(below, above))
    out = {}
    for name, part in (blocks or {"x": slice(0, x.size)}).items():
        d = distance[part]
        if np.any(d > 0):
            out[name] = (int(np.count_nonzero(d > 0)), int(d.size), float(d.max()))
    return OutsideBounds(out)


@dataclass(frozen=True)
class Outcome:
    """What one IPOPT run (or a chain of runs) returns.

    ``x`` the solution; ``objective`` f(x); ``converged`` IPOPT's success (``Solve_Succeeded`` or
    ``Solved_To_Acceptable_Level``); ``status`` its return status; ``iterations``; ``time_s`` the wall-clock
    time of the run, s; ``lam_g``, ``lam_x`` the multipliers of the constraints and the bounds (a warm start's
    for a later run); ``outside`` the start's components that lay outside the bounds and were clipped.
    """

    x: np.ndarray
    objective: float
    converged: bool
    status: str
    iterations: int
    time_s: float
    lam_g: np.ndarray = field(default_factory=lambda: np.zeros(0))
    lam_x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    outside: OutsideBounds = field(default_factory=OutsideBounds)


def options(*, tol: float, max_iter: int, print_level: int = 0, **extra) -> dict:
    """CasADi/IPOPT options shared by every problem: quiet, adaptive barrier update; ``extra`` as given
    (CasADi names, e.g. ``{"ipopt.acceptable_tol": 1e-4}`` passed as ``**{...}``)."""
    return {"print_time": False, "ipopt.print_level": print_level, "ipopt.sb": "yes", "ipopt.tol": tol,
            "ipopt.max_iter": max_iter, "ipopt.mu_strategy": "adaptive", **extra}


def build_solver(name: str, problem: dict, opts: dict) -> ca.Function:
    """An IPOPT ``nlpsol`` for ``problem`` ({"x", "f", "g"[, "p"]}: min f(x, p) s.t. lbg ≤ g(x, p) ≤ ubg,
    lbx ≤ x ≤ ubx) with the options ``opts`` (:func:`options`), in a process prepared for MUMPS
    (:func:`gaitcli.core.native.prepare_solvers`)."""
    prepare_solvers()
    return ca.nlpsol(name, "ipopt", problem, opts)


def solve(solver: ca.Function, x0, lbx, ubx, lbg, ubg, p=None, *, lam_g0=None, lam_x0=None,
          blocks: dict[str, slice] | None = None) -> Outcome:
    """Run ``solver`` from ``x0`` clipped into its bounds, interrupts raised (``core/interrupts.py``).

    Parameters
    ----------
    solver : casadi.Function
        An IPOPT ``nlpsol`` (:func:`build_solver`).
    x0 : array (n,)
        The start; what lies outside [``lbx``, ``ubx``] is reported (:func:`outside_bounds`) and clipped.
    lbx, ubx, lbg, ubg : array or float
        The bounds of x and of g(x, p).
    p : array, optional
        The problem's parameters.
    lam_g0, lam_x0 : array, optional
        An earlier run's multipliers, for a warm start (both or neither).
    blocks : dict of str to slice, optional
        The named blocks of x that ``outside`` reports on.

    Returns
    -------
    Outcome
        The solution, IPOPT's status and counts, the multipliers and what the start had outside its bounds.
    """
    x0 = np.asarray(x0, float)
    outside = outside_bounds(x0, lbx, ubx, blocks)
    args = {"x0": np.clip(x0, lbx, ubx), "lbx": lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg}
    if p is not None:
        args["p"] = p
    if lam_g0 is not None:
        args.update({"lam_g0": lam_g0, "lam_x0": lam_x0})
    start = time.perf_counter()
    with interrupts_raised():  # an interrupted solve is no result (core/interrupts.py)
        sol = solver(**args)
    elapsed = time.perf_counter() - start
    stats = solver.stats()
    return Outcome(x=np.array(sol["x"]).ravel(), objective=float(sol["f"]),
                   converged=bool(stats.get("success", False)), status=str(stats.get("return_status", "")),
                   iterations=int(stats.get("iter_count", -1)), time_s=elapsed,
                   lam_g=np.array(sol["lam_g"]).ravel(), lam_x=np.array(sol["lam_x"]).ravel(), outside=outside)
