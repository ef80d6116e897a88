"""The optimal prosthesis from its warm starts and multi-start (Diss. 5.3.2, 5.3.3): pure functions of one
prediction's starts; running many of them at once is :mod:`gaitcli.run.studies`'s.

- :func:`predict_optimal` — ``--prosthesis optimal``: the device's six coefficients free (``variables.py``'s D),
  started from the best commercial foot's solution and from the normal (intact) solution; the result is never worse
  than the best start, which is itself a feasible point of the optimal problem (its coefficients lie inside
  the bounds and its τ_s decreases over the declared range).
- :func:`perturbed_guess`, :func:`solve_start` — ``--starts N``: seeded perturbations of the initial guess; the
  best converged solution is kept and :func:`agreeing` counts the starts that found it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from gaitcli.predict.ankle_law import ProsthesisLaw
from gaitcli.predict.guess import initial_guess
from gaitcli.predict.layout import DesignLayout, box_bounds
from gaitcli.predict.model import WalkerParameters, WalkingModel
from gaitcli.predict.muscles import present_muscles
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.prosthesis import COMMERCIAL_FEET
from gaitcli.predict.solve import NlpCache
from gaitcli.predict.stage import PredictConfig, PredictResult, run_predict, settings_of
from gaitcli.signal.bands import Band

#: two solutions "agree" when their objectives differ by less than this fraction of the better one
AGREEMENT = 0.01
#: the relative size of a start's perturbation: durations and step ×(1 ± 10 %), angles ± 0.1 rad, ŝ ± 0.1
PERTURBATION = {"durations": 0.10, "steps": 0.05, "angles_rad": 0.10, "stretch": 0.10}


def better(a: PredictResult | None, b: PredictResult | None) -> PredictResult | None:
    """The better of two results: converged before unconverged, then the lower objective J."""
    if a is None or b is None:
        return a if b is None else b
    return min((a, b), key=lambda r: (not r.converged, r.objective))


def as_optimal(start: PredictResult, note: str) -> PredictResult:
    """A commercial-foot (or other) solution as the optimal problem's result: its coefficients are a feasible
    device, and the optimal run did not improve on it."""
    curve = start.prosthesis.with_values(f"optimal (= {start.prosthesis.name})", start.prosthesis.coefficients())
    return dataclasses.replace(start, prosthesis=curve, history=start.history + (note,))


def predict_optimal(cfg: PredictConfig, *, params: WalkerParameters | None, reference: Band,
                    init: np.ndarray | None = None, report=None,
                    feet: dict[str, PredictResult] | None = None,
                    normal: PredictResult | None = None, cache: NlpCache | None = None) -> PredictResult:
    """``--prosthesis optimal`` (5.3.3): the free device warm started from the best commercial foot's solution
    (its χ and its coefficients) and, when that run does not improve on the foot, from the normal solution (with
    that foot's coefficients).

    Parameters
    ----------
    cfg : PredictConfig
        The optimal case (``prosthesis: optimal``).
    params, reference, report
        As :func:`~gaitcli.predict.stage.run_predict`.
    init : array, optional
        Where the normal gait starts when ``normal`` is not given (default: the default guess).
    feet : dict, optional
        The commercial feet's results by name; solved here when not given, each from the normal solution.
    normal : PredictResult, optional
        The normal gait at the same F_max; solved here when not given.
    cache : NlpCache, optional
        The runner's (:func:`~gaitcli.predict.stage.run_predict`; default: one shared by these runs).

    Returns
    -------
    PredictResult
        The best of the optimal runs and of the best foot, which is itself a point of the optimal problem: an
        optimal run never reports a higher J than the foot it started from.
    """
    cache = cache if cache is not None else NlpCache()
    if normal is None:
        normal = run_predict(dataclasses.replace(cfg, prosthesis="none", strength_scale=cfg.strength()),
                             params=params, reference=reference, init=init, report=report, cache=cache)
    if feet is None:  # each foot from the normal solution, as a study does
        feet = {name: run_predict(dataclasses.replace(cfg, prosthesis=name), params=params, reference=reference,
                                  init=normal.design, report=report, cache=cache) for name in COMMERCIAL_FEET}
    best_foot = None
    for result in feet.values():
        best_foot = better(best_foot, result)
    device = best_foot.prosthesis
    optimal_device = device.with_values("optimal", device.coefficients())
    chosen, history = None, []
    for label, start in ((f"the {device.name} solution", best_foot), ("the normal solution", normal)):
        if start is None or (chosen is not None and chosen.converged and chosen.objective < best_foot.objective):
            continue  # the normal solution only when the start from the best foot did not improve on it
        run = run_predict(cfg, params=params, reference=reference, init=start.design, report=report,
                          device=optimal_device, cache=cache)
        history.append(f"predict: optimal prosthesis from {label}: J {run.objective:.4g}"
                       f"{'' if run.converged else ' (not converged)'}")
        chosen = better(chosen, run)
    if best_foot.converged and (not chosen.converged or chosen.objective > best_foot.objective):
        return as_optimal(best_foot, f"predict: the optimal runs ended above the {device.name} solution's J "
                                     f"{best_foot.objective:.4g} (" + "; ".join(history) + "): kept that solution")
    return dataclasses.replace(chosen, history=chosen.history + tuple(history))


def perturbed_guess(cfg: PredictConfig, params: WalkerParameters | None, reference: Band,
                    seed: int) -> np.ndarray:
    """The default initial guess χ with seeded perturbations of :data:`PERTURBATION` (normal noise, clipped
    into the bounds; the durations rescaled so that the speed holds)."""
    layout = DesignLayout.build(cfg.nodes, symmetric=cfg.symmetric)
    transcriber = Transcriber(cfg.nodes, model=WalkingModel(cfg.walker_parameters(params)))
    x = initial_guess(transcriber, reference, settings_of(cfg), symmetric=cfg.symmetric)
    rng = np.random.default_rng(seed)
    blocks = layout.unpack(x)
    for name in ("coordinates", "right_leg", "trunk"):
        if name in blocks:
            v = blocks[name]
            angle_columns = slice(2, None) if name == "coordinates" else (slice(0, None) if name == "right_leg"
                                                                          else slice(2, 3))
            v[:, angle_columns] += PERTURBATION["angles_rad"] * rng.standard_normal(v[:, angle_columns].shape)
    for name in ("tendon_stretch", "right_stretch"):
        if name in blocks:
            blocks[name] += PERTURBATION["stretch"] * rng.standard_normal(blocks[name].shape)
    steps = blocks["steps"] * (1 + PERTURBATION["steps"] * rng.standard_normal(blocks["steps"].shape))
    durations = blocks["durations"] * (1 + PERTURBATION["durations"] * rng.standard_normal(blocks["durations"].shape))
    period = (float(np.sum(steps)) * (2 if cfg.symmetric else 1)) / cfg.speed_m_s
    blocks["durations"] = durations * period / (float(np.sum(durations)) * (2 if cfg.symmetric else 1))
    blocks["steps"] = steps
    low, high = box_bounds(layout, present_muscles(cfg.prosthetic))
    return np.clip(layout.pack(blocks), low, high)


def solve_start(cfg: PredictConfig, *, params: WalkerParameters | None, reference: Band, seed: int | None,
                device: ProsthesisLaw | None = None, init: np.ndarray | None = None,
                cache: NlpCache | None = None) -> PredictResult:
    """One start of ``--starts N``: from ``init`` (default: the default guess) when ``seed`` is None, else from
    :func:`perturbed_guess` with that seed; the optimal prosthesis by :func:`predict_optimal`. ``cache``: the
    runner's built problems (:func:`~gaitcli.predict.stage.run_predict`)."""
    init = init if seed is None else perturbed_guess(cfg, params, reference, seed)
    if cfg.prosthesis == "optimal":
        return predict_optimal(cfg, params=params, reference=reference, init=init, cache=cache)
    return run_predict(cfg, params=params, reference=reference, init=init, device=device, cache=cache)


def start_seeds(cfg: PredictConfig) -> list[int | None]:
    """The seeds of ``cfg.starts`` starts: None (the start itself) for the first, ``cfg.seed + k`` for start k."""
    return [None if k == 0 else cfg.seed + k for k in range(cfg.starts)]


def agreeing(results: list[PredictResult], tolerance: float = AGREEMENT) -> tuple[int, PredictResult]:
    """(how many converged starts reached the best converged J within ``tolerance`` of it, the best result)."""
    best = None
    for r in results:
        best = better(best, r)
    if not best.converged:
        return 0, best
    count = sum(1 for r in results if r.converged and r.objective <= best.objective * (1 + tolerance))
    return count, best
