"""Evaluate a compiled ``casadi.Function`` on numpy arrays of many samples at once."""

from __future__ import annotations

import casadi as ca
import numpy as np


def evaluate(fn: ca.Function, *args) -> np.ndarray | tuple:
    """Call ``fn`` (column-vector inputs/outputs) on samples stacked along axis 0.

    Each argument is (n, k) for n samples or (k,)/scalar for a value shared by
    all samples. CasADi evaluates n samples when the inputs have n times as
    many columns. Column-vector outputs come back as (n, k) arrays, matrix
    outputs (r × c) as (n, r, c); with no (n, k) argument the sample axis is
    dropped. Several outputs are returned as a tuple.
    """
    arrays = [np.asarray(x, dtype=float) for x in args]
    batched = any(x.ndim == 2 for x in arrays)
    n = max((x.shape[0] for x in arrays if x.ndim == 2), default=1)
    cols = []
    for x in arrays:
        c = x.T if x.ndim == 2 else x.reshape(-1, 1)
        cols.append(ca.DM(c if c.shape[1] == n else np.repeat(c, n, axis=1)))
    out = fn(*cols)
    outs = list(out) if isinstance(out, (tuple, list)) else [out]
    result = []
    for k, o in enumerate(outs):
        rows, ncol = fn.size_out(k)
        arr = np.array(o).reshape(rows, n, ncol).transpose(1, 0, 2)  # (n, rows, ncol)
        if ncol == 1:
            arr = arr[:, :, 0]
        result.append(arr if batched else arr[0])
    return result[0] if len(result) == 1 else tuple(result)
