"""``gait idyn`` and ``gait run`` as commands: every sample trial, an exact synthetic trial, bad inputs.

All invocations run once per module, several processes at a time, on copies under tmp_path:

* ``gait idyn`` on a copy of each of the five bundled sample trials (files, columns, summary.json,
  Table 3.1 features against truth/, the ski boot's mass in idyn.h5, the noisy-trial tolerance);
* ``gait synth --noise-mm 0 --artefact-mm 0 --plate-noise-n 0`` then ``gait run`` with a pipeline
  that turns filtering off (filter then idyn; coordinates, moments and residuals against truth);
* ``gait idyn`` on a trial whose two thigh_r markers drop out for 20 frames (NaN and a warning);
* ``gait idyn`` on a trial whose static trial lacks LEFr (exit 2 naming the marker).

Exact trial, measured (normal, seed 0): coordinates 0.01 mm (the CSVs' 6 significant digits) and
0.0004°; leg moments ≤ 0.09 % of each moment's peak in the frames where that foot's load is known;
lumbar moments 0.27, 0.08, 0.03 N·m (0.8 %, 1.8 %, 4.6 % of peak); pelvis residuals 0.53 N and
0.16 N·m in the frames where every contact is measured. The lumbar moments are small and depend on
the HAT's accelerations alone, and C3D stores coordinates as float32 (0.1 µm steps at 2 m), which
the unsmoothed second derivative amplifies: the same trial in float64 gives 0.001 N·m
(tests/dynamics/test_stage.py). Hence the asserted tolerance: 0.5 % of peak for the 18 leg
moments, and for the lumbar moments 0.5 % of peak or 0.5 N·m, whichever is larger. The first and
last two frames are left out (spline end conditions; frame 0: hip 0.47 % of peak).

The exact pipeline also sets ``force_threshold_N: 1``: with the default 20 N threshold the filter
stage sets the plate load to zero until it exceeds 20 N, and the frames between the true heel strike
and that crossing count as swing, so the residual there is the dropped load (8.7 N at the right
heel strike, 3.0 N at the left toe off) — reported, not hidden, but not the < 1 N the exact data allow.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import h5py
import numpy as np
import pandas as pd
import pytest

from gaitcli.core.recording import Markers
from gaitcli.errors import GaitWarning
from gaitcli.io.c3d import read_c3d
from gaitcli.io.c3d_write import write_c3d
from gaitcli.kinematics.anatomical import ANATOMICAL_ANGLES
from gaitcli.kinematics.conventions import PIG_MOMENTS
from gaitcli.kinematics.model import BODIES, COORDINATES, JOINTS, MOMENTS, RESIDUALS

from .conftest import SAMPLES, Result, build_once, copy_sample, gait, gait_many

IDYN_FILES = ("kinematics.csv", "coordinates.csv", "joint_moments.csv", "joint_powers.csv", "residuals.csv",
              "sagittal.csv", "gait_cycle.csv", "idyn.h5", "summary.json")
TABLE_3_1 = ("stride_length_m", "period_s", "speed_m_s", "stance_right_pct", "stance_left_pct", "double_stance_pct")
EXACT_PIPELINE = "filter: {cutoff_hz: 0, force_cutoff_hz: 0, force_threshold_N: 1.0}\n"
SKI_BOOT_KG = 2.431  # Table A.3
#: the sample subjects (sample_trials/README.md): gait synth's default subject walks normally
SAMPLE_MASS_KG = {"normal": 75.0, "ski_boot": 55.0}
#: the sample trials whose figures are drawn here: normal walking and each locked joint (the added masses' figures
#: are the normal trial's code path)
FIGURED = ("normal", "knee_orthosis", "ski_boot")
GAP = (50, 69)  # file frames (first frame 1) where GTr and MRFr are missing: longer than the 10 filled
EDGE = 2


def _drop_thigh_markers(trial: Path) -> None:
    recording = read_c3d(trial / "trial.c3d")
    m = recording.markers
    positions = m.positions_m.copy()
    for name in ("GTr", "MRFr"):
        positions[GAP[0] - m.first_frame:GAP[1] - m.first_frame + 1, m.index(name)] = np.nan
    write_c3d(trial / "trial.c3d", Markers(m.labels, positions, m.rate_hz, m.first_frame), recording.plates,
              model_to_lab=recording.lab_to_model.T)


def _drop_static_marker(trial: Path, name: str) -> None:
    with warnings.catch_warnings():  # a standing trial without plates says so
        warnings.filterwarnings("ignore", message=".*no usable force plates", category=GaitWarning)
        static = read_c3d(trial / "static.c3d", to_model_axes=False).markers
    keep = [i for i, label in enumerate(static.labels) if label != name]
    write_c3d(trial / "static.c3d", Markers(tuple(static.labels[i] for i in keep), static.positions_m[:, keep],
                                            static.rate_hz, static.first_frame), [])


def _build(root: Path) -> dict:
    """Make every trial folder, run every invocation (several at a time); return the results as JSON."""
    jobs = {name: [("idyn", copy_sample(name, root / name), *(() if name in FIGURED else ("--no-plots",)))]
            for name in SAMPLES}
    (root / "exact.yaml").write_text(EXACT_PIPELINE)
    jobs["exact"] = [("synth", root / "exact", "--seed", "0", "--noise-mm", "0", "--artefact-mm", "0",
                      "--plate-noise-n", "0"),
                     ("run", root / "exact", "--pipeline", root / "exact.yaml", "--no-plots")]
    _drop_thigh_markers(copy_sample("normal", root / "dropout"))
    jobs["dropout"] = [("idyn", root / "dropout", "--no-plots")]
    _drop_static_marker(copy_sample("normal", root / "no_lefr"), "LEFr")
    jobs["no_lefr"] = [("idyn", root / "no_lefr", "--no-plots")]
    frames = copy_sample("normal", root / "static_frames")
    (frames / "static.c3d").unlink()
    with open(frames / "subject.yaml", "a") as f:
        f.write("static_frames: [5000, 6000]\n")
    jobs["static_frames"] = [("idyn", frames, "--no-plots")]
    jobs["coordinate"] = [("idyn", copy_sample("normal", root / "coordinate"), "--angles", "posture", "--moments",
                           "coordinate", "--frames", "anatomical", "--no-plots")]

    synth, run = jobs.pop("exact")
    made = gait(*synth, cwd=root)  # the exact trial first: its `gait run` joins the others
    jobs = {"exact": [run], **jobs}
    results = gait_many({key: (commands[0], root) for key, commands in jobs.items()})
    return {key: ([made.to_json()] if key == "exact" else []) + [results[key].to_json()] for key in jobs}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Every invocation of this module, run once per session: (name → [Result, ...], root folder)."""
    root, record = build_once(tmp_path_factory, "cli_idyn", _build)
    return {key: [Result.from_json(r) for r in results] for key, results in record.items()}, root


def out_dir(root: Path, name: str) -> Path:
    return root / name / "gait_out" / "idyn"


def coordinate_moments(folder: Path) -> pd.DataFrame:
    """The 21 joint moments in the truth's convention (positive in the sense of each angle, N·m, NaN where the
    load is unknown) from idyn.h5, with the load masks, as the truth's joint_moments.csv names them."""
    with h5py.File(folder / "idyn.h5", "r") as h5:
        values = h5["joint_moments_clinical"][()]
        known = h5["joint_moments_known"][()].astype(bool)
        time_s = h5["time"][()]
    values = np.where(np.repeat(known, 3, axis=1), values, np.nan)
    table = pd.DataFrame(values, columns=list(MOMENTS))
    table.insert(0, "time_s", time_s)
    legs = pd.read_csv(folder / "joint_moments.csv")
    table["right_foot_load_known"] = legs["right_foot_load_known"]
    table["left_foot_load_known"] = legs["left_foot_load_known"]
    for side in ("r", "l"):  # the load known, outside the filter's edge frames
        table[f"leg_{side}_moment_known"] = known[:, JOINTS.index(f"hip_{side}")]
    return table


def truth_features(trial: Path, threshold_N: float = 20.0) -> dict:
    """Table 3.1 from the synthetic trial's truth: the period from its events, the speed from the pelvis's
    forward motion, stance where the true vertical force exceeds the plates' threshold (the predicted walk
    loads the heel gently: 20 N takes 2 % of the cycle after the kinematic heel strike)."""
    events = pd.read_csv(trial / "truth" / "events.csv")
    kin = pd.read_csv(trial / "truth" / "kinematics.csv")
    grf = pd.read_csv(trial / "truth" / "grf.csv")
    strikes = {s: np.sort(events.time_s[(events.side == s) & (events.event == "heel_strike")].to_numpy()) for s in "rl"}
    period = float(np.mean(np.concatenate([np.diff(strikes[s]) for s in "rl"])))
    speed = float(np.polyfit(kin.time_s, kin.pelvis_x, 1)[0])
    stance = {}
    for s in "rl":
        loaded = grf[f"foot_{s}_force_z_N"].to_numpy() > threshold_N
        edges = np.diff(loaded.astype(int))
        on, off = grf.time_s.to_numpy()[1:][edges == 1], grf.time_s.to_numpy()[1:][edges == -1]
        stance[s] = float(np.mean([off[off > a][0] - a for a in on if (off > a).any()])) / period * 100
    return {"period_s": period, "speed_m_s": speed, "stride_length_m": speed * period,
            "stance_right_pct": stance["r"], "stance_left_pct": stance["l"],
            "double_stance_pct": stance["r"] + stance["l"] - 100}


@pytest.mark.parametrize("name", SAMPLES)
def test_idyn_on_every_sample_trial_writes_the_design_files(runs, name):
    results, root = runs
    (result,) = results[name]
    assert result.returncode == 0, result.describe()
    folder = out_dir(root, name)
    for file in IDYN_FILES:
        assert (folder / file).is_file(), f"{file} missing\n{result.describe()}"
    if name in FIGURED:
        plots = list((folder / "plots").iterdir())
        assert plots and all(p.suffix == ".png" and p.stat().st_size > 1000 for p in plots)
    assert list(pd.read_csv(folder / "kinematics.csv").columns) == ["time_s", *ANATOMICAL_ANGLES]
    kin = pd.read_csv(folder / "coordinates.csv")
    assert list(kin.columns) == ["time_s", *COORDINATES]
    moments = pd.read_csv(folder / "joint_moments.csv")
    assert list(moments.columns) == ["time_s", *PIG_MOMENTS, *(f"{m}_per_kg" for m in PIG_MOMENTS),
                                     "right_foot_load_known", "left_foot_load_known"]
    residuals = pd.read_csv(folder / "residuals.csv")
    assert list(residuals.columns) == ["time_s", *(f"{r}_{u}" for r, u in zip(RESIDUALS, ["N"] * 3 + ["Nm"] * 3)),
                                       "all_contacts_measured"]
    assert pd.read_csv(folder / "sagittal.csv").columns[0] == "time_s"
    assert pd.read_csv(folder / "gait_cycle.csv").columns[0] == "cycle_pct"
    assert len(kin) == len(moments) == len(residuals)
    assert np.isfinite(kin[list(COORDINATES)].to_numpy()).all()
    with h5py.File(folder / "idyn.h5", "r") as h5:
        for key in ("gaitcli_version", "config_yaml", "input_sha256", "created_utc"):
            assert key in h5.attrs
        datasets = []
        h5.visititems(lambda n, o: datasets.append(o) if isinstance(o, h5py.Dataset) else None)
        assert datasets and all("units" in d.attrs for d in datasets)


@pytest.mark.parametrize("name", SAMPLES)
def test_summary_holds_table_3_1_and_honest_residuals(runs, name):
    results, root = runs
    assert results[name][0].returncode == 0, results[name][0].describe()
    folder = out_dir(root, name)
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["dof"] == 27
    assert summary["frames"] == len(pd.read_csv(folder / "kinematics.csv"))
    assert all(isinstance(summary[key], float) and np.isfinite(summary[key]) for key in TABLE_3_1)
    truth = truth_features(root / name)
    # plate events are within a frame of the truth's 20 N crossings
    assert summary["period_s"] == pytest.approx(truth["period_s"], rel=0.01)
    assert summary["stride_length_m"] == pytest.approx(truth["stride_length_m"], rel=0.01)
    assert summary["speed_m_s"] == pytest.approx(truth["speed_m_s"], rel=0.01)
    for key in ("stance_right_pct", "stance_left_pct"):
        assert summary[key] == pytest.approx(truth[key], abs=2.0), key
    assert summary["double_stance_pct"] == pytest.approx(truth["double_stance_pct"], abs=3.0)
    # the residual RMS is the one over the rows residuals.csv marks as all contacts measured
    residuals = pd.read_csv(folder / "residuals.csv")
    measured = residuals["all_contacts_measured"].to_numpy() == 1
    assert measured.sum() == summary["residual_frames"] > 50
    force = residuals[[f"{r}_N" for r in RESIDUALS[:3]]].to_numpy()[measured]
    moment = residuals[[f"{r}_Nm" for r in RESIDUALS[3:]]].to_numpy()[measured]
    assert summary["rms_residual_force_N"] == pytest.approx(np.sqrt(np.mean(np.sum(force ** 2, axis=1))), rel=1e-4)
    assert summary["rms_residual_moment_Nm"] == pytest.approx(np.sqrt(np.mean(np.sum(moment ** 2, axis=1))),
                                                              rel=1e-4)


def test_noisy_sample_trial_moments_within_tolerance(runs):
    # sample_trials/normal is `gait synth --seed 1` (the default 75 kg subject's predicted walk, 1.07 s cycle)
    # with the default 1 mm noise and 10 mm artefact; issue 3 asks < 0.1 N·m/kg. The normative walk with 2 mm
    # noise, seeds 0–9: tests/dynamics/test_stage.py.
    results, root = runs
    assert results["normal"][0].returncode == 0
    moments = coordinate_moments(out_dir(root, "normal"))
    truth = pd.read_csv(root / "normal" / "truth" / "joint_moments.csv")
    bound = {"hip": 0.1, "knee": 0.1, "ankle": 0.1}
    edge = json.loads((out_dir(root, "normal") / "summary.json").read_text())["filter_edge_frames"]
    assert edge == 5  # 6 Hz at 100 Hz: signal/butterworth.edge_frames
    for side, column in (("r", "right_foot_load_known"), ("l", "left_foot_load_known")):
        known = moments[f"leg_{side}_moment_known"].to_numpy()
        inside = np.zeros(known.size, bool)
        inside[edge:-edge] = True
        np.testing.assert_array_equal(known, (moments[column].to_numpy() == 1) & inside)
        for joint in ("hip", "knee", "ankle"):
            name = f"{joint}_{side}_flexion_moment"
            error = (moments[name] - truth[name]).to_numpy()[known] / SAMPLE_MASS_KG["normal"]
            assert np.sqrt(np.mean(error ** 2)) < bound[joint], name


def test_disturbance_mass_is_in_the_segment_parameters(runs):
    results, root = runs
    masses = {}
    for name in ("ski_boot", "normal"):
        assert results[name][0].returncode == 0
        with h5py.File(out_dir(root, name) / "idyn.h5", "r") as h5:
            names = [n.decode() if isinstance(n, bytes) else str(n) for n in h5["segments/names"][()]]
            assert names == list(BODIES)
            masses[name] = dict(zip(names, h5["segments/mass"][()]))
            assert h5["segments/mass"].attrs["units"] == "kg"
            assert h5["segments/mass"].attrs["body_mass_kg"] == pytest.approx(SAMPLE_MASS_KG[name])
    boot = masses["ski_boot"]
    assert boot["foot_r"] - boot["foot_l"] == pytest.approx(SKI_BOOT_KG, abs=1e-9)
    assert sum(boot.values()) == pytest.approx(SAMPLE_MASS_KG["ski_boot"] + SKI_BOOT_KG, abs=1e-9)
    assert sum(masses["normal"].values()) == pytest.approx(SAMPLE_MASS_KG["normal"], abs=1e-9)
    assert masses["normal"]["foot_r"] == pytest.approx(masses["normal"]["foot_l"], abs=1e-12)


# --- gait run on the exact synthetic trial -------------------------------------------------------
@pytest.fixture(scope="module")
def exact(runs):
    results, root = runs
    synth, run = results["exact"]
    assert synth.returncode == 0, synth.describe()
    assert run.returncode == 0, run.describe()
    return run, root / "exact"


def test_run_does_filter_then_idyn(exact):
    run, trial = exact
    lines = run.stderr_lines
    filter_line = next(i for i, line in enumerate(lines) if line.startswith("filter: ") and "wrote" in line)
    idyn_line = next(i for i, line in enumerate(lines) if line.startswith("idyn: ") and "wrote" in line)
    assert filter_line < idyn_line
    assert json.loads((trial / "gait_out" / "filter" / "summary.json").read_text())["cutoff_hz"] == 0
    with h5py.File(trial / "gait_out" / "filter" / "filter.h5", "r") as f, \
            h5py.File(trial / "gait_out" / "idyn" / "idyn.h5", "r") as i:
        assert f.attrs["input_sha256"] == i.attrs["input_sha256"]
        assert f.attrs["config_yaml"] == i.attrs["config_yaml"]
    for file in IDYN_FILES:
        assert (trial / "gait_out" / "idyn" / file).is_file()


def test_exact_trial_coordinates(exact):
    _, trial = exact
    got = pd.read_csv(trial / "gait_out" / "idyn" / "coordinates.csv")
    want = pd.read_csv(trial / "truth" / "kinematics.csv")
    np.testing.assert_allclose(got.time_s, want.time_s, atol=1e-9)
    positions, angles = list(COORDINATES[:3]), list(COORDINATES[3:])
    assert np.abs(got[positions] - want[positions]).to_numpy().max() < 1e-4  # 0.1 mm
    assert np.abs(got[angles] - want[angles]).to_numpy().max() < 0.1  # degrees


def test_exact_trial_moments(exact):
    _, trial = exact
    got = coordinate_moments(trial / "gait_out" / "idyn")
    want = pd.read_csv(trial / "truth" / "joint_moments.csv")
    inner = np.zeros(len(got), dtype=bool)
    inner[EDGE:-EDGE] = True
    known = {"r": got["right_foot_load_known"].to_numpy() == 1, "l": got["left_foot_load_known"].to_numpy() == 1}
    assert known["r"].sum() > 0.4 * len(got) and known["l"].sum() > 0.4 * len(got)
    failures = []
    for name in MOMENTS:
        side = name.split("_")[1]
        rows = inner & known[side] if side in known else inner  # lumbar: no foot involved
        error = np.abs(got[name] - want[name]).to_numpy()[rows].max()
        peak = np.abs(want[name]).to_numpy()[rows].max()
        limit = 0.005 * peak if side in known else max(0.005 * peak, 0.5)
        if not error <= limit:
            failures.append(f"{name}: {error:.4f} N·m of peak {peak:.2f}")
    assert not failures, failures


def test_exact_trial_residuals(exact):
    _, trial = exact
    residuals = pd.read_csv(trial / "gait_out" / "idyn" / "residuals.csv")
    measured = residuals["all_contacts_measured"].to_numpy() == 1
    assert measured.sum() > 50
    assert np.abs(residuals[[f"{r}_N" for r in RESIDUALS[:3]]].to_numpy()[measured]).max() < 1.0
    assert np.abs(residuals[[f"{r}_Nm" for r in RESIDUALS[3:]]].to_numpy()[measured]).max() < 1.0


def test_unknown_loads_are_nan_in_the_tables_and_a_mask_in_the_hdf5(exact):
    """A leg's moments are NaN exactly where its foot's load is unknown, the residuals where any foot's is; the
    lumbar moment (no foot below it) stays; idyn.h5 keeps every value and the mask."""
    _, trial = exact
    out = trial / "gait_out" / "idyn"
    moments, residuals = pd.read_csv(out / "joint_moments.csv"), pd.read_csv(out / "residuals.csv")
    for side, column in (("r", "right_foot_load_known"), ("l", "left_foot_load_known")):
        known = moments[column].to_numpy() == 1
        assert 0 < known.sum() < known.size
        leg = moments[[c for c in moments.columns if c.split("_")[1:2] == [side]]].to_numpy()
        assert leg.shape[1] == 18  # hip, knee, ankle × 3 axes × N·m and N·m/kg
        assert np.isfinite(leg[known]).all() and np.isnan(leg[~known]).all()
    assert np.isfinite(moments[[c for c in moments.columns if c.startswith("lumbar")]].to_numpy()).all()
    measured = residuals["all_contacts_measured"].to_numpy() == 1
    values = residuals.drop(columns=["time_s", "all_contacts_measured"]).to_numpy()
    assert np.isfinite(values[measured]).all() and np.isnan(values[~measured]).all()
    with h5py.File(out / "idyn.h5", "r") as h5:
        assert np.isfinite(h5["joint_moments_clinical"][()]).all()
        mask = h5["joint_moments_known"][()]
    np.testing.assert_array_equal(mask[:, 1], moments["right_foot_load_known"])
    np.testing.assert_array_equal(mask[:, 6], moments["left_foot_load_known"])
    assert (mask[:, 0] == 1).all()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["hat_tracked"] is True


# --- bad input ------------------------------------------------------------------------------------
def test_missing_thigh_markers_give_nan_frames_and_a_warning(runs):
    results, root = runs
    (result,) = results["dropout"]
    assert result.returncode == 0, result.describe()
    assert "Traceback" not in result.stderr
    warning = [line for line in result.stderr_lines if "thigh_r" in line and "misses a tracking marker" in line]
    expected = (f"gait: warning: segment thigh_r misses a tracking marker in frames {GAP[0]}–{GAP[1]}: the pose, "
                "coordinates and moments there are NaN")
    assert warning == [expected], result.stderr
    folder = out_dir(root, "dropout")
    kin = pd.read_csv(folder / "coordinates.csv")
    moments = coordinate_moments(folder)
    gap = np.zeros(len(kin), dtype=bool)
    gap[GAP[0] - 1:GAP[1]] = True  # rows are 0-based, file frames start at 1
    thigh = [f"{j}_r_{a}" for j in ("hip", "knee") for a in ("flexion", "adduction", "rotation")]
    assert kin[thigh].to_numpy()[gap].size and np.isnan(kin[thigh].to_numpy()[gap]).all()
    assert np.isfinite(kin[list(COORDINATES)].to_numpy()[~gap]).all()
    assert np.isnan(moments[list(MOMENTS)].to_numpy()[gap]).all()
    edge = json.loads((folder / "summary.json").read_text())["filter_edge_frames"]
    ends = np.zeros(len(kin), dtype=bool)  # the filter's edge frames at the trial's ends
    ends[:edge] = ends[-edge:] = True
    beside = np.zeros(len(kin), dtype=bool)  # and at the ends of the right thigh's tracked runs, beside the gap
    beside[GAP[0] - 1 - edge:GAP[0] - 1] = beside[GAP[1]:GAP[1] + edge] = True
    assert np.isnan(moments[list(MOMENTS)].to_numpy()[ends | beside]).all()
    for side, column in (("r", "right_foot_load_known"), ("l", "left_foot_load_known")):
        leg = [m for m in MOMENTS if m.split("_")[1] == side]  # NaN elsewhere only where the foot's load is unknown
        known = moments[column].to_numpy() == 1
        assert np.isfinite(moments[leg].to_numpy()[~gap & ~ends & ~beside & known]).all()
    # frames outside the gap agree with the complete sample trial's
    complete = pd.read_csv(out_dir(root, "normal") / "coordinates.csv")
    away = ~gap
    away[GAP[0] - 1 - 10:GAP[1] + 10] = False  # the filter's and the spline's reach around the gap
    np.testing.assert_allclose(kin[thigh].to_numpy()[away], complete[thigh].to_numpy()[away], atol=0.05)


def test_static_trial_missing_a_model_marker_is_exit_2(runs):
    results, root = runs
    (result,) = results["no_lefr"]
    assert result.returncode == 2, result.describe()
    assert "Traceback" not in result.stderr
    errors = [line for line in result.stderr_lines if line.startswith("gait: error:")]
    assert len(errors) == 1 and "static.c3d" in errors[0] and "LEFr" in errors[0], result.stderr
    assert not (root / "no_lefr" / "gait_out" / "idyn").exists()


def test_static_frames_out_of_range_is_exit_2_before_anything_is_written(runs):
    """Found once after the filter's outputs had been written (issue 9): now every stage is computed first."""
    results, root = runs
    (result,) = results["static_frames"]
    assert result.returncode == 2, result.describe()
    assert len(result.stderr_lines) == 1 and "static_frames" in result.stderr and "1–428" in result.stderr, \
        result.stderr
    assert not (root / "static_frames" / "gait_out").exists()


def test_the_coordinates_and_their_moments_by_option(runs):
    """``--angles posture --moments coordinate --frames anatomical``: kinematics.csv holds the 27 coordinates
    (coordinates.csv of the default run), joint_moments.csv each moment in its angle's sense; in the anatomical
    frames (the ISB ones of this marker set) that is Plug-in Gait's moment with the opposite sign."""
    results, root = runs
    (run,) = results["coordinate"]
    assert run.returncode == 0, run.describe()
    default, option = out_dir(root, "normal"), out_dir(root, "coordinate")
    pd.testing.assert_frame_equal(pd.read_csv(option / "kinematics.csv"), pd.read_csv(default / "coordinates.csv"))
    ours, pig = pd.read_csv(option / "joint_moments.csv"), pd.read_csv(default / "joint_moments.csv")
    senses = {"flexion": ("extensor", "plantarflexor"), "adduction": ("abductor", "everter"),
              "rotation": ("external_rotator",)}
    compared = 0
    for column in ours.columns:
        joint, side, axis, *_ = (column.split("_") + [""] * 3)[:4]
        if joint not in ("hip", "knee", "ankle") or not column.endswith("_moment_per_kg"):
            continue
        sense = senses[axis][1] if joint == "ankle" and axis in ("flexion", "adduction") else senses[axis][0]
        theirs = pig[f"{joint}_{side}_{sense}_moment_per_kg"].to_numpy()
        np.testing.assert_allclose(ours[column].to_numpy(), -theirs, rtol=1e-5, atol=1e-6, err_msg=column)
        compared += 1
    assert compared == 18



def test_the_sagittal_figure_draws_the_powers_of_gait_cycle_csv(runs):
    """cycle.png's third row: each joint's total power (W/kg) over the cycle, the mean of the side's strides — the
    same curve as the mean of gait_cycle.csv's ``<joint>_<side>_power_W_per_kg`` strides."""
    from gaitcli.report.plots import cycle_figure

    _, root = runs
    folder = out_dir(root, "normal")
    figure = cycle_figure(folder / "idyn.h5", "sagittal")
    axes = np.array(figure.axes).reshape(3, 3)
    cycles = pd.read_csv(folder / "gait_cycle.csv")
    for col, joint in enumerate(("hip", "knee", "ankle")):
        assert "power" in axes[2, col].get_ylabel()
        right = cycles[cycles.side == "r"]
        expected = right.groupby("cycle_pct")[f"{joint}_r_power_W_per_kg"].mean().to_numpy()
        drawn = next(line for line in axes[2, col].get_lines() if line.get_label().startswith("right"))
        np.testing.assert_allclose(drawn.get_ydata(), expected, rtol=1e-5, atol=1e-4)
    assert len(cycle_figure(folder / "idyn.h5", "frontal").axes) == 6  # no power row in the frontal plane
