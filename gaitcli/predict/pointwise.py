"""Per-point functions of the predictive-gait NLP: one small Function stated at every instant, its derivatives
built once and scattered into the problem's.

A :class:`PointFunction` is a CasADi Function f(z) of one instant's inputs z (n_z,) — its named outputs are rows
of g, its optional ``cost`` output a piece of J — with, for every instant i, z_i = A_i w + b_i an affine function
of the NLP's variables w (a gather with scales, sums, the symmetric model's mirror image and half-stride shift,
the instants' times as sums of phase durations). With L = σ·J + λᵀg and μ_i the multipliers of instant i's rows:

    ∂g_i/∂w = ∂f/∂z(z_i) · A_i
    ∇J      = c(p) · Σ_i A_iᵀ ∇_z cost(z_i)                       c(p): the piece's weight, e.g. w1/100
    ∇²L     = Σ_i A_iᵀ ∇²_z(σ·c(p)·cost + μ_iᵀ f)(z_i) A_i

so f's Jacobian and Hessian are built once (a few hundred non-zeros, in milliseconds), mapped over the
instants, and summed into the problem's by constant sparse matrices (:class:`Scatter`). The groups of g that
are no point function's (the "rest") keep CasADi's derivatives of their expressions. :func:`derivatives`
returns IPOPT's three Functions (``grad_f``, ``jac_g``, ``hess_lag``, nlpsol's signatures).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import scipy.sparse as sparse

COST = "cost"


@dataclass
class PointFunction:
    """``function`` (one input z, outputs: rows of g and optionally ``cost``) at the instants whose inputs are the
    columns of ``inputs`` (n_z × n, SX affine in w); ``weight`` (SX of the parameters p) multiplies Σ cost."""

    name: str
    function: ca.Function
    inputs: ca.SX
    weight: object = None
    outputs: dict = field(init=False)

    def __post_init__(self) -> None:
        values = self.function.call([self.inputs])
        self.outputs = {self.function.name_out(k): values[k] for k in range(self.function.n_out())}

    @property
    def instants(self) -> int:
        """How many instants the function is stated at."""
        return self.inputs.size2()

    @property
    def row_outputs(self) -> list[str]:
        """The outputs that are rows of g, in the function's order."""
        return [n for n in self.function.name_out() if n != COST]

    @property
    def total(self):
        """Σ_i cost(z_i), unweighted (0 without a cost output)."""
        return ca.sum2(self.outputs[COST]) if COST in self.outputs else ca.SX(0)

    @property
    def cost(self):
        """Its part of J: weight · Σ_i cost(z_i)."""
        return self.weight * self.total if COST in self.outputs else ca.SX(0)


@dataclass(frozen=True)
class Placement:
    """Where a point function's output lies in g: its first row (instant i's rows follow at i·rows)."""

    function: PointFunction
    output: str
    start: int


class Scatter:
    """Contributions (target index, source index, coefficient) summed into a target sparsity's non-zeros."""

    def __init__(self):
        self.parts: list[tuple] = []  # (rows, cols, sources, coefficients, source block)

    def add(self, rows, cols, sources, coefficients, block: int) -> None:
        """Entry (rows[e], cols[e]) of the target gets coefficients[e] × value ``sources[e]`` of ``block``."""
        self.parts.append((np.asarray(rows, int), np.asarray(cols, int), np.asarray(sources, int),
                           np.asarray(coefficients, float), block))

    def sparsity(self, shape: tuple[int, int]) -> tuple[ca.Sparsity, list]:
        """The union pattern and, per part, its entries' non-zero indices in it."""
        rows = np.concatenate([p[0] for p in self.parts]) if self.parts else np.zeros(0, int)
        cols = np.concatenate([p[1] for p in self.parts]) if self.parts else np.zeros(0, int)
        pattern, mapping = ca.Sparsity.triplet(shape[0], shape[1], rows.tolist(), cols.tolist(), True)
        mapping, out, start = np.asarray(mapping, int), [], 0
        for p in self.parts:
            out.append(mapping[start:start + p[0].size])
            start += p[0].size
        return pattern, out

    def matrices(self, shape: tuple[int, int], block_sizes: list[int]) -> tuple[ca.Sparsity, list[ca.DM]]:
        """The union pattern and, per source block, the sparse matrix from its values to the pattern's
        non-zeros."""
        pattern, targets = self.sparsity(shape)
        by_block = {}
        for (_, _, sources, coefficients, block), target in zip(self.parts, targets):
            by_block.setdefault(block, []).append((target, sources, coefficients))
        matrices = []
        for block, size in enumerate(block_sizes):
            t, s, c = (np.concatenate([x[k] for x in by_block.get(block, [])] or [np.zeros(0)]) for k in range(3))
            matrices.append(_dm(sparse.csc_matrix((c, (t.astype(int), s.astype(int))), shape=(pattern.nnz(), size))))
        return pattern, matrices


def _dm(matrix: sparse.spmatrix) -> ca.DM:
    """A scipy sparse matrix as a CasADi DM of the same pattern (CasADi's own conversion is slow)."""
    m = sparse.csc_matrix(matrix)
    m.sum_duplicates()
    pattern = ca.Sparsity(m.shape[0], m.shape[1], m.indptr.tolist(), m.indices.tolist())
    return ca.DM(pattern, m.data)


def affine(inputs: ca.SX, w: ca.SX, parameters: ca.SX) -> tuple[sparse.csr_matrix, np.ndarray]:
    """(A, b) with vec(inputs) = A w + b; an error if the inputs are not affine in w or depend on p."""
    flat = ca.vec(inputs)
    if ca.depends_on(flat, parameters):
        raise ValueError("a point function's inputs depend on the parameters")
    jac = ca.jacobian(flat, w)
    if ca.depends_on(jac, w):
        raise ValueError("a point function's inputs are not affine in w")
    f = ca.Function("affine", [w], [jac, flat])
    a, b = f(np.zeros(w.numel()))
    return sparse.csr_matrix(a.sparse()), np.array(b).ravel()


def _padded(a: sparse.csr_matrix) -> tuple[np.ndarray, np.ndarray]:
    """A's rows as padded (rows × width) arrays of columns and values (value 0 in the padding)."""
    counts = np.diff(a.indptr)
    width = max(1, int(counts.max(initial=0)))
    cols, vals = np.zeros((a.shape[0], width), int), np.zeros((a.shape[0], width))
    slot = np.arange(a.nnz) - np.repeat(a.indptr[:-1], counts)
    row = np.repeat(np.arange(a.shape[0]), counts)
    cols[row, slot], vals[row, slot] = a.indices, a.data
    return cols, vals


def _rows_of(padded, n_z: int, instants: int, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A_i's rows ``rows`` at every instant: (columns, coefficients), each (instants × entries × width)."""
    cols, vals = padded
    index = (np.arange(instants) * n_z)[:, None] + rows
    return cols[index], vals[index]


def _single(padded, n_z: int, instants: int, rows: np.ndarray):
    """For entries reading z's rows ``rows``: every (instant, entry, w column, coefficient) of A_i's row."""
    c, v = _rows_of(padded, n_z, instants, rows)
    inst = np.broadcast_to(np.arange(instants)[:, None, None], c.shape)
    entry = np.broadcast_to(np.arange(rows.size)[None, :, None], c.shape)
    keep = v != 0
    return inst[keep], entry[keep], c[keep], v[keep]


def _pairs(padded, n_z: int, instants: int, left: np.ndarray, right: np.ndarray):
    """For entries (left[e], right[e]) of a per-instant n_z × n_z matrix: every (instant, entry, w column of
    A_i's row left[e], w column of its row right[e], product of their coefficients)."""
    lc, lv = _rows_of(padded, n_z, instants, left)
    rc, rv = _rows_of(padded, n_z, instants, right)
    coef = lv[:, :, :, None] * rv[:, :, None, :]
    shape = coef.shape
    inst = np.broadcast_to(np.arange(instants)[:, None, None, None], shape)
    entry = np.broadcast_to(np.arange(left.size)[None, :, None, None], shape)
    a_col = np.broadcast_to(lc[:, :, :, None], shape)
    b_col = np.broadcast_to(rc[:, :, None, :], shape)
    keep = coef != 0
    return inst[keep], entry[keep], a_col[keep], b_col[keep], coef[keep]


@dataclass
class _Kernel:
    """One point function's derivatives on one instant (non-zeros as columns), their patterns, its gathers."""

    pf: PointFunction
    jacobian: ca.Function
    jacobian_pattern: ca.Sparsity
    gradient: ca.Function | None
    hessian: ca.Function
    hessian_pattern: ca.Sparsity
    rows: int
    a: sparse.csr_matrix
    b: np.ndarray
    multipliers: np.ndarray  # (instants × rows) indices into g


def _kernel(pf: PointFunction, w: ca.SX, parameters: ca.SX, starts: dict) -> _Kernel:
    """``pf``'s derivatives on one instant, its gathers (A, b) and its rows' places in g (``starts``: (function,
    output) → first row)."""
    f = pf.function
    z = ca.SX.sym("z", f.size1_in(0))
    named = dict(zip(f.name_out(), f.call([z])))
    r = ca.vertcat(*[ca.vec(named[n]) for n in pf.row_outputs])
    mu, s = ca.SX.sym("mu", r.numel()), ca.SX.sym("s")
    jac = ca.jacobian(r, z)
    hess = ca.triu(ca.hessian(ca.dot(mu, r) + (s * named[COST] if COST in named else 0), z)[0])
    gradient = ca.Function(f"{pf.name}_grad", [z], [ca.gradient(named[COST], z)]) if COST in named else None
    a, b = affine(pf.inputs, w, parameters)
    n = pf.instants
    index = [[starts[(id(pf), name)] + i * pf.outputs[name].size1() + np.arange(pf.outputs[name].size1())
              for name in pf.row_outputs] for i in range(n)]
    multipliers = np.array([np.concatenate(row or [np.zeros(0, int)]) for row in index], int).reshape(n, r.numel())
    return _Kernel(pf=pf, jacobian=ca.Function(f"{pf.name}_jac", [z], [jac.nz[:]]), jacobian_pattern=jac.sparsity(),
                   gradient=gradient, hessian=ca.Function(f"{pf.name}_hess", [z, mu, s], [hess.nz[:]]),
                   hessian_pattern=hess.sparsity(), rows=r.numel(), a=a, b=b, multipliers=multipliers)


def _triplet(pattern: ca.Sparsity) -> tuple[np.ndarray, np.ndarray]:
    """A pattern's (rows, columns) of its non-zeros, in order."""
    rows, cols = pattern.get_triplet()
    return np.asarray(rows, int), np.asarray(cols, int)


def derivatives(w: ca.SX, parameters: ca.SX, constraints: ca.SX, cost: ca.SX, rest_cost: ca.SX,
                functions: list[PointFunction], placements: list[Placement]) -> dict[str, ca.Function]:
    """IPOPT's ``grad_f``, ``jac_g`` and ``hess_lag`` (nlpsol's signatures) of min ``cost`` s.t. ``constraints``:
    the point functions' parts from their kernels (module docstring), the rest (``rest_cost`` and the rows of g
    that no placement covers) by CasADi's symbolic derivatives of their expressions."""
    nw, ng = w.numel(), constraints.numel()
    starts = {(id(p.function), p.output): p.start for p in placements}
    covered = np.zeros(ng, bool)
    for p in placements:
        covered[p.start:p.start + p.function.outputs[p.output].numel()] = True
    rest = np.flatnonzero(~covered)
    g_rest = constraints[rest.tolist()] if rest.size else ca.SX(0, 1)
    lam_f, lam_rest = ca.SX.sym("lam_f"), ca.SX.sym("lam_g", rest.size)
    jac_rest = ca.jacobian(g_rest, w)
    hess_rest = ca.triu(ca.hessian(lam_f * rest_cost + ca.dot(lam_rest, g_rest), w)[0])
    rest_functions = {"jac": ca.Function("rest_jac", [w, parameters], [jac_rest.nz[:]]),
                      "grad": ca.Function("rest_grad", [w, parameters], [ca.gradient(rest_cost, w)]),
                      "hess": ca.Function("rest_hess", [w, parameters, lam_f, lam_rest], [hess_rest.nz[:]])}
    jac_scatter, hess_scatter = Scatter(), Scatter()
    jr, jc = _triplet(jac_rest.sparsity())
    jac_scatter.add(rest[jr], jc, np.arange(jr.size), np.ones(jr.size), 0)
    hr, hc = _triplet(hess_rest.sparsity())
    hess_scatter.add(hr, hc, np.arange(hr.size), np.ones(hr.size), 0)
    jac_sizes, hess_sizes, kernels = [jr.size], [hr.size], []
    for k, pf in enumerate(functions, start=1):
        kern = _kernel(pf, w, parameters, starts)
        n, n_z, padded = pf.instants, pf.inputs.size1(), _padded(kern.a)
        # the Jacobian's entry (r, q) at instant i: row r of instant i's rows, every w column of A_i's row q
        qr, qc = _triplet(kern.jacobian_pattern)
        inst, entry, col, coef = _single(padded, n_z, n, qc)
        jac_scatter.add(kern.multipliers[inst, qr[entry]], col, inst * qr.size + entry, coef, k)
        jac_sizes.append(n * qr.size)
        # the Hessian's (triu) entry (p, q): columns a of row p and b of row q, and for p ≠ q the mirror
        hp, hq = _triplet(kern.hessian_pattern)
        off = np.flatnonzero(hp != hq)
        for left, right, entries in ((hp, hq, np.arange(hp.size)), (hq[off], hp[off], off)):
            inst, entry, col_a, col_b, coef = _pairs(padded, n_z, n, left, right)
            keep = col_a <= col_b  # the upper triangle's share; the rest is its mirror image
            hess_scatter.add(col_a[keep], col_b[keep], (inst * hp.size + entries[entry])[keep], coef[keep], k)
        hess_sizes.append(n * hp.size)
        gradient = None
        if kern.gradient is not None:
            inst, entry, col, coef = _single(padded, n_z, n, np.arange(n_z))
            gradient = _dm(sparse.csc_matrix((coef, (col, inst * n_z + entry)), shape=(nw, n * n_z)))
        kernels.append((kern, gradient))
    jac_pattern, jac_matrices = jac_scatter.matrices((ng, nw), jac_sizes)
    hess_pattern, hess_matrices = hess_scatter.matrices((nw, nw), hess_sizes)
    return _assembled(w, parameters, constraints, cost, rest, rest_functions, kernels,
                      (jac_pattern, jac_matrices), (hess_pattern, hess_matrices))


def _assembled(w, parameters, constraints, cost, rest, rest_functions, kernels, jac, hess) -> dict:
    """The three MX Functions: each point function's derivatives mapped over its instants, scattered."""
    x, p = ca.MX.sym("x", w.numel()), ca.MX.sym("p", parameters.numel())
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", constraints.numel())
    f_value = ca.Function("nlp_f", [w, parameters], [cost])(x, p)
    g_value = ca.Function("nlp_g", [w, parameters], [constraints])(x, p)
    gradient = rest_functions["grad"](x, p)
    jac_nz = ca.mtimes(jac[1][0], rest_functions["jac"](x, p))
    hess_nz = ca.mtimes(hess[1][0], rest_functions["hess"](x, p, lam_f, lam_g[rest.tolist()]))
    for k, (kern, grad_matrix) in enumerate(kernels, start=1):
        pf, n = kern.pf, kern.pf.instants
        z = ca.reshape(ca.mtimes(_dm(kern.a), x) + kern.b, pf.inputs.size1(), n)
        weight = (ca.Function(f"{pf.name}_weight", [parameters], [pf.weight])(p) if pf.weight is not None
                  else ca.MX(0))
        if kern.rows:
            mu = ca.reshape(lam_g[kern.multipliers.ravel().tolist()], kern.rows, n)
        else:
            mu = ca.MX(0, 1)
        jac_nz += ca.mtimes(jac[1][k], ca.vec(kern.jacobian.map(n)(z)))
        hess_nz += ca.mtimes(hess[1][k], ca.vec(kern.hessian.map(n)(z, mu, lam_f * weight)))
        if grad_matrix is not None:
            gradient += weight * ca.mtimes(grad_matrix, ca.vec(kern.gradient.map(n)(z)))
    return {"grad_f": ca.Function("nlp_grad_f", [x, p], [f_value, gradient], ["x", "p"], ["f", "grad_f_x"]),
            "jac_g": ca.Function("nlp_jac_g", [x, p], [g_value, ca.MX(jac[0], jac_nz)], ["x", "p"],
                                 ["g", "jac_g_x"]),
            "hess_lag": ca.Function("nlp_hess_l", [x, p, lam_f, lam_g], [ca.MX(hess[0], hess_nz)],
                                    ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])}
