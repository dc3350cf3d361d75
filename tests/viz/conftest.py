"""Fixtures of the visualisation tests: one Meshcat server (localhost) for the whole session."""

from __future__ import annotations

import pytest

import drake_mh


@pytest.fixture(scope="session")
def meshcat():
    """This process's shared Meshcat server (first free port from 7000, localhost only)."""
    from drake_mh.viz import get_meshcat

    return get_meshcat(announce=False)


@pytest.fixture
def scene(panda):
    """A Panda scene with a resting box and a moving sphere."""
    scene = drake_mh.Scene(panda)
    scene.add("box", drake_mh.Box((0.2, 0.2, 0.2)), [0.55, -0.3, 0.3])
    scene.add("ball", drake_mh.Sphere(0.08), [0.45, 0.25, 0.55], velocity=[0.0, -0.1, 0.0])
    return scene
