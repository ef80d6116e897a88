"""``gait predict --study FILE.yaml`` and ``--starts N``: run the cases, write every case's folder, the study table
and its figures (the edge of :mod:`gaitcli.predict.starts`).

A study's chains (one per speed, :func:`gaitcli.predict.starts.study_cases`) run in parallel
worker processes; within a chain each case starts from the solutions it names. Every case is written whole
into ``OUT/study/<case>/`` (the files of ``gait predict``) with a ``case_key``: the SHA-256 of its resolved
configuration, the subject, the reference and the keys of the cases it started from. A case whose folder
holds the same key is read back instead of solved again, so a rerun (or a run after an interrupt) does
only what is missing. ``study.csv`` has one row per case, unconverged ones included and marked.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import time
from concurrent.futures import as_completed
from pathlib import Path

import numpy as np

from gaitcli.core.registry import Progress, ProgressCallback, no_progress
from gaitcli.errors import InputError
from gaitcli.io.h5 import read_result
from gaitcli.io.outputs import stage_folder, write_json, write_table
from gaitcli.predict.prosthesis import COMMERCIAL_FEET
from gaitcli.predict.stage import PredictResult, run_predict
from gaitcli.predict.starts import (StudyCase, StudySpec, agreeing, pool, predict_optimal, retimed, run_starts,
                                   stop, study_cases)
from gaitcli.resources import stored_solution

#: study.csv's columns after the case's labels
FIGURES = ("objective", "cost_of_transport_J_per_m", "deviation")


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


def stored_case(folder: Path, key: str) -> PredictResult | None:
    """The result in ``folder`` when its summary holds ``key``, else None."""
    try:
        summary = json.loads((folder / "summary.json").read_text())
        if summary.get("case_key") != key:
            return None
        return read_result(folder / "predict.h5", PredictResult)
    except (InputError, OSError, ValueError, KeyError):
        return None


def _tau(result: PredictResult, y: float) -> float:
    return float(result.prosthesis.spring_moment_Nm(y)) if result.prosthesis is not None else float("nan")


def case_row(case: StudyCase, result: PredictResult, *, reused: bool, wall_s: float, agreed: int = 1) -> dict:
    """One study.csv row: labels, J, Et, Jdev (control points and fine grid), convergence and the device."""
    fine = result.fine_grid or {}
    row = {"case": case.name, "speed_m_s": case.speed_m_s, "weights": case.weight_set, "condition": case.condition,
           "objective": result.objective, "cost_of_transport_J_per_m": result.cost_of_transport_J_per_m,
           "deviation": result.deviation, "fine_cost_of_transport_J_per_m": fine.get("cost_of_transport_J_per_m"),
           "fine_deviation": fine.get("deviation"), "converged": bool(result.converged),
           "iterations": int(result.iterations), "solve_time_s": float(result.solve_time_s),
           "wall_time_s": float(wall_s), "reused": bool(reused), "starts_agreeing": int(agreed),
           "tau_s_at_minus_0.1_rad_Nm": _tau(result, -0.1), "tau_s_at_minus_0.2_rad_Nm": _tau(result, -0.2)}
    if result.prosthesis is not None:
        row.update({f"prosthesis_{k}": float(v) for k, v in
                    zip(("a_p", "b_p", "c0", "a_n", "b_n", "d_prosth"), result.prosthesis.coefficients())})
    return row


def _shipped_start(case: StudyCase) -> np.ndarray | None:
    """A chain's first start: the shipped normal solution (``resources.stored_solution``) retimed to the case's
    speed where the layout has one, else None (the default guess)."""
    path = stored_solution(case.cfg.nodes, symmetric=case.cfg.symmetric)
    return None if path is None else retimed(case.cfg, np.loadtxt(path))


def _solve_case(case: StudyCase, spec: StudySpec, solved: dict, params, reference) -> tuple[PredictResult, int]:
    """Solve one case from the solutions it starts from (``solved``: name → result of its chain so far)."""
    if case.condition == "optimal":
        feet = {name: solved[start] for name, start in zip(COMMERCIAL_FEET, case.starts_from)}
        normal = solved[case.starts_from[-1]]
        return predict_optimal(case.cfg, params=params, reference=reference, feet=feet, normal=normal), 1
    # the first start that converged (a foot after the first: that foot's solution, else the normal one)
    starts = [solved[name] for name in case.starts_from]
    init = next((r for r in starts if r.converged), starts[0]).design if starts else _shipped_start(case)
    if spec.starts > 1:  # start 0 from the chain's solution, the others from perturbed guesses
        results = run_starts(case.cfg, spec.starts, params=params, reference=reference, workers=1, init=init)
        agreed, best = agreeing(results)
        return best, agreed
    return run_predict(case.cfg, params=params, reference=reference, init=init), 1


def first_start_keys(spec: StudySpec) -> tuple[str, ...]:
    """The key of a chain's first start: the shipped normal solution's SHA-256 (study cases are symmetric)."""
    shipped = stored_solution(spec.nodes, symmetric=True)
    return (f"shipped {hashlib.sha256(shipped.read_bytes()).hexdigest()}",) if shipped is not None else ()


def run_case(case: StudyCase, spec: StudySpec, root: str, params, reference, subject: str, attrs: dict,
             force: bool, first: tuple[str, ...], *starts: tuple) -> tuple[PredictResult, str, dict]:
    """Run (or read back) one case from its starts (what :func:`run_case` returned for each case it
    ``starts_from``, in order): its result, its key and its study.csv row. A Dask task in a study on a cluster,
    where the starts are the futures of the cases before it."""
    start = time.perf_counter()
    solved = {name: done[0] for name, done in zip(case.starts_from, starts)}
    key = case_key(case, subject, reference.digest(), tuple(done[1] for done in starts) if case.starts_from else first)
    folder = Path(root) / case.name
    result = None if force else stored_case(folder, key)
    reused = result is not None
    if result is None:
        result, agreed = _solve_case(case, spec, solved, params, reference)
        write_case(folder, result, {**attrs, "predict_config": json.dumps(dataclasses.asdict(case.cfg))},
                   {"case_key": key, "case": case.name, "condition": case.condition,
                    "weight_set": case.weight_set, "starts": spec.starts, "starts_agreeing": agreed})
    else:
        agreed = int(json.loads((folder / "summary.json").read_text()).get("starts_agreeing", 1))
    return result, key, case_row(case, result, reused=reused, wall_s=time.perf_counter() - start, agreed=agreed)


def run_chain(chain: list[StudyCase], spec: StudySpec, root: str, params, reference, subject: str,
              attrs: dict, force: bool) -> list[dict]:
    """Run (or read back) one chain's cases in order; returns their study.csv rows. Runs in a worker process."""
    done, rows = {}, []
    first = first_start_keys(spec)
    for case in chain:
        done[case.name] = run_case(case, spec, root, params, reference, subject, attrs, force, first,
                                   *(done[name] for name in case.starts_from))
        rows.append(done[case.name][2])
    return rows


def run_study_on_cluster(client, chains: list[list[StudyCase]], spec: StudySpec, root: str, params, reference,
                         subject: str, attrs: dict, force: bool, on_row=None) -> dict[str, dict]:
    """Every case as a Dask task on ``client``'s cluster, the cases it starts from as its dependencies (so the
    chains, and cases of one chain that do not depend on each other, run side by side). Rows by case name."""
    from distributed import as_completed as completed

    first = first_start_keys(spec)
    futures = {}
    for chain in chains:
        for case in chain:
            futures[case.name] = client.submit(run_case, case, spec, root, params, reference, subject, attrs, force,
                                               first, *(futures[name] for name in case.starts_from), pure=False,
                                               key=f"case-{case.name}-{hashlib.sha1(root.encode()).hexdigest()[:8]}")
    names = {f.key: name for name, f in futures.items()}
    rows = {}
    for future in completed(list(futures.values())):
        rows[names[future.key]] = future.result()[2]
        if on_row is not None:
            on_row(rows[names[future.key]])
    return rows


def run_study(spec: StudySpec, out: Path, *, params, reference, subject: str, attrs: dict,
              workers: int | None = None, force: bool = False, scheduler: str | None = None,
              progress: ProgressCallback = no_progress) -> tuple[list[dict], Path]:
    """Every case of ``spec`` into ``out``/study/: the case folders, study.csv, study.png, curves.png. Returns
    (rows in study order, the study folder). With ``scheduler`` (a Dask scheduler's address) every case is a
    task on that cluster (:func:`run_study_on_cluster`); else the chains run in ``workers`` processes."""
    chains = study_cases(spec)
    root = Path(out) / "study"
    root.mkdir(parents=True, exist_ok=True)
    total = sum(len(c) for c in chains)
    workers = max(1, min(len(chains), workers or os.cpu_count() or 1))
    rows_by_chain: dict[int, list[dict]] = {}
    progress(Progress("study", "cases", 0, total))
    args = [(chain, spec, str(root), params, reference, subject, attrs, force) for chain in chains]
    if scheduler is not None:  # the workers may run elsewhere, in other folders: absolute paths
        from gaitcli.run.cluster import dask_client

        root = root.resolve()

        done = []

        def case_done(row):
            done.append(row)
            progress(Progress("study", "cases", len(done), total))

        with dask_client(1, scheduler) as client:
            by_name = run_study_on_cluster(client, chains, spec, str(root), params, reference, subject, attrs, force,
                                           on_row=case_done)
        rows_by_chain = {k: [by_name[case.name] for case in chain] for k, chain in enumerate(chains)}
    elif workers == 1:
        for k, a in enumerate(args):
            rows_by_chain[k] = run_chain(*a)
            progress(Progress("study", "cases", sum(len(r) for r in rows_by_chain.values()), total))
    else:
        with pool(workers) as executor:
            try:
                futures = {executor.submit(run_chain, *a): k for k, a in enumerate(args)}
                for future in as_completed(futures):
                    rows_by_chain[futures[future]] = future.result()
                    progress(Progress("study", "cases", sum(len(r) for r in rows_by_chain.values()), total))
            except BaseException:
                stop(executor)
                raise
    rows = [row for k in range(len(chains)) for row in rows_by_chain[k]]
    write_table(root / "study.csv", {name: [r.get(name) for r in rows] for name in rows[0]})
    from gaitcli.report.study_plots import study_figures

    study_figures(rows, root, title=spec.name)
    return rows, root


def starts_table(results: list[PredictResult]) -> dict:
    """starts.csv: every start's J, Et, Jdev, convergence, status, iterations and solve time."""
    return {"start": np.arange(len(results)), "objective": [r.objective for r in results],
            "cost_of_transport_J_per_m": [r.cost_of_transport_J_per_m for r in results],
            "deviation": [r.deviation for r in results], "converged": [bool(r.converged) for r in results],
            "status": [r.status for r in results], "iterations": [r.iterations for r in results],
            "solve_time_s": [r.solve_time_s for r in results]}


def best_of_starts(cfg, starts: int, *, params, reference, device, seed: int = 0, workers: int | None = None,
                   scheduler: str | None = None,
                   progress: ProgressCallback = no_progress) -> tuple[PredictResult, dict, int]:
    """``--starts N``: the best converged of N starts (in worker processes, or as tasks on the Dask cluster at
    ``scheduler``), starts.csv's table and how many starts agreed."""
    done = []

    def on_done(k, result):
        done.append(k)
        progress(Progress("predict", "starts", len(done), starts,
                          detail=f"start {k}: J {result.objective:.4g}{'' if result.converged else ' (unconverged)'}"))

    if scheduler is not None:
        from gaitcli.run.cluster import dask_client

        with dask_client(1, scheduler) as client:
            results = run_starts(cfg, starts, params=params, reference=reference, seed=seed, device=device,
                                 on_done=on_done, executor=client.get_executor(pure=False))
    else:
        results = run_starts(cfg, starts, params=params, reference=reference, seed=seed, workers=workers,
                             device=device, on_done=on_done)
    agreed, best = agreeing(results)
    best = dataclasses.replace(best, history=best.history + (
        f"predict: best of {starts} starts (seed {seed}); {agreed} reached its J within 1 %",))
    return best, starts_table(results), agreed

