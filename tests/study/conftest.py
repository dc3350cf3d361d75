"""Fixtures of the study runner tests."""

from __future__ import annotations

from pathlib import Path

import pytest
from study_toys import write_toy


@pytest.fixture
def toy(tmp_path: Path) -> Path:
    """Path of a fast toy study: 2 instances x 3 methods x 4 reps, one case raises."""
    return write_toy(tmp_path)
