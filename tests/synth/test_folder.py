"""The written trial folder (``gaitcli.synth.folder``)."""

from __future__ import annotations

import yaml

from gaitcli.synth import write_trial


def test_subject_yaml_names_the_condition_in_a_comment(tmp_path):
    write_trial(tmp_path, condition="ski_boot", strides=1, mass_kg=55.0, stature_m=1.65)
    text = (tmp_path / "subject.yaml").read_text()
    assert text.splitlines()[1] == "# condition: ski_boot (disturbed side: r)"
    data = yaml.safe_load(text)
    assert "condition" not in data and "disturbed_side" not in data
    assert [d["segment"] for d in data["disturbances"]] == ["foot_r"]
    assert {p.name for p in (tmp_path / "truth").iterdir()} == {"kinematics.csv", "joint_moments.csv", "grf.csv",
                                                                "events.csv", "plates.csv", "anatomical_angles.csv"}


def test_a_plug_in_gait_subject_has_davis_hips_and_its_true_anatomical_angles(tmp_path):
    """subject.yaml of a Plug-in Gait trial names Davis's hip centres (the subject is built on them);
    truth/anatomical_angles.csv has the columns of idyn's kinematics.csv, in degrees and its signs (the ankle
    inversion as Plug-in Gait's AnkleAngles Y: the negative of the sole turned medially)."""
    import numpy as np
    import pandas as pd

    from gaitcli.kinematics.anatomical import ANATOMICAL_ANGLES

    trial = write_trial(tmp_path, strides=1, marker_set="plug_in_gait")
    data = yaml.safe_load((tmp_path / "subject.yaml").read_text())
    assert (data["marker_set"], data["hip_joint_centre"]) == ("plug_in_gait", "davis")
    table = pd.read_csv(tmp_path / "truth" / "anatomical_angles.csv")
    assert list(table.columns) == ["time_s", *ANATOMICAL_ANGLES]
    expected = np.degrees(trial.anatomical_angles_rad)
    for side in "rl":
        expected[:, ANATOMICAL_ANGLES.index(f"ankle_{side}_inversion")] *= -1.0
    np.testing.assert_allclose(table[list(ANATOMICAL_ANGLES)].to_numpy(), expected,
                               rtol=5e-6, atol=1e-9)  # 6 significant digits
