"""The muscle force-sharing problem on a time grid: models, nodes and moment equations (4.20–4.25).

``build_problem`` samples the motion at uniformly spaced nodes, computes the
joint moments by inverse dynamics, subtracts the passive and damping moments
and evaluates muscle lengths, velocities and moment arms, so that each method
only has to find forces with ``R_j·F_j = b_j`` at every node j (4.21).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.dynamics.sagittal import SagittalMotion
from gaitcli.errors import InputError

from .hill import MuscleModel
from .limb import LimbModel, LimbParameters, MotionInterpolant, MotionSamples
from .parameters import JointParameters, MuscleParameters
from .passive import JointModel


@dataclass(frozen=True)
class Models:
    """The compiled muscle, limb and joint models of one subject and parameter set."""

    muscle: MuscleModel
    limb: LimbModel
    joints: JointModel

    @classmethod
    def build(cls, limb: LimbParameters, muscles: MuscleParameters | None = None,
              joints: JointParameters | None = None) -> "Models":
        return cls(MuscleModel(muscles), LimbModel(limb), JointModel(joints))


@dataclass(frozen=True)
class Problem:
    """Everything the methods need at the nodes of the analysis grid.

    Nodes ``time_s`` (n,) spaced ``dt_s``; with ``periodic`` the last node is
    followed by the first after one ``dt_s`` (4.3.1, 4.5.2), otherwise nodes
    ``interval`` (a slice) are the period of interest and the others the extra
    nodes before/after (4.3.6). Arrays: ``l_m``/``v_m`` (n, m) muscle length and
    lengthening velocity, ``arms`` (n, 3, m) moment arms (A.11),
    ``tau_id``/``tau_passive``/``tau_damping`` (n, 3) and ``required`` = b (n, 3)
    the moment the muscles must produce (4.21).
    """

    models: Models
    samples: MotionSamples
    dt_s: float
    periodic: bool
    interval: slice
    t_start_s: float
    t_end_s: float
    l_m: np.ndarray
    v_m: np.ndarray
    arms: np.ndarray
    tau_id: np.ndarray
    tau_passive: np.ndarray
    tau_damping: np.ndarray
    required: np.ndarray
    distance_m: float
    body_mass_kg: float

    @property
    def time_s(self) -> np.ndarray:
        return self.samples.time_s

    @property
    def n(self) -> int:
        return self.time_s.size

    @property
    def scheme(self) -> str:
        """Finite-difference scheme of the inversions (4.10–4.12)."""
        return "periodic" if self.periodic else "central"

    def moment_error(self, force_N: np.ndarray) -> np.ndarray:
        """R_j·F_j − b_j (n, 3) in N·m: muscle + passive + damping − inverse dynamics (4.20)."""
        return np.einsum("nkm,nm->nk", self.arms, force_N) - self.required

    def muscle_moments(self, force_N: np.ndarray) -> np.ndarray:
        return np.einsum("nkm,nm->nk", self.arms, force_N)


def default_interval(motion: SagittalMotion) -> tuple[float, float, bool]:
    """The first full cycle between heel strikes (periodic), else the whole table (not periodic)."""
    hs = sorted(h for h in motion.heel_strike_s if motion.time_s[0] - 1e-9 <= h <= motion.time_s[-1] + 1e-9)
    if len(hs) >= 2:
        return hs[0], hs[1], True
    return float(motion.time_s[0]), float(motion.time_s[-1]), False


def build_problem(motion: SagittalMotion, models: Models, *, nodes: int | None = None,
                  interval: tuple[float, float] | None = None, periodic: bool | None = None,
                  extra_nodes: int = 2) -> Problem:
    """Sample the motion on the analysis grid and set up the moment equations.

    A periodic grid has ``nodes`` nodes on [t_start, t_end); otherwise ``nodes`` nodes on
    [t_start, t_end] plus up to ``extra_nodes`` before and after where the table has data (4.3.6).

    Parameters
    ----------
    motion : SagittalMotion
        The leg's motion (SI, rad).
    models : Models
        The compiled muscle, limb and joint models.
    nodes : int, optional
        Default one per frame of the table.
    interval : (float, float), optional
        (t_start, t_end), s; default :func:`default_interval`.
    periodic : bool, optional
        Default True for a heel-strike-to-heel-strike cycle.
    extra_nodes : int
        Nodes before and after a non-periodic interval.
    """
    t0_default, t1_default, periodic_default = default_interval(motion)
    t0, t1 = (t0_default, t1_default) if interval is None else (float(interval[0]), float(interval[1]))
    if periodic is None:
        periodic = periodic_default if interval is None else False
    if not t1 > t0:
        raise InputError(motion.source, "interval", f"got {t0}–{t1} s (expected t_end > t_start)")
    frame_dt = float(np.median(np.diff(motion.time_s)))
    if nodes is None:
        nodes = int(round((t1 - t0) / frame_dt)) + (0 if periodic else 1)
    if nodes < 4:
        raise InputError(motion.source, "nodes", f"got {nodes} (expected at least 4)")
    if periodic:
        dt = (t1 - t0) / nodes
        times = t0 + dt * np.arange(nodes)
        interior = slice(0, nodes)
    else:
        dt = (t1 - t0) / (nodes - 1)
        t_first, t_last = motion.time_s[0], motion.time_s[-1]
        before = min(extra_nodes, int(np.floor((t0 - t_first) / dt + 1e-9)))
        after = min(extra_nodes, int(np.floor((t_last - t1) / dt + 1e-9)))
        times = t0 + dt * np.arange(-before, nodes + after)
        interior = slice(before, before + nodes)
    interp = MotionInterpolant(motion, times[0], max(times[-1], t1))
    s = interp(times)
    muscle, limb, joints = models.muscle, models.limb, models.joints
    tau_id = limb.evaluate("inverse_dynamics", s.q, s.qd, s.qdd, s.hip_m, s.hip_acc, s.grf_N, s.cop_x_m[:, None])
    # joint angles and rates of the muscle and joint models; ψ = q for the limb, so their moments are τ
    angles, rates = limb.evaluate("joint_angles", s.q), limb.evaluate("joint_angles", s.qd)
    tau_p = joints.evaluate("passive", angles)
    tau_d = joints.evaluate("damping", rates)
    hip_end = interp(np.array([t1])).hip_m[0, 0]
    return Problem(models=models, samples=s, dt_s=dt, periodic=periodic, interval=interior,
                   t_start_s=t0, t_end_s=t1,
                   l_m=muscle.evaluate("length", angles), v_m=muscle.evaluate("velocity", angles, rates),
                   arms=muscle.evaluate("moment_arms", angles), tau_id=tau_id, tau_passive=tau_p,
                   tau_damping=tau_d, required=tau_id - tau_p - tau_d,
                   distance_m=float(hip_end - interp(np.array([t0])).hip_m[0, 0]),
                   body_mass_kg=limb.params.body_mass_kg)
