"""The ``idyn`` stage: segment poses → 27 coordinates → 21 joint moments and 6 pelvis residuals (3.2–3.4).

A pure function from the filtered :class:`~gaitcli.core.container.Trial`, the
standing trial's markers and the subject to an :class:`IdynResult`: body mass
(subject.yaml or the plates), static calibration (once), poses, coordinates,
inverse dynamics, gait features and the sagittal export for the muscle stage.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gaitcli.core.container import Trial
from gaitcli.core.events import SIDE_NAMES, SIDES, Events
from gaitcli.core.numerics import frame_spans, true_runs
from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.core.recording import Markers, Recording
from gaitcli.core.validate import parameter
from gaitcli.dynamics.derivatives import coordinate_derivatives
from gaitcli.dynamics.equations import ExternalWrench
from gaitcli.dynamics.inverse import express_in, inverse_dynamics, moments_about
from gaitcli.dynamics.powers import frame_angular_velocity, joint_powers, sagittal_powers
from gaitcli.dynamics.sagittal import SagittalExport, sagittal_export
from gaitcli.errors import GaitWarning, InputError
from gaitcli.kinematics import cgm
from gaitcli.kinematics.anatomical import anatomical_angles
from gaitcli.kinematics.calibration import StaticCalibration, calibrate, least_flexed_frames, static_landmarks
from gaitcli.kinematics.chain_fit import fit_chain
from gaitcli.kinematics.coordinates import missing_frame_messages, poses_to_coordinates, track_segments
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.joint_centres import JointWidths, functional_joint_centre
from gaitcli.kinematics.markerset import VIRTUAL_JOINT_CENTRES, with_fixed_points
from gaitcli.kinematics.model import BODIES, JOINT_CHILD, JOINTS, BodyParameters
from gaitcli.signal.cycles import GaitFeatures, Stride, gait_features, strides
from gaitcli.signal.stage import HEEL

if TYPE_CHECKING:
    from gaitcli.kinematics.subject import Subject

FRAMES = ("reference", "anatomical")
ANGLES = ("anatomical", "posture")
MOMENT_CONVENTIONS = ("plug_in_gait", "coordinate")
POSES = ("segment_svd", "chain_lsq")
POSE_STEPS = {"segment_svd": "SVD poses", "chain_lsq": "SVD poses refined by a least-squares fit of the whole chain"}


@dataclass(frozen=True)
class IdynConfig:
    """Parameters of ``gait idyn`` (3.2–3.4)."""

    frames: str = parameter("reference", choices=FRAMES,
                            help="Frames the joint moments are expressed in (default: reference).")
    gravity_m_s2: float = parameter(GRAVITY_M_S2, low=9.7, high=9.9,
                                    help="Gravitational acceleration, m/s² (Earth's surface: 9.78–9.83).")
    angles: str = parameter("anatomical", choices=ANGLES,
                            help="anatomical: joint angles between the segments' anatomical frames, as the lab's "
                                 "software reports them (Plug-in Gait's for marker_set plug_in_gait, ISB joint "
                                 "coordinate systems otherwise) in kinematics.csv, gait_cycle.csv and the plots; "
                                 "posture: the 27 coordinates there instead, zero in the standing posture (3.1). "
                                 "coordinates.csv always holds the 27 coordinates.")
    moments: str = parameter("plug_in_gait", choices=MOMENT_CONVENTIONS,
                             help="plug_in_gait: joint moments as Vicon's Plug-in Gait reports them (internal "
                                  "moments in the distal segment's anatomical frame; extensor, abductor, external "
                                  "rotator positive) in joint_moments.csv, gait_cycle.csv and the plots; "
                                  "coordinate: each component positive in the sense of its angle, in the frames "
                                  "`frames` names (as OpenSim's inverse dynamics).")
    pose: str = parameter("segment_svd", choices=POSES,
                          help="segment_svd: each segment fitted to its markers by SVD, the chain hung from the "
                               "pelvis (3.3, the dissertation's); chain_lsq: the 27 coordinates fitted to all "
                               "markers at once (kinematics/chain_fit.py).")


FOOT_BODY = {"r": BODIES.index("foot_r"), "l": BODIES.index("foot_l")}


@dataclass(frozen=True)
class ReferencePosture:
    """How the model was calibrated: ``static`` (the static's file name, "subject.yaml" or "auto: …"), the file frames
    used (None: all of static.c3d), the marker set, the hip-centre method, the plates' stride estimate of the
    body mass (kg, None without one), SCORE's residual per side and the legs' segment table."""

    static: str
    static_frames: tuple[int, int] | None
    marker_set: str
    hip_joint_centre: str
    mass_estimate_kg: float | None
    hip_score_residual_mm: dict = field(default_factory=dict)  # side → SCORE's RMS residual (hip_joint_centre: score)
    segment_inertias: str = "de_leva"  # Subject.segment_table


@dataclass
class IdynResult:
    """Coordinates (m, rad; model signs), joint moments and residuals, and what they came from."""

    trial: Trial
    q: np.ndarray  # (n, 27)
    qd: np.ndarray
    qdd: np.ndarray
    joint_moments_Nm: np.ndarray  # (n, 7, 3) x, y, z components in the distal segment's `frames`
    joint_moments_anatomical_Nm: np.ndarray  # (n, 7, 3) components in the distal segment's anatomical frame
    joint_powers_W: np.ndarray  # (n, 7) total: M · (ω_child − ω_parent)
    joint_powers_sagittal_W: np.ndarray  # (n, 7) about the distal segment's anatomical medio-lateral axis
    joint_moments_global_Nm: np.ndarray  # (n, 7, 3)
    residual_force_N: np.ndarray  # (n, 3) global
    residual_moment_Nm: np.ndarray  # (n, 3) global, about the pelvis CoM
    frames: str
    mass_kg: float
    mass_source: str
    parameters: BodyParameters
    calibration: StaticCalibration
    segment_rms_m: np.ndarray  # (n, 8) marker fit error per segment
    joint_centre_gap_m: np.ndarray  # (n, 7) model joint centre to where the child segment's own markers put it
    marker_rms_m: dict  # tracking marker label → RMS distance (m) of the model's marker from the measured one
    joint_centres_m: np.ndarray  # (n, 7, 3) of the model (forward kinematics of q)
    features: GaitFeatures
    strides: list[Stride]
    sagittal: SagittalExport
    notes: list = field(default_factory=list)
    reference_posture: ReferencePosture | None = None
    anatomical_angles_rad: np.ndarray | None = None  # (n, 23) kinematics.anatomical.ANATOMICAL_ANGLES
    angle_convention: str = "isb"  # "plug_in_gait" or "isb": how the anatomical frames were built
    angles: str = "anatomical"  # IdynConfig.angles: which angles the tables for people show
    moment_convention: str = "plug_in_gait"  # IdynConfig.moments: which moments the tables for people show

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

    @cached_property
    def moment_known(self) -> np.ndarray:
        """(n, 7) whether each joint's moment is meaningful: a leg's joints where its foot's load is known (a
        joint's moment depends only on the bodies distal to it and their loads); the lumbar joint always (the
        HAT carries no measured load; ``hat_tracked`` says whether its motion was measured); no joint within
        the filter's edge frames of a tracked run's ends (:func:`settled_frames`)."""
        known = np.ones((self.q.shape[0], len(JOINTS)), bool)
        for k, joint in enumerate(JOINTS):
            if joint != "lumbar":
                known[:, k] = self.foot_measured[joint[-1]]
        return known & settled_frames(self.q, self.trial.filter_edge_frames)[:, None]

    @property
    def hat_tracked(self) -> bool:
        """Whether the HAT had markers of its own (else it is locked to the pelvis, and the lumbar moment and
        the pelvis residuals are those of a HAT that moves with the pelvis)."""
        return "hat" not in self.calibration.locked


def settled_frames(q: np.ndarray, edge_frames: int) -> np.ndarray:
    """(n,) frames farther than ``edge_frames`` from either end of every run in which a coordinate of ``q``
    (n, 27) is finite: the zero-lag filter's start-up reverses the accelerations at a run's ends
    (:func:`~gaitcli.signal.butterworth.edge_frames`; up to 0.45 N·m/kg RMS on a synthetic walk's hip moment
    in its first frame, docs/decisions.md)."""
    settled = np.ones(q.shape[0], bool)
    if edge_frames <= 0:
        return settled
    for column in np.isfinite(q).T:
        for start, stop in zip(*true_runs(column)):
            settled[start:min(start + edge_frames, stop)] = False
            settled[max(stop - edge_frames, start):stop] = False
    return settled


def joint_centre_gaps(states, poses, params: BodyParameters) -> np.ndarray:
    """(n, 7) m: each model joint centre (the chain of the coordinates) to where the child segment's own SVD pose
    puts that joint — the drift down the chain that a per-segment marker error does not show."""
    own = np.stack([poses.com_m[:, c] + np.einsum("nij,j->ni", poses.rotation[:, c], params.joint_in_child_m[j])
                    for j, c in enumerate(JOINT_CHILD)], axis=1)
    return np.linalg.norm(states.joint_centre_m - own, axis=-1)


def marker_residuals(states, markers: Markers, calibration: StaticCalibration) -> dict[str, float]:
    """Tracking marker label → RMS (m, over the frames it is seen) of the model's marker position from the
    measured one, the model placed by the coordinates."""
    out = {}
    for b, body in enumerate(BODIES):
        for label, local in zip(calibration.tracking_landmarks[body], calibration.cluster(body)):
            if label not in markers:
                continue
            model = states.com_m[:, b] + np.einsum("nij,j->ni", states.rotation[:, b], local)
            d2 = np.sum((model - markers.get(label)) ** 2, axis=-1)
            if np.isfinite(d2).any():
                out[label] = float(np.sqrt(np.nanmean(d2)))
    return out


def estimate_mass_kg(trial: Trial, *, gravity_m_s2: float = GRAVITY_M_S2) -> float | None:
    """Body mass (kg) from the plates: over a full stride each foot carries half the body's weight on average.

    For every stride of a foot (its heel strike to its next one) whose stance was recorded on the plates (timed by
    the plates' events, or by the trial file's where one loaded run of the foot spans them:
    :func:`file_stances_on_plates`) and whose load is known throughout (but within ``FILE_EVENT_TOLERANCE_S`` of
    its events, where it is near zero), ``m = 2 ∫F_z dt / (g T)`` with ``T`` that stride's period
    (:func:`stride_period_s`); the median over those strides (None when none qualifies). The mean period of every
    stride in the trial, or a stance part of whose load went unmeasured, would make a true mass look off.
    """
    rate = trial.rate_hz
    t = trial.time_s
    masses = []
    for side, load in trial.feet.items():
        fz = np.nan_to_num(load.force_N[:, 2])
        known = trial.load_known(side)
        measured = ([(a, b) for a, b in trial.events.stances(side, "plate")]
                    + file_stances_on_plates(trial, side))
        for stride in (s for s in strides(trial.events) if s.side == side):
            start, end = stride.start_s, stride.end_s
            stance = next(((a, b) for a, b in measured
                           if abs(a - start) <= FILE_EVENT_TOLERANCE_S and b < end), None)
            if stance is None:
                continue
            events = np.array([start, end, *stance, *trial.events.times(side, "toe_off")])
            near = np.min(np.abs(t[:, None] - events[None, :]), axis=1) <= FILE_EVENT_TOLERANCE_S
            if not known[(t >= start) & (t < end) & ~near].all():
                continue
            on_plates = (t >= stance[0] - 1.5 / rate) & (t <= stance[1] + 1.5 / rate)  # the swing's load is zero
            impulse = float(np.sum(fz[on_plates]) / rate)
            masses.append(2 * impulse / (gravity_m_s2 * stride_period_s(trial.events, side, start)))
    return float(np.median(masses)) if masses else None


def stride_period_s(events: Events, side: str, strike_s: float) -> float:
    """The period (s) of ``side``'s stride that begins at its heel strike ``strike_s``.

    Heel strikes found by different means (the plate's threshold, the markers, the lab) are offset from each other
    by up to a tenth of a stride (a stiff knee's heel marker lands late), which a stride from a plate's heel strike
    to the markers' next one carries whole. So: that stride's own period when both its heel strikes have one
    source; else half the time from the heel strike before to the one after, where those two share one (the
    offsets cancel); else the stride as it is.
    """
    mine = events.of(side=side, kind="heel_strike")
    order = np.argsort(mine.time_s)
    times, sources = np.asarray(mine.time_s)[order], np.asarray(mine.source)[order]
    k = int(np.argmin(np.abs(times - strike_s)))
    if k + 1 < times.size and sources[k + 1] == sources[k]:
        return float(times[k + 1] - times[k])
    if 0 < k < times.size - 1 and sources[k - 1] == sources[k + 1]:
        return float(times[k + 1] - times[k - 1]) / 2
    return float(times[k + 1] - times[k]) if k + 1 < times.size else float("nan")


#: how far a lab's event may lie from the plate's threshold crossing of the same contact, s
FILE_EVENT_TOLERANCE_S = 0.05


def file_stances_on_plates(trial: Trial, side: str, *, max_s: float = np.inf) -> list[tuple[float, float]]:
    """(first, last) times (s) of the loaded runs of ``side``'s foot that make a whole stance timed by the file's
    events: the run holds the stance's middle, and starts and ends within ``FILE_EVENT_TOLERANCE_S`` of its heel
    strike and toe off."""
    t = trial.time_s
    loaded = np.nan_to_num(trial.feet[side].force_N[:, 2]) > 0
    out = []
    for a, b in trial.events.stances(side, "file", max_s=max_s):
        middle = int(np.argmin(np.abs(t - (a + b) / 2)))
        if not loaded[middle]:
            continue
        first = middle - int(np.argmin(loaded[middle::-1])) + 1 if not loaded[:middle + 1].all() else 0
        last = middle + int(np.argmin(loaded[middle:])) - 1 if not loaded[middle:].all() else t.size - 1
        if abs(t[first] - a) <= FILE_EVENT_TOLERANCE_S and abs(t[last] - b) <= FILE_EVENT_TOLERANCE_S:
            out.append((float(t[first]), float(t[last])))
    return out


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


#: C3D parameters that give the body mass in kg, in order of preference (``Recording.subject_metadata``)
MASS_PARAMETERS = ("PROCESSING:Bodymass", "PROCESSING:BodyMass", "SUBJECTS:MASS", "SUBJECTS:WEIGHT", "SUBJECT:MASS",
                   "SUBJECT:WEIGHT")
#: a body mass further than this from the plates' stride estimate is warned about
MASS_CHECK_FRACTION = 0.05
#: quiet standing on the static trial's plates: the middle half of the samples, steady within this fraction
STANDING_STEADY_FRACTION = 0.05


def standing_mass_kg(static: Recording | None, *, gravity_m_s2: float = GRAVITY_M_S2) -> float | None:
    """Body mass (kg) from quiet standing on the plates of the static trial: the median total vertical force
    of the middle half of the recording over g, when it is steady (interquartile range within 5 %) and above
    200 N; else None."""
    if static is None or not static.plates or len({p.n_samples for p in static.plates}) != 1:
        return None
    total = np.sum([np.nan_to_num(p.force_N[:, 2]) for p in static.plates], axis=0)
    n = total.size
    middle = total[n // 4: max(3 * n // 4, n // 4 + 1)]
    median = float(np.median(middle))
    q1, q3 = np.percentile(middle, [25, 75])
    if median < 200.0 or (q3 - q1) > STANDING_STEADY_FRACTION * median:
        return None
    return median / gravity_m_s2


def body_mass(trial: Trial, subject: Subject, cfg: IdynConfig, *, static: Recording | None = None,
              source: Path | None) -> tuple[float, str, float | None]:
    """The body mass (kg), where it came from, and the plates' stride estimate (kg, None without one).

    In order: subject.yaml (or the .vsk's Bodymass without one); the subject data (:data:`MASS_PARAMETERS`:
    the .vsk's, the trial's, then the static trial's); quiet standing on the static trial's plates; the
    stride estimate (:func:`estimate_mass_kg`). The estimate is always computed: a mass
    from elsewhere that differs from it by more than 5 % is warned about with both values.
    """
    estimate = estimate_mass_kg(trial, gravity_m_s2=cfg.gravity_m_s2)
    metadata = {**(static.subject_metadata if static is not None else {}), **trial.subject_metadata}
    from_file = next(((metadata[k], k) for k in MASS_PARAMETERS if k in metadata), None)
    standing = standing_mass_kg(static, gravity_m_s2=cfg.gravity_m_s2)
    if subject.mass_kg is not None:
        mass, where = float(subject.mass_kg), subject.mass_source
    elif from_file is not None and 0 < from_file[0] <= 500:
        key = from_file[1]
        mass = float(from_file[0])
        where = (f"{subject.measurements_source}'s {key.partition(':')[2]}" if key in subject.measurements
                 else f"the C3D file's {key}")
    elif standing is not None:
        mass, where = standing, "quiet standing on the plates of the static trial (median ΣFz / g)"
    else:
        return (check_mass(estimate, source), "estimated from the force plates (2·∫Fz dt / (g·stride period) "
                                              "per recorded stance)", estimate)
    if estimate is not None and abs(estimate - mass) > MASS_CHECK_FRACTION * mass:
        warnings.warn(f"body mass {mass:.1f} kg ({where}) differs from the force plates' stride estimate "
                      f"{estimate:.1f} kg by {100 * abs(estimate - mass) / mass:.0f} % (more than "
                      f"{100 * MASS_CHECK_FRACTION:.0f} %): check the mass, or the plates' calibration",
                      GaitWarning, stacklevel=2)
    return mass, where, estimate


def reference_frames(trial: Trial, static: Recording | None, subject: Subject, *,
                     subject_path: Path | None) -> tuple[Markers, np.ndarray | None, str]:
    """The markers of the reference posture (3.1.3), the frames of them to average (None: all), and how they
    were chosen: the static trial's file name, the frames subject.yaml names, or ``static_frames: auto``."""
    if static is not None:  # the static's file name (a session's "Static 01.c3d")
        return static.markers, None, static.source.name if static.source is not None else "static.c3d"
    m = trial.markers
    if subject.static_frames in (None, "auto"):
        frames, how = least_flexed_frames(m, source=subject_path)
        if subject.static_frames is None:
            warnings.warn(f"no static.c3d and no static_frames in subject.yaml: the model is calibrated on file "
                          f"frame{'s' if frames.size > 1 else ''} {frame_spans(frames, m.first_frame)} of the trial "
                          f"({how.removeprefix('auto: ')}); joint angles are measured from that posture",
                          GaitWarning, stacklevel=2)
        return m, frames, how
    first, last = subject.static_frames
    frames = np.arange(first, last + 1) - m.first_frame
    if frames[0] < 0 or frames[-1] >= m.n_frames:
        raise InputError(subject_path, "static_frames", f"got [{first}, {last}] (expected frames within "
                                                        f"{m.first_frame}–{m.first_frame + m.n_frames - 1})")
    return m, frames, "subject.yaml"


#: Plug-in Gait's marker diameter when neither subject.yaml nor the C3D gives one, m (Vicon's 14 mm markers)
DEFAULT_MARKER_DIAMETER_M = 0.014


def subject_measurements(subject: Subject, metadata: Mapping[str, float]) -> tuple[JointWidths, float | None, str]:
    """Knee/ankle widths, marker diameter and the preset's wands for the chord method, the leg length (m, None:
    measured from the markers), and where the leg length came from: subject.yaml first, then the C3D's
    ``PROCESSING`` group (Vicon's subject measurements, mm)."""
    def per_side(given, name):
        if given is not None:
            return {s: v / 1000.0 for s, v in given.items()}
        values = {s: cgm.processing_value(metadata, s, name) for s in SIDES}
        return {s: v / 1000.0 for s, v in values.items() if v is not None}

    diameter = (subject.marker_diameter_mm / 1000.0 if subject.marker_diameter_mm is not None
                else metadata.get("PROCESSING:MarkerDiameter", 1000.0 * DEFAULT_MARKER_DIAMETER_M) / 1000.0)
    widths = JointWidths(knee_m=per_side(subject.knee_width_mm, "KneeWidth"),
                         ankle_m=per_side(subject.ankle_width_mm, "AnkleWidth"),
                         marker_diameter_m=diameter, wands=dict(subject.markers.wands))
    if subject.leg_length_m is not None:
        return widths, subject.leg_length_m, "subject.yaml"
    legs = [v / 1000.0 for v in (cgm.processing_value(metadata, s, "LegLength") for s in SIDES) if v is not None]
    if legs:
        return widths, float(np.mean(legs)), "the C3D's PROCESSING group"
    return widths, None, "the markers"


def static_calibration(markers: Markers, frames: np.ndarray | None, subject: Subject, mass_kg: float, *,
                       source: Path | None, hip_method: str | None = None,
                       metadata: Mapping[str, float] | None = None, untracked: tuple[str, ...] = ()
                       ) -> StaticCalibration:
    """Static calibration (3.2, 3.3) on ``frames`` of ``markers`` with the subject's marker set and hip method
    (or ``hip_method``); ``metadata``: the C3D files' subject data (widths, leg length); ``untracked``: points
    that place joint centres but track no body."""
    markers_set = subject.markers
    widths, leg_length, _ = subject_measurements(subject, metadata or {})
    return calibrate(markers, frames=frames, source=source, mass_kg=mass_kg, stature_m=subject.stature_m,
                     sex=subject.sex, thigh_length_m=subject.thigh_length_m, shank_length_m=subject.shank_length_m,
                     disturbances=subject.disturbances, extra_tracking_markers=markers_set.tracking,
                     marker_set=markers_set, hip_method=hip_method or HIP_METHOD[subject.hip_joint_centre],
                     leg_length_m=leg_length, widths=widths, untracked=untracked,
                     segment_inertias=subject.segment_table)


def virtual_centres_only_in_static(static: Markers, frames: np.ndarray | None, trial: Markers) -> tuple[str, ...]:
    """The lab's virtual joint centres (``HJCr``, ``KJCr``, ``AJCr`` …) the reference posture shows and the walking
    trial never does: a static processed in Nexus (its FEO/TIO or KJC/AJC points) beside a raw walk."""
    in_static = static_landmarks(static, frames)
    return tuple(v for v in VIRTUAL_JOINT_CENTRES if v in in_static
                 and not (v in trial and np.isfinite(trial.get(v)).all(axis=-1).any()))


def without_points(markers: Markers, labels: tuple[str, ...]) -> Markers:
    """``markers`` without the trajectories ``labels``."""
    keep = [i for i, lab in enumerate(markers.labels) if lab not in labels]
    return Markers(tuple(markers.labels[i] for i in keep), markers.positions_m[:, keep], markers.rate_hz,
                   markers.first_frame)


def static_only_note(subject: Subject, absent: tuple[str, ...], hip_from_file: bool) -> str:
    """One line for the summary's notes and the warning: which virtual points of the static the walk lacks, and
    what stands in for them."""
    named = ", ".join(f"{v} ({' or '.join(subject.markers.landmarks.get(v, (v,)))})" for v in absent)
    own = [v for v in absent if not (v.startswith("HJC") and hip_from_file)]
    kept = [v for v in absent if v not in own]
    said = []
    if own:
        said.append(f"the tool's own {', '.join(own)} replace them in the calibration")
    if kept:
        said.append(f"{', '.join(kept)} stay the static's (hip_joint_centre {subject.hip_joint_centre}) and each "
                    "thigh is tracked with its hip centre placed by the pelvis")
    return (f"virtual joint centres in the static trial but not in the walking trial: {named}; "
            f"{'; '.join(said)}")


#: SCORE's uncertainty along its weakest direction above which the result is warned about, m
SCORE_SPREAD_M = 0.01
#: subject.yaml's ``hip_joint_centre`` → the calibration's method
HIP_METHOD = {"bell": "bell1990", "harrington": "harrington", "hara": "hara", "davis": "davis",
              "from_file": "from_file", "score": "bell1990"}  # score: Bell first, then functional_hip_centres


def plug_in_gait_model(subject: Subject, markers: Markers, frames: np.ndarray | None,
                       metadata: Mapping[str, float]) -> tuple[cgm.PlugInGait | None, str, dict[str, np.ndarray]]:
    """Plug-in Gait's frames for a ``plug_in_gait`` subject whose measurements and markers are all known (the
    static foot offsets, and with a knee alignment device the thigh and shank rotation offsets, from the
    reference posture ``frames`` of ``markers``), a note saying which frames the anatomical angles use, and the
    points a knee alignment device stands for in the reference posture ({``LEFr``: its hub, ``KJCr``, ``AJCr``:
    its centres}, m; empty without one)."""
    if not subject.markers.name.startswith("plug_in_gait"):
        return None, "anatomical angles: ISB joint coordinate systems on the calibrated anatomical frames", {}
    widths, leg_length, _ = subject_measurements(subject, metadata)
    measurements = cgm.measurements_from(metadata, leg_length_m=leg_length, knee_width_m=widths.knee_m,
                                         ankle_width_m=widths.ankle_m, marker_diameter_m=widths.marker_diameter_m)
    wands = dict(subject.markers.wands)
    standing, kad = cgm.with_kad_hubs(static_landmarks(markers, frames))
    P = None if measurements is None else cgm.plug_in_gait_landmarks(standing, wands)
    if P is not None:
        points = {}
        if kad:
            measurements = cgm.kad_rotation_offsets(P, kad, measurements)
            centres = cgm.leg_frames(P, measurements).joint_centres_m
            for s in (k[-1] for k in kad):
                points.update({f"LEF{s}": P[f"LEF{s}"], f"KJC{s}": centres[f"KJC{s}"], f"AJC{s}": centres[f"AJC{s}"]})
        offsets = cgm.static_foot_offsets(P, measurements)
        shown = ", ".join(f"{SIDE_NAMES[s]} plantarflexion {np.degrees(offsets.plantarflexion_rad[s]):.1f}° "
                          f"rotation {np.degrees(offsets.rotation_rad[s]):.1f}°" for s in SIDES)
        if kad:
            shown += "; knee alignment device: " + ", ".join(
                f"{SIDE_NAMES[k[-1]]} thigh rotation {np.degrees(measurements.thigh_rotation_rad[k[-1]]):.1f}° "
                f"shank rotation {np.degrees(measurements.shank_rotation_rad[k[-1]]):.1f}°" for k in kad)
        return (cgm.PlugInGait(measurements, offsets, wands),
                f"anatomical angles: Plug-in Gait's (CGM 1.0) frames per frame; static foot offsets {shown}", points)
    hubs = {k: v for k, v in standing.items() if k.startswith("LEF") and k not in static_landmarks(markers, frames)}
    return None, ("anatomical angles: ISB joint coordinate systems on the calibrated anatomical frames (Plug-in "
                  "Gait's frames need both legs' lengths, knee and ankle widths and every Plug-in Gait marker)"), hubs


#: Plug-in Gait's joint centres by joint index (:data:`gaitcli.kinematics.model.JOINTS`)
PIG_JOINT_CENTRES = {1: "HJCr", 2: "KJCr", 3: "AJCr", 4: "HJCl", 5: "KJCl", 6: "AJCl"}


def anatomical_frames(states, calibration: StaticCalibration, markers: Markers,
                      plug_in_gait: cgm.PlugInGait | None) -> tuple[dict[str, np.ndarray], np.ndarray, str]:
    """Each segment's anatomical frame per frame (n, 3, 3), the joint centres (n, 7, 3) m the lab's moments are
    taken about, and the ankle convention. Plug-in Gait's frames and joint centres from the markers where the
    model is given; else the tracked reference frames turned into the anatomical ones (``R_anatomical =
    R_reference · C``, 3.3) and the model's own joint centres."""
    centres = states.joint_centre_m
    if plug_in_gait is not None:
        segments = plug_in_gait.segments({label: markers.get(label) for label in markers.labels})
        if segments is not None:
            centres = centres.copy()
            for j, name in PIG_JOINT_CENTRES.items():
                centres[:, j] = segments.joint_centres_m[name]
            return segments.rotation, centres, "plug_in_gait"
    C = calibration.reference_to_anatomical
    return {b: states.rotation[:, i] @ C[i] for i, b in enumerate(BODIES)}, centres, "isb"


def inverse_dynamics_stage(trial: Trial, calibration: StaticCalibration, cfg: IdynConfig, *,
                           mass_kg: float, mass_source: str,
                           plug_in_gait: cgm.PlugInGait | None = None) -> IdynResult:
    """Poses by SVD (3.9–3.15), coordinates (3.17), derivatives, joint moments (3.21) and residuals (3.22), and
    the anatomical joint angles (Plug-in Gait's frames where ``plug_in_gait`` is given)."""
    markers = trial.markers
    poses = track_segments(markers, calibration)
    for line in missing_frame_messages(poses):
        warnings.warn(f"{line}: the pose, coordinates and moments there are NaN", GaitWarning, stacklevel=2)
    q = poses_to_coordinates(poses)
    segment_rms = poses.rms_m
    if cfg.pose == "chain_lsq":  # the segment fit is the start
        fit = fit_chain(q, markers, calibration)
        q, segment_rms = fit.q, fit.segment_rms_m
    qd, qdd = coordinate_derivatives(q, markers.rate_hz)
    params = calibration.body
    n = q.shape[0]
    result = inverse_dynamics(q, qd, qdd, params, external_wrenches(trial), gravity_m_s2=cfg.gravity_m_s2)
    moments = result.joint_moments_distal_Nm
    if cfg.frames == "anatomical":
        # R_anatomical = R_reference @ C: components in the anatomical frame are Cᵀ · (reference components)
        C = calibration.reference_to_anatomical[list(JOINT_CHILD)]
        moments = express_in(moments, np.broadcast_to(C, (n,) + C.shape))
    states = forward_kinematics(q, params, qd)
    frames, lab_centres, convention = anatomical_frames(states, calibration, markers, plug_in_gait)
    C = calibration.reference_to_anatomical
    distal = np.stack([frames.get(BODIES[c], states.rotation[:, c] @ C[c]) for c in JOINT_CHILD], axis=1)
    # the lab's moments: the same loads about its own joint centres (Plug-in Gait's), not the chain's
    global_moments = moments_about(result.joint_moments_global_Nm, result.joint_forces_N, states.joint_centre_m,
                                   lab_centres)
    omega = states.angular_velocity_rad_s.copy()  # the lab's segments turn as its frames do
    if convention == "plug_in_gait":
        for i, body in enumerate(BODIES):
            if body in frames:
                omega[:, i] = frame_angular_velocity(frames[body], markers.rate_hz)
    heel_names = {s: next((name for name in HEEL[s] if name in markers), None) for s in SIDES}
    heels = {s: markers.get(name)[:, :2] for s, name in heel_names.items() if name is not None}
    features = gait_features(trial.events, heels, markers.time_s)
    trial = trial.with_step(f"idyn: calibrated on the standing posture, body mass {mass_kg:.2f} kg "
                            f"({mass_source}); {POSE_STEPS[cfg.pose]}, 27 coordinates, inverse dynamics (3.21, 3.22), "
                            f"moments in {cfg.frames} frames")
    export = sagittal_export(trial, states.joint_centre_m, q, params, body_mass_kg=mass_kg)
    return IdynResult(trial=trial, q=q, qd=qd, qdd=qdd, joint_moments_Nm=moments,
                      joint_moments_global_Nm=result.joint_moments_global_Nm,
                      joint_moments_anatomical_Nm=express_in(global_moments, distal),
                      joint_powers_W=joint_powers(global_moments, omega),
                      joint_powers_sagittal_W=sagittal_powers(global_moments, omega, distal[..., 1]),
                      residual_force_N=result.residual_force_N, residual_moment_Nm=result.residual_moment_Nm,
                      frames=cfg.frames, mass_kg=mass_kg, mass_source=mass_source,
                      parameters=params, calibration=calibration, segment_rms_m=segment_rms,
                      joint_centre_gap_m=joint_centre_gaps(states, poses, params),
                      marker_rms_m=marker_residuals(states, markers, calibration),
                      joint_centres_m=states.joint_centre_m, features=features, strides=strides(trial.events),
                      sagittal=export, notes=list(calibration.notes),
                      anatomical_angles_rad=anatomical_angles(frames, ankle=convention), angle_convention=convention,
                      angles=cfg.angles, moment_convention=cfg.moments)


#: the share of a walk's frames with the right ASIS left of the left one (model y) that means swapped sides
SWAPPED_SIDES_SHARE = 0.9
#: m: how far the pelvis must travel along model +x for the walking direction to say where right is (not on
#: a treadmill, whose direction the markers do not give)
WALKED_M = 0.5


def check_sides(markers: Markers, path: Path | None) -> None:
    """Refuse a walk over ground whose right ASIS lies left of the left one (model +y is left of the walking
    direction) in most frames where both are seen: its right and left labels are swapped, or the subject walks
    backwards. Either mirrors every segment frame: hip flexion near 180°, the knee hyperextended, the ankle
    near −190°."""
    if "ASISr" not in markers or "ASISl" not in markers:
        return
    right, left = markers.get("ASISr"), markers.get("ASISl")
    forward = ((right + left) / 2)[:, 0]
    seen = forward[np.isfinite(forward)]
    if seen.size < 2 or seen[-1] - seen[0] < WALKED_M:
        return
    across = right[:, 1] - left[:, 1]
    across = across[np.isfinite(across)]
    share = float(np.mean(across > 0)) if across.size else 0.0
    if share > SWAPPED_SIDES_SHARE:
        raise InputError(path, None, f"the right ASIS marker lies left of the left one in {100 * share:.0f} % of "
                                     "the frames, seen along the walk: the right and left labels are swapped, or "
                                     "the subject walks backwards (expected the right markers on the right; every "
                                     "angle would come out mirrored)")


def run_idyn(trial: Trial, static: Recording | None, subject: Subject, cfg: IdynConfig, *,
             subject_path: Path | None = None, static_path: Path | None = None,
             trial_path: Path | None = None) -> IdynResult:
    """The whole idyn stage: body mass, static calibration (once), then :func:`inverse_dynamics_stage`; a walk
    with its sides swapped is refused first (:func:`check_sides`)."""
    check_sides(trial.markers, trial_path)
    mass, source, estimate = body_mass(trial, subject, cfg, static=static, source=subject_path)
    markers, frames, how = reference_frames(trial, static, subject, subject_path=subject_path)
    where = static_path if static is not None else trial_path
    residuals = {}
    metadata = {**(static.subject_metadata if static is not None else {}), **trial.subject_metadata}
    absent = virtual_centres_only_in_static(markers, frames, trial.markers)
    hip_from_file = subject.hip_joint_centre == "from_file"
    notes = []
    if absent:  # a Nexus-processed static beside a raw walk: a point of the static alone tracks nothing
        notes.append(static_only_note(subject, absent, hip_from_file))
        warnings.warn(notes[-1], GaitWarning, stacklevel=2)
        markers = without_points(markers, tuple(v for v in absent if not (v.startswith("HJC") and hip_from_file)))
    plug_in_gait, pig_note, device = plug_in_gait_model(subject, markers, frames, metadata)
    if device:  # a knee alignment device's hub is where the walk's knee marker sits; its centres track nothing
        markers = with_fixed_points(markers, device)
        absent += tuple(k for k in device if k[:3] in ("KJC", "AJC"))
        sides = ", ".join(SIDE_NAMES[k[-1]] for k in device if k.startswith("LEF"))
        notes.append(f"knee alignment device ({sides}): the knee marker at its hub" + (
            ", the knee and ankle centres Plug-in Gait's from it" if any(k.startswith("KJC") for k in device) else ""))
    if subject.hip_joint_centre == "score":
        markers, residuals = functional_hip_centres(trial, markers, frames, subject, mass, source=where,
                                                    metadata=metadata, untracked=absent)
    untracked = tuple(v for v in ("HJCr", "HJCl") if v in markers and v not in trial.markers) + absent
    calibration = static_calibration(markers, frames, subject, mass, source=where,
                                     hip_method="from_file" if residuals else None, metadata=metadata,
                                     untracked=untracked)
    calibration.notes.extend(notes)
    result = inverse_dynamics_stage(trial, calibration, cfg, mass_kg=mass, mass_source=source,
                                    plug_in_gait=plug_in_gait)
    result.notes.append(pig_note)
    result.notes[:0] = subject.notes  # where the subject's numbers came from (a .vsk), what was assumed
    first = markers.first_frame
    result.reference_posture = ReferencePosture(
        how, None if frames is None else (int(frames[0]) + first, int(frames[-1]) + first),
        subject.markers.name, subject.hip_joint_centre, estimate, residuals, subject.segment_table)
    return result


def functional_hip_centres(trial: Trial, markers: Markers, frames, subject: Subject, mass_kg: float, *,
                           source, metadata: Mapping[str, float] | None = None,
                           untracked: tuple[str, ...] = ()) -> tuple[Markers, dict[str, float]]:
    """``hip_joint_centre: score``: the reference posture's markers with ``HJCr``/``HJCl`` added where SCORE
    (Ehrig et al. 2006) puts them from the trial's own hip motion, and each side's RMS residual (mm).

    The segments are first tracked with Bell's hip centres; the hip centre is the point fixed in the pelvis and
    in the thigh (:func:`~gaitcli.kinematics.joint_centres.functional_joint_centre`); in the reference posture
    it lies at the pelvis CoM plus its pelvis coordinates turned by the pelvis's static orientation.
    """
    first = static_calibration(markers, frames, subject, mass_kg, source=source, hip_method="bell1990",
                               metadata=metadata, untracked=untracked)
    poses = track_segments(trial.markers, first)
    pelvis = BODIES.index("pelvis")
    added, residuals = {}, {}
    for side in SIDES:
        thigh = BODIES.index(f"thigh_{side}")
        c_pelvis, _, rms, spread = functional_joint_centre(poses.rotation[:, pelvis], poses.com_m[:, pelvis],
                                                           poses.rotation[:, thigh], poses.com_m[:, thigh])
        added[f"HJC{side}"] = first.com_m[pelvis] + first.static_rotation @ c_pelvis
        residuals[side] = 1000.0 * rms
        if spread > SCORE_SPREAD_M:
            warnings.warn(f"hip_joint_centre score, {SIDE_NAMES[side]}: the trial's hip motion fixes the centre only "
                          f"to about {1000 * spread:.0f} mm along its least determined direction (residual "
                          f"{1000 * rms:.1f} mm): a trial that moves the hip about more than one axis (a star arc) "
                          "determines it better", GaitWarning, stacklevel=3)
    return with_fixed_points(markers, added), residuals


def check_mass(mass_kg: float | None, source) -> float:
    """The body mass to use, or a clear error when neither subject.yaml nor the plates give one."""
    if mass_kg is None or not np.isfinite(mass_kg) or mass_kg <= 0:
        raise InputError(source, "mass_kg", "is 'auto' (or not given) but the C3D records no body mass, static.c3d "
                                            "has no quiet standing on its plates and no stance was fully recorded "
                                            "on the force plates (expected mass_kg in kg)")
    return float(mass_kg)
