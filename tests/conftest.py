"""Shared fixtures: where the real C3D files live, and a skip where they are absent."""

from __future__ import annotations

from pathlib import Path

import pytest

from gaitcli.__main__ import single_threaded_blas

single_threaded_blas()  # as the gait command does, before any test module loads numpy (xdist workers inherit it)

REPO = Path(__file__).resolve().parents[1]
SHARED_C3D = REPO.parent / "shared" / "data" / "c3d"
SHARED_PIG = REPO.parent / "shared" / "data" / "pig"


@pytest.fixture(scope="session")
def shared_c3d_dir() -> Path:
    """``../shared/data/c3d`` next to the checkout; the test is skipped where it is absent."""
    if not SHARED_C3D.is_dir():
        pytest.skip("../shared/data/c3d is not present next to this checkout")
    return SHARED_C3D


@pytest.fixture(scope="session")
def shared_pig_dir() -> Path:
    """``../shared/data/pig`` (a Vicon Plug-in Gait session: static and movement C3D with Vicon's outputs,
    Test.vsk); the test is skipped where it is absent."""
    if not (SHARED_PIG / "Movement_trial.c3d").is_file():
        pytest.skip("../shared/data/pig is not present next to this checkout")
    return SHARED_PIG


#: the test files that take longest (processor seconds, their gait processes included, as
#: ``benchmarks/suite_cpu.py`` measures them), run first and longest first so that ``pytest -n 2`` (pyproject:
#: ``--dist loadfile --no-loadscope-reorder``, whole files in this order) ends with short files on both workers
#: rather than one long file on one
HEAVY_FILES = {
    "tests/cli/test_predict_cli.py": 24, "tests/cli/test_muscles_cli.py": 17, "tests/cli/test_batch_cli.py": 14,
    "tests/cli/test_muscles_samples.py": 13, "tests/cli/test_interrupts.py": 10, "tests/cli/test_report_cli.py": 10,
    "tests/cli/test_compare_conditions_cli.py": 9, "tests/io/test_c3d_fuzz.py": 9, "tests/cli/test_emg.py": 9,
    "tests/cli/test_idyn_cli.py": 8, "tests/muscles/test_methods.py": 8, "tests/dynamics/test_stage.py": 8,
    "tests/cli/test_qualisys_doc.py": 8, "tests/predict/test_nlp.py": 7, "tests/predict/test_stage.py": 7,
    "tests/cli/test_session_cli.py": 6, "tests/cli/test_regression_baseline.py": 5, "tests/test_api.py": 5,
    "tests/io/test_c3d_long.py": 5, "tests/cli/test_nexus_folder.py": 5, "tests/predict/test_problem.py": 5,
    "tests/cli/test_emg_real.py": 4, "tests/cli/test_filter_command.py": 4,
}


def pytest_collection_modifyitems(config, items):
    """Heavy files first, longest first; every other test after them in collection order."""
    rank = {name: k for k, name in enumerate(sorted(HEAVY_FILES, key=HEAVY_FILES.get, reverse=True))}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))
