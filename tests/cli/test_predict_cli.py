"""``gait predict`` as a command: bad options and files are one line and exit 2 with nothing written; an
optimization stopped early (``--max-iterations``) writes every output with ``converged: false``, exits 3 and
names the violated constraint groups; ``gait predict TRIAL`` takes that trial's subject and reference."""

from __future__ import annotations

import json
import shutil
import signal
import time

import h5py
import numpy as np
import pandas as pd
import pytest
from PIL import Image

from gaitcli.predict.model import WalkerParameters
from gaitcli.predict.reference import VARIABLES
from gaitcli.predict.speed_reference import speed_reference
from gaitcli.resources import bundled_reference
from gaitcli.run.stages import read_warm

from .conftest import Runner, copy_sample, gait_many, snapshot

#: one worker for the study on a cluster: its tasks run in one process, as a study's tasks on a busy cluster
#: often do (a runner that keeps one gaitcli.predict.solve.NlpCache per process lets them share its compiled NLPs;
#: a first IPOPT solver takes 10–20 s to build)
DASK_WORKERS = 1
PREDICT_FILES = ("motion.csv", "grf.csv", "moments.csv", "muscles.csv", "predict.h5", "summary.json")
#: the predict stage's summary.json keys (README.md's outputs table)
PREDICT_SUMMARY_KEYS = ("speed_m_s", "cost_of_transport_J_per_m", "deviation", "objective", "weights",
                        "max_moment_error_Nm", "max_contact_error_m", "min_excitation", "max_excitation",
                        "converged", "iterations", "solve_time_s")


def test_bad_options_and_files_exit_2_naming_them(tmp_path):
    (tmp_path / "ref.csv").write_text("cycle_pct,hip_r_flexion_deg_mean\n0,1\n100,1\n")
    # a foot whose spring stiffens the wrong way in dorsiflexion (b_n < 0): τ_s rises there (5.3.3)
    (tmp_path / "rising.yaml").write_text("a_p: -17090\nb_p: 1889\nc0: -281.5\na_n: 15.64\nb_n: -3000\n"
                                          "d_prosth: 1.0\n")
    (tmp_path / "walking.yaml").write_text("speeds_m_s: [1.0]\nweights: [b]\nconditions: [normal, walking]\n")
    (tmp_path / "fast.yaml").write_text("speeds_m_s: [9]\nweights: [b]\nconditions: [normal]\n")
    cases = {"odd nodes": (("--nodes", "17"), "--nodes: got 17"),
             "rising prosthesis": (("--prosthesis", "rising.yaml"), "rising.yaml: prosthesis: τ_s rises at"),
             "unknown prosthesis": (("--prosthesis", "carbon"), "--prosthesis: got 'carbon'"),
             "missing prosthesis": (("--prosthesis", "none.yaml"), "none.yaml: --prosthesis: file not found"),
             "monotone range": (("--monotone-range", "10,-5"), "--monotone-range: got '10,-5'"),
             "foot mass at": (("--foot-mass", "2", "--foot-mass-at", "1,2"), "--foot-mass-at: got '1,2'"),
             "missing study": (("--study", "none.yaml"), "none.yaml: --study: file not found"),
             "study condition": (("--study", "walking.yaml"), "walking.yaml: conditions: got 'walking'"),
             "study speed": (("--study", "fast.yaml"), "fast.yaml: speeds_m_s: got 9"),
             "weights": (("--weights", "1,2"), "--weights: got '1,2'"),
             "speed": (("--speed", "0"), "--speed"),
             "reference": (("--reference", "ref.csv"), "ref.csv: hip_r_flexion_deg_sd: missing column"),
             "init": (("--init", "none.h5"), "none.h5: --init: file not found"),
             "start": (("--start", "best"), "--start': got 'best' (expected one of walk, guess)")}
    runs = gait_many({name: (("predict", *args, "-o", "out"), tmp_path) for name, (args, _) in cases.items()})
    for name, (_, expected) in cases.items():
        run = runs[name]
        assert run.returncode == 2 and len(run.stderr_lines) == 1, run.describe()
        assert expected in run.stderr, run.describe()
    assert not (tmp_path / "out").exists()


def test_an_unconverged_prediction_writes_everything_exits_3_and_survives_sigterm(tmp_path, request,
                                                                                  stopped_prediction):
    # "default": gait predict --nodes 6 --max-iterations 2 -o pr (conftest), copied to out/
    prediction, stopped = stopped_prediction
    shutil.copytree(prediction, tmp_path / "out")
    copy_sample("normal", tmp_path / "normal")
    runner = Runner()  # this test's own: the SIGTERM below goes to it
    request.addfinalizer(runner.close)
    trial_args = ("predict", "normal", "--nodes", "6", "--no-plots")
    runs = {"default": stopped, "trial": runner.run((*trial_args, "--max-iterations", "1"), tmp_path)}
    for name, folder in (("default", tmp_path / "out" / "predict"),
                         ("trial", tmp_path / "normal" / "gait_out" / "predict")):
        run = runs[name]
        assert run.returncode == 3, run.describe()
        assert "did not converge" in run.stderr and "violated: " in run.stderr and "moment by" in run.stderr
        assert all((folder / f).is_file() for f in PREDICT_FILES), sorted(p.name for p in folder.iterdir())
        summary = json.loads((folder / "summary.json").read_text())
        assert set(PREDICT_SUMMARY_KEYS) <= set(summary) and summary["converged"] is False
        assert summary["violations"]["moment"] > 2.0  # the guess's moment error, far beyond εm = 2 N·m
        motion = pd.read_csv(folder / "motion.csv")
        assert motion.columns[0] == "time_s" and len(motion) == 112
        with h5py.File(folder / "predict.h5", "r") as h5:
            assert h5.attrs["converged"] == 0 and "result/design" in h5
            design = np.asarray(h5["result/design"][()])
        assert design.size == 11 * 5 + 3 * 3 + 5  # the full model's layout: tests/predict/test_stage.py
        warm = read_warm(folder / "predict.h5")  # what --init of this file continues from
        assert warm is not None and warm.w.size == warm.lam_x.size > design.size and warm.lam_g.size > 0
    with h5py.File(tmp_path / "older.h5", "w") as h5:  # a predict.h5 of a version that stored χ only
        h5["result/design"] = design
    assert read_warm(tmp_path / "older.h5") is None
    figures = ("angles.png", "grf.png", "moments.png", "muscles.png", "stick.png", "walk.gif")
    assert all((tmp_path / "out" / "predict" / "plots" / f).stat().st_size > 1000 for f in figures)
    with Image.open(tmp_path / "out" / "predict" / "plots" / "walk.gif") as gif:  # one frame per motion row
        assert gif.n_frames == len(pd.read_csv(tmp_path / "out" / "predict" / "motion.csv"))
    assert not (tmp_path / "normal" / "gait_out" / "predict" / "plots").exists()
    # without a trial: the shipped reference of the speed, the stride bounded by its group's ± 1 SD (written in the
    # configuration); the trial's own subject (75 kg) and reference, the stride in the box, and its idyn made
    default_summary = json.loads((tmp_path / "out" / "predict" / "summary.json").read_text())
    by_speed = speed_reference(1.1275, WalkerParameters.subject_1().leg_length_m)
    assert default_summary["reference"] == by_speed.reference.source
    assert default_summary["reference_stride_m"] == pytest.approx(by_speed.stride_m, abs=1e-4)
    assert default_summary["stride_range_m"] == pytest.approx([by_speed.stride_m - by_speed.stride_sd_m,
                                                               by_speed.stride_m + by_speed.stride_sd_m], abs=1e-4)
    with h5py.File(tmp_path / "out" / "predict" / "predict.h5", "r") as h5:
        np.testing.assert_allclose(h5["result/reference_mean"][()], by_speed.reference.arrays(VARIABLES)[0],
                                   atol=1e-9)
    trial_summary = json.loads((tmp_path / "normal" / "gait_out" / "predict" / "summary.json").read_text())
    assert trial_summary["symmetric"] is True and "reference" not in trial_summary
    assert (tmp_path / "normal" / "gait_out" / "idyn" / "idyn.h5").is_file()
    with h5py.File(tmp_path / "normal" / "gait_out" / "predict" / "predict.h5", "r") as h5:
        assert abs(float(h5["result/body_mass_kg"][()]) - 75.0) < 0.5

    # SIGTERM during the next run: "gait: interrupted", exit 130, the unconverged result above untouched
    # and no half-written folder. Without an iteration limit the run would go on for minutes. The runner keeps
    # the problem it built for the run above (its NlpCache) and reuses the trial's idyn, so 1 s on the signal
    # comes in IPOPT's iterations (each second more is a second of solving for nothing); an interrupt inside
    # IPOPT is also tests/core/test_ipopt.py's and test_interrupts.py's (EID), every solve going through
    # core/ipopt.solve.
    earlier = snapshot(tmp_path / "normal" / "gait_out")
    runner.send(trial_args, tmp_path)
    time.sleep(1.0)
    assert runner.proc.poll() is None
    runner.proc.send_signal(signal.SIGTERM)
    interrupted = runner.receive(timeout_s=60)
    assert interrupted.returncode == 130 and interrupted.stderr_lines[-1] == "gait: interrupted", \
        interrupted.describe()
    assert snapshot(tmp_path / "normal" / "gait_out") == earlier


def test_a_study_marks_unconverged_cases_exits_3_and_reuses_them_on_a_rerun(tmp_path, dask_cluster):
    # two cases stopped after one IPOPT iteration (6 nodes): both in study.csv, marked, exit 3; the rerun reads
    # both back (the same inputs and configuration). (--starts: tests/predict/test_study.py.) The normal case on a
    # Dask cluster (a task on another process) gives the same case key and objective; a prosthesis case waiting
    # for its normal case's future is the same task graph as tests/test_cluster.py's chains on Dask. --starts goes
    # to the cluster by the same run.cluster.workers: given a scheduler nobody serves, it says so before building
    # anything. (Every case here builds its problem, about 2 s each.)
    address, _ = dask_cluster
    # at the default speed: the normal case is the problem the session's stopped prediction built (conftest), which
    # a runner that made it holds (its NlpCache; the local study runs in the runner, --workers 1)
    grid = "speeds_m_s: [1.1275]\nweights: [b]\nnodes: 6\nmax_iterations: 1\n"
    (tmp_path / "tiny.yaml").write_text(f"name: tiny\nconditions: [normal, sach]\n{grid}")
    (tmp_path / "normal.yaml").write_text(f"name: normal\nconditions: [normal]\n{grid}")
    # a speed's own reference (5.3.3's Winter data per speed): the bundled one with the knees 5° more flexed
    reference = pd.read_csv(bundled_reference())
    for side in "rl":
        reference[f"knee_{side}_flexion_deg_mean"] += 5.0
    (tmp_path / "refs").mkdir()
    reference.to_csv(tmp_path / "refs" / "flexed.csv", index=False)
    (tmp_path / "own.yaml").write_text(f"name: own\nconditions: [normal]\n{grid}references:\n  1.1275: "
                                       "refs/flexed.csv\n")
    jobs = {"study": (("predict", "--study", "tiny.yaml", "-o", "out", "--workers", "1"), tmp_path)}
    runs = gait_many({**jobs, "dask": (("predict", "--study", "normal.yaml", "-o", "dask", "--scheduler", address),
                                       tmp_path),
                      "own": (("predict", "--study", "own.yaml", "-o", "own", "--workers", "1"), tmp_path),
                      "starts": (("predict", "--nodes", "6", "--starts", "2", "-o", "starts",
                                  "--scheduler", "tcp://127.0.0.1:1"), tmp_path)}, workers=3)
    assert runs["dask"].returncode == 3, runs["dask"].describe()
    starts = runs["starts"]
    assert starts.returncode == 2 and len(starts.stderr_lines) == 1, starts.describe()
    assert "--scheduler: cannot reach the Dask scheduler at tcp://127.0.0.1:1" in starts.stderr
    assert not (tmp_path / "starts").exists()
    on_cluster = pd.read_csv(tmp_path / "dask" / "study" / "study.csv")
    keys = [json.loads((tmp_path / name / "study" / "v1.13_b_normal" / "summary.json").read_text())["case_key"]
            for name in ("out", "dask")]
    assert keys[0] == keys[1]
    own = tmp_path / "own" / "study" / "v1.13_b_normal"
    assert json.loads((own / "summary.json").read_text())["case_key"] != keys[0], runs["own"].describe()
    with h5py.File(own / "predict.h5", "r") as h5:
        tracked = h5["result/reference_mean"][()]
    knee = [f"knee_{side}_flexion_deg" for side in "rl"]
    np.testing.assert_allclose(tracked[:, [VARIABLES.index(k) for k in knee]],
                               reference[[f"{k}_mean" for k in knee]].to_numpy(), atol=1e-6)
    run = runs["study"]
    assert run.returncode == 3 and "2 of 2 study cases did not converge" in run.stderr, run.describe()
    study = tmp_path / "out" / "study"
    table = pd.read_csv(study / "study.csv")
    assert list(table["condition"]) == ["normal", "sach"] and not table["converged"].any()
    assert not table["reused"].any() and (table["iterations"] == 1).all()
    # what each case's solve built, with its time (a problem its runner already held is no build)
    assert (table["build_time_s"][table["problems_built"] > 0] > 0).all() and (table["build_time_s"] >= 0).all()
    first = table["objective"].to_numpy()
    np.testing.assert_allclose(on_cluster["objective"], first[:1], rtol=1e-9)
    assert (study / "study.png").stat().st_size > 1000
    sach = json.loads((study / "v1.13_b_sach" / "summary.json").read_text())
    assert sach["prosthesis"]["name"] == "SACH" and sach["strength_scale"] == 1.5
    assert (study / "v1.13_b_sach" / "prosthesis.csv").is_file()
    before = snapshot(study / "v1.13_b_sach")
    again = gait_many({"study": jobs["study"]}, workers=1)["study"]
    assert again.returncode == 3, again.describe()
    table = pd.read_csv(study / "study.csv")
    assert table["reused"].all() and (table["problems_built"] == 0).all() and (table["build_time_s"] == 0).all()
    np.testing.assert_allclose(table["objective"], first, rtol=1e-6)  # CSV's 6 significant digits
    assert snapshot(study / "v1.13_b_sach") == before  # read back, not written again
