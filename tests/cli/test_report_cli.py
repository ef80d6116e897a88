"""``gait report``: self-contained HTML pages for a trial (filter, idyn, EID), a prediction and a batch, opened in
headless Chromium (Debian's ``chromium``, which ``.ci/run`` installs): the page loads with no network request
and every image decodes with a non-zero size, and it is under 5 MB.

The check injects a script into a copy of the page (the page's own Content-Security-Policy forbids scripts)
that, on load, records each image's natural size and the page's resource-timing entries (every fetch the page
made; data: URIs make none) into an attribute, which ``--dump-dom`` prints.
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from gaitcli.resources import sample_trials_dir

from .conftest import CHROMIUM, Result, build_once, gait_many, in_chromium


def _build(root: Path, prediction: Path) -> dict:
    shutil.copytree(prediction, root / "pr")
    trial = root / "normal"
    shutil.copytree(sample_trials_dir() / "normal", trial, ignore=shutil.ignore_patterns("gait_out"))
    lab = root / "lab"
    shutil.copytree(sample_trials_dir() / "ankle_weight", lab / "ankle_weight",
                    ignore=shutil.ignore_patterns("gait_out"))
    (lab / "broken").mkdir()
    shutil.copy(trial / "subject.yaml", lab / "broken" / "subject.yaml")
    (lab / "broken" / "trial.c3d").write_text("not a C3D\n")
    # the stages draw no figures: a page draws its own from the HDF5 files
    made = gait_many({"run": (("run", trial, "--pipeline", "muscles_eid", "--no-plots"), root),
                      "batch": (("batch", lab, "--workers", "1", "--no-plots"), root)}, workers=3)
    reports = gait_many({"trial": (("report", trial / "gait_out"), root), "predict": (("report", root / "pr"), root),
                         "batch": (("report", lab), root)}, workers=3)
    return {"made": {k: r.to_json() for k, r in made.items()}, "reports": {k: r.to_json() for k, r in reports.items()}}


@pytest.fixture(scope="module")
def reports(tmp_path_factory, stopped_prediction):
    prediction, predicted = stopped_prediction
    root, record = build_once(tmp_path_factory, "cli_report", lambda root: _build(root, prediction))
    made = {"predict": predicted, **{k: Result.from_json(v) for k, v in record["made"].items()}}
    assert made["run"].returncode == 0 and made["batch"].returncode == 0, made
    assert made["predict"].returncode == 3, made["predict"].describe()  # stopped after two iterations
    for r in record["reports"].values():
        r = Result.from_json(r)
        assert r.returncode == 0, r.describe()
    return {"trial": root / "normal" / "gait_out" / "report.html", "predict": root / "pr" / "report.html",
            "batch": root / "lab" / "report.html", "batch_trial": root / "lab" / "ankle_weight" / "gait_out" /
            "report.html"}


@pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (.ci/run installs it)")
@pytest.mark.parametrize("name", ["trial", "predict", "batch_trial"])
def test_a_page_loads_offline_with_every_image_decoded(reports, name, tmp_path):
    page = reports[name]
    assert page.stat().st_size < 5e6
    source = page.read_text(encoding="utf-8")
    expected = source.count("<img ")
    assert expected == {"trial": 9, "predict": 6, "batch_trial": 5}[name], expected  # the figures of each page
    check = in_chromium(page, tmp_path)
    assert check["requests"] == []
    assert len(check["images"]) == expected and all(w > 0 and h > 0 for w, h in check["images"]), check["images"]


def test_pages_name_the_trial_folder_and_carry_the_normal_band(reports):
    trial = reports["trial"].read_text(encoding="utf-8")
    assert "<title>normal</title>" in trial and "<h1>normal</h1>" in trial
    assert str(reports["trial"].parents[2]) not in trial  # no path outside the trial folder
    assert len(re.findall("<figcaption>[^<]*grey band is the normal mean ± 1 SD", trial)) == 2
    assert "Gait features (Table 3.1)" in trial and "Muscles: EID" in trial
    assert "The predicted gait, animated." in reports["predict"].read_text(encoding="utf-8")


def test_a_batch_index_links_every_trial_page_with_its_status(reports):
    index = reports["batch"].read_text(encoding="utf-8")
    assert '<a href="ankle_weight/gait_out/report.html">ankle_weight</a></td><td>ok' in index
    assert "<td>broken</td><td>failed</td>" in index and "not a C3D file" in index
    assert reports["batch_trial"].is_file()
