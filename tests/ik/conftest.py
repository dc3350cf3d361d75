"""Shared robots and targets of the IK tests (loaded once per session)."""

from __future__ import annotations

import numpy as np
import pytest

import drake_mh


@pytest.fixture(scope="session")
def panda():
    return drake_mh.load_robot("panda")


@pytest.fixture(scope="session")
def six_dof():
    return drake_mh.load_robot("seed000_6dof")


@pytest.fixture(scope="session")
def panda_targets(panda):
    """Poses ``(8, 4, 4)`` of random configurations within the limits (TRAC-IK protocol)."""
    return panda.batch.fk(panda.random_configurations(8, np.random.default_rng(2024)))
