"""Shared fixtures. Tests that need the real measurements in ../shared/data skip without them."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")  # figures are written to files; no display in CI

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = Path(os.environ.get("ROUGHBRDF_SHARED_DATA", ROOT.parent / "shared" / "data"))


@pytest.fixture(scope="session")
def shared_data() -> Path:
    """Path of ../shared/data (real measurements); skips the test when it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"real measurement data not found at {SHARED_DATA} (the ../shared folder "
                    "beside the checkout); set ROUGHBRDF_SHARED_DATA to run these tests")
    return SHARED_DATA
