"""Where along the gait cycle two conditions differ: statistical parametric mapping (SPM) of a two-sample t-test
over strides (Pataky 2010; the ``spm1d`` package), as chapter 3 compares a subject's conditions.

For one variable, the strides of condition A and of condition B (each a curve over 0–100 % of the cycle) give
the t statistic at every point, SPM{t}; random field theory gives the critical t that the curve of a smooth
random field crosses with probability α, and every span where |t| exceeds it is a difference with its own
p value. The test is two-tailed, the variances are not assumed equal (Welch). A comparison tests many
variables at once; so that two samples of one condition are flagged nowhere with probability 1 − α, each
variable is tested at the Šidák level 1 − (1 − α)^(1/m), m the number of variables tested
(:func:`family_alpha`). A variable with fewer than two strides with no gap in either condition (a moment
off the force plates), or with no spread, is not tested.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

#: the family-wise error rate of a comparison
ALPHA = 0.05
#: the fewest strides per condition a variable is tested with
MIN_STRIDES = 2
#: strides that differ by less than this fraction of their largest value have no spread (round-off)
SPREAD_RTOL = 1e-9


@dataclass(frozen=True)
class Span:
    """A stretch of the cycle where the conditions differ: first and last cycle % (interpolated where |t| crosses
    the critical t), its p value, and the largest difference of the means (B − A) inside it, in the variable's
    unit."""

    start_pct: float
    end_pct: float
    p: float
    largest_difference: float


@dataclass(frozen=True)
class Comparison:
    """One variable compared: SPM{t} over the cycle (B − A), the critical t at ``alpha``, the spans beyond it,
    and the strides used per condition."""

    t: np.ndarray
    t_critical: float
    alpha: float
    spans: tuple[Span, ...]
    strides: tuple[int, int]


def family_alpha(alpha: float, tests: int) -> float:
    """Šidák's per-test level for a family of ``tests`` tests at family-wise level ``alpha``."""
    return 1.0 - (1.0 - alpha) ** (1.0 / max(tests, 1))


def complete_strides(stack: np.ndarray) -> np.ndarray:
    """The rows (strides) of ``stack`` (strides × points) with no NaN."""
    stack = np.asarray(stack, float).reshape(-1, np.shape(stack)[-1])
    return stack[np.all(np.isfinite(stack), axis=1)]


def _spread(stack: np.ndarray) -> bool:
    """Whether the strides differ by more than round-off anywhere."""
    return bool(np.any(stack.std(axis=0) > SPREAD_RTOL * (1.0 + np.abs(stack).max())))


def comparable(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether the two conditions' strides can be compared: at least :data:`MIN_STRIDES` complete strides each,
    and some spread in each."""
    a, b = complete_strides(a), complete_strides(b)
    return len(a) >= MIN_STRIDES and len(b) >= MIN_STRIDES and _spread(a) and _spread(b)


def two_sample(a: np.ndarray, b: np.ndarray, alpha: float) -> Comparison:
    """SPM two-sample t-test of strides ``b`` against ``a`` (strides × cycle points, same points) at the per-test
    level ``alpha`` (:func:`family_alpha`); only complete strides count, and :func:`comparable` must hold."""
    import spm1d

    a, b = complete_strides(a), complete_strides(b)
    with warnings.catch_warnings():  # spm1d's own notes on its smoothness estimate
        warnings.simplefilter("ignore")
        inference = spm1d.stats.ttest2(b, a, equal_var=False).inference(alpha, two_tailed=True, interp=True)
    difference = b.mean(axis=0) - a.mean(axis=0)
    points = difference.size
    spans = []
    for cluster in inference.clusters:
        start, end = (float(x) for x in cluster.endpoints)
        inside = difference[int(np.floor(start)):min(int(np.ceil(end)) + 1, points)]
        largest = inside[np.argmax(np.abs(inside))] if inside.size else float("nan")
        spans.append(Span(100.0 * start / (points - 1), 100.0 * end / (points - 1), float(cluster.P), float(largest)))
    return Comparison(np.asarray(inference.z, float), float(inference.zstar), alpha, tuple(spans), (len(a), len(b)))
