"""subject.yaml validation (gaitcli/kinematics/subject.py) and trial-folder discovery (gaitcli/run/trial.py)."""

from __future__ import annotations

import hashlib
import shutil

import numpy as np
import pytest
import yaml

from gaitcli.errors import InputError
from gaitcli.kinematics.subject import KEYS, load_subject, subject_from_dict
from gaitcli.resources import sample_trial
from gaitcli.run.trial import open_trial, sha256

BASE = {"mass_kg": 75.0, "stature_m": 1.78, "sex": "male"}


def _with(**changes):
    data = dict(BASE)
    for key, value in changes.items():
        if value is ...:
            data.pop(key)
        else:
            data[key] = value
    return data


def _error(data, path="trial/subject.yaml") -> InputError:
    with pytest.raises(InputError) as info:
        subject_from_dict(data, path)
    err = info.value
    message = str(err)
    assert "\n" not in message
    assert message.startswith(str(path)), message  # the message names the file first
    assert err.exit_code == 2
    return err


# ------------------------------------------------------------------------------- valid files


def test_minimal_subject_and_defaults():
    s = subject_from_dict(BASE)
    assert (s.mass_kg, s.stature_m, s.sex) == (75.0, 1.78, "male")
    assert s.thigh_length_m is None and s.shank_length_m is None
    assert s.marker_map == {} and s.disturbances == ()
    assert s.trial is None and s.static is None and s.static_frames is None
    assert isinstance(s.mass_kg, float)


def test_integers_are_accepted_as_numbers():
    s = subject_from_dict(_with(mass_kg=80, stature_m=2))
    assert s.mass_kg == 80.0 and isinstance(s.mass_kg, float) and s.stature_m == 2.0


@pytest.mark.parametrize("mass", ["auto", ...])
def test_mass_auto_or_missing_means_estimated(mass):
    assert subject_from_dict(_with(mass_kg=mass)).mass_kg is None


def test_every_optional_field():
    data = _with(thigh_length_m=0.45, shank_length_m=0.42, trial="walk03.c3d", static="stand.c3d",
                 static_frames=[1, 100], marker_map={"RHEE": "CAr", "LHEE": "CAl"},
                 disturbances=[{"segment": "foot_r", "name": "ski_boot", "mass_kg": 2.431,
                                "inertia_kgm2": [0.02, 0.033, 0.012], "com_offset_m": [0.01, 0.0, -0.02]}])
    s = subject_from_dict(data)
    assert (s.thigh_length_m, s.shank_length_m) == (0.45, 0.42)
    assert (s.trial, s.static, s.static_frames) == ("walk03.c3d", "stand.c3d", (1, 100))
    assert s.marker_map == {"RHEE": "CAr", "LHEE": "CAl"}
    (d,) = s.disturbances
    assert (d.segment, d.name, d.mass_kg) == ("foot_r", "ski_boot", 2.431)
    # principal moments about the added mass's own centre become a diagonal inertia tensor
    np.testing.assert_array_equal(np.asarray(d.inertia_kgm2), np.diag([0.02, 0.033, 0.012]))
    np.testing.assert_array_equal(np.asarray(d.com_offset_m), [0.01, 0.0, -0.02])


def test_disturbance_defaults():
    (d,) = subject_from_dict(_with(disturbances=[{"segment": "shank_l", "mass_kg": 1.0}])).disturbances
    np.testing.assert_array_equal(np.asarray(d.inertia_kgm2), np.zeros((3, 3)))
    np.testing.assert_array_equal(np.asarray(d.com_offset_m), np.zeros(3))


@pytest.mark.parametrize("name", ["normal", "ankle_weight", "knee_orthosis", "ankle_fixed", "ski_boot"])
def test_sample_subjects_load(name):
    path = sample_trial(name) / "subject.yaml"
    raw = yaml.safe_load(path.read_text())
    s = load_subject(path)
    # the sample subjects of sample_trials/README.md: gait synth's default subject walks normally
    assert (s.mass_kg, s.stature_m, s.sex) == ((75.0, 1.78, "male") if name == "normal" else (55.0, 1.65, "male"))
    assert len(s.disturbances) == len(raw.get("disturbances", []))
    for d, r in zip(s.disturbances, raw.get("disturbances", [])):
        assert d.segment == r["segment"] and d.mass_kg == r["mass_kg"] and d.name == r["name"]
        np.testing.assert_allclose(np.diag(np.asarray(d.inertia_kgm2)), r["inertia_kgm2"])


# ---------------------------------------------------------------------------------- bad files


@pytest.mark.parametrize("mass", ["heavy", True, [75], {"kg": 75}, None, "75"])
def test_mass_wrong_type(mass):
    err = _error(_with(mass_kg=mass))
    assert err.field == "mass_kg" and "kg" in err.problem


@pytest.mark.parametrize("mass", [0, 0.0, -3, -0.1, 501, float("nan"), float("inf")])
def test_mass_out_of_range(mass):
    assert _error(_with(mass_kg=mass)).field == "mass_kg"


@pytest.mark.parametrize("stature", [175, 178.0, 40, 260])
def test_stature_in_centimetres_says_so(stature):
    err = _error(_with(stature_m=stature))
    assert err.field == "stature_m" and "centimetres" in err.problem and f"{stature / 100:.2f}" in err.problem


@pytest.mark.parametrize("stature", [0, 0.3, 2.7, 3.5, 1000, -1.7, float("nan"), "tall", True])
def test_stature_out_of_range(stature):
    err = _error(_with(stature_m=stature))
    assert err.field == "stature_m" and "centimetres" not in err.problem


@pytest.mark.parametrize("key", ["stature_m", "sex"])
def test_required_keys(key):
    err = _error(_with(**{key: ...}))
    assert err.field == key and "missing" in err.problem


@pytest.mark.parametrize("sex", ["Male", "m", "x", 1, ["male"]])
def test_sex(sex):
    assert _error(_with(sex=sex)).field == "sex"


@pytest.mark.parametrize("key,hint", [("mass", "mass_kg"), ("stature", "stature_m"), ("marker_mapping", "marker_map"),
                                      ("disturbance", "disturbances")])
def test_unknown_key_did_you_mean(key, hint):
    data = _with(**{key: 1})
    err = _error(data)
    assert err.field == key and "unknown key" in err.problem and f"did you mean '{hint}'" in err.problem


@pytest.mark.parametrize("key,value", [("condition", "ski_boot"), ("disturbed_side", "r")])
def test_keys_older_synth_wrote_say_they_are_no_longer_read(key, value):
    err = _error(_with(**{key: value}))
    assert err.field == key and "no longer read" in err.problem and "# condition" in err.problem


def test_unknown_key_without_a_close_match_lists_the_allowed_keys():
    err = _error(_with(shoe_size=42))
    assert err.field == "shoe_size" and "did you mean" not in err.problem
    for key in KEYS:
        assert key in err.problem


@pytest.mark.parametrize("key,value", [("thigh_length_m", 45), ("thigh_length_m", 0.05), ("shank_length_m", "long"),
                                       ("shank_length_m", float("nan"))])
def test_segment_lengths(key, value):
    assert _error(_with(**{key: value})).field == key


@pytest.mark.parametrize("key,value", [("leg_length_m", 90), ("leg_length_m", 0.1), ("hip_joint_centre", "davies"),
                                       ("hip_joint_centre", "Bell"), ("marker_set", "plug_in_gait_v9"),
                                       ("marker_map", {"RTHI": "thigh"}), ("segment_inertias", "dempster")])
def test_marker_set_and_hip_centre_keys(key, value):
    assert _error(_with(**{key: value})).field.startswith(key)


def test_marker_set_hip_centre_and_static_frames_are_read():
    s = subject_from_dict(_with(marker_set="cleveland", hip_joint_centre="harrington", leg_length_m=0.92,
                                static_frames="auto", marker_map={"RTHI": "thigh_r", "RKNX": "LEFr"}))
    assert (s.marker_set, s.hip_joint_centre, s.leg_length_m, s.static_frames) == ("cleveland", "harrington", 0.92,
                                                                                    "auto")
    assert s.markers.landmarks["LEFr"] == ("RKNX",) and "RTHI" in s.markers.tracking["thigh_r"]
    plain = subject_from_dict(_with())
    assert (plain.marker_set, plain.hip_joint_centre, plain.markers.name) == (None, "bell", "dissertation")


def test_segment_inertias_follow_the_marker_set_unless_given():
    """A Plug-in Gait session's legs are Plug-in Gait's (its moments Vicon's), every other session's de Leva's
    (3.2.2); ``segment_inertias`` says otherwise for either."""
    table = {(marker_set, given): subject_from_dict(_with(**{k: v for k, v in (("marker_set", marker_set),
                                                                              ("segment_inertias", given)) if v}))
             .segment_table for marker_set in (None, "plug_in_gait") for given in (None, "de_leva", "plug_in_gait")}
    assert table == {(None, None): "de_leva", (None, "de_leva"): "de_leva", (None, "plug_in_gait"): "plug_in_gait",
                     ("plug_in_gait", None): "plug_in_gait", ("plug_in_gait", "de_leva"): "de_leva",
                     ("plug_in_gait", "plug_in_gait"): "plug_in_gait"}


@pytest.mark.parametrize("frames", [[10, 5], [0, 5], [1], [1, 5.5], "1-10", [True, 5]])
def test_static_frames(frames):
    assert _error(_with(static_frames=frames)).field == "static_frames"


@pytest.mark.parametrize("mapping", [["RHEE", "CAr"], {"RHEE": 3}, {1: "CAr"}, "RHEE: CAr"])
def test_marker_map_shape(mapping):
    assert _error(_with(marker_map=mapping)).field == "marker_map"


@pytest.mark.parametrize("key,value", [("trial", 3), ("static", ["a.c3d"])])
def test_other_fields(key, value):
    assert _error(_with(**{key: value})).field == key


@pytest.mark.parametrize("item,field", [
    ("foot_r", "disturbances[0]"),
    ({"segment": "toe_r", "mass_kg": 1.0}, "disturbances[0].segment"),
    ({"segment": "foot_r"}, "disturbances[0].mass_kg"),
    ({"segment": "foot_r", "mass_kg": 0}, "disturbances[0].mass_kg"),
    ({"segment": "foot_r", "mass_kg": 60}, "disturbances[0].mass_kg"),
    ({"segment": "foot_r", "mass_kg": 1.0, "inertia_kgm2": [0.1, 0.2]}, "disturbances[0].inertia_kgm2"),
    ({"segment": "foot_r", "mass_kg": 1.0, "com_offset_m": [0, "x", 0]}, "disturbances[0].com_offset_m"),
    ({"segment": "foot_r", "mass_kg": 1.0, "com_offset_m": [0, float("nan"), 0]}, "disturbances[0].com_offset_m"),
    ({"segment": "foot_r", "mass_kg": 1.0, "name": ["boot"]}, "disturbances[0].name"),
    ({"segment": "foot_r", "mas_kg": 1.0}, "disturbances[0].mas_kg"),
])
def test_disturbances(item, field):
    err = _error(_with(disturbances=[item]))
    assert err.field == field
    if field.endswith("mas_kg"):
        assert "did you mean 'mass_kg'" in err.problem


def test_disturbances_must_be_a_list():
    assert _error(_with(disturbances={"segment": "foot_r", "mass_kg": 1})).field == "disturbances"


@pytest.mark.parametrize("data", [None, [], ["mass_kg", 75], "mass_kg: 75", 75])
def test_not_a_mapping(data):
    assert _error(data).field is None


# ----------------------------------------------------------------------------- load_subject


def test_load_subject_file_errors(tmp_path):
    with pytest.raises(InputError, match="subject.yaml: file not found"):
        load_subject(tmp_path / "subject.yaml")
    bad = tmp_path / "subject.yaml"
    bad.write_text("mass_kg: 75\nsex: [male\n")
    with pytest.raises(InputError, match=r"subject.yaml: line \d+: not valid YAML"):
        load_subject(bad)
    bad.write_bytes(b"\xff\xfe\x00\x80 binary")
    with pytest.raises(InputError, match="subject.yaml: not a text file"):
        load_subject(bad)
    bad.write_text("")
    with pytest.raises(InputError, match="subject.yaml: expected a YAML mapping"):
        load_subject(bad)


def test_load_subject_round_trip(tmp_path):
    path = tmp_path / "subject.yaml"
    path.write_text(yaml.safe_dump(_with(marker_map={"RHEE": "CAr"})))
    s = load_subject(path)
    assert s.marker_map == {"RHEE": "CAr"} and s.mass_kg == 75.0


# ------------------------------------------------------------------------------ open_trial


def _folder(tmp_path, *files, subject=BASE):
    folder = tmp_path / "trial"
    folder.mkdir()
    (folder / "subject.yaml").write_text(yaml.safe_dump(subject))
    for name in files:
        (folder / name).write_bytes(b"x")
    return folder


def test_open_trial_finds_trial_and_static(tmp_path):
    folder = _folder(tmp_path, "trial.c3d", "static.c3d", "notes.txt")
    t = open_trial(folder)
    assert t.trial_path == folder / "trial.c3d" and t.static_path == folder / "static.c3d"
    assert t.forces_path is None and t.subject_path == folder / "subject.yaml" and t.name == "trial"
    assert t.input_files() == [folder / "subject.yaml", folder / "trial.c3d", folder / "static.c3d"]


def test_open_trial_csv(tmp_path):
    folder = _folder(tmp_path, "markers.csv", "forces.csv")
    t = open_trial(folder)
    assert (t.trial_path, t.forces_path, t.static_path) == (folder / "markers.csv", folder / "forces.csv", None)
    (folder / "forces.csv").unlink()
    assert open_trial(folder).forces_path is None  # markers only


def test_open_trial_prefers_c3d_over_csv(tmp_path):
    folder = _folder(tmp_path, "trial.c3d", "markers.csv", "forces.csv")
    assert open_trial(folder).trial_path == folder / "trial.c3d"


def test_open_trial_named_files(tmp_path):
    folder = _folder(tmp_path, "walk03.c3d", "trial.c3d", "stand.c3d", "static.c3d",
                     subject=_with(trial="walk03.c3d", static="stand.c3d"))
    t = open_trial(folder)
    assert t.trial_path == folder / "walk03.c3d" and t.static_path == folder / "stand.c3d"


@pytest.mark.parametrize("key", ["trial", "static", "vsk"])
def test_open_trial_named_file_missing(tmp_path, key):
    folder = _folder(tmp_path, "trial.c3d", subject=_with(**{key: "gone.c3d"}))
    with pytest.raises(InputError) as info:
        open_trial(folder)
    assert info.value.path == folder / "subject.yaml" and info.value.field == key and "gone.c3d" in str(info.value)


@pytest.mark.parametrize("key", ["trial", "static", "vsk"])
def test_named_files_stay_inside_the_trial_folder(tmp_path, key):
    """``../``, absolute paths and symlinks that lead out of the folder are refused, naming the key; the outside
    file is neither read nor quoted."""
    outside = tmp_path / "secret.c3d"
    outside.write_bytes(b"top secret")
    for name in ("../secret.c3d", str(outside), "link.c3d", "sub/../../secret.c3d"):
        folder = _folder(tmp_path, "trial.c3d", subject=_with(**{key: name}))
        (folder / "link.c3d").symlink_to(outside)
        with pytest.raises(InputError, match="outside the trial folder") as info:
            open_trial(folder)
        assert info.value.path == folder / "subject.yaml" and info.value.field == key
        assert "top secret" not in str(info.value)
        shutil.rmtree(folder)


def test_named_files_inside_the_folder_by_subfolder_or_symlink(tmp_path):
    folder = _folder(tmp_path, "trial.c3d", subject=_with(trial="raw/walk.c3d", static="stand.c3d"))
    (folder / "raw").mkdir()
    (folder / "raw" / "walk.c3d").write_bytes(b"x")
    (folder / "stand.c3d").symlink_to(folder / "raw" / "walk.c3d")
    t = open_trial(folder)
    assert t.trial_path == folder / "raw" / "walk.c3d" and t.static_path == folder / "stand.c3d"


@pytest.mark.parametrize("name", ["trial.c3d", "static.c3d", "markers.csv", "Test.vsk"])
def test_files_found_by_name_that_link_out_of_the_folder_are_refused(tmp_path, name):
    """The rule of `trial:` for the files found by their usual names: a link out of the folder is not read."""
    outside = tmp_path / "secret"
    outside.write_bytes(b"top secret")
    folder = _folder(tmp_path, *(() if name in ("trial.c3d", "markers.csv") else ("trial.c3d",)))
    (folder / name).symlink_to(outside)
    with pytest.raises(InputError, match="outside the trial folder") as info:
        open_trial(folder)
    assert info.value.path == folder / name and "top secret" not in str(info.value)


def test_files_found_by_name_may_link_inside_the_folder(tmp_path):
    folder = _folder(tmp_path, "raw.c3d", "stand.c3d")
    (folder / "trial.c3d").symlink_to("raw.c3d")
    (folder / "static.c3d").symlink_to(folder / "stand.c3d")
    t = open_trial(folder)
    assert (t.trial_path, t.static_path) == (folder / "trial.c3d", folder / "static.c3d")


def test_open_trial_missing_files(tmp_path):
    with pytest.raises(InputError, match="trial folder not found"):
        open_trial(tmp_path / "nowhere")
    folder = _folder(tmp_path)
    with pytest.raises(InputError) as info:
        open_trial(folder)
    assert info.value.path == folder / "trial.c3d" and "not found" in str(info.value)
    (folder / "subject.yaml").unlink()
    (folder / "trial.c3d").write_bytes(b"x")
    with pytest.raises(InputError) as info:
        open_trial(folder)
    assert info.value.path == folder / "subject.yaml"


def test_open_trial_modifies_nothing(tmp_path):
    folder = tmp_path / "normal"
    shutil.copytree(sample_trial("normal"), folder, ignore=shutil.ignore_patterns("gait_out", "truth"))
    before = {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()}
    open_trial(folder)
    assert {p: p.read_bytes() for p in folder.rglob("*") if p.is_file()} == before


def test_sha256(tmp_path):
    path = tmp_path / "f.bin"
    data = np.random.default_rng(0).bytes(3 << 20)  # more than one 1 MiB block
    path.write_bytes(data)
    assert sha256(path) == hashlib.sha256(data).hexdigest()


# ------------------------------------------------------------------------ the Vicon subject file (.vsk)


def _vsk(folder, name="Subject.vsk", model="PlugInGait FullBody Ai", **values):
    """A .vsk in ``folder`` with ``values`` as StaticParameters (Vicon's units: kg, mm) and one fitted Parameter."""
    values = {"Bodymass": 81.5, "Height": 1745, "RightKneeWidth": 104, "LeftKneeWidth": 106, "RightLegLength": 902,
              "LeftLegLength": 898, **values}
    lines = [f'<StaticParameter NAME="{k}" VALUE="{v}" QUANTITY="length"/>' for k, v in values.items() if v is not None]
    lines += ['<StaticParameter NAME="LeftTibialTorsion" PRIOR="0" QUANTITY="angle"/>',
              '<Parameter NAME="HipWidth" VALUE="123.8125" PRIOR="98.4" SD="0"/>']
    path = folder / name
    path.write_text(f'<?xml version="1.0" encoding="UTF-8"?>\n<KinematicModel MODEL="{model}" VERSION="3.2">\n'
                    "<Parameters>\n" + "\n".join(lines) + "\n</Parameters>\n</KinematicModel>\n")
    return path


def _vsk_folder(tmp_path, *files, **values):
    """A trial folder without subject.yaml: trial.c3d, static.c3d and a .vsk."""
    folder = tmp_path / "session"
    folder.mkdir()
    for name in ("trial.c3d", "static.c3d", *files):
        (folder / name).write_bytes(b"x")
    _vsk(folder, **values)
    return folder


def test_a_vsk_beside_subject_yaml_gives_the_measurements(tmp_path):
    """Every numeric parameter under PROCESSING:<NAME>, in the vsk's units; subject.yaml's own keys are untouched;
    the .vsk is an input (its hash in every output's provenance) and a note says where its values went."""
    folder = _folder(tmp_path, "trial.c3d", subject=_with(knee_width_mm=[110, 111]))
    vsk = _vsk(folder)
    t = open_trial(folder)
    s = t.subject
    assert s.measurements == {"PROCESSING:Bodymass": 81.5, "PROCESSING:Height": 1745.0,
                              "PROCESSING:RightKneeWidth": 104.0, "PROCESSING:LeftKneeWidth": 106.0,
                              "PROCESSING:RightLegLength": 902.0, "PROCESSING:LeftLegLength": 898.0,
                              "PROCESSING:HipWidth": 123.8125}
    assert (s.mass_kg, s.stature_m, s.sex, s.knee_width_mm) == (75.0, 1.78, "male", {"r": 110.0, "l": 111.0})
    assert (s.mass_source, s.measurements_source, s.vsk) == ("subject.yaml", "Subject.vsk", "Subject.vsk")
    assert (t.subject_path, t.vsk_path) == (folder / "subject.yaml", vsk)
    assert t.input_files() == [folder / "subject.yaml", folder / "trial.c3d", vsk]
    # the keys subject.yaml leaves out that the .vsk gives: its model's marker set and hip joint centres
    assert (s.marker_set, s.hip_joint_centre) == ("plug_in_gait", "davis")
    *filled, note = s.notes
    assert filled == [f"Subject.vsk's model 'PlugInGait FullBody Ai': {key} {value} (subject.yaml gives none)"
                      for key, value in (("marker_set", "plug_in_gait"), ("hip_joint_centre", "davis"))]
    assert note.startswith("subject measurements: Subject.vsk ('PlugInGait FullBody Ai'): 7 parameters as "
                           "PROCESSING:<NAME>") and "under subject.yaml's keys" in note
    # what the stages will use: not the knee widths (subject.yaml gives them), nor Bodymass (mass_kg given)
    assert note.endswith("used: RightLegLength 902, LeftLegLength 898")


def test_a_subject_yaml_naming_only_its_vsk_takes_every_key_the_vsk_gives(tmp_path):
    """stature_m from Height (mm → m), sex male assumed and said, the model's marker set and hip centres; Bodymass
    stays a measurement (mass_kg absent is the .vsk's, as the stages read it); subject.yaml's own keys win."""
    folder = _folder(tmp_path, "trial.c3d", subject={"vsk": "Subject.vsk"})
    _vsk(folder, Height=1632)
    s = open_trial(folder).subject
    assert (s.stature_m, s.sex, s.mass_kg, s.marker_set, s.hip_joint_centre) == (1.632, "male", None,
                                                                                "plug_in_gait", "davis")
    assert s.measurements["PROCESSING:Bodymass"] == 81.5
    assert any(n.startswith("Subject.vsk records no sex: male assumed") for n in s.notes)
    assert "Subject.vsk's Height: stature_m 1.632 (subject.yaml gives none)" in s.notes
    (folder / "subject.yaml").write_text(yaml.safe_dump({"vsk": "Subject.vsk", "sex": "female", "stature_m": 1.6,
                                                        "hip_joint_centre": "harrington"}))
    s = open_trial(folder).subject
    assert (s.stature_m, s.sex, s.hip_joint_centre, s.marker_set) == (1.6, "female", "harrington", "plug_in_gait")


def test_a_subject_yaml_naming_a_vsk_without_height_still_needs_stature(tmp_path):
    folder = _folder(tmp_path, "trial.c3d", subject={"vsk": "Subject.vsk", "sex": "female"})
    _vsk(folder, Height="")
    with pytest.raises(InputError, match="stature_m: missing"):
        open_trial(folder)


def test_a_vsk_height_out_of_range_is_refused_naming_the_vsk(tmp_path):
    folder = _folder(tmp_path, "trial.c3d", subject={"vsk": "Subject.vsk", "sex": "female"})
    _vsk(folder, Height=17.5)
    with pytest.raises(InputError) as info:
        open_trial(folder)
    assert (info.value.path, info.value.field) == (folder / "Subject.vsk", "Height")


def test_without_subject_yaml_the_vsk_describes_the_subject(tmp_path):
    folder = _vsk_folder(tmp_path)
    t = open_trial(folder)
    s = t.subject
    assert (s.mass_kg, s.stature_m, s.sex) == (81.5, 1.745, "male")
    assert (s.marker_set, s.hip_joint_centre, s.mass_source) == ("plug_in_gait", "davis", "Subject.vsk's Bodymass")
    assert s.measurements["PROCESSING:RightKneeWidth"] == 104.0 and s.knee_width_mm is None  # read as the C3D's
    assert (t.trial_path, t.static_path) == (folder / "trial.c3d", folder / "static.c3d")
    assert t.subject_path == t.vsk_path == folder / "Subject.vsk"
    assert t.input_files() == [folder / "Subject.vsk", folder / "trial.c3d", folder / "static.c3d"]
    described, sex, merged = s.notes
    assert described.startswith("subject: Subject.vsk, no subject.yaml: body mass 81.5 kg from Bodymass, stature "
                                "1.745 m from Height; marker set plug_in_gait and Davis hip joint centres")
    assert sex.startswith("sex: Subject.vsk records none, male assumed (de Leva's male segment tables)")
    assert merged.startswith("subject measurements: Subject.vsk") and "subject.yaml" not in merged
    assert "Bodymass 81.5, Height 1745" in merged


def test_a_vsk_of_another_model_keeps_the_default_marker_set(tmp_path):
    folder = _vsk_folder(tmp_path, model="MyLab LowerLimb", Bodymass=None)
    s = open_trial(folder).subject
    assert (s.marker_set, s.hip_joint_centre) == (None, "bell")
    assert s.mass_kg is None  # no Bodymass: estimated as with mass_kg: auto
    assert "not Plug-in Gait" in s.notes[0] and "not recorded" in s.notes[0]


def test_without_subject_yaml_the_vsk_needs_a_height(tmp_path):
    folder = _vsk_folder(tmp_path, Height=None)
    with pytest.raises(InputError, match=r"Subject.vsk: Height: missing \(expected the subject's height in mm, "
                                         r"or a subject.yaml with stature_m and sex\)") as info:
        open_trial(folder)
    assert info.value.path == folder / "Subject.vsk"


@pytest.mark.parametrize("name,value,given", [("Bodymass", 0, {}), ("Height", 17.45, None),
                                              ("RightKneeWidth", 0, {}), ("LeftLegLength", 8.98, {}),
                                              ("MarkerDiameter", -14, {})])
def test_implausible_measurements_the_stages_would_use_are_refused(tmp_path, name, value, given):
    """A measurement the stages read is checked as subject.yaml's key would be; Height only without
    subject.yaml (with one, stature_m is required)."""
    folder = _folder(tmp_path, "trial.c3d", subject=_with(mass_kg=..., **given)) if given is not None else \
        _vsk_folder(tmp_path)
    _vsk(folder, **{name: value})
    with pytest.raises(InputError) as info:
        open_trial(folder)
    assert info.value.path == folder / "Subject.vsk" and info.value.field == name
    assert f"got {value:g} (expected a" in str(info.value) and "\n" not in str(info.value)


def test_a_measurement_subject_yaml_replaces_is_not_checked(tmp_path):
    folder = _folder(tmp_path, "trial.c3d", subject=_with(knee_width_mm=100))
    _vsk(folder, RightKneeWidth=0)
    assert open_trial(folder).subject.measurements["PROCESSING:RightKneeWidth"] == 0.0


@pytest.mark.parametrize("with_yaml", [True, False])
def test_two_vsk_files_need_subject_yaml_to_name_one(tmp_path, with_yaml):
    folder = _folder(tmp_path, "trial.c3d") if with_yaml else _vsk_folder(tmp_path)
    _vsk(folder, "Anna.vsk", Bodymass=61)
    _vsk(folder, "Ben.VSK", Bodymass=90)
    if not with_yaml:
        (folder / "Subject.vsk").unlink()
    with pytest.raises(InputError) as info:
        open_trial(folder)
    message = str(info.value)
    assert info.value.path == folder and info.value.field == "vsk" and "\n" not in message
    assert "2 Vicon subject files: 'Anna.vsk', 'Ben.VSK' (expected one, or" in message
    assert ("`vsk:` in subject.yaml naming one" if with_yaml else "a subject.yaml naming one under `vsk:`") in message
    (folder / "subject.yaml").write_text(yaml.safe_dump(_with(mass_kg=..., vsk="Ben.VSK")))
    t = open_trial(folder)
    assert t.vsk_path == folder / "Ben.VSK" and t.subject.measurements["PROCESSING:Bodymass"] == 90.0


def test_a_named_vsk_in_a_subfolder_and_hidden_ones_ignored(tmp_path):
    folder = _folder(tmp_path, "trial.c3d", subject=_with(vsk="vicon/Subject.vsk"))
    (folder / "vicon").mkdir()
    _vsk(folder / "vicon")
    _vsk(folder, ".Subject.vsk.1234.part")  # a hidden file (e.g. a copy in progress) is not a subject file
    t = open_trial(folder)
    assert t.vsk_path == folder / "vicon" / "Subject.vsk" and t.subject.measurements_source == "vicon/Subject.vsk"
    (folder / "subject.yaml").write_text(yaml.safe_dump(BASE))
    assert open_trial(folder).vsk_path is None  # only the folder itself is searched


def test_a_bad_vsk_is_one_line_naming_it(tmp_path):
    folder = _vsk_folder(tmp_path)
    (folder / "Subject.vsk").write_text("<!DOCTYPE x>\n<KinematicModel/>")
    with pytest.raises(InputError, match=r"Subject.vsk: line 1: has a document type declaration"):
        open_trial(folder)


def test_no_subject_yaml_and_no_vsk(tmp_path):
    folder = tmp_path / "empty"
    folder.mkdir()
    (folder / "trial.c3d").write_bytes(b"x")
    with pytest.raises(InputError, match=r"subject.yaml: file not found \(every trial folder needs a subject.yaml "
                                         r"or a Vicon .vsk\)"):
        open_trial(folder)


def test_vsk_is_a_subject_yaml_key():
    assert "vsk" in KEYS and subject_from_dict(_with(vsk="Test.vsk")).vsk == "Test.vsk"
    assert _error(_with(vsk=3)).field == "vsk"


@pytest.mark.shared
def test_the_real_session_without_subject_yaml(shared_pig_dir, tmp_path):
    """Test.vsk beside the session's C3D files (copies: links out of the folder are refused): the README's
    measurements."""
    folder = tmp_path / "session"
    folder.mkdir()
    shutil.copy(shared_pig_dir / "Movement_trial.c3d", folder / "trial.c3d")
    shutil.copy(shared_pig_dir / "Static_trial.c3d", folder / "static.c3d")
    shutil.copy(shared_pig_dir / "Test.vsk", folder / "Test.vsk")
    s = open_trial(folder).subject
    assert (s.mass_kg, s.stature_m, s.marker_set, s.hip_joint_centre) == (85.0, 1.679, "plug_in_gait", "davis")
    m = s.measurements
    assert (m["PROCESSING:RightKneeWidth"], m["PROCESSING:LeftKneeWidth"]) == (139.0, 144.0)
    assert (m["PROCESSING:RightAnkleWidth"], m["PROCESSING:LeftAnkleWidth"]) == (89.0, 85.0)
    assert (m["PROCESSING:RightLegLength"], m["PROCESSING:LeftLegLength"], m["PROCESSING:InterAsisDistance"]) == \
        (866.0, 877.0, 306.0)


# ------------------------------------------------------------------------------------------ session folders

def _session(tmp_path, names, subject=None):
    """A session folder of empty files named ``names`` (discovery reads no C3D) and a subject.yaml."""
    folder = tmp_path / "Session 1"
    folder.mkdir()
    (folder / "subject.yaml").write_text(yaml.safe_dump(subject or BASE))
    for name in names:
        (folder / name).write_bytes(b"")
    return folder


def test_a_session_finds_its_walks_in_natural_order_and_its_static(tmp_path):
    from gaitcli.run.trial import session_walks

    folder = _session(tmp_path, ["Walking 10.c3d", "Walking 02.c3d", "Static 01.c3d", "Walking 01.C3D", ".x.c3d",
                                 "notes.txt"])
    assert [p.name for p in session_walks(folder)] == ["Walking 01.C3D", "Walking 02.c3d", "Walking 10.c3d"]
    walk = open_trial(folder / "Walking 02.c3d")
    assert walk.walk and walk.name == "Walking 02" and walk.static_path == folder / "Static 01.c3d"
    assert walk.out_root == folder / "gait_out" / "Walking 02" and walk.ref == folder / "Walking 02.c3d"
    assert walk.title == "Session 1 / Walking 02"
    assert walk.input_files() == [folder / "subject.yaml", folder / "Walking 02.c3d", folder / "Static 01.c3d"]
    with pytest.raises(InputError, match=r"a session of 3 walks \('Walking 01.C3D' …\): `gait run .*` runs every "
                                         r"walk; a command runs one walk named by its file"):
        open_trial(folder)


def test_a_trial_folder_is_no_session_and_one_walk_is_taken(tmp_path):
    from gaitcli.run.trial import session_walks

    assert session_walks(sample_trial("normal")) is None
    folder = _session(tmp_path, ["walk.c3d"])
    trial = open_trial(folder)
    assert trial.walk and trial.trial_path == folder / "walk.c3d" and trial.static_path is None
    assert trial.out_root == folder / "gait_out" / "walk"


def test_trials_and_static_globs(tmp_path):
    from gaitcli.run.trial import session_walks

    subject = {**BASE, "trials": ["Walking 0*.c3d", "Fast *.c3d"], "static": "Cal*.c3d"}
    folder = _session(tmp_path, ["Walking 01.c3d", "Walking 02.c3d", "Walking 10.c3d", "Fast 1.c3d", "Cal 03.c3d"],
                      subject)
    assert [p.name for p in session_walks(folder)] == ["Walking 01.c3d", "Walking 02.c3d", "Fast 1.c3d"]
    assert open_trial(folder / "Fast 1.c3d").static_path == folder / "Cal 03.c3d"
    (folder / "subject.yaml").write_text(yaml.safe_dump({**subject, "trials": "Slow *.c3d"}))
    with pytest.raises(InputError, match="subject.yaml: trials: 'Slow \\*.c3d' matches no file in"):
        session_walks(folder)
    (folder / "subject.yaml").write_text(yaml.safe_dump({**subject, "trials": "../*.c3d"}))
    with pytest.raises(InputError, match="trials: got '../\\*.c3d' \\(expected a file name or glob inside"):
        session_walks(folder)
    _error(_with(trials=[3]), "s/subject.yaml")


@pytest.mark.parametrize(("names", "static", "match"), [
    (["Static 01.c3d", "Static 02.c3d", "Walking 01.c3d"], None, "static: 2 static trials: 'Static 01.c3d', "
                                                                  "'Static 02.c3d' \\(expected one, or `static:`"),
    (["Cal 1.c3d", "Cal 2.c3d", "Walking 01.c3d"], "Cal*.c3d", "static: 'Cal\\*.c3d' matches 2 files"),
    (["Walking 01.c3d"], "Cal*.c3d", "static: 'Cal\\*.c3d' matches 0 files \\(expected one\\)"),
])
def test_a_static_must_be_one(tmp_path, names, static, match):
    folder = _session(tmp_path, names, {**BASE, "static": static} if static else None)
    with pytest.raises(InputError, match=match):
        open_trial(folder / "Walking 01.c3d")


def test_two_statics_one_named(tmp_path):
    folder = _session(tmp_path, ["Static 01.c3d", "Static 02.c3d", "Walking 01.c3d"],
                      {**BASE, "static": "Static 02.c3d"})
    assert open_trial(folder / "Walking 01.c3d").static_path == folder / "Static 02.c3d"


def test_an_emg_map_names_each_channels_muscle_and_side():
    s = subject_from_dict(_with(emg={"RTIBA": "tibialis_anterior_r", "EMG 4": " Soleus_L "}))
    assert s.emg == {"RTIBA": "tibialis_anterior_r", "EMG 4": "soleus_l"}
    assert subject_from_dict(BASE).emg == {}
    for emg, field, words in (({"RTIBA": "tibialis_anterior"}, "emg.RTIBA", "expected a muscle and its side"),
                              ({"RTIBA": "deltoid_r"}, "emg.RTIBA", "expected a muscle and its side"),
                              (["RTIBA"], "emg", "expected a mapping of EMG channel label")):
        err = _error(_with(emg=emg))
        assert err.field == field and words in str(err)
