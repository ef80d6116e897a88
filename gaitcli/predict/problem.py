"""The predictive gait transcribed numerically (Diss. 5.2.4–5.2.9): χ → everything at the control points.

:class:`Transcriber` evaluates, for a design vector χ (called on χ: numpy or CasADi; layout
:class:`gaitcli.predict.layout.DesignLayout`, full model) or for a gait given by its values at the
instants (:meth:`Transcriber.at`, e.g. the symmetric model's, :func:`gait_at`), at the P control points
of the phase-wise grid (``grid.py``): the coordinates and their rates from the
quartic splines (y1 with the drift ΔS/T), the 16 muscle forces from the cubic
tendon-stretch splines, the equations of motion's right-hand side

    rhs = M(y) ÿ + k(y, ẏ) − g(y) − Q_p(y, ẏ) − R(y) f_m                     (5.1)

the ground reactions λ = G_ph⁺ rhs and residual e = rhs − G_ph λ (5.30–5.31), the
joint-moment error B⁺ e = τm* − τm (5.49–5.51; R = B·A), the contact error c_ph
(5.57), the clearance of the points not in contact and the per-foot reactions;
and, at the I distinct instants, the muscle states by inversion (5.25–5.26) and
the metabolic rates, in a :class:`Transcription`.

The NLP (``nlp.py``) does not use these expressions: it states the same quantities as lifted variables.
This transcription is independent of it: it gives the NLP its start (``NLP.lifted_start``) and evaluates a
solution anew (``stage.evaluate_design``, the fine grid), λ by the pseudoinverse. A :class:`Transcriber`
also holds what both share: the model, contact, muscles, grid and splines of one subject and node count.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitcli.predict.contact import ContactModel, ground_reactions, joint_moment_map
from gaitcli.predict.cost import invert_muscles
from gaitcli.predict.grid import (
    ControlGrid,
    control_grid,
    cycle_period,
    instant_times,
    point_times,
)
from gaitcli.predict.layout import DesignLayout, full_trunk_spline
from gaitcli.predict.model import WalkingModel
from gaitcli.predict.muscles import WalkerMuscles
from gaitcli.predict.splines import cubic, evaluate, hip_x, is_casadi, quartic


@dataclass
class Transcription:
    """Everything at the control points (P rows, in grid order) and at the distinct instants (I rows).

    ``y``, ``yd``, ``ydd`` (P × 9); ``forces_N`` (P × 16); ``generalized_forces`` rhs (P rows of 9, N or
    N·m, what the ground must balance, 5.1); ``reactions[j]`` λ at point j (the phase's
    reaction names, ``ContactModel.reaction_names``); ``residual[j]`` e (9,); ``moment_error_Nm``
    (P × 6) B⁺e; ``contact_error_m[j]`` c_ph (rows of the phase); ``period_s``, ``stride_m``,
    ``point_times_s`` (P,), ``instant_times_s`` (I,); ``muscle_lengths_m``, ``muscle_velocities_m_s``
    (I × 16); ``muscle_state`` (I × 16 arrays of the inversion);
    ``metabolic_rate_W`` (I × 16).
    """

    y: object
    yd: object
    ydd: object
    forces_N: object
    stretch: object
    generalized_forces: object
    reactions: list
    residual: list
    moment_error_Nm: list
    contact_error_m: list
    period_s: object
    stride_m: object
    point_times_s: object
    instant_times_s: object
    muscle_lengths_m: object
    muscle_velocities_m_s: object
    muscle_state: dict
    metabolic_rate_W: object


class Transcriber:
    """The fixed parts of the transcription for one subject, node count and control grid."""

    def __init__(self, nodes: int = 18, *, model: WalkingModel | None = None, grid: ControlGrid | None = None,
                 muscles: WalkerMuscles | None = None, smoothing: float = 1e-2):
        self.layout = DesignLayout.build(nodes, symmetric=False)
        self.model = model or WalkingModel()
        self.contact = ContactModel(self.model)
        self.muscles = muscles or WalkerMuscles()
        self.grid = grid or control_grid()
        self.quartic, self.cubic = quartic(nodes), cubic(nodes)
        self.joint_map_pinv = np.linalg.pinv(joint_moment_map())
        self.metabolic = self.muscles.muscle.smoothed_metabolic_rate(smoothing)
        #: what makes two transcribers' problems the same (the NLP cache's key): subject, muscles, grid
        self.key = (nodes, repr(self.model.params), repr(self.muscles.muscle.params), self.muscles.device_law,
                    tuple(self.grid.counts), smoothing, self.model.gravity_m_s2)

    def design(self, x) -> tuple:
        """(durations (8,), L_r, L_l, T, ΔS) of χ; CasADi expressions for a symbolic χ."""
        blocks = self.layout.unpack(x)
        durations, steps = blocks["durations"], blocks["steps"]
        if is_casadi(x):
            durations, steps_r, steps_l = ca.vec(durations), steps[0, 0], steps[1, 0]
        else:
            durations, steps_r, steps_l = durations.ravel(), float(steps[0, 0]), float(steps[1, 0])
        return durations, steps_r, steps_l, cycle_period(durations), steps_r + steps_l

    def instant_values(self, x) -> tuple:
        """y, ẏ, ÿ (I × 9; hip x with its drift) and the tendon stretch ŝ (I × 16) at the I instants of χ."""
        durations, _, _, period, stride = self.design(x)
        return splines_at(self.layout, self.layout.unpack(x), period, stride, instant_times(self.grid, durations))

    def __call__(self, x) -> Transcription:
        """The transcription of χ (numpy or CasADi; the full model's layout)."""
        durations, steps_r, steps_l, _, _ = self.design(x)
        return self.at(durations, steps_r, steps_l, self.instant_values(x))

    def at(self, durations, steps_r, steps_l, values) -> Transcription:
        """The transcription of a gait given by its phase durations (8), step lengths and ``values`` = (y, ẏ, ÿ,
        ŝ) at the I instants (as :meth:`instant_values`; e.g. from the symmetric model's splines)."""
        symbolic = is_casadi(durations, steps_r, steps_l, *values)
        period, stride = cycle_period(durations), steps_r + steps_l
        times = point_times(self.grid, durations)
        # the points' values are their instants'; the cycle's closing point (t = T) is instant 0 one stride on
        index = [int(i) for i in self.grid.instant]
        wraps = np.zeros((self.grid.points, 9))
        wraps[self.grid.wraps, 0] = 1.0
        y_i, yd_i, ydd_i, stretch_i = values
        y = y_i[index, :] + (ca.DM(wraps) * stride if symbolic else wraps * stride)
        yd, ydd, stretch = yd_i[index, :], ydd_i[index, :], stretch_i[index, :]
        f_max = np.tile(np.asarray(self.muscles.muscle.params.max_isometric_force_N), 2)
        f_m = (ca.repmat(ca.DM(f_max).T, stretch.shape[0], 1) * stretch ** 2 if symbolic
               else f_max * stretch ** 2)  # F = F_max·ŝ² (2.19)
        model, contact, muscles = self.model, self.contact, self.muscles
        reactions, residual, moment_error, contact_error, generalized = [], [], [], [], []
        for j in range(self.grid.points):
            phase = int(self.grid.phase[j]) + 1
            yj, ydj, yddj = y[j, :].T, yd[j, :].T, ydd[j, :].T
            if not symbolic:
                yj, ydj, yddj = (np.ravel(v) for v in (yj, ydj, yddj))
            fj = f_m[j, :].T if symbolic else np.ravel(f_m[j, :])
            rhs = (model.mass_matrix(yj) @ yddj + model.bias(yj, ydj) - model.gravity(yj)
                   - muscles.passive(yj, ydj) - muscles.moment_arms(yj) @ fj)
            G = contact.reaction_matrix[phase](yj)
            if not symbolic:
                rhs, G = np.ravel(np.array(rhs)), np.array(G)
            lam, e = ground_reactions(G, rhs)
            generalized.append(rhs)
            reactions.append(lam)
            residual.append(e)
            moment_error.append(ca.DM(self.joint_map_pinv) @ e if symbolic else self.joint_map_pinv @ e)
            c = contact.constraint[phase](yj, steps_r, steps_l, 0.0)
            contact_error.append(c if symbolic else np.ravel(np.array(c)))
        # muscle states at the distinct instants (forces are continuous: one value per instant)
        inst_times = instant_times(self.grid, durations)
        if symbolic:
            l_m = ca.vertcat(*[muscles.lengths(y_i[i, :].T).T for i in range(self.grid.instants)])
            v_m = ca.vertcat(*[muscles.velocities(y_i[i, :].T, yd_i[i, :].T).T for i in range(self.grid.instants)])
        else:
            l_m = np.vstack([np.ravel(np.array(muscles.lengths(y_i[i]))) for i in range(self.grid.instants)])
            v_m = np.vstack([np.ravel(np.array(muscles.velocities(y_i[i], yd_i[i])))
                             for i in range(self.grid.instants)])
        stretch_instants = stretch_i
        force_instants = (ca.repmat(ca.DM(f_max).T, stretch_i.shape[0], 1) * stretch_i ** 2 if symbolic
                          else f_max * stretch_i ** 2)
        params = self.muscles.muscle.params
        slack = np.tile(np.asarray(params.tendon_slack_length_m), 2)
        eps0 = params.tendon_strain_at_max_force
        l_se = (ca.repmat(ca.DM(slack).T, stretch_instants.shape[0], 1) * (1 + eps0 * stretch_instants) if symbolic
                else slack * (1 + eps0 * stretch_instants))
        # each leg's muscles on that leg's inversion: the model is one leg's 8 muscles
        states = {}
        for k in (0, 1):
            cols = slice(8 * k, 8 * k + 8)
            part = invert_muscles(muscles.muscle, force_instants[:, cols], l_m[:, cols], v_m[:, cols], inst_times,
                                  period, tendon_length_m=l_se[:, cols])
            for name, value in part.items():
                states.setdefault(name, []).append(value)
        states = {name: (ca.horzcat(*v) if symbolic else np.hstack(v)) for name, v in states.items()}
        rate = []
        for k in (0, 1):
            cols = slice(8 * k, 8 * k + 8)
            args = [states[n][:, cols] for n in ("u", "a", "l_ce", "v_ce", "f_ce")]
            rate.append(self.metabolic(*(a.T for a in args)).T if symbolic else
                        np.array(self.metabolic(*(a.T for a in args))).T)
        # the removed muscles (a prosthetic ankle's) carry no force and cost nothing
        present = muscles.present.astype(float)
        metabolic = (ca.horzcat(*rate) * ca.repmat(ca.DM(present).T, self.grid.instants, 1) if symbolic
                     else np.where(muscles.present, np.hstack(rate), 0.0))
        return Transcription(y=y, yd=yd, ydd=ydd, forces_N=f_m, stretch=stretch, generalized_forces=generalized,
                             reactions=reactions, residual=residual,
                             moment_error_Nm=moment_error, contact_error_m=contact_error, period_s=period,
                             stride_m=stride, point_times_s=times, instant_times_s=inst_times,
                             muscle_lengths_m=l_m, muscle_velocities_m_s=v_m, muscle_state=states,
                             metabolic_rate_W=metabolic)



def gait_at(layout: DesignLayout, x, times) -> tuple:
    """(durations (8,), L_r, L_l, (y, ẏ, ÿ (n × 9), ŝ (n × 16))) of a numeric χ of either model at ``times``
    (s since t_1): the splines of ``layout`` evaluated there (the symmetric model's left leg the right leg half
    a cycle later, its hip and HAT T/2-periodic) — for :meth:`Transcriber.at` on any grid."""
    durations, (steps_r, steps_l) = layout.phase_durations(x), layout.step_lengths(x)
    values = splines_at(layout, layout.unpack(np.asarray(x, float)), float(durations.sum()), steps_r + steps_l,
                        np.asarray(times, float).ravel())
    return durations, steps_r, steps_l, values


def splines_at(layout: DesignLayout, blocks: dict, period, stride, times) -> tuple:
    """(y, ẏ, ÿ (n × 9), ŝ (n × 16)) of the χ ``blocks`` of ``layout`` at ``times`` (s since t_1; numpy or CasADi
    throughout), T = ``period``, ΔS = ``stride``. The left leg's splines are read half a cycle on (symmetric
    model: the right leg's; full model: its own, on nodes half a cycle after the right's); the symmetric
    model's hip and HAT over T/2 with half the stride."""
    leg, forces = quartic(layout.nodes), cubic(layout.nodes)
    left_times = times + period / 2 if layout.symmetric else times - period / 2
    left, left_stretch = ((blocks["right_leg"], blocks["right_stretch"]) if layout.symmetric
                          else (blocks["left_leg"], blocks["left_stretch"]))
    trunk_spline, trunk_period, trunk_stride = ((quartic(blocks["trunk"].shape[0] + 1), period / 2, stride / 2)
                                                if layout.symmetric else (full_trunk_spline(layout.nodes), period,
                                                                          stride))
    trunk = blocks["trunk"]
    symbolic = is_casadi(trunk, period, times)
    stack = ca.horzcat if symbolic else (lambda *c: np.column_stack([np.reshape(a, (len(a), -1)) for a in c]))
    rows = []
    for r in range(3):
        rows.append(stack(hip_x(trunk_spline, trunk[:, 0], trunk_period, trunk_stride, times, r),
                          evaluate(trunk_spline, trunk[:, 1:], trunk_period, times, r),
                          evaluate(leg, blocks["right_leg"], period, times, r),
                          evaluate(leg, left, period, left_times, r)))
    stretch = stack(evaluate(forces, blocks["right_stretch"], period, times),
                    evaluate(forces, left_stretch, period, left_times))
    return (*rows, stretch)
