"""2-D thigh–shank–foot model with prescribed hip motion (Diss. 4.5.1), and its input.

Geometry (model axes x forward, z up, motion in the x–z plane). Generalized
coordinates ``q = (θ, β, δ)``: θ thigh angle from the downward vertical,
positive when the knee is in front of the hip (hip flexion with the trunk
upright), β knee flexion, δ ankle dorsiflexion (0 with the foot ⟂ shank). The
hip centre (x_hip(t), z_hip(t)) is prescribed (two rheonomic constraints).
Absolute segment angles, counter-clockwise seen with x to the right and z up
(= rotation about −y, i.e. flexion-positive): thigh θ, shank θ − β, foot
θ − β + δ. The generalized forces conjugate to q are the hip flexion, knee
flexion and ankle dorsiflexion moments, the signs of the output tables.

The equations come from the planar-chain builder (:mod:`gaitcli.dynamics.planar`,
prescribed base = the hip); segment inertia from de Leva (1996) (docs/model_constants.md §1,
the table of :mod:`gaitcli.kinematics.anthropometry`). The ground reaction acts
on the foot at (cop_x, 0): the floor is the plane z = 0.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np
from scipy.interpolate import CubicSpline

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.dynamics.planar import Joint, PlanarChain, Segment
from gaitcli.dynamics.sagittal import SagittalMotion
from gaitcli.errors import InputError
from gaitcli.kinematics.anthropometry import DE_LEVA, REFERENCE_STATURE_M, normalise_sex

from .evaluation import evaluate

#: the limb's generalized coordinates, in order
LIMB_COORDINATES = ("thigh_angle", "knee_flexion", "ankle_dorsiflexion")

#: de Leva (1996) segments of the limb (kinematics.anthropometry.DE_LEVA): thigh HJC→KJC, shank KJC→AJC,
#: foot HEEL→TTIP, and the radius of gyration of each for the sagittal plane: r_trans, except the foot,
#: where the dissertation (Table A.5, I_Y = 0.0047 kg m²) uses r_sag
_SAGITTAL_GYRATION = {"thigh": "r_trans_pct", "shank": "r_trans_pct", "foot": "r_sag_pct"}
#: heel-to-ankle distance along the foot / stature (gait2dc: 0.06 m at 1.8 m; docs/model_constants.md §12)
_HEEL_TO_ANKLE_PER_STATURE = 0.060 / 1.8
#: foot CoM below the ankle / stature (Diss. Table A.5, subject 1: 0.043 m at 1.792 m)
_FOOT_COM_BELOW_ANKLE_PER_STATURE = 0.043 / 1.792

@dataclass(frozen=True)
class LimbParameters:
    """Mass, geometry and inertia of thigh, shank and foot (SI units).

    ``thigh_com_m`` from the hip along the thigh, ``shank_com_m`` from the knee
    along the shank; the foot CoM lies ``foot_com_forward_m`` ahead of the ankle
    along the foot and ``foot_com_down_m`` below it (foot frame, foot ⟂ shank at
    neutral). Inertias are sagittal, about the segment CoM.
    """

    body_mass_kg: float
    stature_m: float
    thigh_length_m: float
    shank_length_m: float
    foot_length_m: float
    thigh_mass_kg: float
    shank_mass_kg: float
    foot_mass_kg: float
    thigh_com_m: float
    shank_com_m: float
    foot_com_forward_m: float
    foot_com_down_m: float
    thigh_inertia_kgm2: float
    shank_inertia_kgm2: float
    foot_inertia_kgm2: float
    sex: str = "male"
    gravity_m_s2: float = GRAVITY_M_S2
    notes: tuple = field(default=())

    @classmethod
    def from_body(cls, body, side: str, *, body_mass_kg: float, stature_m: float, sex: str) -> "LimbParameters":
        """The sagittal limb of one side from the 3-D model's segment parameters (idyn), added masses included.

        Lengths are the hip–knee and knee–ankle joint-centre distances, CoM distances
        their projections on the segment axis, inertias the segments' I_yy about their
        CoM; the foot CoM relative to the ankle in the foot's reference frame.
        """
        from gaitcli.kinematics.model import BODIES, JOINTS

        j = {name: JOINTS.index(f"{name}_{side}") for name in ("hip", "knee", "ankle")}
        b = {name: BODIES.index(f"{name}_{side}") for name in ("thigh", "shank", "foot")}
        top = {"thigh": body.joint_in_child_m[j["hip"]], "shank": body.joint_in_child_m[j["knee"]]}
        bottom = {"thigh": body.joint_in_parent_m[j["knee"]], "shank": body.joint_in_parent_m[j["ankle"]]}
        length = {k: float(np.linalg.norm(bottom[k] - top[k])) for k in top}
        com = {k: float(np.dot(-top[k], (bottom[k] - top[k]) / length[k])) for k in top}
        ankle_in_foot = body.joint_in_child_m[j["ankle"]]
        return cls(
            body_mass_kg=float(body_mass_kg), stature_m=float(stature_m),
            thigh_length_m=length["thigh"], shank_length_m=length["shank"],
            foot_length_m=0.152 * float(stature_m),  # Winter: heel–toe 0.152·H (docs/model_constants.md §12)
            thigh_mass_kg=float(body.mass_kg[b["thigh"]]), shank_mass_kg=float(body.mass_kg[b["shank"]]),
            foot_mass_kg=float(body.mass_kg[b["foot"]]),
            thigh_com_m=com["thigh"], shank_com_m=com["shank"],
            foot_com_forward_m=float(-ankle_in_foot[0]), foot_com_down_m=float(ankle_in_foot[2]),
            thigh_inertia_kgm2=float(body.inertia_kgm2[b["thigh"]][1, 1]),
            shank_inertia_kgm2=float(body.inertia_kgm2[b["shank"]][1, 1]),
            foot_inertia_kgm2=float(body.inertia_kgm2[b["foot"]][1, 1]), sex=sex,
            notes=("segment parameters of the idyn stage's 3-D model (de Leva with measured lengths and any "
                   "added masses), sagittal inertia I_yy",))

    @classmethod
    def from_anthropometry(cls, mass_kg: float, stature_m: float, sex: str, *,
                           thigh_length_m: float | None = None,
                           shank_length_m: float | None = None) -> "LimbParameters":
        """de Leva (1996) parameters; lengths scaled by stature unless measured."""
        sex = normalise_sex(sex)
        if not (mass_kg > 0 and stature_m > 0):
            raise InputError(None, "mass_kg/stature_m", f"got {mass_kg}, {stature_m} (expected numbers > 0)")
        table = DE_LEVA[sex]
        scale = stature_m * 1000.0 / (REFERENCE_STATURE_M[sex] * 1000.0)
        segs = {}
        for name, measured in (("thigh", thigh_length_m), ("shank", shank_length_m), ("foot", None)):
            row = table[name]
            length = measured if measured is not None else row.length_mm * scale / 1000.0
            mass = row.mass_pct / 100.0 * mass_kg
            gyration = getattr(row, _SAGITTAL_GYRATION[name]) / 100.0 * length
            segs[name] = (length, mass, row.com_pct / 100.0 * length, mass * gyration ** 2)
        foot_len = segs["foot"][0]
        return cls(
            body_mass_kg=float(mass_kg), stature_m=float(stature_m),
            thigh_length_m=segs["thigh"][0], shank_length_m=segs["shank"][0], foot_length_m=foot_len,
            thigh_mass_kg=segs["thigh"][1], shank_mass_kg=segs["shank"][1], foot_mass_kg=segs["foot"][1],
            thigh_com_m=segs["thigh"][2], shank_com_m=segs["shank"][2],
            foot_com_forward_m=segs["foot"][2] - _HEEL_TO_ANKLE_PER_STATURE * stature_m,
            foot_com_down_m=_FOOT_COM_BELOW_ANKLE_PER_STATURE * stature_m,
            thigh_inertia_kgm2=segs["thigh"][3], shank_inertia_kgm2=segs["shank"][3],
            foot_inertia_kgm2=segs["foot"][3], sex=sex,
            notes=("de Leva (1996), docs/model_constants.md §1; foot CoM offsets: heel–ankle 0.033·H "
                   "(gait2dc), CoM 0.024·H below the ankle (Diss. Table A.5, subject 1)",))


def limb_chain(params: LimbParameters) -> PlanarChain:
    """The thigh–shank–foot chain on a prescribed hip (4.5.1), built with :mod:`gaitcli.dynamics.planar`.

    Coordinates (θ, β, δ): thigh absolute angle, knee flexion (turns the shank
    backward, sign −1), ankle dorsiflexion. The foot frame's *along* axis is
    ⟂ to the foot (down at neutral) and its *across* axis along the foot (forward),
    so the foot CoM is at (foot_com_down_m, foot_com_forward_m) from the ankle.
    """
    p = params
    segments = [
        Segment("thigh", p.thigh_mass_kg, p.thigh_inertia_kgm2, p.thigh_length_m, p.thigh_com_m,
                points={"knee": (p.thigh_length_m, 0.0)}),
        Segment("shank", p.shank_mass_kg, p.shank_inertia_kgm2, p.shank_length_m, p.shank_com_m,
                points={"ankle": (p.shank_length_m, 0.0)}),
        Segment("foot", p.foot_mass_kg, p.foot_inertia_kgm2, p.foot_length_m, p.foot_com_down_m,
                com_across_m=p.foot_com_forward_m),
    ]
    joints = [Joint(LIMB_COORDINATES[0], None, "thigh", absolute=True),
              Joint(LIMB_COORDINATES[1], "thigh", "shank", sign=-1.0),
              Joint(LIMB_COORDINATES[2], "shank", "foot")]
    return PlanarChain(segments, joints, base="prescribed", gravity_m_s2=p.gravity_m_s2)


class LimbModel:
    """The limb's equations of motion, written once in CasADi (2.13, 2.29, 4.5.1).

    Functions:
    - ``points(q, hip) → (knee, ankle)`` joint centres (x, z) in m
    - ``inverse_dynamics(q, qd, qdd, hip, hip_acc, grf, cop_x) → τ`` (3): the hip
      flexion, knee flexion and ankle dorsiflexion moments that reproduce the
      motion, τ = M(q)q̈ + k(q, q̇, ḧ) − q_g(q) − q_gr(q, f_gr) (4.2, 4.21)
    - ``forward_dynamics(q, qd, tau, hip, hip_acc, grf, cop_x) → q̈`` (2.29)
    - ``mass_matrix(q) → M`` (3 × 3)
    - ``joint_angles(q) → ψ``: hip flexion, knee flexion, ankle dorsiflexion, the
      angles the muscle and passive-joint models take. ψ = P·q is linear (hip
      flexion = thigh angle − trunk angle), so the same map gives the joint angle
      rates and Pᵀ turns joint moments into generalized forces; with the trunk
      upright P = I: ψ = q and the joint moments are τ.
    """

    def __init__(self, params: LimbParameters):
        self.params = params
        self.chain = chain = limb_chain(params)
        sym = ca.SX.sym
        q, qd, qdd, tau = sym("q", 3), sym("qd", 3), sym("qdd", 3), sym("tau", 3)
        hip, hip_acc, grf, cop = sym("hip", 2), sym("hip_acc", 2), sym("grf", 2), sym("cop_x")
        mass_matrix = chain.mass_matrix(q)
        # ground reaction at (cop_x, 0) on the foot, the floor being the plane z = 0
        q_gr = chain.applied_force["foot"](q, hip, ca.vertcat(cop, 0), grf, 0)
        tau_id = chain.inverse_dynamics(q, qd, qdd, hip_acc) - q_gr
        bias = chain.inverse_dynamics(q, qd, ca.SX.zeros(3), hip_acc) - q_gr  # k − g − q_gr
        knee, ankle = chain.points(q, hip)
        args, names = [hip, hip_acc, grf, cop], ["hip", "hip_acc", "grf", "cop_x"]
        self.points = ca.Function("points", [q, hip], [knee, ankle], ["q", "hip"], ["knee", "ankle"])
        self.mass_matrix = ca.Function("mass_matrix", [q], [mass_matrix], ["q"], ["M"])
        self.inverse_dynamics = ca.Function("inverse_dynamics", [q, qd, qdd, *args], [tau_id],
                                            ["q", "qd", "qdd", *names], ["tau"])
        self.forward_dynamics = ca.Function("forward_dynamics", [q, qd, tau, *args],
                                            [ca.solve(mass_matrix, tau - bias)], ["q", "qd", "tau", *names], ["qdd"])
        self.joint_angles = ca.Function("joint_angles", [q], [q], ["q"], ["joint_angles"])

    def evaluate(self, name: str, *args):
        """Evaluate Function ``name`` on arrays shaped (n, k) (see ``evaluation.evaluate``)."""
        return evaluate(getattr(self, name), *args)


@dataclass(frozen=True)
class MotionSamples:
    """The motion at analysis times: coordinates and derivatives, hip, ground reaction.

    Shapes: ``time_s`` (n,), ``q``/``qd``/``qdd`` (n, 3), ``hip_m``/``hip_vel``/``hip_acc``
    (n, 2), ``grf_N`` (n, 2), ``cop_x_m`` (n,).
    """

    time_s: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    hip_m: np.ndarray
    hip_vel: np.ndarray
    hip_acc: np.ndarray
    grf_N: np.ndarray
    cop_x_m: np.ndarray


class MotionInterpolant:
    """Continuous-time motion: cubic splines of coordinates and hip, linear ground reaction.

    Built on the frames covering ``[t_start, t_end]`` (plus two frames either
    side where available); raises InputError if any of them holds NaN.
    """

    def __init__(self, motion: SagittalMotion, t_start: float, t_end: float):
        t = motion.time_s
        first = max(int(np.searchsorted(t, t_start, side="right")) - 3, 0)
        last = min(int(np.searchsorted(t, t_end, side="left")) + 2, t.size - 1)
        if t_start < t[0] - 1e-9 or t_end > t[-1] + 1e-9:
            raise InputError(motion.source, "time_s",
                             f"the analysed interval {t_start:.3f}–{t_end:.3f} s is outside the table "
                             f"({t[0]:.3f}–{t[-1]:.3f} s)")
        motion.check_finite(first, last)
        sl = slice(first, last + 1)
        ts = t[sl]
        self.t_range = (ts[0], ts[-1])
        self._q = CubicSpline(ts, motion.angles_rad[sl], axis=0)
        self._hip = CubicSpline(ts, np.column_stack([motion.hip_x_m[sl], motion.hip_z_m[sl]]), axis=0)
        self._ts = ts
        self._grf = np.column_stack([motion.grf_x_N[sl], motion.grf_z_N[sl]])
        cop = motion.cop_x_m[sl]
        ok = np.isfinite(cop)
        # where the foot is unloaded the COP is irrelevant; hold the nearest measured value
        self._cop = np.interp(ts, ts[ok], cop[ok]) if ok.any() else np.zeros_like(ts)

    def __call__(self, times) -> MotionSamples:
        times = np.atleast_1d(np.asarray(times, dtype=float))
        grf = np.column_stack([np.interp(times, self._ts, self._grf[:, k]) for k in range(2)])
        return MotionSamples(time_s=times, q=self._q(times), qd=self._q(times, 1), qdd=self._q(times, 2),
                             hip_m=self._hip(times), hip_vel=self._hip(times, 1), hip_acc=self._hip(times, 2),
                             grf_N=grf, cop_x_m=np.interp(times, self._ts, self._cop))
