"""Targets of the IK tests (the robots come from tests/conftest.py)."""

from __future__ import annotations

import numpy as np
import pytest



@pytest.fixture(scope="session")
def panda_targets(panda):
    """Poses ``(8, 4, 4)`` of random configurations within the limits (TRAC-IK protocol)."""
    return panda.batch.fk(panda.random_configurations(8, np.random.default_rng(2024)))
