"""``gait compare`` reads its tables in chunks (gaitcli/run/compare.py, CHUNK_CELLS): the findings do not depend on
the chunk size, so memory stays flat in the tables' length (figures: benchmarks/bench_long_trial.py)."""

from __future__ import annotations

import numpy as np
import pytest

import gaitcli.run.compare as compare
from gaitcli.run.compare import compare_trees


def write_table(path, rows: int, *, edits=()) -> None:
    time_s = np.arange(rows) / 100.0
    columns = {"time_s": time_s, "knee_r_moment": np.sin(time_s), "side": np.where(time_s < 0.3, "r", "l")}
    cells = {name: [f"{v:.6g}" if isinstance(v, float) else str(v) for v in values.tolist()]
             for name, values in columns.items()}
    for name, row, value in edits:
        cells[name][row] = value
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(",".join(cells) + "\n" + "".join(",".join(row) + "\n" for row in zip(*cells.values())))


def findings(tmp_path, rows_b: int, edits) -> list:
    write_table(tmp_path / "a" / "idyn" / "joint_moments.csv", 60)
    write_table(tmp_path / "b" / "idyn" / "joint_moments.csv", rows_b, edits=edits)
    return sorted((f.column, f.problem, f.difference, f.where, f.detail) for f in
                  compare_trees(tmp_path / "a", tmp_path / "b").findings)


@pytest.mark.parametrize("rows_b, edits", [
    (60, [("knee_r_moment", 3, "5"), ("knee_r_moment", 40, "9"), ("knee_r_moment", 55, "NaN"),
          ("knee_r_moment", 7, "NaN"), ("side", 50, "x"), ("side", 2, "y")]),
    (61, []), (59, [("knee_r_moment", 3, "5")]),
])
def test_findings_do_not_depend_on_the_chunk_size(tmp_path, monkeypatch, rows_b, edits):
    whole = findings(tmp_path, rows_b, edits)
    monkeypatch.setattr(compare, "CHUNK_CELLS", 7)  # two rows of three columns per chunk
    assert findings(tmp_path, rows_b, edits) == whole
    assert whole
