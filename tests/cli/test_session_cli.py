"""A session folder as Nexus leaves one (``gait synth --session``): ``gait run SESSION`` runs every walk into
``gait_out/<walk>/`` and pools their strides into ``gait_out/session/``; a rerun runs nothing; a single-trial
command on the session names the choice."""

from __future__ import annotations

import base64
import io
import json
import re

import numpy as np
import pandas as pd
from PIL import Image

from .conftest import CHROMIUM, gait, in_chromium

WALKS = ("Walking 01", "Walking 02")


def test_a_session_runs_every_walk_and_pools_its_strides(tmp_path):
    made = gait("synth", "S", "--session", "--walks", "2", "--strides", "2", "--seed", "4", cwd=tmp_path)
    assert made.returncode == 0, made.describe()
    session = tmp_path / "S"
    assert sorted(p.name for p in session.glob("*.c3d")) == ["Static 01.c3d", "Walking 01.c3d", "Walking 02.c3d"]
    # one walk after the other in the runner (in parallel the walks are gait batch's tasks: test_batch_cli.py)
    run = gait("run", "S", "--no-plots", "--workers", "1", cwd=tmp_path)
    assert run.returncode == 0, run.describe()
    assert "2 ok, 0 failed, 0 skipped" in run.stdout and "session: wrote" in run.stderr
    out = session / "gait_out"
    for walk in WALKS:
        assert (out / walk / "idyn" / "gait_cycle.csv").is_file() and (out / walk / "filter" / "events.csv").is_file()
    strides = pd.read_csv(out / "session" / "strides.csv")
    cycles = {w: pd.read_csv(out / w / "idyn" / "gait_cycle.csv") for w in WALKS}
    complete = strides[strides.status != "rejected"]
    assert len(complete) == sum(c.groupby(["side", "stride"]).ngroups for c in cycles.values())
    # the session's mean: every right stride of both walks' gait_cycle.csv, averaged here directly
    right = np.array([block.knee_r_flexion.to_numpy() for c in cycles.values()
                      for _, block in c[c.side == "r"].groupby("stride")])
    cycle = pd.read_csv(out / "session" / "cycle.csv")
    np.testing.assert_allclose(cycle[cycle.side == "r"].knee_r_flexion_mean, right.mean(axis=0), rtol=1e-5,
                               atol=1e-4)
    np.testing.assert_allclose(cycle[cycle.side == "r"].knee_r_flexion_sd, right.std(axis=0, ddof=1), rtol=1e-4,
                               atol=1e-4)
    # the ground reaction in % body weight: above body weight in the loading response, nothing in swing
    vertical = cycle[cycle.side == "r"].grf_r_vertical_pct_body_weight_mean.to_numpy()
    assert 100 < vertical[:30].max() < 140 and np.nanmax(np.abs(vertical[70:95])) < 1.0
    walks = pd.read_csv(out / "session" / "walks.csv").set_index("walk")
    for walk in WALKS:
        idyn = json.loads((out / walk / "idyn" / "summary.json").read_text())
        assert walks.loc[walk, "speed_m_s"] == np.float64(f"{idyn['speed_m_s']:.6g}")
    summary = json.loads((out / "session" / "summary.json").read_text())
    assert summary["walks"] == 2 and abs(summary["table_3_1_mean"]["speed_m_s"] - walks.loc["mean", "speed_m_s"]) < 1e-5
    profile = summary["gait_profile"]  # against the package's band (tests/signal/test_profile.py: known answers)
    assert 0 < profile["gps_right_deg"] < 20 and set(profile["gvs_deg"]["right"]) >= {"knee_r_flexion"}
    # the synthetic subject's angles are ISB's, the band's Plug-in Gait's: said (issue 52, item 6)
    assert (profile["angle_conventions"], profile["band_angle_convention"]) == (["isb"], "plug_in_gait")
    assert "gait profile score: the walks' angles are in isb frames, the band's in Plug-in Gait's" in run.stderr

    report = gait("report", "S", cwd=tmp_path)
    assert report.returncode == 0, report.describe()
    page = (out / "report.html").read_text(encoding="utf-8")
    for heading in ("Warnings", "Temporal-spatial parameters (Table 3.1)", "Strides", "Gait Profile Score",
                    "Kinematics and kinetics", "Walks"):
        assert f"<h2>{heading}</h2>" in page, heading
    assert "No stage gave a warning." in page and 'href="Walking 02/report.html"' in page
    assert "<strong>Warning:</strong> the walks&#x27; angles are in isb frames" in page
    images = re.findall(r'<img src="data:image/png;base64,([^"]*)"', page)
    assert len(images) == 2
    for data in images:
        with Image.open(io.BytesIO(base64.b64decode(data))) as image:
            image.load()
            assert image.size[0] > 800
    assert all((out / walk / "report.html").is_file() for walk in WALKS)
    if CHROMIUM is not None:  # .ci/run installs it
        check = in_chromium(out / "report.html", tmp_path)
        assert check["requests"] == [] and len(check["images"]) == 2
        assert all(w > 800 and h > 400 for w, h in check["images"]), check["images"]
    cadence = next(row for row in re.findall(r"<tr>(.*?)</tr>", page) if "cadence (steps/min)" in row)
    right = complete[complete.side == "r"]
    assert f"<td>{np.mean(120 / right.period_s):.1f} ± {np.std(120 / right.period_s, ddof=1):.1f}</td>" in cadence
    # steady walking: every step half a stride (tests/signal/test_cycles.py: footprints with known steps)
    steps = complete.step_length_m.dropna()
    assert len(steps) >= len(complete) - 2 and np.allclose(steps, complete.stride_length_m.mean() / 2, rtol=0.02)
    step = next(row for row in re.findall(r"<tr>(.*?)</tr>", page) if "step length (m)" in row)
    right_steps = right.step_length_m.dropna()
    assert f"<td>{right_steps.mean():.2f} ± {right_steps.std(ddof=1):.2f}</td>" in step

    again = gait("run", "S", "--no-plots", "--workers", "1", cwd=tmp_path)
    assert again.returncode == 0 and "0 ok, 0 failed, 2 skipped" in again.stdout, again.describe()
    (session / "Walking 03.c3d").write_text("not a C3D\n")  # a damaged walk: the others still pooled
    damaged = gait("run", "S", "--no-plots", "--workers", "1", cwd=tmp_path)
    assert damaged.returncode == 2 and damaged.stderr_lines[-1].startswith("gait: error: "), damaged.describe()
    assert "Walking 03.c3d" in damaged.stderr_lines[-1] and "1 of 3 walks failed" in damaged.stderr_lines[-1]
    assert json.loads((out / "session" / "summary.json").read_text())["walks"] == 2
    (session / "Walking 03.c3d").unlink()
    one = gait("idyn", "S", cwd=tmp_path)
    assert one.returncode == 2 and len(one.stderr_lines) == 1, one.describe()
    assert "a session of 2 walks" in one.stderr and "gait run" in one.stderr and "Walking 01.c3d" in one.stderr
