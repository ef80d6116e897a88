"""A synthetic trial folder (``gait synth``): trial.c3d, static.c3d, subject.yaml and truth/.

The C3D files hold the noisy markers and the two TYPE-2 plates (millimetres);
``truth/`` the exact kinematics and joint moments (clinical signs), the body's
true anatomical angles, the ground reactions of both feet at every contact, the
events and which foot each plate measured.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

from gaitcli.errors import InputError
from gaitcli.kinematics.anatomical import ANATOMICAL_ANGLES
from gaitcli.kinematics.model import COORDINATES, MOMENTS
from gaitcli.synth.recording import DEFAULT_NOISE_MM, MARKER_RATE_HZ, SyntheticTrial, simulate_trial

#: the side carrying the condition's added masses and locked joints
DISTURBED_SIDE = "r"


def subject_yaml(trial: SyntheticTrial, *, condition: str, mass_kg: float, stature_m: float, sex: str,
                 marker_set: str = "dissertation", emg: dict[str, str] | None = None) -> str:
    """The trial's ``subject.yaml``: the subject, its marker set (unless the dissertation's), the condition's
    added masses written out and the EMG channels' map (``emg``); the condition and its disturbed side as a
    comment."""
    from gaitcli.kinematics.disturbances import preset_disturbances

    data = {"mass_kg": mass_kg, "stature_m": stature_m, "sex": sex}
    if marker_set != "dissertation":
        data["marker_set"] = marker_set
    if marker_set == "plug_in_gait":  # the subject's hip centres are Davis's (synth.recording.plug_in_gait_body)
        data["hip_joint_centre"] = "davis"
        data["segment_inertias"] = "de_leva"  # the body's, as everywhere in synth (not Plug-in Gait's default)
    comment = f"# condition: {condition}"
    if condition != "normal":
        comment += f" (disturbed side: {DISTURBED_SIDE})"
        data["disturbances"] = [
            {"segment": d.segment, "name": d.name, "mass_kg": round(float(d.mass_kg), 6),
             "inertia_kgm2": [round(float(x), 8) for x in np.diag(np.asarray(d.inertia_kgm2))],
             "com_offset_m": [round(float(x), 6) for x in d.com_offset_m]}
            for d in preset_disturbances(condition, trial.calibration.segments, side=DISTURBED_SIDE)]
    if emg:
        data["emg"] = dict(emg)
    return f"# written by `gait synth`; the truth is in truth/\n{comment}\n" + yaml.safe_dump(data, sort_keys=False)


def write_truth(out: Path, trial: SyntheticTrial) -> None:
    """``truth/``: kinematics.csv and joint_moments.csv (clinical signs), grf.csv, events.csv, plates.csv and
    anatomical_angles.csv (deg, the columns of idyn's kinematics.csv: the body's true anatomical angles by the
    definitions of its marker set, :mod:`gaitcli.synth.anatomy`)."""
    from gaitcli.io.outputs import write_table
    from gaitcli.kinematics.conventions import anatomical_to_degrees, coordinates_to_clinical, moments_to_clinical

    time_s = trial.markers.time_s
    kin = coordinates_to_clinical(trial.q)
    write_table(out / "kinematics.csv", {"time_s": time_s, **{c: kin[:, k] for k, c in enumerate(COORDINATES)}})
    mom = moments_to_clinical(trial.joint_moments_Nm)
    write_table(out / "joint_moments.csv", {"time_s": time_s, **{c: mom[:, k] for k, c in enumerate(MOMENTS)}})
    grf = {"time_s": time_s}
    for s in "rl":
        for k, a in enumerate("xyz"):
            grf[f"foot_{s}_force_{a}_N"] = trial.feet[s]["force_N"][:, k]
        for k, a in enumerate("xyz"):
            grf[f"foot_{s}_cop_{a}_m"] = trial.feet[s]["cop_m"][:, k]
        grf[f"foot_{s}_free_moment_Nm"] = trial.feet[s]["free_moment_Nm"]
    write_table(out / "grf.csv", grf)
    ev = trial.events
    write_table(out / "events.csv", {"time_s": [e[0] for e in ev], "frame": [e[1] + 1 for e in ev],
                                     "side": [e[2] for e in ev], "event": [e[3] for e in ev],
                                     "on_plate": [int(e[4]) for e in ev]})
    write_table(out / "plates.csv", {"plate": [p.name for p in trial.plates], "foot": trial.plate_feet})
    if trial.anatomical_angles_rad is not None:
        angles = anatomical_to_degrees(trial.anatomical_angles_rad)  # kinematics.csv's signs (Plug-in Gait's ankle)
        write_table(out / "anatomical_angles.csv",
                    {"time_s": time_s, **{c: angles[:, k] for k, c in enumerate(ANATOMICAL_ANGLES)}})


def write_trial(out_dir: str | Path, *, condition: str = "normal", seed: int = 0, noise_mm: float = DEFAULT_NOISE_MM,
                artefact_mm: float = 10.0, plate_noise_N: float = 1.0, strides: int = 3, mass_kg: float = 75.0,
                stature_m: float = 1.78, sex: str = "male", period_s: float | None = None,
                marker_set: str = "dissertation", gait: str = "normative", emg: bool = False,
                marker_rate_hz: float = MARKER_RATE_HZ, medial_markers: bool = False) -> SyntheticTrial:
    """``gait synth``: write a trial folder with trial.c3d, static.c3d, subject.yaml and truth/.

    The options are those of :func:`~gaitcli.synth.recording.simulate_trial`; ``emg``: the trial also has an
    EMG channel per muscle and leg (:mod:`gaitcli.synth.emg`; the activations in truth/activations.csv).
    Returns the trial written.
    """
    from gaitcli.io.atomic import atomic_path, make_parent
    from gaitcli.io.c3d_write import write_c3d

    trial = simulate_trial(condition=condition, seed=seed, noise_mm=noise_mm, artefact_mm=artefact_mm,
                           plate_noise_N=plate_noise_N, strides=strides, mass_kg=mass_kg, stature_m=stature_m,
                           sex=sex, period_s=period_s, marker_set=marker_set, gait=gait,
                           marker_rate_hz=marker_rate_hz, medial_markers=medial_markers)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(out, None, "is a file (expected the trial folder to write)")
    analogs = activations = mapping = None
    if emg:
        from gaitcli.synth.emg import emg_channels, emg_map, truth_activations

        activations = truth_activations(trial, stature_m=stature_m, sex=sex, mass_kg=mass_kg)
        plates = trial.plates[0]
        analogs = emg_channels(activations, trial.markers.time_s, plates.rate_hz, plates.n_samples,
                               np.random.default_rng([seed, 39]))
        mapping = emg_map()
    make_parent(out / "trial.c3d")
    write_c3d(out / "trial.c3d", trial.markers, trial.plates, metadata=trial.metadata, analogs=analogs)
    write_c3d(out / "static.c3d", trial.static, [], metadata=trial.metadata)
    with atomic_path(out / "subject.yaml") as tmp:
        tmp.write_text(subject_yaml(trial, condition=condition, mass_kg=mass_kg, stature_m=stature_m, sex=sex,
                                    marker_set=marker_set, emg=mapping))
    write_truth(out / "truth", trial)
    if activations is not None:
        from gaitcli.io.outputs import write_table

        write_table(out / "truth" / "activations.csv", {"time_s": trial.markers.time_s, **activations})
    return trial


#: the names a Nexus session gives its trials
SESSION_STATIC, SESSION_WALK = "Static 01.c3d", "Walking {:02d}.c3d"


def write_session(out_dir: str | Path, *, walks: int = 3, seed: int = 0, **options) -> list[SyntheticTrial]:
    """``gait synth --session``: a session folder as Nexus leaves one: ``Static 01.c3d``, ``Walking 01.c3d`` …
    (walk k with the seed ``seed + k - 1``), one subject.yaml, and each walk's truth in ``truth/Walking 0k/``.

    ``options``: those of :func:`write_trial`; returns the walks written.
    """
    from gaitcli.io.atomic import atomic_path, make_parent
    from gaitcli.io.c3d_write import write_c3d

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError(out, None, "is a file (expected the session folder to write)")
    settings = {"condition": "normal", "mass_kg": 75.0, "stature_m": 1.78, "sex": "male",
                "marker_set": "dissertation", "gait": "normative", **options}
    written = []
    for k in range(1, walks + 1):
        trial = simulate_trial(seed=seed + k - 1, **settings)
        name = SESSION_WALK.format(k)
        make_parent(out / name)
        write_c3d(out / name, trial.markers, trial.plates, metadata=trial.metadata)
        if k == 1:
            write_c3d(out / SESSION_STATIC, trial.static, [], metadata=trial.metadata)
            with atomic_path(out / "subject.yaml") as tmp:
                tmp.write_text(subject_yaml(trial, **{key: settings[key] for key in
                                                      ("condition", "mass_kg", "stature_m", "sex", "marker_set")}))
        write_truth(out / "truth" / Path(name).stem, trial)
        written.append(trial)
    return written
