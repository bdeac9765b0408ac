"""Shared fixtures: the real third-party data in ../shared/data, skipped only when absent."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import settings

# Property tests draw the same examples on every run and machine, so a test run is reproducible
# (a CI failure can be re-run); `HYPOTHESIS_PROFILE=explore` draws fresh examples to hunt for new
# failures, which then become fixed regression tests.
settings.register_profile("ci", derandomize=True, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

ROOT = Path(__file__).resolve().parents[1]
SHARED_DATA = ROOT.parent / "shared" / "data"


def require_shared(*parts: str) -> Path:
    """Path under ../shared/data; skip when the folder is absent, fail when CI requires it."""
    path = SHARED_DATA.joinpath(*parts)
    if not path.exists():
        msg = f"shared data not found: {path}"
        if os.environ.get("WELDPLAN_REQUIRE_SHARED") == "1":
            pytest.fail(msg + " (WELDPLAN_REQUIRE_SHARED=1)")
        pytest.skip(msg)
    return path


@pytest.fixture
def shared_data() -> Path:
    return require_shared()
