"""Fixtures shared by every test folder: the bundled robots, loaded once per session."""

from __future__ import annotations

import pytest

import drake_mh


@pytest.fixture(scope="session")
def panda():
    return drake_mh.load_robot("panda")


@pytest.fixture(scope="session")
def six_dof():
    return drake_mh.load_robot("seed000_6dof")


@pytest.fixture(scope="session")
def planar5():
    return drake_mh.load_robot("planar5")


@pytest.fixture(scope="session")
def planar12():
    return drake_mh.load_robot("planar12")


@pytest.fixture(scope="session")
def planar2r():
    return drake_mh.load_robot("planar2r")
