"""Prediction studies (Diss. 5.3.2, 5.3.3): the optimal prosthesis from its warm starts, multi-start, study grids.

- :func:`predict_optimal` — ``--prosthesis optimal``: the device's six coefficients free (``variables.py``'s D), started
  from the best commercial foot's solution and from the normal (intact) solution; the result is never worse
  than the best start, which is itself a feasible point of the optimal problem (its coefficients lie inside
  the bounds and its τ_s decreases over the declared range).
- :func:`perturbed_guess`, :func:`run_starts` — ``--starts N``: seeded perturbations of the initial guess solved
  in parallel processes; the best converged solution is kept and :func:`agreeing` counts the starts that
  found it.
- :class:`StudySpec`, :func:`study_cases` — ``--study FILE.yaml``: speeds × weight sets × conditions, ordered in
  chains (one per speed, run in parallel): per weight set the normal case first (from the previous weight
  set's normal solution), every other case warm started from it, except the second and third commercial
  feet: they start from the first foot's solution when it converged (else from the normal one), the optimal
  prosthesis last from the best foot and the normal solution. Why the feet from a foot: the normal gait's
  ankle angles put Seattle's τ_s (a_p = −34020 N·m/rad³) hundreds of N·m off, and IPOPT from there spends
  6 s per iteration in inertia corrections (measured at 1.00 m/s, weights a): 67 iterations in 400 s, J 179);
  from the SACH solution it converges in 83 iterations, 25 s (J 22.48), and Flex in 142 iterations, 42 s.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field

import numpy as np

from gaitcli.core.interrupts import as_worker
from gaitcli.core.validate import check_parameter, one_of
from gaitcli.errors import InputError, shown
from gaitcli.predict.guess import initial_guess
from gaitcli.predict.layout import DesignLayout, box_bounds
from gaitcli.predict.model import WalkerParameters, WalkingModel
from gaitcli.predict.muscles import present_muscles
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.prosthesis import COMMERCIAL_FEET, ProsthesisCurve
from gaitcli.predict.reference import Reference
from gaitcli.predict.solve import NlpCache
from gaitcli.predict.stage import PredictConfig, PredictResult, run_predict, settings_of, weight_pair

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
    curve = ProsthesisCurve(f"optimal (= {start.prosthesis.name})", *start.prosthesis.coefficients())
    return dataclasses.replace(start, prosthesis=curve, history=start.history + (note,))


def predict_optimal(cfg: PredictConfig, *, params: WalkerParameters | None, reference: Reference,
                    init: np.ndarray | None = None, report=None,
                    feet: dict[str, PredictResult] | None = None,
                    normal: PredictResult | None = None, cache: NlpCache | None = None) -> PredictResult:
    """``--prosthesis optimal`` (5.3.3): the free device warm started from the best commercial foot's solution
    (its χ and its coefficients) and, when that run does not improve on the foot, from the normal solution (with
    that foot's coefficients). ``feet``
    (name → result) and ``normal`` are solved here when not given: the normal gait (same F_max) from ``init``
or the default guess, each foot from it. The
    result is the best of the optimal runs and of the best foot, which is itself a point of the optimal
    problem: an optimal run never reports a higher J than the foot it started from. ``cache``: the runner's
    (:func:`~gaitcli.predict.stage.run_predict`; default: one shared by these runs)."""
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
    optimal_device = ProsthesisCurve("optimal", *device.coefficients())
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


def perturbed_guess(cfg: PredictConfig, params: WalkerParameters | None, reference: Reference,
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


def retimed(cfg: PredictConfig, x: np.ndarray) -> np.ndarray:
    """χ ``x`` (a solution at another speed) with its phase durations scaled so that it walks at
    ``cfg.speed_m_s`` (5.43, ΣT = ΔS/v): a start for a neighbouring case."""
    layout = DesignLayout.build(cfg.nodes, symmetric=cfg.symmetric)
    blocks = layout.unpack(np.array(x, float))
    period = float(layout.phase_durations(x).sum())
    blocks["durations"] = blocks["durations"] * (sum(layout.step_lengths(x)) / cfg.speed_m_s) / period
    return layout.pack(blocks)


def _one_start(args) -> PredictResult:
    cfg, params, reference, seed, device, init = args
    init = init if seed is None else perturbed_guess(cfg, params, reference, seed)
    if cfg.prosthesis == "optimal":
        return predict_optimal(cfg, params=params, reference=reference, init=init)
    return run_predict(cfg, params=params, reference=reference, init=init, device=device)


def pool(workers: int) -> ProcessPoolExecutor:
    """Worker processes (forked where the platform allows: no re-import, the parent's thread settings) that end
    with their parent and leave interrupts to it (:func:`~gaitcli.core.interrupts.as_worker`)."""
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    return ProcessPoolExecutor(max_workers=max(1, workers), mp_context=multiprocessing.get_context(method),
                               initializer=as_worker, initargs=(os.getpid(),))


#: how long stopped workers get to unwind (remove their temporary folders) before they are killed
STOP_GRACE_S = 1.0


def stop(executor: ProcessPoolExecutor) -> None:
    """Cancel what has not started and end the workers now (an interrupt of the parent: SIGTERM reaches the
    parent alone): SIGTERM, which unwinds a worker's run (its atomic writes leave nothing half-written), then
    SIGKILL after :data:`STOP_GRACE_S` for any still running, which a worker that caught the interrupt in
    a solve and took its next queued task would be."""
    # no public API ends running workers; shutdown() sets _processes to None, so take them first. SIGTERM before
    # shutdown(): shutdown closes the task queue, and an idle worker reading it would die of EOFError, loudly
    processes = list((getattr(executor, "_processes", None) or {}).values())
    for process in processes:
        process.terminate()
    executor.shutdown(wait=False, cancel_futures=True)
    deadline = time.monotonic() + STOP_GRACE_S
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.kill()
            process.join(1.0)


def run_starts(cfg: PredictConfig, starts: int, *, params: WalkerParameters | None, reference: Reference,
               seed: int = 0, workers: int | None = None, device: ProsthesisCurve | None = None,
               init: np.ndarray | None = None, on_done=None, executor=None) -> list[PredictResult]:
    """``starts`` solves of ``cfg`` in parallel processes (or on ``executor``, a ``concurrent.futures`` executor
    such as a Dask client's): start 0 from ``init`` (default: the default guess), start k from
    :func:`perturbed_guess` with seed ``seed + k``. ``on_done(k, result)`` as each finishes."""
    jobs = [(cfg, params, reference, None if k == 0 else seed + k, device, init) for k in range(starts)]
    workers = min(starts, workers or os.cpu_count() or 1)
    if executor is not None:
        return _run_on(executor, jobs, on_done)
    if workers <= 1:
        results = []
        for k, job in enumerate(jobs):
            results.append(_one_start(job))
            if on_done:
                on_done(k, results[-1])
        return results
    with pool(workers) as executor:
        return _run_on(executor, jobs, on_done, stop)


def _run_on(executor, jobs, on_done, stopping=None) -> list[PredictResult]:
    """The starts as tasks of ``executor``; on an interrupt what has not started is cancelled (and ``stopping``
    ends the running ones, for a process pool)."""
    results: list = [None] * len(jobs)
    try:
        futures = {executor.submit(_one_start, job): k for k, job in enumerate(jobs)}
        for future in as_completed(futures):
            k = futures[future]
            results[k] = future.result()
            if on_done:
                on_done(k, results[k])
    except BaseException:
        (stopping or (lambda e: e.shutdown(wait=False, cancel_futures=True)))(executor)
        raise
    return results


def agreeing(results: list[PredictResult], tolerance: float = AGREEMENT) -> tuple[int, PredictResult]:
    """(how many converged starts reached the best converged J within ``tolerance`` of it, the best result)."""
    best = None
    for r in results:
        best = better(best, r)
    if not best.converged:
        return 0, best
    count = sum(1 for r in results if r.converged and r.objective <= best.objective * (1 + tolerance))
    return count, best


# ----------------------------------------------------------------------------------------------- study grids
CONDITIONS = ("normal", "foot_mass", *COMMERCIAL_FEET, "optimal")
#: Table 5.2/5.3's weight sets a)–d) (5.3.1), read as the command line reads --weights
WEIGHT_SETS = {k: weight_pair(v) for k, v in {"a": "1,1", "b": "4/3,2/3", "c": "8/5,2/5", "d": "20/11,2/11"}.items()}


@dataclass(frozen=True)
class StudySpec:
    """A study file (``--study``): speeds (m/s) × weight sets × conditions, and what every case shares.

    ``weights``: labels of :data:`WEIGHT_SETS` or "W1,W2" strings; ``conditions``: of :data:`CONDITIONS`;
    ``strength_scale``: every case's F_max scale, the normal one's included (5.3.3: 1.5; 0: each condition's
    default); ``foot_mass_kg``: the foot_mass condition's added mass (5.3.2: 2); ``starts``: solves per case;
    ``time_limit_s``: each case's wall-clock budget (s; 0: none).
    """

    name: str
    speeds_m_s: tuple[float, ...]
    weights: tuple[str, ...]
    conditions: tuple[str, ...]
    nodes: int = 18
    strength_scale: float = 0.0
    foot_mass_kg: float = 2.0
    starts: int = 1
    max_iterations: int = 3000
    time_limit_s: float = 0.0

    @classmethod
    def from_mapping(cls, data, path) -> StudySpec:
        """The spec of a study file's contents (an InputError naming ``path`` and the field otherwise)."""
        if not isinstance(data, dict):
            raise InputError(path, "study", f"got {shown(data)} (expected a mapping: name, speeds_m_s, weights, "
                                            "conditions)")
        known = {f.name for f in dataclasses.fields(cls)}
        for key in data:
            if key not in known:
                raise InputError(path, str(key), f"unknown key (expected {', '.join(sorted(known))})")

        def listed(key, kind):
            value = data.get(key)
            if not isinstance(value, list) or not value:
                raise InputError(path, key, f"got {shown(value)} (expected a non-empty list)")
            return tuple(kind(v) for v in value)

        def speed(v):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v <= 3:
                raise InputError(path, "speeds_m_s", f"got {shown(v)} (expected speeds in m/s, 0 < v ≤ 3)")
            return float(v)

        weights_field = next(f for f in dataclasses.fields(PredictConfig) if f.name == "weights")

        def weight(v):
            if str(v) not in WEIGHT_SETS:
                check_parameter(weights_field, v, where="weights", path=path)
            return str(v)

        def condition(v):
            return one_of(str(v), CONDITIONS, where="conditions", path=path)

        spec = {"name": str(data.get("name", "study")), "speeds_m_s": listed("speeds_m_s", speed),
                "weights": listed("weights", weight), "conditions": listed("conditions", condition)}
        for key, kind, low, high in (("nodes", int, 6, 40), ("strength_scale", float, 0.0, 5.0),
                                     ("foot_mass_kg", float, 0.0, 20.0), ("starts", int, 1, 100),
                                     ("max_iterations", int, 1, 100000), ("time_limit_s", float, 0.0, 1e6)):
            if key in data:
                value = data[key]
                if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high \
                        or (kind is int and value != int(value)):
                    raise InputError(path, key, f"got {shown(value)} (expected {kind.__name__} in [{low}, {high}])")
                spec[key] = kind(value)
        if "optimal" in spec["conditions"] and not set(COMMERCIAL_FEET) <= set(spec["conditions"]):
            raise InputError(path, "conditions", "optimal needs sach, seattle and flex as well (its warm starts, "
                                                 "5.3.3)")
        return cls(**spec)


@dataclass(frozen=True)
class StudyCase:
    """One case of a study: its folder name, labels and configuration; ``starts_from``: the cases (of its chain)
    whose solutions start it."""

    name: str
    speed_m_s: float
    weight_set: str
    condition: str
    cfg: PredictConfig
    starts_from: tuple[str, ...] = field(default=())


def weight_label(weights: tuple[float, float], given: str) -> str:
    """A weight set's label: "a"–"d" for Table 5.2's sets, else the "W1,W2" text ``given``."""
    return next((k for k, v in WEIGHT_SETS.items() if v == weights), given)


def study_cases(spec: StudySpec) -> list[list[StudyCase]]:
    """The study's cases in chains, one per speed: for each weight set in turn, the normal case (started from
    the previous weight set's normal solution; the chain's first from the default guess), every other condition
    from that normal solution except the second and third feet (from the first foot's solution, then the normal
    one: module docstring), and the optimal prosthesis last (from the feet and the normal solution)."""
    chains = []
    for speed in spec.speeds_m_s:
        chain, previous = [], None
        for w in spec.weights:
            weights = WEIGHT_SETS.get(w) or weight_pair(w)
            label = weight_label(weights, w)
            base = dataclasses.replace(PredictConfig(), speed_m_s=speed, weights=weights, nodes=spec.nodes,
                                       max_iterations=spec.max_iterations, time_limit_s=spec.time_limit_s,
                                       strength_scale=spec.strength_scale)
            prefix = f"v{speed:.2f}_{label.replace(',', '-').replace('/', '_')}"
            normal = f"{prefix}_normal"
            order = ["normal"] + [c for c in spec.conditions if c not in ("normal", "optimal")] + \
                    (["optimal"] if "optimal" in spec.conditions else [])
            for condition in order:
                if condition == "normal":
                    cfg, starts = base, (() if previous is None else (previous,))
                elif condition == "foot_mass":
                    cfg, starts = dataclasses.replace(base, foot_mass_kg=spec.foot_mass_kg), (normal,)
                elif condition == "optimal":
                    cfg = dataclasses.replace(base, prosthesis="optimal")
                    starts = tuple(f"{prefix}_{f}" for f in COMMERCIAL_FEET) + (normal,)
                else:  # the first foot from the normal solution, the others from the first foot's (module doc)
                    feet = [c for c in order if c in COMMERCIAL_FEET]
                    first_foot = f"{prefix}_{feet[0]}"
                    cfg = dataclasses.replace(base, prosthesis=condition)
                    starts = (normal,) if condition == feet[0] else (first_foot, normal)
                chain.append(StudyCase(f"{prefix}_{condition}", speed, label, condition, cfg, starts))
            previous = normal
        chains.append(chain)
    return chains
