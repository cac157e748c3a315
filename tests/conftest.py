"""Shared fixtures: the public map corpus in ../shared/maps (skipped when absent)."""

from __future__ import annotations

from pathlib import Path

import pytest

SHARED_MAPS = Path(__file__).resolve().parents[2] / "shared" / "maps"


@pytest.fixture
def shared_maps() -> Path:
    """The folder of real public map files beside the checkout, or skip."""
    if not SHARED_MAPS.is_dir():
        pytest.skip(f"public map corpus not found at {SHARED_MAPS}")
    return SHARED_MAPS


@pytest.fixture
def optional_shared_maps() -> Path | None:
    """The public map corpus folder, or None when it is absent (for tests that need not skip)."""
    return SHARED_MAPS if SHARED_MAPS.is_dir() else None
