"""Shared fixtures of the cyclic-planning tests (robots load once per session)."""

from __future__ import annotations

import pytest

import drake_mh


@pytest.fixture(scope="session")
def planar12():
    return drake_mh.load_robot("planar12")


@pytest.fixture(scope="session")
def planar5():
    return drake_mh.load_robot("planar5")
