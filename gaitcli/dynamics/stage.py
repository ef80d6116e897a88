"""The ``idyn`` stage: segment poses → 27 coordinates → 21 joint moments and 6 pelvis residuals (3.2–3.4).

A pure function from the filtered trial and the static calibration to an
:class:`IdynResult`; reading files and writing outputs happen in the pipeline.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from gaitcli.config import IdynConfig
from gaitcli.dynamics.derivatives import coordinate_derivatives
from gaitcli.dynamics.equations import ExternalWrench
from gaitcli.dynamics.inverse import express_in, inverse_dynamics
from gaitcli.dynamics.sagittal import sagittal_columns
from gaitcli.errors import GaitWarning, InputError
from gaitcli.kinematics.calibration import StaticCalibration
from gaitcli.kinematics.coordinates import missing_frame_messages, poses_to_coordinates, track_segments
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import BODIES, JOINT_CHILD, BodyParameters
from gaitcli.core.recording import Markers
from gaitcli.signal.cycles import GaitFeatures, Stride, gait_features, strides
from gaitcli.core.events import Events

FOOT_BODY = {"r": BODIES.index("foot_r"), "l": BODIES.index("foot_l")}
HEEL = {"r": "CAr", "l": "CAl"}


@dataclass
class FilteredTrial:
    """What the idyn stage needs of the filter stage: markers, per-foot loads, events (model axes, SI).

    ``feet[side]`` holds ``force_N`` (n, 3), ``cop_m`` (n, 3) and ``free_moment_Nm`` (n,)
    at the marker rate; a side is missing when no plate measured that foot.
    """

    markers: Markers
    feet: dict
    events: Events


@dataclass
class IdynResult:
    """Coordinates (m, rad; model signs), joint moments and residuals, and what they came from."""

    time_s: np.ndarray
    q: np.ndarray  # (n, 27)
    qd: np.ndarray
    qdd: np.ndarray
    joint_moments_Nm: np.ndarray  # (n, 7, 3) x, y, z components in the distal segment's `frames`
    joint_moments_global_Nm: np.ndarray  # (n, 7, 3)
    residual_force_N: np.ndarray  # (n, 3) global
    residual_moment_Nm: np.ndarray  # (n, 3) global, about the pelvis CoM
    measured: np.ndarray  # (n,) every foot on the ground stands on a plate (residuals are meaningful)
    foot_measured: dict  # side -> (n,) that foot's load is known (its leg's moments are meaningful)
    frames: str
    mass_kg: float
    mass_source: str
    parameters: BodyParameters
    calibration: StaticCalibration
    segment_rms_m: np.ndarray  # (n, 8) marker fit error per segment
    joint_centres_m: np.ndarray  # (n, 7, 3) of the model (forward kinematics of q)
    features: GaitFeatures
    strides: list[Stride]
    sagittal: dict
    events: Events
    notes: list = field(default_factory=list)


def estimate_mass_kg(trial: FilteredTrial, *, gravity_m_s2: float = 9.81) -> float | None:
    """Body mass from the plates: over a stride each foot carries half the body's weight on average.

    For every stance fully recorded on the plates (heel strike and toe off inside a
    loaded run of that foot), ``m = 2 ∫F_z dt / (g T)`` with ``T`` the mean stride
    period; the median over stances is returned (None when no stance qualifies).
    """
    rate = trial.markers.rate_hz
    t = trial.markers.time_s
    periods = [s.period_s for s in strides(trial.events)]
    if not periods:
        return None
    period = float(np.mean(periods))
    masses = []
    for side, load in trial.feet.items():
        fz = np.nan_to_num(np.asarray(load["force_N"])[:, 2])
        ev = trial.events
        on = np.sort(ev.time_s[(ev.side == side) & (ev.kind == "heel_strike") & (ev.source == "plate")])
        off = np.sort(ev.time_s[(ev.side == side) & (ev.kind == "toe_off") & (ev.source == "plate")])
        for a in on:
            later = off[off > a]
            if later.size and later[0] - a < period:
                inside = (t >= a - 1.5 / rate) & (t <= later[0] + 1.5 / rate)
                impulse = float(np.sum(fz[inside]) / rate)
                masses.append(2 * impulse / (gravity_m_s2 * period))
    return float(np.median(masses)) if masses else None


def foot_measured(trial: FilteredTrial) -> dict[str, np.ndarray]:
    """Per side, the frames in which that foot's ground reaction is known: in swing, or on a plate.

    A leg's joint moments are right wherever its own foot's load is known; the
    pelvis residuals need both feet known.
    """
    t = trial.markers.time_s
    ev = trial.events
    out = {}
    for side in ("r", "l"):
        known = np.ones(t.size, dtype=bool)
        strikes = np.sort(ev.time_s[(ev.side == side) & (ev.kind == "heel_strike")])
        offs = np.sort(ev.time_s[(ev.side == side) & (ev.kind == "toe_off")])
        loaded = np.zeros(t.size, dtype=bool)
        if side in trial.feet:
            loaded = np.nan_to_num(np.asarray(trial.feet[side]["force_N"])[:, 2]) > 0
        for a in strikes:  # stance from each strike to the next toe off (or the end of the trial)
            later = offs[offs > a]
            stance = (t >= a) & (t <= (later[0] if later.size else np.inf))
            known &= ~stance | loaded
        if offs.size and (not strikes.size or offs[0] < strikes[0]):  # on the ground from the start
            known &= ~(t <= offs[0]) | loaded
        out[side] = known
    return out


def external_wrenches(feet: dict, n: int) -> list[ExternalWrench]:
    """Ground reactions on the feet at their COP plus the vertical free moment (zero where unloaded)."""
    out = []
    for side, load in feet.items():
        force = np.nan_to_num(np.asarray(load["force_N"], dtype=float))
        cop = np.asarray(load["cop_m"], dtype=float)
        point = np.where(np.isfinite(cop), cop, 0.0)
        free = np.zeros((n, 3))
        free[:, 2] = np.nan_to_num(np.asarray(load["free_moment_Nm"], dtype=float))
        out.append(ExternalWrench(body=FOOT_BODY[side], force_N=force, point_m=point, moment_Nm=free))
    return out


def inverse_dynamics_stage(trial: FilteredTrial, calibration: StaticCalibration, cfg: IdynConfig, *,
                           mass_kg: float, mass_source: str) -> IdynResult:
    """Poses by SVD (3.9–3.15), coordinates (3.17), derivatives, joint moments (3.21) and residuals (3.22)."""
    markers = trial.markers
    poses = track_segments(markers, calibration)
    for line in missing_frame_messages(poses):
        warnings.warn(f"{line}: the pose, coordinates and moments there are NaN", GaitWarning, stacklevel=2)
    q = poses_to_coordinates(poses)
    qd, qdd = coordinate_derivatives(q, markers.rate_hz)
    params = calibration.body
    n = q.shape[0]
    result = inverse_dynamics(q, qd, qdd, params, external_wrenches(trial.feet, n), gravity_m_s2=cfg.gravity_m_s2)
    moments = result.joint_moments_distal_Nm
    if cfg.frames == "anatomical":
        # R_anatomical = R_reference @ C: components in the anatomical frame are Cᵀ · (reference components)
        C = calibration.reference_to_anatomical[list(JOINT_CHILD)]
        moments = express_in(moments, np.broadcast_to(C, (n,) + C.shape))
    known = foot_measured(trial)
    states = forward_kinematics(q, params)
    heel_x = {s: markers.get(HEEL[s])[:, 0] for s in ("r", "l") if HEEL[s] in markers}
    features = gait_features(trial.events, heel_x, markers.time_s)
    sagittal = sagittal_columns(markers.time_s, states.joint_centre_m, q, trial.feet)
    return IdynResult(time_s=markers.time_s, q=q, qd=qd, qdd=qdd, joint_moments_Nm=moments,
                      joint_moments_global_Nm=result.joint_moments_global_Nm,
                      residual_force_N=result.residual_force_N, residual_moment_Nm=result.residual_moment_Nm,
                      measured=known["r"] & known["l"], foot_measured=known, frames=cfg.frames, mass_kg=mass_kg, mass_source=mass_source,
                      parameters=params, calibration=calibration, segment_rms_m=poses.rms_m,
                      joint_centres_m=states.joint_centre_m, features=features, strides=strides(trial.events),
                      sagittal=sagittal, events=trial.events, notes=list(calibration.notes))


def check_mass(mass_kg: float | None, source) -> float:
    """The body mass to use, or a clear error when neither subject.yaml nor the plates give one."""
    if mass_kg is None or not np.isfinite(mass_kg) or mass_kg <= 0:
        raise InputError(source, "mass_kg", "is 'auto' but no stance was fully recorded on the force plates "
                                            "(expected mass_kg in kg)")
    return float(mass_kg)
