"""``gait reference`` as a command: the bundled reference is what the documented command makes of the bundled
normal sample trial; a bad trial is one line, exit 2."""

from __future__ import annotations

import numpy as np
import pandas as pd

from gaitcli.resources import bundled_reference

from .conftest import copy_sample, gait_many


def test_the_bundled_reference_is_what_the_command_makes(tmp_path):
    copy_sample("normal", tmp_path / "normal")
    runs = gait_many({"made": (("reference", "normal", "-o", "ref.csv"), tmp_path),
                      "missing": (("reference", "no_such_trial", "-o", "bad.csv"), tmp_path)})
    made = runs["made"]
    assert made.returncode == 0, made.describe()
    got, bundled = pd.read_csv(tmp_path / "ref.csv"), pd.read_csv(bundled_reference())
    assert list(got.columns) == list(bundled.columns) and len(got) == 101
    np.testing.assert_allclose(got.to_numpy(), bundled.to_numpy(), rtol=1e-5, atol=1e-9)
    # plausible walking: vertical GRF above body weight in the loading response, none in the right swing
    assert got.grf_z_r_N_per_kg_mean[10:20].max() > 9.81 and got.grf_z_r_N_per_kg_mean[75:95].max() < 0.5
    missing = runs["missing"]
    assert missing.returncode == 2 and len(missing.stderr_lines) == 1, missing.describe()
    assert "no_such_trial" in missing.stderr and "trial folder not found" in missing.stderr
    assert not (tmp_path / "bad.csv").exists()
