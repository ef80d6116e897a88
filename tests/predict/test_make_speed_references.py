"""scripts/make_speed_references.py on a workbook made here with known answers: the mean column, the SD from the
±1 SD columns (either way round), 2 % → 1 %, the hip less the pelvic tilt, fractions of body weight → N/kg, the
left leg half a cycle later, and the groups' dimensionless parameters."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parents[2] / "scripts" / "make_speed_references.py"


@pytest.fixture(scope="module")
def script():
    spec = importlib.util.spec_from_file_location("make_speed_references", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def rows(label: str, curve, sd: float, reversed_sd: bool = False) -> list[list]:
    """A sheet's 51 rows of one variable: every group's mean ``curve(fraction) + group index``, ±``sd``."""
    out = []
    for fraction in np.arange(51) / 50:
        row = [label, fraction]
        for k in range(5):
            mean = curve(fraction) + k
            low, high = (mean + sd, mean - sd) if reversed_sd else (mean - sd, mean + sd)
            row += [low, mean, high]
        out.append(row)
    return out


def test_a_group_reference_from_a_known_workbook(script):
    angles = (rows("Hip Flex/Extension", lambda f: 30 * np.cos(2 * np.pi * f), 6.0)
              + rows("Pelvic Ant/Posterior Tilt", lambda f: 10 + f, 4.0)
              + rows("Knee Flex/Extension", lambda f: 100 * f, 5.0)
              + rows("Ankle Dorsi/Plantarflexion", lambda f: -20 * f, 3.0))
    forces = rows("Anterior/Posterior", lambda f: 0.2 * f, 0.05) + rows("Vertical", lambda f: f, 0.1, True)
    columns = script.group_reference({"Joint Rotations": angles, "Ground Reaction Forces": forces}, "Free")
    pct = np.arange(101.0)
    free = 2  # the group's index: its curves are the base curve + 2
    # 2 % → 1 %: linear between the samples (the knee's ramp is linear: exact at every 1 %)
    np.testing.assert_allclose(columns["knee_r_flexion_deg_mean"], pct + free, atol=1e-12)
    np.testing.assert_allclose(columns["knee_r_flexion_deg_sd"], 5.0)
    # the hip less the tilt at the same instant, at a sample and halfway between two
    hip = 30 * np.cos(2 * np.pi * pct / 100) + free - (10 + pct / 100 + free)
    assert columns["hip_r_flexion_deg_mean"][50] == pytest.approx(hip[50], abs=1e-12)
    between = (30 * np.cos(2 * np.pi * 0.50) + 30 * np.cos(2 * np.pi * 0.52)) / 2 - (10 + 0.51)
    assert columns["hip_r_flexion_deg_mean"][51] == pytest.approx(between, abs=1e-12)
    np.testing.assert_allclose(columns["hip_r_flexion_deg_sd"], 6.0)
    # fractions of body weight → N/kg; the SD positive whichever way the ±1 SD columns run
    np.testing.assert_allclose(columns["grf_z_r_N_per_kg_mean"], (pct / 100 + free) * 9.81, atol=1e-12)
    np.testing.assert_allclose(columns["grf_z_r_N_per_kg_sd"], 0.1 * 9.81, atol=1e-12)
    np.testing.assert_allclose(columns["grf_x_r_N_per_kg_sd"], 0.05 * 9.81, atol=1e-12)
    # the left leg: the right half a cycle later, its 100 % its 0 %
    np.testing.assert_allclose(columns["knee_l_flexion_deg_mean"][:50], pct[50:100] + free, atol=1e-12)
    np.testing.assert_allclose(columns["knee_l_flexion_deg_mean"][50:], pct[:51] + free, atol=1e-12)
    np.testing.assert_allclose(columns["ankle_l_dorsiflexion_deg_mean"][10], -20 * 0.60 + free, atol=1e-12)


def test_the_groups_parameters_and_a_short_sheet(script):
    anova = [["", "", "N", "Mean", "Std. Deviation"]]
    labels = (("Dimensionless Speed", 0.1), ("Dimensionless Cadence", 0.3), ("Dimensionless Step Length", 0.5))
    for label, base in labels:
        for k, group in enumerate(script.GROUPS):
            anova.append([label if k == 0 else "", group, 70 + k, base + 0.1 * k, 0.01 * (k + 1)])
        anova.append(["", "Total", 400, 0.0, 0.0])
    table = script.group_parameters(anova)
    assert table["group"] == ["very_slow", "slow", "free", "fast", "very_fast"]
    assert table["subjects"] == [70, 71, 72, 73, 74]
    np.testing.assert_allclose(table["step_length_mean"], [0.5, 0.6, 0.7, 0.8, 0.9])
    np.testing.assert_allclose(table["cadence_sd"], [0.01, 0.02, 0.03, 0.04, 0.05])
    with pytest.raises(ValueError, match="step_length"):
        script.group_parameters(anova[:12])
    with pytest.raises(ValueError, match="51 rows"):
        script.curve(rows("Vertical", lambda f: f, 0.1)[:-1], "Vertical", "Free")
