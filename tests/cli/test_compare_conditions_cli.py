"""``gait report A B --compare`` as a command, on two bundled conditions of one subject (normal walking and the
right knee in an orthosis; their filter and idyn run by the command into OUT/<name>/): the knee's swing flexion
flagged, each condition's Table 3.1 and mean curves those of its own strides, the page whole and offline; bad
conditions are one line, exit 2, nothing written."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from .conftest import CHROMIUM, gait, in_chromium


@pytest.fixture(scope="module")
def compared(tmp_path_factory):
    root = tmp_path_factory.mktemp("compare")
    done = gait("report", "normative", "knee_orthosis", "--compare", "-o", "out", cwd=root)
    assert done.returncode == 0, done.describe()
    return root / "out", done


def test_the_orthosis_knee_is_flagged_in_swing(compared):
    out, done = compared
    spans = pd.read_csv(out / "compare" / "spm.csv")
    knee = spans[(spans.condition == "knee_orthosis") & (spans.variable == "knee_r_flexion")]
    swing = knee[(knee.start_pct < 70) & (knee.end_pct > 80)]  # the normal knee flexes ~60° at 70–75 %
    assert len(swing) == 1 and swing.largest_difference.iloc[0] < -40
    assert set(spans.condition) == {"knee_orthosis"} and "2 conditions" in done.stderr


def test_each_condition_is_its_own_strides(compared):
    out, _ = compared
    conditions = pd.read_csv(out / "compare" / "conditions.csv").set_index("condition")
    cycle = pd.read_csv(out / "compare" / "cycle.csv")
    for name in ("normative", "knee_orthosis"):
        idyn = out / name / "gait_out" / "idyn"
        features = json.loads((idyn / "summary.json").read_text())
        assert conditions.loc[name, "speed_m_s"] == pytest.approx(features["speed_m_s"], rel=1e-5)
        strides = pd.read_csv(idyn / "gait_cycle.csv")
        right = strides[strides.side == "r"].groupby("cycle_pct").knee_r_flexion.mean().to_numpy()
        mine = cycle[(cycle.condition == name) & (cycle.side == "r")].knee_r_flexion_mean.to_numpy()
        np.testing.assert_allclose(mine, right, rtol=1e-5, atol=1e-6)


def test_the_page_has_every_block(compared):
    out, _ = compared
    page = (out / "compare" / "report.html").read_text(encoding="utf-8")
    for block in ("Conditions compared: normative, knee_orthosis", "Warnings", "Table 3.1",
                  "Where each condition differs from normative", "knee_r_flexion", "Šidák"):
        assert block in page, block
    assert page.count("<img") == 4


def test_the_page_is_part_of_the_comparison_and_a_rerun_replaces_both(compared):
    """Issue 53, item 5: report.html is in compare/'s list of gait's files (before, it was written after the
    folder was complete, unlisted, and every rerun stopped: "is not an output of gait"); a rerun replaces it."""
    out, done = compared
    listed = json.loads((out / "compare" / ".gait_files").read_text())
    assert "report.html" in listed and f"wrote {out / 'compare' / 'report.html'}" in done.stderr
    again = gait("report", "normative", "knee_orthosis", "--compare", "-o", "out", cwd=out.parent)
    assert again.returncode == 0, again.describe()
    assert (out / "compare" / "report.html").is_file()


def test_sigint_while_comparing_leaves_the_earlier_comparison_whole(compared):
    """Issue 53, item 6: SIGINT sent to a real `gait report … --compare` when it starts reading its second
    condition (a console line, no timing): exit 130, OUT/compare exactly as the earlier run left it (before: its
    tables replaced and no report.html), no temporary folder left."""
    import signal
    import subprocess
    import sys

    from .conftest import ENV, snapshot

    out, _ = compared
    before = snapshot(out / "compare")
    process = subprocess.Popen([sys.executable, "-m", "gaitcli", "report", "normative", "knee_orthosis", "--compare",
                                "-o", "out"], cwd=out.parent, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    for line in process.stderr:
        if line.startswith("compare: reading knee_orthosis"):
            process.send_signal(signal.SIGINT)
            break
    _, rest = process.communicate(timeout=120)
    assert process.returncode == 130 and rest.strip().splitlines()[-1] == "gait: interrupted", rest
    assert snapshot(out / "compare") == before
    assert not [p.name for p in out.iterdir() if p.name.startswith(".compare")]


@pytest.mark.skipif(CHROMIUM is None, reason="needs Debian's chromium (.ci/run installs it)")
def test_the_page_loads_offline(compared, tmp_path):
    out, _ = compared
    check = in_chromium(out / "compare" / "report.html", tmp_path)
    assert check["requests"] == [] and len(check["images"]) == 4 and all(w > 0 for w, _ in check["images"])


@pytest.mark.parametrize("args, message", [(("normative", "--compare"), "two or more conditions"),
                                           (("normative", "no_such_condition", "--compare"), "no_such_condition"),
                                           (("normative", "ski_boot"), "one OUT_DIR")])
def test_bad_conditions_are_one_line_and_write_nothing(tmp_path, args, message):
    done = gait("report", *args, "-o", "out", cwd=tmp_path)
    assert done.returncode == 2 and message in done.stderr and len(done.stderr_lines) == 1, done.describe()
    assert not (tmp_path / "out").exists()
