"""The HTML page (gaitcli/report/html.py) from small output trees: text escaped, each stage's rows, damaged
summaries and rows refused with the file, line and key, figures embedded only where they exist."""

from __future__ import annotations

import csv
import html
import json
import re

import pytest

from gaitcli.errors import InputError
from gaitcli.report import html as report_html
from gaitcli.report import plots

from . import synthetic

HOSTILE = '<script>alert("x")</script> & co'
PNG = bytes.fromhex("89504e470d0a1a0a")  # a PNG signature: the page embeds the file's bytes as they are


def write_json(path, data) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data), encoding="utf-8")


def cells(page: str) -> list[list[str]]:
    """Every table row's cells (header and data), as text."""
    return [[html.unescape(c) for c in re.findall(r"<t[dh]>(.*?)</t[dh]>", row)]
            for row in re.findall(r"<tr>(.*?)</tr>", page)]


@pytest.fixture
def no_figures(monkeypatch):
    """Trial pages without their figures (drawn from HDF5 files these trees do not have)."""
    for name in ("filter_figures", "idyn_figures", "muscle_figures"):
        monkeypatch.setattr(plots, name, lambda *a, **k: [])


def test_a_batch_index_escapes_trial_names_and_reasons(tmp_path):
    lab = tmp_path / "lab"
    lab.mkdir()
    with (lab / "batch_summary.csv").open("w", encoding="utf-8", newline="") as fh:
        csv.writer(fh).writerows([("trial", "stage", "status", "reason"), (HOSTILE, "filter", "failed", HOSTILE)])
    (index,) = report_html.write_report(lab, band=None)
    page = index.path.read_text(encoding="utf-8")
    assert "<script>" not in page
    assert page.count(html.escape(HOSTILE)) == 2  # the trial (not linked: it failed) and its reason
    assert cells(page)[1] == [HOSTILE, "failed", HOSTILE]


def test_a_trial_page_escapes_the_trial_name_the_files_record(tmp_path):
    root = tmp_path / "gait_out"
    (root / "filter").mkdir(parents=True)
    synthetic.write_filter(root / "filter" / "filter.h5", trial=HOSTILE)
    write_json(root / "filter" / "summary.json", {"frames": 221})
    (page,) = report_html.write_report(root, band=None)
    text = page.path.read_text(encoding="utf-8")
    assert page.title == HOSTILE and "<script>" not in text
    assert f"<title>{html.escape(HOSTILE)}</title>" in text and f"<h1>{html.escape(HOSTILE)}</h1>" in text
    # the two filter figures, drawn from the file and embedded: nothing loads from elsewhere
    sources = re.findall(r'<img src="([^"]*)"', text)
    assert len(sources) == 2 and all(s.startswith("data:image/png;base64,") for s in sources)
    assert "default-src 'none'" in text


def test_a_damaged_file_among_the_outputs_does_not_name_the_trial(tmp_path, no_figures):
    root = tmp_path / "walk 3" / "gait_out"
    (root / "archive").mkdir(parents=True)
    (root / "archive" / "old.h5").write_bytes(b"\x89HDF\r\n\x1a\n" + bytes(100))  # read first: sorted
    write_json(root / "idyn" / "summary.json", {})
    assert report_html.write_report(root, band=None)[0].title == "walk 3"  # the trial folder's name
    synthetic.write_idyn(root / "idyn" / "idyn.h5", trial="recorded name")
    assert report_html.write_report(root, band=None)[0].title == "recorded name"


def test_the_trial_page_has_the_rows_of_each_stage(tmp_path, no_figures):
    root = tmp_path / "gait_out"
    write_json(root / "idyn" / "summary.json", {"mass_kg": 71.25, "speed_m_s": 1.2345, "stride_length_m": 1.3,
                                                 "period_s": 1.05, "stance_right_pct": 60.04, "stance_left_pct": 61.96,
                                                 "double_stance_pct": None, "step_length_left_m": 0.649,
                                                 "step_width_m": 0.123})
    write_json(root / "muscles" / "eid" / "summary.json", {"metabolic_cost_J": 123.456,
                                                           "cost_of_transport_J_per_m": 98.76, "converged": True})
    write_json(root / "muscles" / "so" / "summary.json", {"metabolic_cost_J": None, "converged": False})
    for folder in ("eid", "so"):
        (root / "muscles" / folder / "muscles.h5").write_bytes(b"")  # the figures are not drawn here
    (page,) = report_html.write_report(root, band=None)
    text = page.path.read_text(encoding="utf-8")
    rows = cells(text)
    assert rows[0] == ["feature", "this trial", "normal walking (3.3.3: 26 subjects, Heidelberg)", "unit"]
    assert rows[1:] == [["walking speed", "1.23", "1.38", "m/s"], ["stride length", "1.30", "1.41", "m"],
                        ["stride period", "1.05", "—", "s"], ["stance, right", "60.0", "61.0", "% of cycle"],
                        ["stance, left", "62.0", "61.0", "% of cycle"], ["double stance", "—", "—", "% of cycle"],
                        ["step length, right", "—", "0.70", "m"], ["step length, left", "0.65", "0.70", "m"],
                        ["step width", "0.12", "—", "m"]]
    assert "body mass 71.2 kg" in text  # no subject.yaml beside the outputs
    assert "<h2>Muscles: EID</h2><p>metabolic cost of one leg over the interval: 123.5 J; cost of transport " \
           "98.8 J/m</p>" in text
    assert '<h2>Muscles: SO <span class="bad">(did not converge)</span></h2><p>metabolic cost of one leg over the ' \
           "interval: — J; cost of transport — J/m</p>" in text


def test_the_prediction_rows(tmp_path, monkeypatch):
    from gaitcli.report import predict_plots

    monkeypatch.setattr(predict_plots, "predict_figures", lambda *a, **k: [])
    root = tmp_path / "gait_out"
    checks = {"stance_pct": {"value": 62.0, "ok": True}, "ankle_moment_peak_pct": {"value": 32.0, "ok": False}}
    write_json(root / "predict" / "summary.json", {"speed_m_s": 1.1275, "cost_of_transport_J_per_m": 250.04,
                                                    "deviation": 3.14159, "objective": 0.98765, "converged": False,
                                                    "status": "Maximum_Iterations_Exceeded", "iterations": 2,
                                                    "gait_checks": checks})
    (root / "predict" / "predict.h5").write_bytes(b"")
    text = report_html.write_report(root, band=None)[0].path.read_text(encoding="utf-8")
    assert ('<p class="bad">did not converge (Maximum_Iterations_Exceeded) in 2 iterations; gait checks failed: '
            "ankle_moment_peak_pct</p>") in text
    assert cells(text) == [["", "value", "unit"], ["speed", "1.13", "m/s"],
                           ["metabolic cost of transport Et", "250.0", "J/m"],
                           ["deviation from the reference Jdev", "3.14", ""], ["objective J", "0.988", ""]]
    assert '<h2>Predicted gait <span class="bad">(did not converge)</span></h2>' in text


@pytest.mark.parametrize("content,where,problem", [
    ('{"speed_m_s": "fast"}', "speed_m_s", "got 'fast' (expected a number)"),
    ('{"speed_m_s": true}', "speed_m_s", "got True (expected a number)"),
    ('{"speed_m_s": 1e301}', "speed_m_s", "expected a number"),
    ('{"speed_m_s": 1.2', None, "not valid JSON"),
    ('[1, 2]', None, "holds a list (expected a mapping"),
])
def test_a_damaged_summary_is_an_input_error_naming_file_and_key(tmp_path, no_figures, content, where, problem):
    root = tmp_path / "gait_out"
    write_json(root / "idyn" / "summary.json", {})
    (root / "idyn" / "summary.json").write_text(content, encoding="utf-8")
    with pytest.raises(InputError) as caught:
        report_html.write_report(root, band=None)
    assert caught.value.path.name == "summary.json" and caught.value.field == where
    assert problem in caught.value.problem


@pytest.mark.parametrize("table,where", [
    ("trial,stage,status,reason\nwalk,filter,ok,\nrun,filter\n", "line 3: status"),
    ("trial,stage,reason\nwalk,filter,\n", "line 2: status"),
])
def test_a_damaged_batch_row_is_an_input_error_naming_line_and_column(tmp_path, table, where):
    (tmp_path / "batch_summary.csv").write_text(table, encoding="utf-8")
    with pytest.raises(InputError) as caught:
        report_html.write_report(tmp_path, band=None)
    assert caught.value.path.name == "batch_summary.csv" and caught.value.field == where


STUDY_HEADER = "case,speed_m_s,weights,condition,objective,cost_of_transport_J_per_m,deviation,converged\n"


def test_a_damaged_study_row_is_an_input_error_naming_line_and_column(tmp_path):
    study = tmp_path / "study"
    study.mkdir()
    (study / "study.csv").write_text(STUDY_HEADER + "1,1.1,\"4/3,2/3\",normal,1.5,250,2,True\n"
                                                    "2,1.1,\"4/3,2/3\",sach,n/a,260,3,False\n", encoding="utf-8")
    with pytest.raises(InputError) as caught:
        report_html.write_report(tmp_path, band=None)
    assert caught.value.field == "line 3: objective" and "got 'n/a'" in caught.value.problem


def test_a_study_page_embeds_the_figures_it_has_and_no_other(tmp_path):
    study = tmp_path / "study"
    study.mkdir()
    (study / "study.csv").write_text(STUDY_HEADER + "1,1.1,\"4/3,2/3\",normal,1.5,250.04,2,True\n"
                                                    "2,1.1,\"4/3,2/3\",sach,,,,False\n", encoding="utf-8")
    (study / "study.png").write_bytes(PNG)  # no curves.png: no optimal prosthesis in this study
    (page,) = report_html.write_report(tmp_path, band=None)
    text = page.path.read_text(encoding="utf-8")
    assert re.findall(r'<img src="([^"]*)"', text) == ["data:image/png;base64,iVBORw0KGgo="]
    assert "J per condition" in text and "spring moment" not in text
    assert cells(text)[1:] == [["1", "1.1", "4/3,2/3", "normal", "1.500", "250.0", "2.00", "yes"],
                               ["2", "1.1", "4/3,2/3", "sach", "—", "—", "—", "NO"]]


def test_a_study_figure_linking_outside_its_folder_is_refused(tmp_path):
    study = tmp_path / "study"
    study.mkdir()
    (study / "study.csv").write_text(STUDY_HEADER, encoding="utf-8")
    (tmp_path / "secret.png").write_bytes(PNG)
    (study / "study.png").symlink_to(tmp_path / "secret.png")
    with pytest.raises(InputError, match="links outside the study folder"):
        report_html.write_report(tmp_path, band=None)


def test_the_warnings_of_every_stage_open_the_page_escaped(tmp_path, no_figures):
    root = tmp_path / "gait_out"
    write_json(root / "filter" / "summary.json", {"frames": 3, "warnings": ["trial.c3d: no usable force plates",
                                                                            HOSTILE]})
    write_json(root / "muscles" / "eid_l" / "summary.json", {"converged": True, "warnings": ["excitation clipped"]})
    (root / "muscles" / "eid_l" / "muscles.h5").write_bytes(b"")
    (page,) = report_html.write_report(root, band=None)
    text = page.path.read_text(encoding="utf-8")
    block = re.search(r'<div class="warnings">(.*?)</div>', text)[1]
    assert "<strong>3 warnings</strong>" in block and "<script>" not in text
    assert re.findall(r"<li>(.*?)</li>", block) == [
        "filter: trial.c3d: no usable force plates", f"filter: {html.escape(HOSTILE)}",
        "muscles/eid_l: excitation clipped"]
    assert text.index('class="warnings"') < text.index("<h2>Muscles: EID, left leg</h2>")
    write_json(root / "filter" / "summary.json", {"frames": 3, "warnings": []})
    write_json(root / "muscles" / "eid_l" / "summary.json", {"converged": True})
    (page,) = report_html.write_report(root, band=None)
    assert "No stage gave a warning." in page.path.read_text(encoding="utf-8")


def test_a_session_page_lists_each_walks_muscles(tmp_path, monkeypatch):
    from gaitcli.report import session_plots

    monkeypatch.setattr(session_plots, "session_figures", lambda *a, **k: [])
    root = tmp_path / "S" / "gait_out"
    (root / "session").mkdir(parents=True)
    (root / "session" / "walks.csv").write_text("walk,speed_m_s\nWalking 01,1.2\nmean,1.2\nsd,\n")
    (root / "session" / "strides.csv").write_text("walk,side,start_s,period_s,stance_pct,speed_m_s,stride_length_m,"
                                                  "status,reason\nWalking 01,r,0.5,1.1,60,1.2,1.3,used,\n")
    write_json(root / "session" / "summary.json", {"walks": 1})
    write_json(root / "Walking 01" / "muscles" / "eid_l_swing" / "summary.json",
               {"converged": False, "metabolic_cost_J": 41.96, "cost_of_transport_J_per_m": None})
    body = report_html.session_body(root, None, tmp_path / "work", {})
    assert ["Walking 01", "EID, left leg, swing", "no", "42.0", "—"] in cells(body)


@pytest.mark.parametrize("speeds", [(1.234,), (1.1, 1.3)])
def test_a_session_of_one_walk_shows_its_mean_alone(tmp_path, monkeypatch, speeds):
    """walks.csv's SD is NaN for one walk: the session's cell is the mean alone, never "± nan"; with two walks
    it is their mean ± SD (ddof 1: 1.20 ± 0.14 for 1.1 and 1.3 m/s)."""
    import numpy as np

    from gaitcli.report import session_plots

    monkeypatch.setattr(session_plots, "session_figures", lambda *a, **k: [])
    root = tmp_path / "S" / "gait_out"
    (root / "session").mkdir(parents=True)
    sd = f"{np.std(speeds, ddof=1):.6f}" if len(speeds) > 1 else "NaN"
    walks = "".join(f"Walking {k:02d},{v}\n" for k, v in enumerate(speeds, 1))
    (root / "session" / "walks.csv").write_text(f"walk,speed_m_s\n{walks}mean,{np.mean(speeds)}\nsd,{sd}\n")
    (root / "session" / "strides.csv").write_text("walk,side,start_s,period_s,stance_pct,speed_m_s,stride_length_m,"
                                                  "status,reason\nWalking 01,r,0.5,1.1,60,1.2,1.3,used,\n")
    write_json(root / "session" / "summary.json", {"walks": len(speeds)})
    body = report_html.session_body(root, None, tmp_path / "work", {})
    row = next(c for c in cells(body) if c and c[0] == "walking speed (m/s)")
    expected = "1.23" if len(speeds) == 1 else "1.20 ± 0.14"
    assert row[1 + len(speeds)] == expected
    assert not re.search(r"\bnan\b", body, re.IGNORECASE)
