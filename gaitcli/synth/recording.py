"""The recording of a synthetic walk: markers, force plates and the exact truth.

The designed cycle (:mod:`gaitcli.synth.gait`) is tiled over the trial at the
analog rate. Markers (Table A.6) ride rigidly on the bodies, plus white noise
(RMS 3-D error ``noise_mm``) and a low-frequency skin artefact (peak 3-D
displacement ``artefact_mm``). Two TYPE-2 plates measure one right and one left
stance. The truth joint moments carry every ground contact, not only the plates.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from gaitcli.core.numerics import true_runs
from gaitcli.core.recording import ForcePlate, Markers
from gaitcli.core.validate import one_of
from gaitcli.errors import InputError
from gaitcli.kinematics.model import BODIES
from gaitcli.synth.gait import ANALOG_RATE_HZ, CONDITIONS, Condition, GaitDesign, Geometry, balanced_gait
from gaitcli.synth.ground import ground_reactions
from gaitcli.synth.predicted import predicted_gait, predicted_period_s

MARKER_RATE_HZ = 100.0
#: the markers' default white noise, RMS 3-D error, mm: still well above an optical system's own (a Vicon
#: marker's position varies by < 0.025 mm standing and errs by < 2 mm moving, systematic part included:
#: Merriaux et al., Sensors 17:1591, 2017); the skin artefact (10 mm) stays the larger error, as on a subject.
#: Not 2 mm: the filtered moments would then change at push-off faster than MSO's muscles can follow
#: (docs/decisions.md)
DEFAULT_NOISE_MM = 1.0

#: the marker set of Table A.6 and the body each marker rides on
MARKER_BODY = {
    "ASISr": "pelvis", "ASISl": "pelvis", "PSISr": "pelvis", "PSISl": "pelvis",
    "C7": "hat", "ST": "hat", "ACr": "hat", "ACl": "hat",
    "GTr": "thigh_r", "MRFr": "thigh_r", "LEFr": "thigh_r", "MEFr": "thigh_r",
    "TTr": "shank_r", "LMr": "shank_r", "MMr": "shank_r",
    "CAr": "foot_r", "VMr": "foot_r", "FMr": "foot_r",
    "GTl": "thigh_l", "MRFl": "thigh_l", "LEFl": "thigh_l", "MEFl": "thigh_l",
    "TTl": "shank_l", "LMl": "shank_l", "MMl": "shank_l",
    "CAl": "foot_l", "VMl": "foot_l", "FMl": "foot_l",
}


@dataclass
class SyntheticTrial:
    """Everything ``write_trial`` writes, in memory (model axes, SI)."""

    markers: Markers
    static: Markers
    plates: list
    q: np.ndarray  # (frames, 27) at the marker rate
    qd: np.ndarray
    qdd: np.ndarray
    feet: dict  # side -> force_N, cop_m, free_moment_Nm at the marker rate (all contacts)
    plate_feet: list  # side of each plate
    events: list  # (time_s, frame, side, kind, on_plate)
    calibration: object
    design: GaitDesign
    joint_moments_Nm: np.ndarray  # (frames, 7, 3) in the distal segment frame
    split_clip: float
    # C3D subject parameters {"PROCESSING:RightKneeWidth": mm, ...} (Plug-in Gait)
    metadata: dict = field(default_factory=dict)
    anatomical_angles_rad: np.ndarray | None = None  # (frames, 23) true anatomical angles (synth.anatomy)
    angle_convention: str = "isb"  # "plug_in_gait" or "isb": the definition of the anatomical frames

    def joint_centres_m(self) -> dict[str, np.ndarray]:
        """The true hip, knee and ankle centres over the walk, (frames, 3) m in model axes: ``HJCr`` … ``AJCl``."""
        from gaitcli.kinematics.forward import forward_kinematics
        from gaitcli.kinematics.model import JOINTS

        states = forward_kinematics(self.q, self.calibration.body)
        return {f"{c}{s}": states.joint_centre_m[:, JOINTS.index(f"{j}_{s}")]
                for s in "rl" for c, j in (("HJC", "hip"), ("KJC", "knee"), ("AJC", "ankle"))}


def white_noise(rng, rms_mm, shape):
    """White marker noise (m) of RMS 3-D error ``rms_mm``: σ = rms/√3 per axis."""
    return rng.normal(0.0, rms_mm / 1000.0 / np.sqrt(3.0), shape)


def skin_artefact(rng, time_s, period_s, amplitude_m, bodies):
    """Low-frequency skin artefact (m) of peak 3-D displacement ``amplitude_m`` for markers on ``bodies``.

    Each axis moves as ``0.6 sin(ωt + φ₀) + 0.4 sin(2ωt + φ₁)``, ω the gait
    frequency: per segment a common part (70 %) plus a per-marker part (30 %).
    """
    w = 2 * np.pi / period_s

    def wave():
        phases = rng.uniform(0, 2 * np.pi, (2, 3))
        return 0.6 * np.sin(w * time_s[:, None] + phases[0]) + 0.4 * np.sin(2 * w * time_s[:, None] + phases[1])

    common = {body: wave() for body in sorted(set(bodies))}  # a fixed order: the same seed gives the same trial
    out = np.zeros((time_s.size, len(bodies), 3))
    for i, body in enumerate(bodies):
        out[:, i] = amplitude_m / np.sqrt(3.0) * (0.7 * common[body] + 0.3 * wave())  # ≤ amplitude in 3-D
    return out


#: the marker sets ``gait synth`` can place: Table A.6 markers left out, and the tracking clusters added (body →
#: how many markers of the preset's tracking list). Plug-in Gait's wands, ankle and toe markers are placed by
#: :func:`plug_in_gait_points`.
SYNTH_MARKER_SETS = {"dissertation": ((), {}),
                     "cleveland": (("GT", "MRF", "TT"), {"thigh_r": 3, "thigh_l": 3, "shank_r": 3, "shank_l": 3}),
                     "cast": (("MRF",), {"thigh_r": 1, "thigh_l": 1, "shank_r": 2, "shank_l": 2}),
                     "plug_in_gait": (("GT", "MRF", "MEF", "TT", "LM", "MM", "VM", "FM"), {})}
#: the walking motions ``gait synth --gait`` makes (``simulate_trial``)
SYNTH_GAITS = ("normative", "predicted")
#: Plug-in Gait's synthetic subject: marker diameter (m), how far lateral of the joint centre the ankle marker sits
#: (× stature; the knee marker is the template's LEF, 0.025 × stature) and of the segment axis the wands sit (m)
PIG_MARKER_DIAMETER_M = 0.014
PIG_ANKLE_OFFSET = 0.02
PIG_WAND_LATERAL_M = {"thigh": 0.08, "shank": 0.07}
#: a cluster's markers about its centre, m (forward, down) in the sagittal plane of the segment's lateral side
CLUSTER_PATTERN = ((0.03, -0.04), (0.03, 0.04), (-0.03, 0.0))
#: how far lateral of the segment's axis a cluster's centre sits, m
CLUSTER_LATERAL_M = {"thigh": 0.07, "shank": 0.06}


def cluster_template(template: dict, joint_centres: dict, marker_set: str) -> dict[str, np.ndarray]:
    """Standing positions (m) of the preset's tracking clusters: per thigh and shank a plate of markers centred
    lateral of the segment's mid-point (between the joint centres), named by the preset's tracking labels."""
    from gaitcli.kinematics.markerset import marker_set as preset

    tracking = preset(marker_set).tracking
    out = {}
    for body, count in SYNTH_MARKER_SETS[marker_set][1].items():
        segment, side = body.split("_")
        top, bottom = (("HJC", "KJC") if segment == "thigh" else ("KJC", "AJC"))
        mid = (joint_centres[f"{top}{side}"] + joint_centres[f"{bottom}{side}"]) / 2
        lateral = -1.0 if side == "r" else 1.0
        centre = mid + [0.0, lateral * CLUSTER_LATERAL_M[segment], 0.0]
        for label, (forward, down) in zip(tracking[body][:count], CLUSTER_PATTERN):
            out[label] = centre + [forward, 0.0, -down]
    return out


def plug_in_gait_points(template: dict, joint_centres: dict, stature_m: float,
                        medial_markers: bool = False) -> tuple[dict, dict, dict]:
    """Plug-in Gait's markers beyond Table A.6's as they stand (m): per side the wands THI and TIB lateral of the
    thigh's and shank's mid-points in the leg's frontal plane, ANK at the ankle centre plus ``PIG_ANKLE_OFFSET`` ×
    stature laterally (so that the chord method's right angle holds exactly), TOE at the mid-metatarsal heads;
    with ``medial_markers`` KNM at the medial epicondyle (MEF: the knee centre is KNE's and KNM's midpoint) and
    MED where ANK's and MED's midpoint is the malleoli's (LM, MM: the calibration's de Leva ankle centre holds).
    Returns the points by lab label, the body each tracks, and the subject measurements the C3D's PROCESSING
    group carries (widths from the marker offsets: width = 2 × offset − marker diameter, mm; leg lengths)."""
    points, bodies, metadata = {}, {}, {"PROCESSING:MarkerDiameter": 1000.0 * PIG_MARKER_DIAMETER_M}
    for s, side, lateral in (("r", "Right", -1.0), ("l", "Left", 1.0)):
        prefix = s.upper()
        hjc, kjc, ajc = (joint_centres[f"{j}{s}"] for j in ("HJC", "KJC", "AJC"))
        out = np.array([0.0, lateral, 0.0])
        points[f"{prefix}THI"] = (hjc + kjc) / 2 + PIG_WAND_LATERAL_M["thigh"] * out
        points[f"{prefix}TIB"] = (kjc + ajc) / 2 + PIG_WAND_LATERAL_M["shank"] * out
        points[f"{prefix}ANK"] = ajc + PIG_ANKLE_OFFSET * stature_m * out
        points[f"{prefix}TOE"] = (template[f"FM{s}"] + template[f"VM{s}"]) / 2
        bodies.update({f"{prefix}THI": f"thigh_{s}", f"{prefix}TIB": f"shank_{s}", f"{prefix}ANK": f"shank_{s}",
                       f"{prefix}TOE": f"foot_{s}"})
        if medial_markers:
            points[f"{prefix}KNM"] = template[f"MEF{s}"]
            points[f"{prefix}MED"] = template[f"LM{s}"] + template[f"MM{s}"] - points[f"{prefix}ANK"]
            bodies.update({f"{prefix}KNM": f"thigh_{s}", f"{prefix}MED": f"shank_{s}"})
        knee_offset = float(np.linalg.norm(template[f"LEF{s}"] - kjc))
        metadata[f"PROCESSING:{side}KneeWidth"] = 1000.0 * (2 * knee_offset - PIG_MARKER_DIAMETER_M)
        metadata[f"PROCESSING:{side}AnkleWidth"] = 1000.0 * (2 * PIG_ANKLE_OFFSET * stature_m - PIG_MARKER_DIAMETER_M)
        # Plug-in Gait's leg length, as a lab measures it: the ASIS to the medial malleolus
        metadata[f"PROCESSING:{side}LegLength"] = 1000.0 * pig_leg_length_m(template, s)
    return points, bodies, metadata


def plug_in_gait_body(template: dict) -> tuple[dict, dict]:
    """A Plug-in Gait subject on which Plug-in Gait's assumptions hold: the hip centres where Davis et al. (1991)
    put them (the leg length the C3D records, :func:`plug_in_gait_points`, and the marker radius), and the knee
    markers at right angles to the thigh (:func:`~gaitcli.synth.anatomy.plug_in_gait_template`). Returns the
    standing template and the calibration options that build that body."""
    from gaitcli.kinematics.joint_centres import JointWidths
    from gaitcli.synth.anatomy import davis_hip_centres_m, plug_in_gait_template

    leg_length = pig_leg_length_m(template)
    hips = davis_hip_centres_m(template, leg_length_m=leg_length, marker_radius_m=PIG_MARKER_DIAMETER_M / 2)
    return (plug_in_gait_template(template, hip_centres_m=hips),
            {"hip_method": "davis", "leg_length_m": leg_length,
             "widths": JointWidths(marker_diameter_m=PIG_MARKER_DIAMETER_M)})


def pig_leg_length_m(template: dict, side: str | None = None) -> float:
    """Plug-in Gait's leg length (m) as a lab measures it, ASIS to medial malleolus: one side's, or both sides'
    mean (what Plug-in Gait's hip regression takes)."""
    sides = (side,) if side else ("r", "l")
    return float(np.mean([np.linalg.norm(template[f"ASIS{s}"] - template[f"MM{s}"]) for s in sides]))


def true_anatomical_angles(q, calibration, template: dict, plug_in_gait_points: dict | None) -> np.ndarray:
    """(frames, 23) rad: the body's true anatomical angles over ``q`` (:mod:`gaitcli.synth.anatomy`) from its own
    rotations, joint centres and the standing ``template``; Plug-in Gait's definitions when its markers
    (``RANK``, ``RTOE`` … standing) are given, else ISB's."""
    from gaitcli.kinematics.forward import forward_kinematics
    from gaitcli.synth.anatomy import anatomical_angles, anatomical_frames, standing_frames

    centres = calibration.joint_centres_m
    pig = None
    if plug_in_gait_points is not None:
        pig = {}
        for s in "rl":
            lab = s.upper()
            pig.update({f"ANK{s}": plug_in_gait_points[f"{lab}ANK"], f"TOE{s}": plug_in_gait_points[f"{lab}TOE"],
                        f"HEE{s}": template[f"CA{s}"], f"AJC{s}": centres[f"AJC{s}"]})
    states = forward_kinematics(q, calibration.body)
    rotation = {b: states.rotation[:, i] for i, b in enumerate(BODIES)}
    return anatomical_angles(anatomical_frames(rotation, standing_frames(template, centres, plug_in_gait=pig),
                                               plug_in_gait=pig))


def model_markers(q, calibration, extra: dict[str, tuple[str, ...]] | None = None):
    """The segment markers riding on the calibrated bodies over ``q`` (Table A.6's and ``extra`` {body: labels}):
    names, positions (frames, markers, 3) in m, and the body of each."""
    from gaitcli.kinematics.forward import marker_positions
    from gaitcli.kinematics.markerset import SEGMENT_MARKERS

    extra = extra or {}
    in_body, labels = calibration.markers_in_body()
    wanted = {bi: [k for k, name in enumerate(labels[bi])
                   if name in SEGMENT_MARKERS[BODIES[bi]] + tuple(extra.get(BODIES[bi], ()))]
              for bi in in_body}
    positions = marker_positions(q, calibration.body, {bi: in_body[bi][wanted[bi]] for bi in in_body})
    names, columns, bodies = [], [], []
    for bi in in_body:
        for col, k in enumerate(wanted[bi]):
            names.append(labels[bi][k])
            columns.append(positions[bi][:, col])
            bodies.append(BODIES[bi])
    return names, np.stack(columns, axis=1), bodies


def stance_contacts(stance, samples):
    """(side, first, end) trial indices of every stance of each side, ``samples`` being the cycle's sample
    index of each trial sample."""
    contacts = []
    for s in "rl":
        contacts += [(s, a, b) for a, b in zip(*true_runs(stance[s][samples]))]
    return contacts


def plate_recording(name, stances, rng, noise_N, rate_hz: float = ANALOG_RATE_HZ):
    """A plate under the stances ``[(foot, first, end), …]`` (a foot's loads over samples ``first:end``): 0.6 m ×
    0.4 m centred ``o`` under a single stance's mean COP, or, under two feet's stances, 0.4 m longer and wider
    than the span of their COPs.

    Force ``F`` (N) and moment about its centre ``Σ (c − o) × F + T e_z`` (N·m, ``T``
    the free moment), plus white noise of σ ``noise_N`` and ``0.05 noise_N``; sampled at ``rate_hz``.
    """
    cops = np.concatenate([foot["cop_m"][first:end] for foot, first, end in stances])
    low, high = np.nanmin(cops, axis=0), np.nanmax(cops, axis=0)
    centre = np.nanmean(cops, axis=0) if len(stances) == 1 else (low + high) / 2
    centre[2] = 0.0
    half = np.array([0.3, 0.2]) if len(stances) == 1 else (high - low)[:2] / 2 + 0.2
    corners = centre + np.array([[half[0], -half[1], 0], [-half[0], -half[1], 0],
                                 [-half[0], half[1], 0], [half[0], half[1], 0]])
    force = np.zeros_like(stances[0][0]["force_N"])
    moment = np.zeros_like(force)
    for foot, first, end in stances:
        force[first:end] += foot["force_N"][first:end]
        lever = np.nan_to_num(foot["cop_m"][first:end] - centre)
        moment[first:end] += np.cross(lever, foot["force_N"][first:end])
        moment[first:end, 2] += foot["free_moment_Nm"][first:end]
    force += rng.normal(0.0, noise_N, force.shape)
    moment += rng.normal(0.0, noise_N * 0.05, moment.shape)
    return ForcePlate(name=name, force_N=force, moment_Nm=moment, centre_m=centre, corners_m=corners,
                      rate_hz=rate_hz)


def contact_events(contacts, on_plates, time_s, marker_rate_hz: float = MARKER_RATE_HZ):
    """(time_s, marker frame at ``marker_rate_hz``, side, kind, on_plate) of every heel strike and toe off inside
    the trial, in order."""
    events = []
    for side, a, b in contacts:
        on_plate = (side, a, b) in on_plates
        if a > 0:
            events.append((float(time_s[a]), int(round(time_s[a] * marker_rate_hz)), side, "heel_strike", on_plate))
        if b < time_s.size:
            events.append((float(time_s[b - 1]), int(round(time_s[b - 1] * marker_rate_hz)), side, "toe_off",
                           on_plate))
    events.sort()
    return events


def contact_moments(q, qd, qdd, params, feet):
    """Joint moments (frames, 7, 3), N·m in the distal segment frames, with every ground contact of ``feet``."""
    from gaitcli.dynamics.equations import ExternalWrench
    from gaitcli.dynamics.inverse import inverse_dynamics

    external = [ExternalWrench(body=BODIES.index(f"foot_{s}"), force_N=feet[s]["force_N"],
                               point_m=np.nan_to_num(feet[s]["cop_m"]),
                               moment_Nm=np.column_stack([np.zeros((q.shape[0], 2)), feet[s]["free_moment_Nm"]]))
                for s in "rl"]
    return inverse_dynamics(q, qd, qdd, params, external).joint_moments_distal_Nm


def simulate_trial(*, condition: str = "normal", seed: int = 0, noise_mm: float = DEFAULT_NOISE_MM,
                   artefact_mm: float = 10.0, strides: int = 3, mass_kg: float = 75.0, stature_m: float = 1.78,
                   sex: str = "male", plate_noise_N: float = 1.0, period_s: float | None = None,
                   shared_plate: bool = False, marker_set: str = "dissertation",
                   gait: str = "normative", plates: int = 2, marker_rate_hz: float = MARKER_RATE_HZ,
                   medial_markers: bool = False) -> SyntheticTrial:
    """Make a synthetic walking trial with known truth (nothing written).

    Two plates measure one right and one left stance in the middle of the walk. The stride
    length follows from stature and joint angles.

    Parameters
    ----------
    condition : str
        An experiment of 3.1.1 (:data:`~gaitcli.synth.gait.CONDITIONS`): added masses, locked joints.
    seed : int
        Seed of the marker noise and artefact.
    noise_mm : float
        RMS of each marker's 3-D position error, mm (white, σ = noise/√3 per axis), as optical
        systems quote their accuracy.
    artefact_mm : float
        Peak 3-D displacement of the low-frequency skin artefact, mm.
    strides : int
        Gait cycles in the trial.
    mass_kg, stature_m, sex : float, float, str
        The subject.
    plate_noise_N : float
        White noise on the plate channels, N (moments: 0.05 of it, N·m).
    period_s : float, optional
        Gait cycle, s (0.6–3.0); default the condition's, or with ``gait="predicted"`` the
        prediction's scaled to the stature.
    shared_plate : bool
        One plate measures both stances (the second foot steps on it before the first steps off).
    marker_set : str
        :data:`SYNTH_MARKER_SETS`: the labels of that preset, without the Table A.6 markers it lacks
        and with its thigh and shank clusters.
    plates : int
        How many consecutive stances in the middle of the walk a plate each measures: 2 (one right, one
        left) or 3 (as a lab with three plates in a row); 2 with ``shared_plate``.
    gait : str
        :data:`SYNTH_GAITS`: ``normative``, the normative curves re-timed over the stance foot
        (:mod:`~gaitcli.synth.gait`), or ``predicted``, the shipped muscle-driven prediction
        (:mod:`~gaitcli.synth.predicted`; every joint free, so not with a locked-joint condition).
    marker_rate_hz : float
        The markers' sampling rate, Hz (100 or 120 as labs record; 50–500); the plates sample at
        ``ANALOG_SAMPLES_PER_FRAME`` times it (1000 or 1200 Hz), the designed cycle on that grid.
    medial_markers : bool
        Plug-in Gait only: medial knee and ankle markers (RKNM, LKNM, RMED, LMED) on thigh and shank, each with
        its own noise and artefact (:func:`plug_in_gait_points`).
    """
    from gaitcli.kinematics.calibration import calibrate
    from gaitcli.kinematics.markerset import landmarks_to_markers, standing_template

    cond = trial_condition(condition, marker_set=marker_set, gait=gait, plates=plates, shared_plate=shared_plate,
                           noise_mm=noise_mm, artefact_mm=artefact_mm, period_s=period_s, stature_m=stature_m)
    check_rate_and_medial(marker_rate_hz, medial_markers, marker_set)
    analog_rate_hz = marker_rate_hz * ANALOG_SAMPLES_PER_FRAME
    samples = int(round(cond.period_s * analog_rate_hz))  # the cycle on the plates' grid
    rng = np.random.default_rng(seed)
    template = {k: v for k, v in standing_template(stature_m).items() if k in MARKER_BODY}
    joint_centre_options = {}  # how the body's joint centres are placed: the dissertation's (Bell), or Plug-in Gait's
    if marker_set == "plug_in_gait":
        template, joint_centre_options = plug_in_gait_body(template)
    subject = dict(mass_kg=mass_kg, stature_m=stature_m, sex=sex,
                   disturbances=() if condition == "normal" else (condition,), **joint_centre_options)
    cal = calibrate(landmarks_to_markers(template, rate_hz=MARKER_RATE_HZ), **subject)
    params = cal.body
    if gait == "predicted":
        design = predicted_gait(cond, params, stature_m=stature_m, samples=samples)
    else:
        design = balanced_gait(Geometry.standing(template, cal.joint_centres_m), cond, params, samples=samples)
    qd_c, qdd_c, feet_c, clip = ground_reactions(design, params)

    i, t_abs, q, feet = tile_cycle(design, feet_c, strides, analog_rate_hz)
    t = t_abs - t_abs[0]
    contacts = stance_contacts(design.stance, i)
    chosen = middle_stances(contacts, i.size, plates)
    plate_recordings = measuring_plates(chosen, feet, shared_plate, rng, plate_noise_N, analog_rate_hz)

    frames = slice(0, None, ANALOG_SAMPLES_PER_FRAME)
    qm, qd, qdd, tm = q[frames], qd_c[i][frames], qdd_c[i][frames], t[frames]
    names, exact, bodies, placed, metadata = placed_markers(qm, cal, template, marker_set, subject, medial_markers)
    noisy = exact + white_noise(rng, noise_mm, exact.shape) \
        + skin_artefact(rng, tm, design.period_s, artefact_mm / 1000.0, bodies)
    static_positions = np.stack([placed[nm] for nm in names])[None] \
        + white_noise(rng, noise_mm, (int(marker_rate_hz), len(names), 3))  # one second standing
    names = lab_labels(names, marker_set)
    sub_feet = {s: {k: v[frames] for k, v in feet[s].items()} for s in "rl"}
    convention = "plug_in_gait" if marker_set == "plug_in_gait" else "isb"
    truth_angles = true_anatomical_angles(qm, cal, template, placed if convention == "plug_in_gait" else None)
    return SyntheticTrial(markers=Markers(tuple(names), noisy, marker_rate_hz),
                          static=Markers(tuple(names), static_positions, marker_rate_hz), plates=plate_recordings,
                          q=qm, qd=qd, qdd=qdd, feet=sub_feet,
                          plate_feet=["".join(c[0] for c in chosen)] if shared_plate else [c[0] for c in chosen],
                          events=contact_events(contacts, chosen, t, marker_rate_hz), calibration=cal, design=design,
                          joint_moments_Nm=contact_moments(qm, qd, qdd, params, sub_feet), split_clip=clip,
                          metadata=metadata, anatomical_angles_rad=truth_angles, angle_convention=convention)


def trial_condition(condition: str, *, marker_set: str, gait: str, plates: int, shared_plate: bool,
                    noise_mm: float, artefact_mm: float, period_s: float | None, stature_m: float) -> Condition:
    """The experiment :func:`simulate_trial` walks (3.1.1), its period set by ``period_s`` (s) or by the prediction
    scaled to ``stature_m`` (m) with ``gait="predicted"``, once every option is checked."""
    one_of(condition, CONDITIONS, where="--condition")
    one_of(marker_set, SYNTH_MARKER_SETS, where="--marker-set")
    one_of(gait, SYNTH_GAITS, where="--gait")
    if plates not in (2, 3) or (shared_plate and plates != 2):
        raise InputError(None, "plates", f"got {plates} (expected 2 or 3 plates; 2 with one shared plate)")
    if noise_mm < 0 or artefact_mm < 0:
        raise InputError(None, "--noise-mm", "expected noise and artefact amplitudes ≥ 0 mm")
    cond = CONDITIONS[condition]
    if gait == "predicted":
        if cond.locked_knee_r or cond.locked_ankle_r:
            raise InputError(None, "--gait", f"predicted walks with every joint free (expected --gait normative "
                                             f"with --condition {condition})")
        cond = replace(cond, period_s=predicted_period_s(stature_m))
    if period_s is not None:
        if not 0.6 <= period_s <= 3.0:
            raise InputError(None, "--period-s", f"got {period_s} s (expected a gait cycle of 0.6–3.0 s)")
        cond = replace(cond, period_s=float(period_s))
    return cond


#: analog (force plate) samples per marker frame
ANALOG_SAMPLES_PER_FRAME = int(round(ANALOG_RATE_HZ / MARKER_RATE_HZ))
#: the marker rates :func:`simulate_trial` samples at, Hz
MARKER_RATES_HZ = (50.0, 500.0)


def check_rate_and_medial(marker_rate_hz: float, medial_markers: bool, marker_set: str) -> None:
    """Refuse a marker rate outside :data:`MARKER_RATES_HZ` and medial markers on a set other than Plug-in Gait."""
    low, high = MARKER_RATES_HZ
    if not low <= marker_rate_hz <= high:
        raise InputError(None, "marker_rate_hz", f"got {marker_rate_hz} Hz (expected {low:g}–{high:g} Hz)")
    if medial_markers and marker_set != "plug_in_gait":
        raise InputError(None, "medial_markers", f"marker set {marker_set} (expected plug_in_gait: KNM and MED "
                                                 "are Plug-in Gait's medial markers)")


def tile_cycle(design: GaitDesign, feet_cycle: dict, strides: int,
               analog_rate_hz: float = ANALOG_RATE_HZ) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict]:
    """The designed cycle tiled over the trial at the analog rate ``analog_rate_hz`` (the design's own): from a
    quarter cycle in to a quarter cycle past ``strides`` + 1 cycles, cut to whole marker frames. Returns each
    sample's index in the cycle, its time since the cycle's start (s), the coordinates (samples, 27) with the pelvis
    moved forward a stride per cycle, and each foot's force (N), COP (m, moved forward at the walking speed) and
    free moment (N·m)."""
    n = design.q.shape[0]
    first, end = int(round(0.25 * n)), int(round((strides + 1.25) * n))
    j = np.arange(first, end - (end - first) % ANALOG_SAMPLES_PER_FRAME)  # analog = frames × samples per frame
    cycle, i = j // n, j % n
    t_abs = j / analog_rate_hz
    q = design.q[i].copy()
    q[:, 0] += cycle * design.stride_m
    feet = {}
    for s in "rl":
        cop = feet_cycle[s]["cop_m"][i].copy()
        cop[:, 0] += design.speed_m_s * t_abs
        feet[s] = {"force_N": feet_cycle[s]["force_N"][i], "cop_m": cop,
                   "free_moment_Nm": feet_cycle[s]["free_moment_Nm"][i]}
    return i, t_abs, q, feet


def middle_stances(contacts: list, samples: int, plates: int) -> list:
    """The ``plates`` consecutive stances (side, first, end) in the middle of the walk, among those that begin and
    end inside its ``samples``."""
    complete = sorted([c for c in contacts if c[1] > 0 and c[2] < samples], key=lambda c: c[1])
    middle = len(complete) // 2 - 1
    return complete[middle:middle + plates]


def measuring_plates(chosen: list, feet: dict, shared_plate: bool, rng, noise_N: float,
                     rate_hz: float = ANALOG_RATE_HZ) -> list[ForcePlate]:
    """A plate under each chosen stance (``plate1``, ``plate2`` …), or one plate under them all (``shared_plate``)."""
    if shared_plate:
        return [plate_recording("plate1", [(feet[side], a, b) for side, a, b in chosen], rng, noise_N, rate_hz)]
    return [plate_recording(f"plate{k + 1}", [(feet[side], a, b)], rng, noise_N, rate_hz)
            for k, (side, a, b) in enumerate(chosen)]


def placed_markers(q, calibration, template: dict, marker_set: str, subject: dict,
                   medial_markers: bool = False) -> tuple:
    """The markers of ``marker_set`` riding on the bodies over ``q``: names (model landmarks or lab labels), exact
    positions (frames, markers, 3) m, the body of each, every marker's standing position (m) and the C3D's subject
    parameters. A preset's clusters (or Plug-in Gait's wands, ankle and toe markers) join Table A.6's less the ones
    it lacks, their reference positions from a calibration of the standing template with them (``subject``: its
    :func:`~gaitcli.kinematics.calibration.calibrate` options)."""
    if marker_set == "dissertation":
        return (*model_markers(q, calibration), template, {})
    from gaitcli.kinematics.calibration import calibrate
    from gaitcli.kinematics.markerset import landmarks_to_markers
    from gaitcli.kinematics.markerset import marker_set as preset

    metadata = {}
    if marker_set == "plug_in_gait":
        clusters, owner, metadata = plug_in_gait_points(template, calibration.joint_centres_m, subject["stature_m"],
                                                        medial_markers)
        extra = {body: tuple(lab for lab in clusters if owner[lab] == body) for body in set(owner.values())}
    else:
        clusters = cluster_template(template, calibration.joint_centres_m, marker_set)
        extra = {body: tuple(lab for lab in clusters if lab in preset(marker_set).tracking[body])
                 for body in SYNTH_MARKER_SETS[marker_set][1]}
    placed = {**template, **clusters}
    markers_cal = calibrate(landmarks_to_markers(placed, rate_hz=MARKER_RATE_HZ), extra_tracking_markers=extra,
                            **subject)
    names, exact, bodies = model_markers(q, markers_cal, extra)
    dropped = SYNTH_MARKER_SETS[marker_set][0]
    keep = [k for k, nm in enumerate(names) if nm[:-1] not in dropped]
    return [names[k] for k in keep], exact[:, keep], [bodies[k] for k in keep], placed, metadata


def lab_labels(names: list[str], marker_set: str) -> list[str]:
    """The preset's lab label of each model landmark in ``names`` (cluster labels kept as they are)."""
    if marker_set == "dissertation":
        return names
    from gaitcli.kinematics.markerset import marker_set as preset

    landmarks = preset(marker_set).landmarks
    return [landmarks[nm][0] if nm in landmarks else nm for nm in names]
