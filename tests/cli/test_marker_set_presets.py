"""Synthetic clinical trials with only ``marker_set:`` in subject.yaml (``gait synth --marker-set``), and a
preset's missing marker: exit 2, one line naming the preset, the lab label and what the marker is for.

The Plug-in Gait trial carries its knee and ankle widths and marker diameter only in the C3D's PROCESSING group
(as Vicon writes them), so the chord method reads them from there.
"""

from __future__ import annotations

import json
import shutil
import warnings
from pathlib import Path

import pytest

from gaitcli.io.c3d import read_c3d
from gaitcli.io.c3d_write import write_c3d

from .conftest import Result, build_once, gait_many

#: (preset, label removed from static.c3d, what the one-line error must say besides preset and label)
MISSING = {
    "pig_thigh_wand": ("plug_in_gait", "RTHI", "tracking the right thigh"),
    "pig_toe": ("plug_in_gait", "RTOE", "right second metatarsal head (toe marker), MT2r; needed for the foot"),
    "pig_knee": ("plug_in_gait", "LKNE", "left lateral femoral epicondyle, LEFl; needed for the knee joint centre"),
    "cleveland_medial_ankle": ("cleveland", "RMMAL", "right medial malleolus, MMr; needed for the ankle joint centre"),
    "cast_heel": ("cast", "L_FCC", "left posterior calcaneus, CAl; needed for the foot"),
}


def _without(folder: Path, label: str | None, *, metadata: bool = True) -> None:
    """Rewrite folder's static.c3d (and, without metadata, trial.c3d) without ``label`` / the PROCESSING group."""
    for name in ("static.c3d",) if metadata else ("static.c3d", "trial.c3d"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the static trial has no plates
            rec = read_c3d(folder / name)
        markers = rec.markers
        if label is not None:
            keep = [k for k, lab in enumerate(markers.labels) if lab != label]
            markers = type(markers)(tuple(markers.labels[k] for k in keep), markers.positions_m[:, keep],
                                    markers.rate_hz, markers.first_frame)
        write_c3d(folder / name, markers, rec.plates, metadata=rec.subject_metadata if metadata else None)


def _build(root: Path) -> dict:
    synth = {name: (("synth", root / name, "--marker-set", name, "--seed", "3"), root)
             for name in ("plug_in_gait", "cleveland", "cast")}
    made = gait_many(synth)
    for r in made.values():
        assert r.returncode == 0, r.describe()
    cases = {**{case: (preset, label, True) for case, (preset, label, _) in MISSING.items()},
             "pig_no_widths": ("plug_in_gait", None, False)}
    for case, (preset, label, metadata) in cases.items():
        shutil.copytree(root / preset, root / case)
        _without(root / case, label, metadata=metadata)
    # idyn runs the filter stage itself (its outputs are missing); figures are not what is tested here
    idyn = gait_many({name: (("idyn", root / name, "--no-plots"), root) for name in (*synth, *cases)})
    return {"idyn": {k: r.to_json() for k, r in idyn.items()}}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root, record = build_once(tmp_path_factory, "cli_marker_set_presets", _build)
    return root, {k: Result.from_json(v) for k, v in record["idyn"].items()}


@pytest.mark.parametrize("preset", ["plug_in_gait", "cleveland", "cast"])
def test_a_synthetic_trial_runs_with_only_its_marker_set(runs, preset):
    root, idyn = runs
    assert idyn[preset].returncode == 0, idyn[preset].describe()
    summary = json.loads((root / preset / "gait_out" / "idyn" / "summary.json").read_text())
    assert summary["marker_set"] == preset and summary["locked_segments"] == []
    if preset == "plug_in_gait":
        chords = [n for n in summary["notes"] if "chord method" in n]
        assert len(chords) == 4, summary["notes"]  # both knees and ankles, widths from PROCESSING
        assert "foot_r: tracked by CAr, MT2r and the AJCr placed by the parent's pose" in summary["notes"]


@pytest.mark.parametrize("case", sorted(MISSING))
def test_a_missing_preset_marker_exits_2_naming_preset_label_and_role(runs, case):
    root, idyn = runs
    preset, label, role = MISSING[case]
    r = idyn[case]
    assert r.returncode == 2, r.describe()
    assert len(r.stderr_lines) == 1 and "Traceback" not in r.stderr, r.stderr
    line = r.stderr_lines[0]
    assert f"static.c3d: {label}: marker missing from the static trial: {label}" in line, line
    assert f"(marker_set {preset}: " in line and role in line, line
    assert not (root / case / "gait_out" / "idyn").exists()


def test_without_widths_plug_in_gait_asks_for_the_medial_marker_or_the_width(runs):
    root, idyn = runs
    r = idyn["pig_no_widths"]
    assert r.returncode == 2 and len(r.stderr_lines) == 1, r.describe()
    line = r.stderr_lines[0]
    assert "RKNM or RMKN" in line and "knee_width_mm in subject.yaml or the C3D's PROCESSING:RightKneeWidth" in line
