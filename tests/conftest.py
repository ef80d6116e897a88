"""Shared fixtures: where the real C3D files live, and a skip where they are absent."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED_C3D = REPO.parent / "shared" / "data" / "c3d"


@pytest.fixture(scope="session")
def shared_c3d_dir() -> Path:
    """``../shared/data/c3d`` next to the checkout; the test is skipped where it is absent."""
    if not SHARED_C3D.is_dir():
        pytest.skip("../shared/data/c3d is not present next to this checkout")
    return SHARED_C3D
