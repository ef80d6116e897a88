"""A Plug-in Gait session as Nexus leaves it (issue 34, item 5): ../shared/data/pig's static, processed in Nexus
(it holds Plug-in Gait's bone points: RFEO/LFEO, the knee centres, and RTIO/LTIO, the ankle centres, beside
PELO, RFOO …), with its walk written again without any of those points, as a raw walk would come.

Before: the static's knee and ankle centres were tracking points of thighs, shanks and feet the walk never shows,
so all six leg segments were NaN in all 323 frames, exit 0. Now the tool's own centres stand in, a warning and a
note in summary.json say so, and every coordinate is finite.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd
import pytest

from gaitcli.io.c3d_write import writable_text_parameters

from .conftest import Result, build_once, gait

pytestmark = pytest.mark.shared

#: Plug-in Gait's bone points (origin, anterior, lateral, proximal of each segment), as Nexus writes them
BONES = ("PEL", "HED", "TRX") + tuple(f"{s}{b}" for s in "LR" for b in ("FE", "TI", "FO", "TO", "CL", "HU", "RA", "HN"))


def _without_bone_points(source: Path, target: Path) -> None:
    """``source`` written to ``target`` without the bone points (a raw walk's labels)."""
    c = ezc3d.c3d(str(source), extract_forceplat_data=False)
    writable_text_parameters(c, source)
    labels = list(c["parameters"]["POINT"]["LABELS"]["value"])
    keep = [i for i, lab in enumerate(labels) if not (len(lab) == 4 and lab[:3] in BONES and lab[3] in "OALP")]
    c["data"]["points"] = c["data"]["points"][:, keep]
    for key in ("residuals", "camera_masks"):
        c["data"]["meta_points"][key] = c["data"]["meta_points"][key][:, keep]
    point = c["parameters"]["POINT"]
    descriptions = list(point["DESCRIPTIONS"]["value"]) + [""] * len(labels)
    point["LABELS"]["value"] = [labels[i] for i in keep]
    point["DESCRIPTIONS"]["value"] = [descriptions[i] for i in keep]
    point["USED"]["value"] = np.array([len(keep)])
    c.write(str(target))


def _build(pig: Path, root: Path) -> dict:
    folder = root / "raw_walk"
    folder.mkdir()
    _without_bone_points(pig / "Movement_trial.c3d", folder / "trial.c3d")
    shutil.copy(pig / "Static_trial.c3d", folder / "static.c3d")
    shutil.copy(pig / "Test.vsk", folder / "Test.vsk")
    return gait("idyn", "--no-plots", folder, cwd=root).to_json()


@pytest.fixture(scope="module")
def raw_walk(shared_pig_dir, tmp_path_factory):
    root, record = build_once(tmp_path_factory, "cli_nexus_raw_walk", lambda root: _build(shared_pig_dir, root))
    return root / "raw_walk", Result.from_json(record)


def test_a_nexus_static_with_a_raw_walk_tracks_every_leg_segment(raw_walk):
    folder, result = raw_walk
    assert result.returncode == 0, result.describe()
    assert "FEO" not in "".join(ezc3d.c3d(str(folder / "trial.c3d"))["parameters"]["POINT"]["LABELS"]["value"])
    warned = [line for line in result.stderr_lines if "virtual joint centres in the static trial" in line]
    assert warned == ["gait: warning: virtual joint centres in the static trial but not in the walking trial: "
                      "KJCr (RKJC or RFEO), KJCl (LKJC or LFEO), AJCr (RAJC or RTIO), AJCl (LAJC or LTIO); the "
                      "tool's own KJCr, KJCl, AJCr, AJCl replace them in the calibration"], result.stderr
    assert not [line for line in result.stderr_lines if "misses a tracking marker" in line], result.stderr
    coordinates = pd.read_csv(folder / "gait_out" / "idyn" / "coordinates.csv")
    assert len(coordinates) == 323 and np.isfinite(coordinates.to_numpy()).all()
    notes = json.loads((folder / "gait_out" / "idyn" / "summary.json").read_text())["notes"]
    assert warned[0].removeprefix("gait: warning: ") in notes
    for centre in ("KJCr", "KJCl", "AJCr", "AJCl"):  # one source each: the chord method's
        said = [n for n in notes if n.startswith(f"{centre}:")]
        assert said == [f"{centre}: estimated", f"{centre}: Plug-in Gait's chord method (no medial marker)"], said
