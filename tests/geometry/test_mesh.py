"""Mesh obstacles read from files: formats, scale, and the errors of bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh

from drake_mh.errors import DrakeMhError, ObstacleFileError, ObstacleFileNotFound, SceneError
from drake_mh.geometry import Mesh

DATA = Path(__file__).resolve().parents[1] / "data"


def test_formats_read_the_same_geometry_as_trimesh():
    for name in ("bin.obj", "bracket.obj", "cube.stl", "wedge.ply"):
        mesh = Mesh(DATA / name)
        reference = trimesh.load(DATA / name, force="mesh")
        assert np.allclose(mesh.bounds, reference.bounds)
        assert len(mesh.faces) == len(reference.faces)


def test_scale_one_number_or_three():
    metres = Mesh(DATA / "bracket.obj")
    millimetres = Mesh(DATA / "bracket_mm.stl", scale=0.001)
    assert np.allclose(millimetres.bounds, metres.bounds, atol=1e-9)
    stretched = Mesh(DATA / "cube.stl", scale=(2.0, 1.0, 0.5))
    assert np.allclose(np.ptp(stretched.vertices, axis=0), [0.2, 0.1, 0.05])
    assert stretched.digest != Mesh(DATA / "cube.stl").digest  # the scale is part of the name
    assert Mesh(DATA / "cube.stl") == Mesh(str(DATA / "cube.stl"), scale=[1.0])


def test_convexity():
    assert Mesh(DATA / "cube.stl").is_convex
    assert Mesh(DATA / "wedge.ply").is_convex
    assert not Mesh(DATA / "bin.obj").is_convex
    assert not Mesh(DATA / "bracket.obj").is_convex


@pytest.mark.parametrize("scale", [0, -1, np.nan, np.inf, "1", (1, 2), None, True, (1, 0, 1)])
def test_bad_scale(scale):
    with pytest.raises(ObstacleFileError, match="scale"):
        Mesh(DATA / "cube.stl", scale=scale)


def test_missing_unknown_empty_flat(tmp_path):
    with pytest.raises(ObstacleFileNotFound, match="no such file") as info:
        Mesh(tmp_path / "nothing.stl")
    assert isinstance(info.value, FileNotFoundError) and isinstance(info.value, SceneError)
    with pytest.raises(ObstacleFileNotFound):
        Mesh(tmp_path)  # a folder
    (tmp_path / "a.txt").write_text("v 0 0 0\n")
    with pytest.raises(ObstacleFileError, match="unknown mesh format"):
        Mesh(tmp_path / "a.txt")
    with pytest.raises(ObstacleFileError, match="no triangle"):
        Mesh(DATA / "empty.obj")
    with pytest.raises(ObstacleFileError, match="flat"):
        Mesh(DATA / "flat.obj")
    (tmp_path / "broken.stl").write_bytes(b"solid x\nfacet normal 0 0 1\n outer loop\n vertex 0 0 nope\n")
    with pytest.raises(DrakeMhError):
        Mesh(tmp_path / "broken.stl")
    with pytest.raises(ObstacleFileError, match="path"):
        Mesh(3)


def test_vtk_is_read_by_drake_as_its_hull(tmp_path):
    vtk = tmp_path / "tet.vtk"
    vtk.write_text("# vtk DataFile Version 3.0\ntet\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 4 double\n"
                   "0 0 0\n0.1 0 0\n0 0.1 0\n0 0 0.1\nCELLS 1 5\n4 0 1 2 3\nCELL_TYPES 1\n10\n")
    mesh = Mesh(vtk, scale=2.0)
    assert np.allclose(mesh.bounds, [[0, 0, 0], [0.2, 0.2, 0.2]])
    assert len(mesh.faces) == 4 and mesh.is_convex
