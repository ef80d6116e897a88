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
                                                                "events.csv", "plates.csv"}
