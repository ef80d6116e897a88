"""A prediction study's figures and terminal table (gaitcli/report/study_plots.py) from rows of known values."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from gaitcli.report import study_plots


def row(speed, weights, condition, objective, converged=True, reused=False):
    return {"speed_m_s": speed, "weights": weights, "condition": condition, "objective": objective,
            "converged": converged, "reused": reused, "cost_of_transport_J_per_m": 10 * objective,
            "deviation": objective / 10}


ROWS = [row(1.1, "4/3,2/3", "normal", 1.0), row(1.1, "4/3,2/3", "sach", 1.5, converged=False),
        row(1.1, "1,1", "normal", 2.0), row(1.3, "4/3,2/3", "normal", 3.0)]


def test_one_panel_per_speed_and_one_bar_per_case_hatched_where_unconverged(tmp_path, monkeypatch):
    figures = {}

    def keep(fig, path):
        figures[path.name] = fig
        return path
    monkeypatch.setattr(study_plots, "save", keep)  # the figure kept open for inspection
    written = study_plots.study_figures(ROWS, tmp_path, title="s")
    assert [p.name for p in written] == ["study.png"]  # no optimal prosthesis: no curves
    slow, fast = figures["study.png"].axes
    assert (slow.get_title(), fast.get_title()) == ("1.10 m/s", "1.30 m/s")
    assert slow.get_ylabel() == "objective J (5.29)"
    assert sorted(bar.get_height() for bar in slow.patches) == [1.0, 1.5, 2.0]
    assert [bar.get_height() for bar in fast.patches] == [3.0]
    assert [bar.get_height() for bar in slow.patches if bar.get_hatch() == "//"] == [1.5]
    assert [t.get_text() for t in slow.get_xticklabels()] == ["weights 4/3,2/3", "weights 1,1"]
    plt.close("all")


def test_the_terminal_table_marks_the_unconverged_cases():
    lines = study_plots.study_text(ROWS).splitlines()
    assert len(lines) == 2 + len(ROWS)
    assert lines[3].split() == ["1.10", "4/3,2/3", "sach", "1.500", "15.0", "0.15", "-", "-", "*", "NOT", "CONVERGED"]
    assert [line.endswith("converged") for line in lines[2:]] == [True, False, True, True]
    walked = study_plots.study_text([{**ROWS[0], "stride_m": 1.3937, "cadence_steps_per_min": 114.06}])
    assert walked.splitlines()[2].split()[6:8] == ["1.394", "114.1"]
    assert np.isclose(float(lines[5].split()[3]), 3.0)
