"""Fixtures shared by every test folder: the bundled robots, loaded once per session; the number
of pytest-xdist workers of ``-n auto``."""

from __future__ import annotations

import os

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


def pytest_xdist_auto_num_workers(config):
    """``-n auto``: one worker per CPU this process may use, at most 4 (each worker holds Drake's
    plants and compiles or loads the kernels it needs: more workers mostly repeat that work)."""
    try:
        cpus = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cpus = os.cpu_count() or 1
    return max(1, min(cpus, 4))
