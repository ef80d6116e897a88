"""The ``idyn`` stage: segment poses → 27 coordinates → 21 joint moments and 6 pelvis residuals (3.2–3.4).

A pure function from the filtered :class:`~gaitcli.core.container.Trial`, the
standing trial's markers and the subject to an :class:`IdynResult`: body mass
(subject.yaml or the plates), static calibration (once), poses, coordinates,
inverse dynamics, gait features and the sagittal export for the muscle stage.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gaitcli.core.container import Trial
from gaitcli.core.events import SIDES, Events
from gaitcli.core.recording import Markers
from gaitcli.core.validate import parameter
from gaitcli.dynamics.derivatives import coordinate_derivatives
from gaitcli.dynamics.equations import ExternalWrench
from gaitcli.dynamics.inverse import express_in, inverse_dynamics
from gaitcli.dynamics.sagittal import SagittalExport, sagittal_export
from gaitcli.errors import GaitWarning, InputError
from gaitcli.kinematics.calibration import StaticCalibration, calibrate
from gaitcli.kinematics.coordinates import missing_frame_messages, poses_to_coordinates, track_segments
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.model import BODIES, JOINT_CHILD, BodyParameters
from gaitcli.signal.cycles import GaitFeatures, Stride, gait_features, strides

if TYPE_CHECKING:
    from gaitcli.trial import Subject

FRAMES = ("reference", "anatomical")


@dataclass(frozen=True)
class IdynConfig:
    """Parameters of ``gait idyn`` (3.2–3.4)."""

    frames: str = parameter("reference", choices=FRAMES,
                            help="Frames the joint moments are expressed in (default: reference).")
    gravity_m_s2: float = parameter(9.81, low=9.7, high=9.9,
                                    help="Gravitational acceleration, m/s² (Earth's surface: 9.78–9.83).")


FOOT_BODY = {"r": BODIES.index("foot_r"), "l": BODIES.index("foot_l")}
HEEL = {"r": "CAr", "l": "CAl"}


@dataclass
class IdynResult:
    """Coordinates (m, rad; model signs), joint moments and residuals, and what they came from."""

    trial: Trial
    q: np.ndarray  # (n, 27)
    qd: np.ndarray
    qdd: np.ndarray
    joint_moments_Nm: np.ndarray  # (n, 7, 3) x, y, z components in the distal segment's `frames`
    joint_moments_global_Nm: np.ndarray  # (n, 7, 3)
    residual_force_N: np.ndarray  # (n, 3) global
    residual_moment_Nm: np.ndarray  # (n, 3) global, about the pelvis CoM
    frames: str
    mass_kg: float
    mass_source: str
    parameters: BodyParameters
    calibration: StaticCalibration
    segment_rms_m: np.ndarray  # (n, 8) marker fit error per segment
    joint_centres_m: np.ndarray  # (n, 7, 3) of the model (forward kinematics of q)
    features: GaitFeatures
    strides: list[Stride]
    sagittal: SagittalExport
    notes: list = field(default_factory=list)

    @property
    def time_s(self) -> np.ndarray:
        return self.trial.time_s

    @property
    def events(self) -> Events:
        return self.trial.events

    @property
    def measured(self) -> np.ndarray:
        """(n,) every foot on the ground stands on a plate (the residuals are meaningful)."""
        return self.trial.all_loads_known

    @property
    def foot_measured(self) -> dict[str, np.ndarray]:
        """side → (n,) that foot's load is known (its leg's moments are meaningful)."""
        return {s: self.trial.load_known(s) for s in SIDES}


def estimate_mass_kg(trial: Trial, *, gravity_m_s2: float = 9.81) -> float | None:
    """Body mass from the plates: over a stride each foot carries half the body's weight on average.

    For every stance fully recorded on the plates (heel strike and toe off inside a
    loaded run of that foot), ``m = 2 ∫F_z dt / (g T)`` with ``T`` the mean stride
    period; the median over stances is returned (None when no stance qualifies).
    """
    rate = trial.rate_hz
    t = trial.time_s
    periods = [s.period_s for s in strides(trial.events)]
    if not periods:
        return None
    period = float(np.mean(periods))
    masses = []
    for side, load in trial.feet.items():
        fz = np.nan_to_num(load.force_N[:, 2])
        for a, b in trial.events.stances(side, "plate", max_s=period):
            inside = (t >= a - 1.5 / rate) & (t <= b + 1.5 / rate)
            impulse = float(np.sum(fz[inside]) / rate)
            masses.append(2 * impulse / (gravity_m_s2 * period))
    return float(np.median(masses)) if masses else None


def external_wrenches(trial: Trial) -> list[ExternalWrench]:
    """Ground reactions on the feet the plates saw, at their COP, plus the vertical free moment."""
    out = []
    for side, load in trial.feet.items():
        if not load.on_plates:
            continue
        force = np.nan_to_num(load.force_N)
        point = np.where(np.isfinite(load.cop_m), load.cop_m, 0.0)
        free = np.zeros((trial.n_frames, 3))
        free[:, 2] = np.nan_to_num(load.free_moment_Nm)
        out.append(ExternalWrench(body=FOOT_BODY[side], force_N=force, point_m=point, moment_Nm=free))
    return out


def body_mass(trial: Trial, subject: Subject, cfg: IdynConfig, *, source: Path | None) -> tuple[float, str]:
    """The body mass (kg) and where it came from: subject.yaml, else the force plates."""
    if subject.mass_kg is not None:
        return float(subject.mass_kg), "subject.yaml"
    mass = check_mass(estimate_mass_kg(trial, gravity_m_s2=cfg.gravity_m_s2), source)
    return mass, "estimated from the force plates (2·∫Fz dt / (g·stride period) per recorded stance)"


def static_calibration(trial: Trial, static: Markers | None, subject: Subject, mass_kg: float, *,
                       subject_path: Path | None, static_path: Path | None,
                       trial_path: Path | None) -> StaticCalibration:
    """Static calibration from the standing trial's markers, or from named frames of the filtered trial."""
    common = dict(mass_kg=mass_kg, stature_m=subject.stature_m, sex=subject.sex,
                  thigh_length_m=subject.thigh_length_m, shank_length_m=subject.shank_length_m,
                  disturbances=subject.disturbances)
    if static is not None:
        return calibrate(static, source=static_path, **common)
    if subject.static_frames is None:
        raise InputError(subject_path, "static_frames", "no static.c3d in the trial folder: name the standing "
                                                        "frames of the trial as [first, last] (file frame numbers)")
    first, last = subject.static_frames
    m = trial.markers
    frames = np.arange(first, last + 1) - m.first_frame
    if frames[0] < 0 or frames[-1] >= m.n_frames:
        raise InputError(subject_path, "static_frames", f"got [{first}, {last}] (expected frames within "
                                                        f"{m.first_frame}–{m.first_frame + m.n_frames - 1})")
    return calibrate(m, frames=frames, source=trial_path, **common)


def inverse_dynamics_stage(trial: Trial, calibration: StaticCalibration, cfg: IdynConfig, *,
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
    result = inverse_dynamics(q, qd, qdd, params, external_wrenches(trial), gravity_m_s2=cfg.gravity_m_s2)
    moments = result.joint_moments_distal_Nm
    if cfg.frames == "anatomical":
        # R_anatomical = R_reference @ C: components in the anatomical frame are Cᵀ · (reference components)
        C = calibration.reference_to_anatomical[list(JOINT_CHILD)]
        moments = express_in(moments, np.broadcast_to(C, (n,) + C.shape))
    states = forward_kinematics(q, params)
    heel_x = {s: markers.get(HEEL[s])[:, 0] for s in SIDES if HEEL[s] in markers}
    features = gait_features(trial.events, heel_x, markers.time_s)
    trial = trial.with_step(f"idyn: calibrated on the standing posture, body mass {mass_kg:.2f} kg "
                            f"({mass_source}); SVD poses, 27 coordinates, inverse dynamics (3.21, 3.22), "
                            f"moments in {cfg.frames} frames")
    export = sagittal_export(trial, states.joint_centre_m, q, params, body_mass_kg=mass_kg)
    return IdynResult(trial=trial, q=q, qd=qd, qdd=qdd, joint_moments_Nm=moments,
                      joint_moments_global_Nm=result.joint_moments_global_Nm,
                      residual_force_N=result.residual_force_N, residual_moment_Nm=result.residual_moment_Nm,
                      frames=cfg.frames, mass_kg=mass_kg, mass_source=mass_source,
                      parameters=params, calibration=calibration, segment_rms_m=poses.rms_m,
                      joint_centres_m=states.joint_centre_m, features=features, strides=strides(trial.events),
                      sagittal=export, notes=list(calibration.notes))


def run_idyn(trial: Trial, static: Markers | None, subject: Subject, cfg: IdynConfig, *,
             subject_path: Path | None = None, static_path: Path | None = None,
             trial_path: Path | None = None) -> IdynResult:
    """The whole idyn stage: body mass, static calibration (once), then :func:`inverse_dynamics_stage`."""
    mass, source = body_mass(trial, subject, cfg, source=subject_path)
    calibration = static_calibration(trial, static, subject, mass, subject_path=subject_path,
                                     static_path=static_path, trial_path=trial_path)
    return inverse_dynamics_stage(trial, calibration, cfg, mass_kg=mass, mass_source=source)


def check_mass(mass_kg: float | None, source) -> float:
    """The body mass to use, or a clear error when neither subject.yaml nor the plates give one."""
    if mass_kg is None or not np.isfinite(mass_kg) or mass_kg <= 0:
        raise InputError(source, "mass_kg", "is 'auto' but no stance was fully recorded on the force plates "
                                            "(expected mass_kg in kg)")
    return float(mass_kg)
