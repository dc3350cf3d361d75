"""Fixtures of the trajectory tests."""

from __future__ import annotations

import pytest

import drake_mh


@pytest.fixture(scope="session")
def panda():
    return drake_mh.load_robot("panda")


@pytest.fixture(scope="session")
def planar2r():
    return drake_mh.load_robot("planar2r")
