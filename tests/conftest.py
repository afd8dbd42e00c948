"""Shared test set-up: deterministic hypothesis profile and the path to ../shared/data."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

settings.register_profile(
    "splineimu",
    derandomize=True,
    database=None,
    deadline=None,  # the first example pays JIT compilation
    max_examples=60,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "splineimu"))

REPO = Path(__file__).resolve().parent.parent
SHARED_DATA = Path(os.environ.get("SPLINEIMU_SHARED_DATA", REPO.parent / "shared" / "data"))


@pytest.fixture
def shared_data():
    """Path to ../shared/data; skips the test (naming the path) when it is absent."""
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data not found at {SHARED_DATA}")
    return SHARED_DATA


def require_shared(*parts) -> Path:
    """Path to a file in ../shared/data, or skip naming it."""
    p = SHARED_DATA.joinpath(*parts)
    if not p.exists():
        pytest.skip(f"shared data file not found: {p}")
    return p
