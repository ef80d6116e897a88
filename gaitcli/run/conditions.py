"""``gait report A B … --compare``: a subject's conditions side by side, as chapter 3 compares them (3.3; normal
walking, ankle weight, orthosis, ski boot …): each condition's strides, its Table 3.1, and where along the cycle
each condition differs from the first one (:mod:`gaitcli.signal.spm`).

A condition is a trial folder, a walk's C3D, a session folder (every walk's strides pooled) or the name of a
bundled sample trial (``ankle_weight``) where no such path exists. Its filter and idyn outputs are used where
they are up to date and made first where not (a sample trial's into ``OUT/<name>/gait_out``). The comparison
writes into ``OUT``: ``conditions.csv`` (Table 3.1 per condition), ``cycle.csv`` (each condition's mean ± SD per
side and cycle %), ``spm.csv`` (every span where a condition differs from the first), ``summary.json``.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from gaitcli.errors import InputError, shown
from gaitcli.io.atomic import check_replaceable
from gaitcli.io.outputs import stage_folder, write_json, write_table
from gaitcli.resources import sample_trial
from gaitcli.run.config import PipelineConfig
from gaitcli.run.pipeline import fresh_output
from gaitcli.run.session import read_walk, run_session, session_folder
from gaitcli.run.trial import output_root
from gaitcli.signal.bands import stride_statistics
from gaitcli.signal.cycles import CYCLE_PCT
from gaitcli.signal.session import WALK_FEATURES, side_stacks, stride_table, walk_table
from gaitcli.signal.spm import ALPHA, comparable, family_alpha, two_sample

#: the variables a comparison tests: angles, moments, powers, ground reactions (not the lumbar joint's)
COMPARED = ("pelvis_", "hip_", "knee_", "ankle_", "foot_", "grf_")


@dataclass(frozen=True)
class Condition:
    """One condition: its name, its walks' strides and their curves per side ({side: {variable: (n, 101)}}) and
    its Table 3.1 and steps (the mean over its walks)."""

    name: str
    strides: pd.DataFrame
    stacks: dict[str, dict[str, np.ndarray]]
    features: dict[str, float]
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class ConditionSource:
    """Where a condition's data are: its name, its trial, walk or session path, and the output root of a bundled
    sample trial (None: the path's own)."""

    name: str
    path: Path
    root: Path | None


def condition_sources(refs, out: Path) -> list[ConditionSource]:
    """Every condition of ``refs`` found (module docstring) and named apart, before anything runs; one-line
    errors naming the first that is not."""
    names = [Path(str(r)).name or str(r) for r in refs]
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise InputError(None, "conditions", f"{shown(repeated[0])} names two conditions (expected folders of "
                                             "different names)")
    sources = []
    for ref, name in zip(refs, names):
        path = Path(ref)
        if path.exists():
            sources.append(ConditionSource(name, path.resolve(), None))
        elif str(ref) == path.name and (sample_trial(str(ref)) / "subject.yaml").is_file():
            sources.append(ConditionSource(name, sample_trial(str(ref)), out / name / "gait_out"))
        else:
            raise InputError(path, None, "not found (expected a trial or session folder, a walk's C3D or the name "
                                         "of a bundled sample trial)")
    return sources


def read_condition(source: ConditionSource, cfg: PipelineConfig, **batch) -> Condition:
    """The condition at ``source``, its idyn outputs made first where they are not up to date; ``batch``: the
    options of :func:`gaitcli.run.batch.run_batch` for a session's walks."""
    path, root = source.path, source.root
    walks_of = session_folder(path) if root is None and path.is_dir() else None
    if walks_of:
        run_session(path, cfg, **batch)
        walks = [read_walk(w, cfg) for w in walks_of]
    else:  # a trial folder or one walk's C3D
        fresh_output(path, "idyn", cfg, out=root, plots=False)
        walks = [read_walk(path, cfg, root)]
    walks = [w for w in walks if w is not None]
    if not walks:
        raise InputError(output_root(path) if root is None else root, "idyn",
                         "no gait_cycle.csv (expected idyn outputs with at least one complete stride)")
    table = stride_table(walks)
    means = walk_table(walks).set_index("walk").loc["mean"]
    said = tuple(f"{w.name}: {message}" for w in walks for message in w.features.get("warnings", ()))
    return Condition(source.name, table, side_stacks(walks, table), {k: float(means[k]) for k in WALK_FEATURES}, said)


@dataclass(frozen=True)
class ConditionComparison:
    """The conditions, and each later condition's differences from the first: rows of (condition, side,
    variable, span); the variables tested per side and the per-test level."""

    conditions: list[Condition]
    spans: pd.DataFrame
    tested: dict[str, int]
    alpha: float


def compare_conditions(conditions: list[Condition], alpha: float = ALPHA) -> ConditionComparison:
    """SPM of every compared variable (:data:`COMPARED`) of each later condition against the first, per side,
    family-wise ``alpha`` over each side's tested variables of one pair (:func:`family_alpha`)."""
    first, rows, tested = conditions[0], [], {}
    for other in conditions[1:]:
        for side in ("r", "l"):
            variables = [v for v in first.stacks.get(side, {}) if v.startswith(COMPARED) and
                         v in other.stacks.get(side, {}) and comparable(first.stacks[side][v], other.stacks[side][v])]
            tested[f"{other.name}/{side}"] = len(variables)
            level = family_alpha(alpha, len(variables))
            for variable in variables:
                result = two_sample(first.stacks[side][variable], other.stacks[side][variable], level)
                rows += [{"condition": other.name, "side": side, "variable": variable, "start_pct": s.start_pct,
                          "end_pct": s.end_pct, "p": s.p, "largest_difference": s.largest_difference,
                          "strides_first": result.strides[0], "strides": result.strides[1]} for s in result.spans]
    columns = ["condition", "side", "variable", "start_pct", "end_pct", "p", "largest_difference", "strides_first",
               "strides"]
    return ConditionComparison(conditions, pd.DataFrame(rows, columns=columns), tested, alpha)


def cycle_table(conditions: list[Condition]) -> pd.DataFrame:
    """Each condition's mean, SD and stride count per side, variable and cycle %."""
    blocks = []
    for condition in conditions:
        for side, stacks in condition.stacks.items():
            block = {"condition": np.full(CYCLE_PCT.size, condition.name), "side": np.full(CYCLE_PCT.size, side),
                     "cycle_pct": CYCLE_PCT}
            for name, stack in stacks.items():
                mean, sd, n = stride_statistics(stack)
                block.update({f"{name}_mean": mean, f"{name}_sd": sd, f"{name}_n": n})
            blocks.append(pd.DataFrame(block))
    return pd.concat(blocks, ignore_index=True)


def write_comparison(out: Path, comparison: ConditionComparison, page=None) -> Path:
    """``OUT/compare/`` whole (module docstring); replaces an earlier comparison there. ``page(folder)``, where
    given, writes the comparison's page into the folder before it is complete (its tables are there): the page
    is part of the folder, listed in its manifest, and an interrupt leaves the earlier comparison whole."""
    target = out / "compare"
    check_replaceable(target)
    conditions = pd.DataFrame([{"condition": c.name, **c.features,
                                "strides_right": int((c.strides.side == "r").sum()),
                                "strides_left": int((c.strides.side == "l").sum())} for c in comparison.conditions])
    with stage_folder(target) as tmp:
        for name, table in (("conditions.csv", conditions), ("cycle.csv", cycle_table(comparison.conditions)),
                            ("spm.csv", comparison.spans)):
            write_table(tmp / name, {c: table[c].to_numpy() for c in table.columns})
        write_json(tmp / "summary.json", {
            "conditions": [c.name for c in comparison.conditions], "alpha": comparison.alpha,
            "test": "SPM two-sample t-test over strides (spm1d), two-tailed, unequal variances; family-wise alpha "
                    "over each side's variables (Sidak)",
            "variables_tested": comparison.tested, "spans": int(len(comparison.spans)),
            "warnings": {c.name: list(c.warnings) for c in comparison.conditions}})
        if page is not None:
            page(tmp)
    return target
