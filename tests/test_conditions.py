"""Conditions compared (gaitcli/run/conditions.py) on strides with truth: thirteen variables per side with smooth
stride-to-stride variation, one condition with +10° knee flexion over 60–80 % of the right cycle; the
comparison flags that span and nothing else, and two samples of one condition nowhere (family-wise α)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from gaitcli.errors import InputError
from gaitcli.run.conditions import Condition, compare_conditions, condition_sources, cycle_table

from .signal.test_spm import strides

VARIABLES = ("pelvis_tilt", "pelvis_obliquity", "pelvis_rotation", "hip_{s}_flexion", "hip_{s}_adduction",
             "hip_{s}_rotation", "knee_{s}_flexion", "knee_{s}_adduction", "knee_{s}_rotation", "ankle_{s}_flexion",
             "ankle_{s}_inversion", "ankle_{s}_rotation", "foot_{s}_progression")


def condition(name: str, seed: int, bump: str | None = None) -> Condition:
    """Ten strides a side of every variable, each its own random variation; +10° over 60–80 % on ``bump``."""
    stacks = {side: {v.format(s=side): strides(10, seed + 100 * k + (0 if side == "r" else 50),
                                               bump_deg=10.0 if v.format(s=side) == bump else 0.0)
                     for k, v in enumerate(VARIABLES)} for side in ("r", "l")}
    table = pd.DataFrame({"side": ["r"] * 10 + ["l"] * 10})
    return Condition(name, table, stacks, {"speed_m_s": 1.2})


def test_an_inserted_knee_difference_is_flagged_there_and_nowhere_else():
    comparison = compare_conditions([condition("normal", 1), condition("orthosis", 7, bump="knee_r_flexion")])
    spans = comparison.spans
    assert comparison.tested == {"orthosis/r": 13, "orthosis/l": 13}
    assert list(zip(spans.side, spans.variable)) == [("r", "knee_r_flexion")]
    assert spans.start_pct[0] == pytest.approx(60, abs=3) and spans.end_pct[0] == pytest.approx(80, abs=3)
    assert spans.largest_difference[0] > 5


def test_two_samples_of_one_condition_are_flagged_nowhere():
    comparison = compare_conditions([condition("normal", 1), condition("normal again", 2),
                                     condition("normal once more", 3)])
    assert comparison.spans.empty and sum(comparison.tested.values()) == 4 * 13


def test_the_cycle_table_holds_each_conditions_mean_of_its_strides():
    a, b = condition("a", 1), condition("b", 2)
    table = cycle_table([a, b])
    block = table[(table.condition == "b") & (table.side == "l")]
    np.testing.assert_allclose(block.knee_l_flexion_mean, b.stacks["l"]["knee_l_flexion"].mean(axis=0))
    np.testing.assert_allclose(block.knee_l_flexion_sd, b.stacks["l"]["knee_l_flexion"].std(axis=0, ddof=1))


def test_conditions_must_be_found_and_named_apart(tmp_path):
    (tmp_path / "a" / "walk").mkdir(parents=True)
    with pytest.raises(InputError, match="names two conditions"):
        condition_sources([tmp_path / "a" / "walk", tmp_path / "b" / "walk"], tmp_path / "out")
    with pytest.raises(InputError, match="bundled sample trial"):  # found before anything runs
        condition_sources([tmp_path / "a" / "walk", tmp_path / "nowhere"], tmp_path / "out")
    found = condition_sources([tmp_path / "a" / "walk", "ski_boot"], tmp_path / "out")
    assert [(s.name, s.root) for s in found] == [("walk", None),
                                                 ("ski_boot", tmp_path / "out" / "ski_boot" / "gait_out")]


def test_an_interrupt_while_the_page_is_drawn_leaves_the_earlier_comparison_whole(tmp_path):
    """Issue 53, item 6: SIGINT while compare/report.html is drawn. Before, the tables were already in place and
    the page missing; now the page is drawn inside the folder before it is complete: all or nothing."""
    from gaitcli.run.conditions import write_comparison

    comparison = compare_conditions([condition("normal", 1), condition("orthosis", 7, bump="knee_r_flexion")])
    write_comparison(tmp_path, comparison, page=lambda folder: (folder / "report.html").write_text("first"))
    before = {p.name: p.read_bytes() for p in (tmp_path / "compare").iterdir()}

    def interrupted(folder):
        (folder / "report.html").write_text("half a page")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        write_comparison(tmp_path, compare_conditions([condition("a", 2), condition("b", 3)]), page=interrupted)
    assert {p.name: p.read_bytes() for p in (tmp_path / "compare").iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["compare"]  # no half-written folder left
