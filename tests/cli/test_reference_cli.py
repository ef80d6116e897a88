"""``gait reference`` as a command: the bundled reference is what the documented command (sample_trials/README.md)
makes of `gait synth`'s normative trial, whose band has the published band's shape; against the published band
that walk's Gait Profile Score is below the ski boot's and the knee orthosis's; a bad trial is one line, exit 2."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from gaitcli.resources import bundled_reference
from gaitcli.signal.bands import SD_FLOOR, default_band, read_band
from gaitcli.signal.profile import gait_profile

from .conftest import gait, gait_many

#: the trial the bundled reference and band come from (sample_trials/README.md)
NORMATIVE_TRIAL = ("--gait", "normative", "--seed", "1", "--mass-kg", "55", "--stature-m", "1.65", "--period-s", "1.40",
                   "--noise-mm", "2")


#: the disturbed conditions' idyn outputs, of the normative walker's subject (sample_trials/README.md)
BASELINE = Path(__file__).resolve().parent.parent / "baseline"


def gait_profile_deg(trial: Path) -> float:
    """The trial's Gait Profile Score against the package's band: each side's mean over its strides."""
    cycles = pd.read_csv(trial / "gait_out" / "idyn" / "gait_cycle.csv")
    means = {side: {c: block.groupby("cycle_pct")[c].mean().to_numpy() for c in block.columns if c != "side"}
             for side, block in cycles.groupby("side")}
    return gait_profile(means, default_band()).gps


def test_the_bundled_reference_is_what_the_command_makes(tmp_path):
    made = gait("synth", tmp_path / "normal", *NORMATIVE_TRIAL, cwd=tmp_path)
    assert made.returncode == 0, made.describe()
    runs = gait_many({"made": (("reference", "normal", "-o", "ref.csv", "--band", "band.csv", "--sd-floor"), tmp_path),
                      "missing": (("reference", "no_such_trial", "-o", "bad.csv"), tmp_path)})
    raw = gait("reference", "normal", "-o", "raw.csv", cwd=tmp_path)  # the SDs as measured
    assert raw.returncode == 0, raw.describe()
    made = runs["made"]
    assert made.returncode == 0, made.describe()
    got, bundled = pd.read_csv(tmp_path / "ref.csv"), pd.read_csv(bundled_reference())
    assert list(got.columns) == list(bundled.columns) and len(got) == 101
    np.testing.assert_allclose(got.to_numpy(), bundled.to_numpy(), rtol=1e-5, atol=1e-9)
    band, published = read_band(tmp_path / "band.csv"), default_band()
    assert set(published.variables) - {"knee_adduction_deg", "knee_rotation_deg"} <= set(band.variables)
    # Winter's shapes are Schwartz's; the pelvis pooled over both sides only with the left one mirrored
    for variable, r in (("pelvis_obliquity_deg", 0.6), ("pelvis_rotation_deg", 0.6), ("hip_flexion_deg", 0.95),
                        ("knee_flexion_deg", 0.9), ("ankle_flexion_deg", 0.9), ("ankle_power_W_per_kg", 0.9)):
        assert np.corrcoef(band.mean[variable], published.mean[variable])[0, 1] > r, variable
    for variable in band.variables:
        floor = next(v for suffix, v in SD_FLOOR.items() if variable.endswith(suffix))
        assert np.nanmin(band.sd[variable]) >= floor - 1e-9, variable
    assert gait_profile_deg(tmp_path / "normal") < min(gait_profile_deg(BASELINE / condition)
                                                       for condition in ("ski_boot", "knee_orthosis"))
    # a typical adult's sagittal angles (Winter: loading knee 19°, stance dorsiflexion 10°), not a crouch
    assert 13 < got.knee_r_flexion_deg_mean[:25].max() < 25
    assert 5 < got.ankle_r_dorsiflexion_deg_mean[10:60].max() < 15
    # plausible walking: vertical GRF above body weight in the loading response, none in the right swing
    assert got.grf_z_r_N_per_kg_mean[10:20].max() > 9.81 and got.grf_z_r_N_per_kg_mean[75:95].max() < 0.5
    raw = pd.read_csv(tmp_path / "raw.csv")
    sds = [c for c in got.columns if c.endswith("_sd")]
    np.testing.assert_allclose(got[sds].to_numpy(), np.maximum(raw[sds].to_numpy(), got[sds].to_numpy().min(axis=0)),
                               rtol=1e-5)
    assert (raw.knee_r_flexion_deg_sd < 3.0).mean() > 0.5  # one subject's strides: mostly below the 3° floor
    missing = runs["missing"]
    assert missing.returncode == 2 and len(missing.stderr_lines) == 1, missing.describe()
    assert "no_such_trial" in missing.stderr and "trial folder not found" in missing.stderr
    assert not (tmp_path / "bad.csv").exists()
