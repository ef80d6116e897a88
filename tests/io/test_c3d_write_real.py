"""The C3D export's copy (:func:`add_points`) on every real C3D file in ``../shared/data`` that ezc3d reads:
Vicon's 22 Plug-in Gait point names added (or, in Vicon's stair trial that holds them, replaced), the units and
point lists, an EVENT group; ezc3d reads the copy back with one label per point, the added values, and the file's
own points, analog channels and text parameters (ANALOG:UNITS: the crash of issue 34 on a Nexus 2018 trial) as
they were. sgi_int.c3d is left out: ezc3d cannot read it (the reader refuses it, tests/cli/test_bad_inputs.py)."""

from __future__ import annotations

import warnings

import ezc3d
import numpy as np
import pytest

from gaitcli.core.events import Events
from gaitcli.io.c3d_write import add_points

pytestmark = pytest.mark.shared

FILES = ("c3d/walking2.c3d", "c3d/walking5.c3d", "c3d/Qualisys.c3d", "c3d/BTS.c3d", "c3d/Eb015pr.c3d",
         "c3d/Eb015pi.c3d", "c3d/dec_real.c3d", "c3d/FP_Type3.c3d", "c3d/duplicate_labels.c3d", "emg/Gait.c3d",
         "pig/Movement_trial.c3d", "pig/Static_trial.c3d")
VICON = [f"{side}{name}" for side in "RL" for name in ("PelvisAngles", "FootProgressAngles", "HipAngles",
                                                       "KneeAngles", "AnkleAngles", "HipMoment", "KneeMoment",
                                                       "AnkleMoment", "HipPower", "KneePower", "AnklePower")]


def _labels(c) -> list[str]:
    point = c["parameters"]["POINT"]
    return [lab.strip() for lab in point["LABELS"]["value"] + point.get("LABELS2", {}).get("value", [])]


@pytest.mark.parametrize("name", FILES)
def test_the_export_copy_of_every_real_file_reads_back(name, shared_c3d_dir, tmp_path):
    source = shared_c3d_dir.parent / name
    if not source.is_file():
        pytest.skip(f"../shared/data/{name} is not present")
    original = ezc3d.c3d(str(source))
    n_frames = original["data"]["points"].shape[2]
    rng = np.random.default_rng(0)
    added = {label: rng.normal(0, 100, (n_frames, 3)) for label in VICON}
    events = Events.from_times([0.0, 1.0 / 3], rate_hz=100.0, side="r", kind="heel_strike", source="plate")
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        add_points(source, tmp_path / "copy.c3d", added, descriptions={lab: "gaitcli" for lab in added},
                   parameters={"POINT:ANGLES": [lab for lab in VICON if lab.endswith("Angles")],
                               "POINT:ANGLE_UNITS": "deg", "POINT:MOMENT_UNITS": "Nmm/kg"},
                   events=events, merged=("POINT:ANGLES",))
    copy = ezc3d.c3d(str(tmp_path / "copy.c3d"))
    labels, own = _labels(copy), _labels(original)[:original["data"]["points"].shape[1]]
    held = [lab for lab in VICON if lab in own]
    assert [str(w.message).split(": its own points ")[0] for w in said if "replaced" in str(w.message)] == \
        ([source.name] if held else [])
    assert labels == own + [lab for lab in VICON if lab not in own]
    assert all(labels.count(lab) == 1 for lab in VICON)
    points = copy["data"]["points"][:3]
    for label, values in added.items():
        np.testing.assert_allclose(points[:, labels.index(label)].T, values, rtol=1e-6, atol=1e-3)  # float32
    kept = [j for j, lab in enumerate(own) if lab not in held]
    np.testing.assert_allclose(points[:, kept], original["data"]["points"][:3, kept], rtol=1e-6)  # float32 of
    # files stored as scaled integers (Gait.c3d)
    np.testing.assert_array_equal(copy["data"]["analogs"], original["data"]["analogs"])
    assert copy["parameters"]["POINT"]["ANGLE_UNITS"]["value"] == ["deg"]
    assert copy["parameters"]["EVENT"]["USED"]["value"][0] == 2
    analog, channels = original["parameters"].get("ANALOG", {}), original["data"]["analogs"].shape[1]
    for key in ("LABELS", "UNITS"):  # as many as the stored channels (the c3d.org files describe 32 of 16)
        if key in analog:
            assert copy["parameters"]["ANALOG"][key]["value"] == [v.strip() for v in analog[key]["value"]][:channels]
