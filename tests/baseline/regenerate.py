"""Regenerate ``tests/baseline/``: the outputs of the standard pipeline (filter, idyn) on every bundled sample
trial, as ``gait batch`` leaves them (CSV tables and summary.json; no HDF5, no plots), which
``tests/cli/test_regression_baseline.py`` compares today's results with.

Run from the repository root when a change of results is intended (and say why in the commit):
``python tests/baseline/regenerate.py``.
"""

from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from gaitcli.resources import sample_trials_dir
from gaitcli.run.batch import run_batch
from gaitcli.run.compare import outputs_only, tree_files
from gaitcli.run.config import configure

BASELINE = Path(__file__).resolve().parent
SAMPLES = ("normal", "ankle_weight", "knee_orthosis", "ankle_fixed", "ski_boot")


def copy_lab(root: Path) -> Path:
    """Copies of the sample trials (inputs only) below ``root``/lab."""
    lab = root / "lab"
    for name in SAMPLES:
        shutil.copytree(sample_trials_dir() / name, lab / name, ignore=shutil.ignore_patterns("gait_out"))
    return lab


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        lab = copy_lab(Path(tmp))
        result = run_batch(lab, configure(None), workers=2, plots=False)
        print(result.line())
        for name in SAMPLES:
            shutil.rmtree(BASELINE / name, ignore_errors=True)
        for rel in tree_files(lab):
            if outputs_only(rel):
                (BASELINE / rel).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(lab / rel, BASELINE / rel)
    print(f"wrote {BASELINE}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
