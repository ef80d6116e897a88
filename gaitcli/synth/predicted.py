"""The synthetic walk from a predictive simulation of the walking model (Diss. 5.2): ``gait synth --gait predicted``.

A converged ``gait predict`` cycle of the 9-DoF planar model for the default subject (75 kg, 1.78 m) at
1.30 m/s, every step 0.39·H (shipped as its design vector χ in ``data/``; :func:`make_walk` made it).
In each contact phase its feet are pinned at heel and metatarsal heads (to εk = 2 mm), so the double-support
chain closes by construction, and its joint moments are those its eight muscles produce with excitations in
[0, 1] (to εm = 0.5 N·m), with F_max at 0.65 × Table A.1 so that the muscle stage's full-strength muscles
keep a margin for the markers' noise and artefact. Its Jdev also tracks each foot's centre of pressure rolling
from heel to metatarsal heads and a steady trunk, and its hip moments are bounded (WALK_TRACKING says why).
The 27-DoF motion takes the sagittal plane from it — the hip
centres' path, the HAT angle as the pelvis's tilt (lumbar joint straight), hip, knee and ankle flexion —
scaled to the subject by stature (lengths ∝ H) and to the cycle's period (time); sideways, the pelvis sways
as the linear inverted pendulum over the stance foot's lane and each hip adducts (the ankle everts as much)
to keep its foot in the lane. Its exact whole-body wrench is the planar model's, its single-support centre of
pressure rolling from just ahead of the ankle towards the metatarsal heads (tests/synth/test_predicted.py).
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.kinematics.conventions import SIGNS, walker_joint_angles
from gaitcli.kinematics.model import JOINTS
from gaitcli.synth.gait import ANALOG_RATE_HZ, Condition, GaitDesign

#: the shipped prediction: subject, speed and step it was solved for
WALK_FILE = Path(__file__).resolve().parent / "data" / "normal_walk_nn18.csv"
#: the reference gait its Jdev tracked: the package's bundled reference when it was made (from the 55 kg sample
#: trial of the normative curves; since then the bundled reference comes from this walk's own sample trial)
WALK_REFERENCE = Path(__file__).resolve().parent / "data" / "walk_reference.csv"
WALK_SUBJECT = {"mass_kg": 75.0, "stature_m": 1.78, "sex": "male"}
WALK_SPEED_M_S = 1.30
STRIDE_PER_STATURE = 0.78  # the prescribed stride, 1.39 m at 1.78 m
WALK_NODES = 18
#: how the shipped file was made (its header says so too)
MAKE_COMMAND = 'python -c "from gaitcli.synth.predicted import make_walk; print(make_walk())"'
WALK_STRENGTH_SCALE = 0.65  # the prediction's F_max, × Table A.1
#: the second solve's settings (PredictSettings) beyond the dissertation's, each one so that the muscle stage can
#: follow the walk's 3-D truth (docs/decisions.md): Jdev also tracks each foot's centre of pressure rolling from
#: heel to MTP over 85 % of its stance and a steady trunk; the equations of motion are met to εm = 0.5 N·m; the
#: hip moment is within ±0.25 N·m/kg in swing (a typical adult's) and ±0.72 N·m/kg elsewhere
WALK_TRACKING = {"cop_sd_m": 0.007, "trunk_rate_sd_deg_s": 5.0, "moment_tolerance_Nm": 0.5,
                 "swing_hip_moment_Nm_per_kg": 0.25, "hip_moment_Nm_per_kg": 0.72}
STEP_WIDTH_PER_STATURE = 0.067  # between the ankle centres, m per m of stature
RIGHT_STANCE_PHASES = (1, 2, 3, 4, 5, 6)
LEFT_STANCE_PHASES = (5, 6, 7, 8, 1, 2)


def shipped_walk() -> np.ndarray:
    """The shipped prediction's χ (read once per process; a copy)."""
    return _read_walk().copy()


@lru_cache(maxsize=1)
def _read_walk() -> np.ndarray:
    return np.loadtxt(WALK_FILE)


def walk_durations(x: np.ndarray | None = None) -> np.ndarray:
    """The eight contact phases' durations (s) of the shipped prediction (or of χ ``x``)."""
    from gaitcli.predict.layout import DesignLayout

    return DesignLayout.build(WALK_NODES, symmetric=True).phase_durations(shipped_walk() if x is None else x)


def predicted_period_s(stature_m: float) -> float:
    """The prediction's gait cycle for a subject of ``stature_m``, s: Froude-similar (T ∝ √H), to 10 ms (the
    trials' marker frames)."""
    return round(float(np.sum(walk_durations())) * np.sqrt(stature_m / WALK_SUBJECT["stature_m"]), 2)


def walker_cycle(times_s, x: np.ndarray | None = None):
    """(y, durations (8,), step lengths (r, l)) of the shipped prediction at ``times_s`` (s from right heel
    strike, within its own period): y (n, 9) in the walking model's coordinates and signs."""
    from gaitcli.predict.layout import DesignLayout
    from gaitcli.predict.problem import gait_at

    x = shipped_walk() if x is None else x
    layout = DesignLayout.build(WALK_NODES, symmetric=True)
    durations, step_r, step_l, (y, _, _, _) = gait_at(layout, x, times_s)
    return y, np.asarray(durations, float), (float(step_r), float(step_l))


def phase_of(durations) -> dict:
    """Each contact phase's start and end as fractions of the cycle."""
    edges = np.concatenate([[0.0], np.cumsum(durations)]) / float(np.sum(durations))
    return {ph: (edges[ph - 1], edges[ph]) for ph in range(1, 9)}


def lateral_sway(phase, stance, lane, com_height_m: float, period_s: float):
    """Pelvis sideways position (m) over the cycle: the linear inverted pendulum ``c − (z/g) c̈ = p`` (periodic)
    over a centre of pressure ``p`` in the stance foot's lane, moving across in double support."""
    n = phase.size
    plan = np.where(stance["r"] & ~stance["l"], lane["r"], 0.0) + np.where(stance["l"] & ~stance["r"], lane["l"], 0.0)
    both = stance["r"] & stance["l"]
    # across double support: from the trailing foot's lane to the leading one's, linearly in time
    starts = np.flatnonzero(both & ~np.roll(both, 1))
    for first in starts:
        length = int(np.argmin(np.roll(both, -first)))
        idx = (first + np.arange(length)) % n
        before, after = plan[(first - 1) % n], plan[(idx[-1] + 1) % n]
        plan[idx] = before + (after - before) * (np.arange(length) + 0.5) / length
    k = np.fft.rfftfreq(n, d=period_s / n) * 2 * np.pi
    return np.fft.irfft(np.fft.rfft(plan) / (1 + com_height_m / GRAVITY_M_S2 * k ** 2), n=n)


def predicted_gait(condition: Condition, params, *, stature_m: float, x: np.ndarray | None = None,
                   samples: int | None = None) -> GaitDesign:
    """One periodic cycle of the predicted walk for a subject of ``stature_m`` over ``condition.period_s``,
    starting at right heel strike, on the analog grid (module docstring) or over ``samples`` per cycle."""
    from gaitcli.kinematics.forward import forward_kinematics

    T = condition.period_s
    n = samples or int(round(T * ANALOG_RATE_HZ))
    phase = np.arange(n) / n
    durations = walk_durations(x)
    own_period = float(np.sum(durations))
    y, _, (step_r, step_l) = walker_cycle(phase * own_period, x)
    scale = stature_m / WALK_SUBJECT["stature_m"]
    stride = (step_r + step_l) * scale
    phases = phase_of(durations)

    def within(names):
        return np.any([(phases[p][0] <= phase) & (phase < phases[p][1]) for p in names], axis=0)

    stance = {"r": within(RIGHT_STANCE_PHASES), "l": within(LEFT_STANCE_PHASES)}
    events = [(0.0, "r", "heel_strike"), (phases[2][1], "l", "toe_off"), (phases[4][1], "l", "heel_strike"),
              (phases[6][1], "r", "toe_off")]

    q = np.zeros((n, 27))
    q[:, 4] = y[:, 2]  # pelvis tilt = the HAT's forward lean (both turn the trunk's top forward when positive)
    for side, (thigh, knee, ankle) in (("r", (3, 4, 5)), ("l", (6, 7, 8))):
        hip_flexion, knee_flexion, dorsiflexion = walker_joint_angles(y[:, 2], y[:, thigh], y[:, knee], y[:, ankle])
        for joint, angle in (("hip", hip_flexion), ("knee", knee_flexion), ("ankle", dorsiflexion)):
            j = JOINTS.index(f"{joint}_{side}")
            q[:, 6 + 3 * j] = SIGNS[j, 0] * angle
    # the hip centres' midpoint on the walker's hip path (scaled), the pelvis placed under it
    states = forward_kinematics(q, params)
    hips = states.joint_centre_m[:, [JOINTS.index("hip_r"), JOINTS.index("hip_l")]]
    middle = hips.mean(axis=1)
    q[:, 0] = y[:, 0] * scale - middle[:, 0]
    q[:, 2] = y[:, 1] * scale - middle[:, 2]
    # sideways: sway over the lanes, each hip adducting so its ankle stays in its lane
    lane = {"r": -0.5 * STEP_WIDTH_PER_STATURE * stature_m, "l": 0.5 * STEP_WIDTH_PER_STATURE * stature_m}
    masses = np.asarray(params.mass_kg)
    com_height = float(np.mean(np.einsum("b,nb->n", masses, states.com_m[:, :, 2]) / masses.sum() + q[:, 2]))
    q[:, 1] = lateral_sway(phase, stance, lane, com_height, T)
    return GaitDesign(time_s=phase * T, q=_keep_lanes(q, lane, params), stance=stance, events=events,
                      speed_m_s=stride / T, period_s=T, stride_m=stride)


def _keep_lanes(q, lane, params, iterations: int = 3, step: float = 1e-6):
    """``q`` with each hip's adduction (and the ankle's opposite adduction, keeping the sole level) putting the
    ankle centre in its lane: a few secant steps on the frontal angle, per sample."""
    from gaitcli.kinematics.forward import forward_kinematics

    q = q.copy()
    for _ in range(iterations):
        ankles = forward_kinematics(q, params).joint_centre_m
        for side in "rl":
            j_hip, j_ankle = JOINTS.index(f"hip_{side}"), JOINTS.index(f"ankle_{side}")
            column = 6 + 3 * j_hip + 1
            moved = q.copy()
            moved[:, column] += step
            y_ankle = ankles[:, j_ankle, 1]
            slope = (forward_kinematics(moved, params).joint_centre_m[:, j_ankle, 1] - y_ankle) / step
            change = -(y_ankle - lane[side]) / slope
            q[:, column] += change
            q[:, 6 + 3 * j_ankle + 1] -= change
    return q


def make_walk(out: Path = WALK_FILE, *, strength_scale: float = WALK_STRENGTH_SCALE) -> dict:
    """Solve the shipped prediction anew and write its χ to ``out``: ``gait predict``'s symmetric model for
    WALK_SUBJECT at WALK_SPEED_M_S with its default weights and WALK_REFERENCE, every step STRIDE_PER_STATURE · H / 2
    long, the muscles' F_max × ``strength_scale`` (weaker than the muscle stage's, so that the walk leaves
    the muscles of Table A.1 a margin for the markers' noise and artefact); solved from the default guess with
    the dissertation's settings, then again from there with WALK_TRACKING's (Jdev also tracking each foot's
    centre of pressure and a steady trunk, εm 0.5 N·m, the hip moments bounded). Returns the last solve's
    summary."""
    import dataclasses
    import time

    from gaitcli.predict.guess import initial_guess
    from gaitcli.predict.layout import DesignLayout
    from gaitcli.predict.model import WalkerParameters, WalkingModel
    from gaitcli.predict.problem import Transcriber
    from gaitcli.predict.reference import read_reference
    from gaitcli.predict.solve import NlpCache, solve_windowed
    from gaitcli.predict.stage import PredictConfig, evaluate_design, settings_of, walker_muscles

    cfg = PredictConfig(speed_m_s=WALK_SPEED_M_S, nodes=WALK_NODES, strength_scale=strength_scale)
    stature = WALK_SUBJECT["stature_m"]
    plain = dataclasses.replace(settings_of(cfg), step_m=STRIDE_PER_STATURE * stature / 2)
    reference = read_reference(WALK_REFERENCE)
    params = WalkerParameters.from_subject(**WALK_SUBJECT)
    transcriber = Transcriber(cfg.nodes, model=WalkingModel(params), muscles=walker_muscles(cfg, None))
    began = time.perf_counter()
    x = initial_guess(transcriber, reference, plain, symmetric=True)
    steps, rows, _ = DesignLayout.build(WALK_NODES, symmetric=True).blocks["steps"]
    x[steps:steps + rows] = plain.step_m  # the default guess, its steps at the prescribed length
    iterations, cache = [], NlpCache()
    for settings in (plain, dataclasses.replace(plain, **WALK_TRACKING)):
        solved = solve_windowed(transcriber, reference, x, settings, symmetric=True, cache=cache)
        if not solved.outcome.converged:
            raise RuntimeError(f"the walk's prediction did not converge: {solved.outcome.status}")
        x = solved.x
        iterations.append(str(solved.outcome.iterations))
    summary = evaluate_design(cfg, x, reference=reference, params=params).summary()
    tracking = ", ".join(f"{k} {v:g}" for k, v in WALK_TRACKING.items())
    header = (f"A converged prediction (issue 11 item 7): the symmetric model's design vector chi ({x.size} "
              f"values), nn = {WALK_NODES},\n{WALK_SUBJECT['mass_kg']:g} kg, {stature:g} m, {WALK_SPEED_M_S:g} m/s, "
              f"steps {plain.step_m:.4f} m, F_max x {strength_scale:g}, default weights, reference\n"
              f"{WALK_REFERENCE.name}, then {tracking};\nmade by `{MAKE_COMMAND}`\n"
              f"({' + '.join(iterations)} iterations, "
              f"{time.perf_counter() - began:.0f} s; J {summary['objective']:.3f}, Et "
              f"{summary['cost_of_transport_J_per_m']:.1f} J/m, the dissertation's Jdev {summary['deviation']:.3f}).")
    if not summary["converged"]:
        raise RuntimeError("the walk's prediction ends outside its constraints")
    np.savetxt(out, x, fmt="%.17g", header=header)
    return summary
