"""Prediction studies and multi-start (Diss. 5.3.2, 5.3.3): a study file's grid, its cases and their execution,
and the best of ``gait predict --starts N``.

A study file (``gait predict --study FILE.yaml``; ``pipelines/study_*.yaml``) names speeds (m/s) × weight sets ×
conditions and the settings every case shares; each value is checked as the predict stage's own
(:func:`gaitcli.core.validate.check_parameter`), an error naming the file and its key. :func:`study_cases` orders
the cases in chains, one per speed: per weight set the normal case first (from the previous weight set's normal
solution; the chain's first from ``gait predict``'s default start, the shipped walk), every other case warm started
from it, except the added foot mass and the commercial feet: the foot mass and the first foot from the previous
weight set's foot mass or first foot when that converged (the chain's first from the normal solution), the second
and third feet from the first foot's solution when it converged (else from the normal one), and the optimal
prosthesis last from the feet and the normal solution. Why the feet from a foot: the normal gait's ankle angles put
Seattle's τ_s (a_p = −34020 N·m/rad³) hundreds of N·m off, where IPOPT spends its iterations in inertia corrections;
from the SACH solution it converges many times faster, and SACH at 1.00 m/s, c), from the SACH solution of b) in 139
iterations where from the normal solution it stalled at J 119; d) with 2 kg per foot from d)'s normal solution
stopped at the 150-s limit, from c)'s 2 kg solution it converged in 83 iterations (``benchmarks/README.md``,
"Prediction").

Once every chain is done, a case other than the optimal device that did not converge is solved once more from
the nearest converged case of its condition (:func:`retry_start`: another weight set at its speed, else its
weight set at another speed), a start its chain did not have; the new result replaces the first where it
converges (:func:`retry_case`). At 1.33 m/s, weights a), SACH from the normal solution stopped at the 150-s limit
at J 39.4; from SACH's b) solution it converged in 110 iterations, 20 s (J 18.90; ``benchmarks/README.md``).

Every case is a task on the workers (:func:`gaitcli.run.cluster.workers`), started once the cases it starts
from are done, and written whole into ``OUT/study/<case>/`` (the files of ``gait predict``) with a
``case_key``: the SHA-256 of its resolved configuration, the subject, the reference and the keys of the cases
it started from. A case whose folder holds the same key is read back instead of solved again, so a rerun (or
a run after an interrupt) does only what is missing. ``study.csv`` has one row per case, unconverged ones
included and marked.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gaitcli.core.registry import Progress, ProgressCallback, no_progress
from gaitcli.core.validate import check_parameter, known_keys, one_of, replace_checked
from gaitcli.errors import InputError, shown
from gaitcli.io.atomic import check_output_folder, remove_stale
from gaitcli.io.h5 import provenance, read_result
from gaitcli.io.outputs import stage_folder, write_json, write_table
from gaitcli.predict.guess import SHIPPED_WALK, SPEED_WALKS
from gaitcli.predict.prosthesis import COMMERCIAL_FEET
from gaitcli.predict.reference import read_reference
from gaitcli.predict.stage import PredictConfig, PredictResult, run_predict, weight_pair
from gaitcli.predict.starts import agreeing, predict_optimal, solve_start, start_seeds
from gaitcli.run.cluster import Task, Workers, completed, map_in_order, workers
from gaitcli.run.config import PipelineConfig, to_yaml
from gaitcli.run.stages import prediction_cache

#: a study's conditions (5.3.2, 5.3.3)
CONDITIONS = ("normal", "foot_mass", *COMMERCIAL_FEET, "optimal")
#: Table 5.2/5.3's weight sets a)–d) (5.3.1), read as the predict stage reads its weights
WEIGHT_SETS = {k: weight_pair(v) for k, v in {"a": "1,1", "b": "4/3,2/3", "c": "8/5,2/5", "d": "20/11,2/11"}.items()}
#: the predict settings a study file may set for every case
SHARED = ("nodes", "strength_scale", "starts", "max_iterations", "time_limit_s")
#: a study file's keys
KEYS = ("name", "speeds_m_s", "weights", "conditions", "foot_mass_kg", "references", *SHARED)
#: the most values a study's list may hold (Table 5.3's grid: 3 speeds, 4 weight sets, 5 conditions)
MAX_GRID_VALUES = 100
#: the most cases a study may hold (speeds × weight sets × conditions)
MAX_CASES = 1000
#: the foot_mass condition's added mass per foot, kg (5.3.2)
FOOT_MASS_KG = 2.0
#: study.csv's columns after the case's labels
FIGURES = ("objective", "cost_of_transport_J_per_m", "deviation")


def _field(name: str) -> dataclasses.Field:
    return next(f for f in dataclasses.fields(PredictConfig) if f.name == name)


@dataclass(frozen=True)
class StudySpec:
    """A study file: speeds (m/s) × weight sets × conditions; ``weights``: (label, (w1, w2)) per set, the label
    "a"–"d" for Table 5.2's sets, else the file's text; ``foot_mass_kg``: the foot_mass condition's added mass;
    ``base``: what every case shares (the predict defaults with the file's :data:`SHARED` settings);
    ``references``: (speed, file) where a speed tracks its own reference (5.3.3: Winter's slow, natural and fast
    cadence at 1.00, 1.33 and 1.68 m/s), the file's path resolved against the study file's folder; the other
    speeds track the run's."""

    name: str
    speeds_m_s: tuple[float, ...]
    weights: tuple[tuple[str, tuple[float, float]], ...]
    conditions: tuple[str, ...]
    foot_mass_kg: float = FOOT_MASS_KG
    base: PredictConfig = field(default_factory=PredictConfig)
    references: tuple[tuple[float, Path], ...] = ()

    @classmethod
    def from_mapping(cls, data, path) -> StudySpec:
        """The spec of a study file's contents (an InputError naming ``path`` and the key otherwise)."""
        if not isinstance(data, dict):
            raise InputError(path, "study", f"got {shown(data)} (expected a mapping: name, speeds_m_s, weights, "
                                            "conditions)")
        known_keys(data, KEYS, path=path)

        def listed(key):
            value = data.get(key)
            if not isinstance(value, list) or not value:
                raise InputError(path, key, f"got {shown(value)} (expected a non-empty list)")
            if len(value) > MAX_GRID_VALUES:
                raise InputError(path, key, f"{len(value):,} values (expected at most {MAX_GRID_VALUES} per list)")
            return value

        def distinct(key, values):
            seen = {}
            for v in values:
                if v in seen:
                    raise InputError(path, key, f"{shown(v)} is given twice (expected each value once)")
                seen[v] = None
            return values

        def weight_set(v):
            if isinstance(v, str) and v in WEIGHT_SETS:
                return v, WEIGHT_SETS[v]
            pair = check_parameter(_field("weights"), v, where="weights", path=path)
            label = next((k for k, w in WEIGHT_SETS.items() if w == pair), None)
            return label or (v if isinstance(v, str) else ",".join(f"{w:g}" for w in pair)), pair

        conditions = distinct("conditions", tuple(one_of(str(v), CONDITIONS, where="conditions", path=path)
                                                  for v in listed("conditions")))
        if "optimal" in conditions and not set(COMMERCIAL_FEET) <= set(conditions):
            raise InputError(path, "conditions", f"optimal needs {', '.join(COMMERCIAL_FEET)} as well (its warm "
                                                 "starts, 5.3.3)")
        foot_mass = data.get("foot_mass_kg", FOOT_MASS_KG)
        speeds = distinct("speeds_m_s", tuple(check_parameter(_field("speed_m_s"), v, where="speeds_m_s", path=path)
                                              for v in listed("speeds_m_s")))
        weights = tuple(weight_set(v) for v in listed("weights"))
        distinct("weights", tuple(pair for _, pair in weights))
        cases = len(speeds) * len(weights) * len(conditions)
        if cases > MAX_CASES:
            raise InputError(path, "study", f"{len(speeds)} speeds × {len(weights)} weight sets × {len(conditions)} "
                                            f"conditions = {cases:,} cases (expected at most {MAX_CASES:,})")
        return cls(name=str(data.get("name", "study")), speeds_m_s=speeds, references=_references(data, speeds, path),
                   weights=weights, conditions=conditions,
                   foot_mass_kg=check_parameter(_field("foot_mass_kg"), foot_mass, where="foot_mass_kg", path=path),
                   base=replace_checked(PredictConfig(), {k: data[k] for k in SHARED if k in data}, section=None,
                                        path=path))


def _references(data: dict, speeds: tuple[float, ...], path) -> tuple[tuple[float, Path], ...]:
    """A study file's ``references``: {speed: file}, each speed one of ``speeds_m_s``, each file a reference
    table (``gait reference``) that exists, its path relative to the study file's folder."""
    given = data.get("references", {})
    if not isinstance(given, dict):
        raise InputError(path, "references", f"got {shown(given)} (expected a mapping of a speed in speeds_m_s, "
                                             "m/s, to a reference file)")
    out = []
    for speed, name in given.items():
        match = [v for v in speeds if isinstance(speed, (int, float)) and abs(v - speed) < 1e-9]
        if not match:
            raise InputError(path, "references", f"got the speed {shown(speed)} (expected one of speeds_m_s: "
                                                 f"{', '.join(f'{v:g}' for v in speeds)})")
        if not isinstance(name, str) or not name:
            raise InputError(path, f"references: {speed:g}", f"got {shown(name)} (expected a reference file)")
        file = Path(path).parent / name
        if not file.is_file():
            raise InputError(path, f"references: {speed:g}", f"{file}: file not found (expected a reference "
                                                               "table, gait reference)")
        out.append((match[0], file))
    return tuple(out)


def read_study(path: Path) -> StudySpec:
    """The study file at ``path``, validated."""
    from gaitcli.io.yamlfile import read_yaml

    if not Path(path).is_file():
        raise InputError(path, "--study", "file not found (expected a study YAML: name, speeds_m_s, weights, "
                                          "conditions)")
    return StudySpec.from_mapping(read_yaml(path), path)


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


def study_cases(spec: StudySpec) -> list[list[StudyCase]]:
    """The study's cases in chains, one per speed, in the order of the module docstring."""
    chains = []
    for speed in spec.speeds_m_s:
        chain, previous, previous_foot, previous_mass = [], None, None, None
        for label, weights in spec.weights:
            base = dataclasses.replace(spec.base, speed_m_s=speed, weights=weights)
            prefix = f"v{speed:.2f}_{label.replace(',', '-').replace('/', '_')}"
            normal = f"{prefix}_normal"
            order = ["normal"] + [c for c in spec.conditions if c not in ("normal", "optimal")] + \
                    (["optimal"] if "optimal" in spec.conditions else [])
            for condition in order:
                if condition == "normal":
                    cfg, starts = base, (() if previous is None else (previous,))
                elif condition == "foot_mass":  # as the first foot: from the last weight set's, else the normal
                    cfg = dataclasses.replace(base, foot_mass_kg=spec.foot_mass_kg)
                    starts = (normal,) if previous_mass is None else (previous_mass, normal)
                    previous_mass = f"{prefix}_{condition}"
                elif condition == "optimal":
                    cfg = dataclasses.replace(base, prosthesis="optimal")
                    starts = tuple(f"{prefix}_{f}" for f in COMMERCIAL_FEET) + (normal,)
                else:  # the first foot from the last weight set's, the others from the first foot's (module doc)
                    feet = [c for c in order if c in COMMERCIAL_FEET]
                    first_foot = f"{prefix}_{feet[0]}"
                    cfg = dataclasses.replace(base, prosthesis=condition)
                    if condition == feet[0]:
                        starts = (normal,) if previous_foot is None else (previous_foot, normal)
                        previous_foot = first_foot
                    else:
                        starts = (first_foot, normal)
                chain.append(StudyCase(f"{prefix}_{condition}", speed, label, condition, cfg, starts))
            previous = normal
        chains.append(chain)
    return chains


def tracked_cases(cases: list[StudyCase], start, references: dict) -> tuple[list[StudyCase], dict]:
    """The cases with the stride bounds of the reference each tracks, and that reference by case name: its
    speed's in ``references`` (a study file's), else the run's (``--reference``, a trial's strides), else the
    shipped one of its speed (:meth:`gaitcli.run.stages.PredictionInputs.at_speed`)."""
    out, tracked = [], {}
    for case in cases:
        cfg, tracked[case.name], _ = start.at_speed(case.cfg, references.get(case.speed_m_s))
        out.append(dataclasses.replace(case, cfg=cfg))
    return out, tracked


def width(cases: list[StudyCase]) -> int:
    """How many of ``cases`` can run at once: the most at one depth of their starts."""
    depth: dict[str, int] = {}
    for case in cases:  # every case after the cases it starts from
        depth[case.name] = 1 + max((depth[n] for n in case.starts_from), default=-1)
    return max(list(depth.values()).count(d) for d in set(depth.values()))


# ---------------------------------------------------------------------------------------------------- one case
def case_key(case: StudyCase, subject: str, reference_sha: str, start_keys: tuple[str, ...]) -> str:
    """The SHA-256 that says a case folder holds this case's result (module docstring)."""
    text = json.dumps({"cfg": dataclasses.asdict(case.cfg), "subject": subject, "reference": reference_sha,
                       "starts": list(start_keys)}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def write_case(folder: Path, result: PredictResult, attrs: dict, extra: dict) -> dict:
    """Write one case's files whole (atomic) with its summary plus ``extra`` (the case key and labels)."""
    from gaitcli.predict.outputs import write_predict_outputs

    with stage_folder(folder) as tmp:
        summary = write_predict_outputs(tmp, result, attrs)
        summary.update(extra)
        write_json(tmp / "summary.json", summary)
    return summary


def _write_solved(folder: Path, case: StudyCase, result: PredictResult, pipeline: PipelineConfig, inputs: dict,
                  key: str, agreed: int, **extra) -> None:
    """:func:`write_case` of a case just solved: its provenance, configuration, key and labels, and ``extra``."""
    attrs = provenance(to_yaml(pipeline.replace_section("predict", case.cfg)), inputs, result.history)
    write_case(folder, result, {**attrs, "predict_config": json.dumps(dataclasses.asdict(case.cfg))},
               {"case_key": key, **extra, "case": case.name, "condition": case.condition,
                "weight_set": case.weight_set, "starts": case.cfg.starts, "starts_agreeing": agreed})


def stored_case(folder: Path, key: str) -> PredictResult | None:
    """The result in ``folder`` when its summary holds ``key`` (as its own, or as the key of the unconverged
    solve its retry replaced, :func:`retry_case`), else None."""
    try:
        summary = json.loads((folder / "summary.json").read_text())
        if key not in (summary.get("case_key"), summary.get("replaces_key")):
            return None
        return read_result(folder / "predict.h5", PredictResult)
    except (InputError, OSError, ValueError, KeyError):
        return None


def _tau(result: PredictResult, y: float) -> float:
    return float(result.prosthesis.spring_moment_Nm(y)) if result.prosthesis is not None else float("nan")


def case_row(case: StudyCase, result: PredictResult, *, reused: bool, wall_s: float, agreed: int = 1,
             built: tuple[int, float] = (0, 0.0)) -> dict:
    """One study.csv row: labels, J, Et, Jdev (control points and fine grid), convergence and the device;
    ``built``: the problems its solve built and the seconds spent building them and their solvers."""
    fine = result.fine_grid or {}
    row = {"case": case.name, "speed_m_s": case.speed_m_s, "weights": case.weight_set, "condition": case.condition,
           "objective": result.objective, "cost_of_transport_J_per_m": result.cost_of_transport_J_per_m,
           "deviation": result.deviation, "stride_m": result.stride_m,
           "cadence_steps_per_min": result.cadence_steps_per_min,
           "fine_cost_of_transport_J_per_m": fine.get("cost_of_transport_J_per_m"),
           "fine_deviation": fine.get("deviation"), "converged": bool(result.converged),
           "iterations": int(result.iterations), "solve_time_s": float(result.solve_time_s),
           "wall_time_s": float(wall_s), "reused": bool(reused), "starts_agreeing": int(agreed),
           "problems_built": int(built[0]), "build_time_s": float(built[1]),
           "tau_s_at_minus_0.1_rad_Nm": _tau(result, -0.1), "tau_s_at_minus_0.2_rad_Nm": _tau(result, -0.2)}
    if result.prosthesis is not None:
        row.update(result.prosthesis.named("prosthesis_"))
    return row


def first_start_keys() -> tuple[str, ...]:
    """The key of a chain's first start, ``gait predict``'s default start: the shipped walks' SHA-256
    (``guess.shipped_walk``: the nearest speed's, fitted to the case's nodes and speed, which its own key holds)."""
    digest = hashlib.sha256()
    for path in (SHIPPED_WALK, *SPEED_WALKS):
        digest.update(path.read_bytes())
    return (f"shipped {digest.hexdigest()}",)


def _solve_case(case: StudyCase, solved: dict, params, reference) -> tuple[PredictResult, int]:
    """Solve one case from the solutions it starts from (``solved``: name → result of its chain so far)."""
    cache = prediction_cache()
    if case.condition == "optimal":
        feet = {name: solved[start] for name, start in zip(COMMERCIAL_FEET, case.starts_from)}
        normal = solved[case.starts_from[-1]]
        return predict_optimal(case.cfg, params=params, reference=reference, feet=feet, normal=normal,
                               cache=cache), 1
    # the first start that converged (a foot after the first: that foot's solution, else the normal one)
    starts = [solved[name] for name in case.starts_from]
    init = next((r for r in starts if r.converged), starts[0]).design if starts else None  # None: the default
    if case.cfg.starts > 1:  # start 0 from the chain's solution, the others from perturbed guesses, one by one
        with workers(1) as here:
            agreed, best = agreeing(run_starts(case.cfg, here, params=params, reference=reference, init=init))
        return best, agreed
    return run_predict(case.cfg, params=params, reference=reference, init=init, cache=cache), 1


def _solve_counting_builds(case: StudyCase, solved: dict, params, reference
                           ) -> tuple[PredictResult, int, tuple[int, float]]:
    """:func:`_solve_case`, with the problems its solve built in this worker's cache and the seconds spent
    building them and their solvers (study.csv's ``problems_built``, ``build_time_s``)."""
    cache = prediction_cache()
    builds, build_s = cache.builds, cache.build_s
    result, agreed = _solve_case(case, solved, params, reference)
    return result, agreed, (cache.builds - builds, cache.build_s - build_s)


def retry_start(case: StudyCase, cases: list[StudyCase], results: dict[str, PredictResult]) -> str | None:
    """Where an unconverged case (not the optimal device's) starts again (None: converged, or no
    such start): the nearest converged case of its condition at its speed (the weight sets' order, the later one
    first: the chain solved it after this case, so it is a start this case did not have), else at the nearest
    other speed with its weight set. The optimal device starts from the feet (:func:`predict_optimal`)."""
    if results[case.name].converged or case.condition == "optimal":
        return None
    order = list(dict.fromkeys(c.weight_set for c in cases))
    same = [c for c in cases if c.condition == case.condition and c.name != case.name
            and c.name not in case.starts_from and results[c.name].converged]
    here = [c for c in same if c.speed_m_s == case.speed_m_s]
    there = [c for c in same if c.speed_m_s != case.speed_m_s and c.weight_set == case.weight_set]
    ranked = sorted(here, key=lambda c: (abs(order.index(c.weight_set) - order.index(case.weight_set)),
                                         order.index(c.weight_set) < order.index(case.weight_set)))
    ranked += sorted(there, key=lambda c: abs(c.speed_m_s - case.speed_m_s))
    return ranked[0].name if ranked else None


def retry_case(case: StudyCase, root: str, params, reference, subject: str, pipeline: PipelineConfig, inputs: dict,
               force: bool, first_try: tuple, start: str, started: tuple) -> tuple[PredictResult, str, dict]:
    """Solve an unconverged case (``first_try``: what :func:`run_case` returned for it) again from the solution of
    case ``start`` (``started``: its run_case return) and keep the new result where it converged, with the key
    its first solve had as ``replaces_key`` (a rerun reads it back there); else the first try stands."""
    began = time.perf_counter()
    again = dataclasses.replace(case, starts_from=(start,))
    key = case_key(again, subject, reference.digest(), (started[1],))
    folder = Path(root) / case.name
    result = None if force else stored_case(folder, key)
    reused = result is not None
    built = (0, 0.0)
    if result is None:
        result, agreed, built = _solve_counting_builds(again, {start: started[0]}, params, reference)
        if not result.converged:
            return first_try
        _write_solved(folder, case, result, pipeline, inputs, key, agreed, replaces_key=first_try[1],
                      started_again_from=start)
    first_row = first_try[2]
    row = case_row(case, result, reused=reused, wall_s=first_row["wall_time_s"] + time.perf_counter() - began,
                   built=(first_row["problems_built"] + built[0], first_row["build_time_s"] + built[1]))
    return result, key, {**row, "started_again_from": start}


def run_case(case: StudyCase, root: str, params, reference, subject: str, pipeline: PipelineConfig, inputs: dict,
             force: bool, first: tuple[str, ...], *starts: tuple) -> tuple[PredictResult, str, dict]:
    """Run (or read back) one case from its starts (what :func:`run_case` returned for each case it
    ``starts_from``, in order): its result, its key and its study.csv row. A task on the study's workers."""
    start = time.perf_counter()
    solved = {name: done[0] for name, done in zip(case.starts_from, starts)}
    key = case_key(case, subject, reference.digest(), tuple(done[1] for done in starts) if case.starts_from else first)
    folder = Path(root) / case.name
    result = None if force else stored_case(folder, key)
    reused = result is not None
    built = (0, 0.0)
    if result is None:
        result, agreed, built = _solve_counting_builds(case, solved, params, reference)
        _write_solved(folder, case, result, pipeline, inputs, key, agreed)
    else:
        agreed = int(json.loads((folder / "summary.json").read_text()).get("starts_agreeing", 1))
    return result, key, case_row(case, result, reused=reused, wall_s=time.perf_counter() - start, agreed=agreed,
                                 built=built)


# ---------------------------------------------------------------------------------------------------- a study
def run_study(trial: Path | None, study_path: Path, cfg: PipelineConfig, *, out: Path | None = None,
              files: dict[str, Path] | None = None, workers_count: int | None = None, scheduler: str | None = None,
              force: bool = False, progress: ProgressCallback = no_progress) -> tuple[list[dict], Path]:
    """``gait predict --study FILE``: every case of the study file into ``OUT/study/``: the case folders,
    study.csv and its figures.

    Parameters
    ----------
    trial : Path or None
        The trial whose subject and idyn output may give the subject and the reference; the subject and the
        reference are the predict stage's (:func:`gaitcli.run.stages.prediction_inputs`).
    study_path : Path
        The study file.
    cfg : PipelineConfig
        The run's configuration, recorded in each case's provenance with the case's own ``predict`` section
        (the cases' settings are the study file's).
    out : Path, optional
        The output root.
    files : dict, optional
        Files named for the run (``subject``, ``reference``, ``init``).
    workers_count, scheduler
        Where the cases run (:func:`gaitcli.run.cluster.workers`).
    force : bool
        Solve every case again, also those already in their folders with the same key.
    progress : callable
        Receives one report per case done.

    Returns
    -------
    (list of dict, Path)
        study.csv's rows in study order, and the study folder.
    """
    from gaitcli.report.study_plots import study_figures
    from gaitcli.run.pipeline import TrialRun
    from gaitcli.run.stages import prediction_inputs

    spec = read_study(study_path)
    references = {speed: read_reference(file) for speed, file in spec.references}  # checked before any output
    run = TrialRun(trial, out, cfg, files=files, needs_trial=False)
    check_output_folder(run.out_root)
    start = prediction_inputs(run.context("predict", progress=progress, plots=False), spec.base)
    run.record("predict", Path(study_path))
    for _, file in spec.references:
        run.record("predict", file)
    inputs = {**run.inputs, **run.read.get("predict", {})}
    cases, tracked = tracked_cases([case for chain in study_cases(spec) for case in chain], start, references)
    root = (run.out_root / "study").resolve()  # the workers may run elsewhere, in other folders
    root.mkdir(parents=True, exist_ok=True)
    first = first_start_keys()
    tasks = {case.name: Task(run_case, (case, str(root), start.params, tracked[case.name], repr(start.params), cfg,
                                        inputs, force, first), case.starts_from) for case in cases}
    done: dict[str, tuple] = {}
    progress(Progress("study", "cases", 0, len(cases)))
    count = min(workers_count or os.cpu_count() or 1, width(cases))
    try:
        with workers(count, scheduler) as pool:
            for name, future in completed(pool, tasks):
                done[name] = future.result()
                progress(Progress("study", "cases", len(done), len(cases)))
            # an unconverged case solved again from a neighbour's solution its chain did not have (retry_start)
            results = {name: d[0] for name, d in done.items()}
            again = {case.name: name for case in cases if (name := retry_start(case, cases, results))}
            retries = {case.name: Task(retry_case, (case, str(root), start.params, tracked[case.name],
                                                    repr(start.params), cfg, inputs, force, done[case.name],
                                                    again[case.name], done[again[case.name]]))
                       for case in cases if case.name in again}
            for k, (name, future) in enumerate(completed(pool, retries), 1):
                done[name] = future.result()
                progress(Progress("study", "cases started again", k, len(retries)))
    except BaseException:
        for case in cases:  # what a stopped worker was writing
            remove_stale(root / case.name)
        raise
    table = [{**done[case.name][2], "started_again_from": done[case.name][2].get("started_again_from", "")}
             for case in cases]
    write_table(root / "study.csv", {name: [r.get(name) for r in table] for name in table[0]})
    study_figures(table, root, title=spec.name)
    return table, root


# ------------------------------------------------------------------------------------------------ multi-start
def run_starts(cfg: PredictConfig, pool: Workers, *, params, reference, device=None, init: np.ndarray | None = None,
               on_done=None) -> list[PredictResult]:
    """``cfg.starts`` solves of ``cfg`` on ``pool``: start 0 from ``init`` (default: the default guess), start k
    from a perturbed guess of seed ``cfg.seed + k`` (:func:`gaitcli.predict.starts.solve_start`).
    ``on_done(k, result)`` as each finishes."""
    return map_in_order(pool, _StartOf(cfg, params, reference, device, init), start_seeds(cfg), on_done=on_done)


@dataclass(frozen=True)
class _StartOf:
    """``seed`` → that start's :func:`~gaitcli.predict.starts.solve_start` with the process's built problems: a
    picklable task function."""

    cfg: PredictConfig
    params: object
    reference: object
    device: object
    init: np.ndarray | None

    def __call__(self, seed: int | None) -> PredictResult:
        return solve_start(self.cfg, params=self.params, reference=self.reference, seed=seed, device=self.device,
                           init=self.init, cache=prediction_cache())


def starts_table(results: list[PredictResult]) -> dict:
    """starts.csv: every start's J, Et, Jdev, convergence, status, iterations and solve time."""
    return {"start": np.arange(len(results)), "objective": [r.objective for r in results],
            "cost_of_transport_J_per_m": [r.cost_of_transport_J_per_m for r in results],
            "deviation": [r.deviation for r in results], "converged": [bool(r.converged) for r in results],
            "status": [r.status for r in results], "iterations": [r.iterations for r in results],
            "solve_time_s": [r.solve_time_s for r in results]}


def best_of_starts(cfg: PredictConfig, *, params, reference, device, workers_count: int | None = None,
                   scheduler: str | None = None, progress: ProgressCallback = no_progress,
                   ) -> tuple[PredictResult, dict, int]:
    """``--starts N``: the best converged of ``cfg.starts`` starts, solved on :func:`gaitcli.run.cluster.workers`
    (``workers_count``, ``scheduler``) for the subject ``params``, the ``reference`` and the prostheses'
    ``device``; ``progress`` receives one report per start done.

    Returns
    -------
    (PredictResult, dict, int)
        The best result, starts.csv's table, and how many starts reached its J (:func:`agreeing`).
    """
    done = []

    def on_done(k, result):
        done.append(k)
        progress(Progress("predict", "starts", len(done), cfg.starts,
                          detail=f"start {k}: J {result.objective:.4g}{'' if result.converged else ' (unconverged)'}"))

    with workers(min(cfg.starts, workers_count or os.cpu_count() or 1), scheduler) as pool:
        results = run_starts(cfg, pool, params=params, reference=reference, device=device, on_done=on_done)
    agreed, best = agreeing(results)
    best = dataclasses.replace(best, history=best.history + (
        f"predict: best of {cfg.starts} starts (seed {cfg.seed}); {agreed} reached its J within 1 %",))
    return best, starts_table(results), agreed
