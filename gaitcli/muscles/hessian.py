"""A positive semi-definite curvature of EID's metabolic objective for IPOPT's Hessian of the Lagrangian.

The metabolic rate (4.29, A.12–A.21) is concave in parts (a_m^0.6 of the maintenance heat (A.15), the
ṽ-dependent heat and the work −f_ce·v_ce (2.26)), so its exact Hessian is indefinite and IPOPT regularises the
Hessian of the Lagrangian (inertia corrections) and takes short steps for hundreds of iterations
(benchmarks/README.md, "EID's growth with its nodes"). The NLP itself is not changed: IPOPT still sees the exact
objective, gradient, constraints and Jacobian, so its KKT points are those of the dissertation's problem; only the
Hessian it steps with is replaced, as a sequential-convex-programming method does.

The rate at node j of muscle i depends on five variables only: ŝ at j and at the (at most two) other nodes of
the finite difference of row j (4.10–4.12), a and u at j. Its 5 × 5 Hessian block in these variables is
computed exactly and its negative eigenvalues λ are replaced by :data:`NEGATIVE_CURVATURE_REFLECTED`·|λ|; the
objective's curvature is the sum of these blocks, each weighted as in (4.29). The constraints' curvature (λᵀ∇²g)
is kept exact. Near the KKT point (:data:`SMALL_STEPS` small steps) the blocks are passed exact, so that IPOPT
finishes with Newton's fast local convergence.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gaitcli.core.numerics import finite_difference_matrix

#: a block's negative eigenvalue λ becomes this fraction of |λ| (0: the nearest positive semi-definite matrix;
#: 1: |λ|, the "saddle-free" Newton model); benchmarks/README.md, "EID's growth with its nodes"
NEGATIVE_CURVATURE_REFLECTED = 0.5
#: the exact curvature from the call after this many successive steps (calls at new points) each moved every
#: variable (ŝ, a, u: all O(1)) by less than :data:`SMALL_STEP`: IPOPT is then near its KKT point, where the
#: exact Hessian converges fast and the modified one only linearly
SMALL_STEPS, SMALL_STEP = 3, 1e-4
#: the local variables of one block, in this order
BLOCK = ("stretch", "stretch_other_1", "stretch_other_2", "activation", "excitation")


def _neighbours(d: np.ndarray):
    """Per row j of the difference matrix D: its coefficient on node j and on the (≤ 2) other nodes.

    Returns (self coefficient (n,), other nodes (n, 2), their coefficients (n, 2)); a row with fewer
    than two other nodes is padded with node j and coefficient 0.
    """
    n = d.shape[0]
    others, coefs = np.tile(np.arange(n)[:, None], (1, 2)), np.zeros((n, 2))
    for j in range(n):
        cols = [k for k in np.flatnonzero(d[j]) if k != j]
        if len(cols) > 2:
            raise ValueError(f"row {j} of the difference matrix has {len(cols)} other nodes (at most 2 expected)")
        others[j, :len(cols)], coefs[j, :len(cols)] = cols, d[j, cols]
    return np.diag(d).copy(), others, coefs


def _block_function(muscle, smoothing: float) -> ca.Function:
    """The upper triangle of each muscle's 5 × 5 Hessian of its metabolic rate (W) in the local variables
    (:data:`BLOCK`), elementwise over muscles: 15 outputs (m,), row-major over the upper triangle."""
    m = muscle.m
    sym = ca.SX.sym
    s, s1, s2, a, u = (sym(name, m) for name in ("s", "s1", "s2", "a", "u"))
    c0, c1, c2, l_m, v_m = (sym(name, m) for name in ("c0", "c1", "c2", "l_m", "v_m"))
    force, l_se = muscle.stretch_tendon(s)
    v_se = c0 * l_se + c1 * muscle.stretch_tendon(s1)[1] + c2 * muscle.stretch_tendon(s2)[1]  # (4.10)–(4.14)
    l_ce, v_ce = muscle.fibre_kinematics(l_se, v_se, l_m, v_m)  # (4.15), (4.17)
    cos_pen = ca.DM(np.cos(muscle.params.pennation_rad))
    rate = muscle.smoothed_metabolic_rate(smoothing)(u, a, l_ce, v_ce, force / cos_pen)
    hess = ca.hessian(ca.sum1(rate), ca.vertcat(s, s1, s2, a, u))[0]
    # each muscle's rate depends on that muscle's variables only: muscle i's block is rows/columns i + m·k
    entries = [ca.vertcat(*[hess[p * m + i, q * m + i] for i in range(m)]) for p in range(5) for q in range(p, 5)]
    return ca.Function("metabolic_rate_hessian_blocks", [s, s1, s2, a, u, c0, c1, c2, l_m, v_m], entries)


class ConvexObjectiveCurvature(ca.Callback):
    """σ·Σ_j w_j·Δt·Σ_i [∇²Ė_ij]₊ (upper triangle) as a CasADi Function of (x, σ): see the module docstring."""

    def __init__(self, problem, smoothing: float, weights: np.ndarray):
        ca.Callback.__init__(self)
        muscle = problem.models.muscle
        m, n = muscle.m, problem.n
        self._m, self._n, self._nx = m, n, 3 * m * n
        c_self, others, coefs = _neighbours(finite_difference_matrix(n, problem.dt_s, problem.scheme))
        self._others = others
        x = ca.SX.sym("x", self._nx)
        s, a, u = (ca.reshape(x[k * m * n:(k + 1) * m * n], m, n) for k in range(3))
        tiled = [ca.DM(np.tile(c[None, :], (m, 1))) for c in (c_self, coefs[:, 0], coefs[:, 1])]
        entries = _block_function(muscle, smoothing).map(n)(
            s, s[:, others[:, 0].tolist()], s[:, others[:, 1].tolist()], a, u, *tiled,
            ca.DM(problem.l_m.T), ca.DM(problem.v_m.T))
        self._blocks = ca.Function("metabolic_rate_hessian_blocks", [x], [ca.vertcat(*map(ca.vec, entries))])
        self._block_values = np.zeros(15 * m * n)
        self._buffer, self._buffer_eval = self._blocks.buffer()  # evaluated in place, no DM conversions
        self._buffer.set_res(0, memoryview(self._block_values))
        self._scale = (problem.dt_s * np.asarray(weights, float))[None, :]  # (1, n)
        muscles, nodes = np.meshgrid(np.arange(m), np.arange(n), indexing="ij")  # (m, n)
        size = m * n
        stretch_at = nodes * m + muscles  # index of ŝ_ij in x (node-major, eid.py)
        index = np.stack([stretch_at, others[None, :, 0] * m + muscles, others[None, :, 1] * m + muscles,
                          size + stretch_at, 2 * size + stretch_at], axis=-1)  # (m, n, 5)
        rows, cols = index[..., :, None], index[..., None, :]  # every ordered pair of a block
        keep = np.broadcast_to(rows <= cols, (m, n, 5, 5))
        self._kept = np.flatnonzero(keep)
        r, c = np.broadcast_to(rows, keep.shape)[keep], np.broadcast_to(cols, keep.shape)[keep]
        key = c.astype(np.int64) * self._nx + r  # column-major, the order of a CasADi sparsity's non-zeros
        unique = np.unique(key)
        self._position = np.searchsorted(unique, key)
        self._pattern = ca.Sparsity.triplet(self._nx, self._nx, (unique % self._nx).tolist(),
                                            (unique // self._nx).tolist())
        self._last_x, self._small_steps = None, 0
        #: IPOPT's Hessian evaluations so far, and the first that was exact (None: none yet)
        self.calls, self.exact_from = 0, None
        self.construct("convex_objective_curvature", {})

    def get_n_in(self):
        return 2

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ("x", "lam_f")[i]

    def get_name_out(self, i):
        return "hess"

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(self._nx, 1) if i == 0 else ca.Sparsity.dense(1, 1)

    def get_sparsity_out(self, i):
        return self._pattern

    def _entries(self, x: np.ndarray) -> np.ndarray:
        """The 15 upper-triangle entries of every block (m, n, 15), evaluated into a preallocated buffer."""
        m, n = self._m, self._n
        x = np.ascontiguousarray(x, dtype=float)
        self._buffer.set_arg(0, memoryview(x))
        self._buffer_eval()
        return self._block_values.reshape(15, n, m).transpose(2, 1, 0)

    def blocks(self, x: np.ndarray) -> np.ndarray:
        """The exact Hessian blocks (m, n, 5, 5) of Ė_ij in the local variables, W per unit² of the variables."""
        m, n = self._m, self._n
        entries = self._entries(x)
        h = np.zeros((m, n, 5, 5))
        rows, cols = np.triu_indices(5)
        h[:, :, rows, cols] = entries
        h[:, :, cols, rows] = entries
        return h

    def has_eval_buffer(self):
        return True  # eval_buffer: the arrays in place, without conversions to and from DM

    def eval_buffer(self, arg, res):
        x = np.frombuffer(arg[0], dtype=float)
        sigma = np.frombuffer(arg[1], dtype=float)[0]
        np.frombuffer(res[0], dtype=float)[:] = self.nonzeros(x, sigma)
        return 0

    def eval(self, arg):
        return [ca.DM(self._pattern, self.nonzeros(np.asarray(arg[0], float).ravel(), float(arg[1])))]

    def nonzeros(self, x: np.ndarray, sigma: float) -> np.ndarray:
        """The non-zeros of σ·Σ w_j·Δt·[∇²Ė_ij]₊ in the order of the output's sparsity (the exact blocks after
        :data:`SMALL_STEPS` small steps)."""
        self.calls += 1
        if self._last_x is not None and self.exact_from is None:
            step = np.abs(x - self._last_x).max()
            if step > 0:  # a second call at the same point is no step
                self._small_steps = self._small_steps + 1 if step < SMALL_STEP else 0
            if self._small_steps >= SMALL_STEPS:
                self.exact_from = self.calls
        self._last_x = x.copy()
        h = self.blocks(x) * (sigma * self._scale)[:, :, None, None]
        if self.exact_from is None:
            values, vectors = np.linalg.eigh(h)
            values = np.maximum(values, NEGATIVE_CURVATURE_REFLECTED * np.abs(values))
            h = (vectors * values[..., None, :]) @ vectors.swapaxes(-1, -2)
        return np.bincount(self._position, weights=h.reshape(-1)[self._kept], minlength=self._pattern.nnz())


def convex_hessian(problem, smoothing: float, weights: np.ndarray, x, cost, g
                   ) -> tuple[ca.Function, ConvexObjectiveCurvature]:
    """IPOPT's ``hess_lag`` for EID's metabolic NLP (x, cost, g of ``eid._eid_nlp``, its quadrature ``weights``
    (n,)): the constraints' exact curvature plus :class:`ConvexObjectiveCurvature`. Returns the Function and the
    callback (keep it alive as long as the solver)."""
    lam_g = ca.SX.sym("lam_g", g.shape[0])
    constraint_curvature = ca.Function("constraint_curvature", [x, lam_g],
                                       [ca.triu(ca.hessian(ca.dot(lam_g, g), x)[0])])
    curvature = ConvexObjectiveCurvature(problem, smoothing, weights)
    xs, p, lam_f, lam_gs = (ca.MX.sym(name, *shape) for name, shape in
                            (("x", x.shape), ("p", (0, 1)), ("lam_f", (1, 1)), ("lam_g", (g.shape[0], 1))))
    hess = constraint_curvature(xs, lam_gs) + curvature(xs, lam_f)
    return ca.Function("nlp_hess_l", [xs, p, lam_f, lam_gs], [hess], ["x", "p", "lam_f", "lam_g"],
                       ["hess_gamma_x_x"]), curvature
