"""drake_mh: metaheuristic and gradient motion planning side by side on Drake.

The public entry points are importable from the top level; heavy sub-packages
(optimizers, IK, studies, visualisation) are imported lazily on first access.
"""

from __future__ import annotations

import importlib

from drake_mh._support import compilation, numba_cache

numba_cache.configure()  # before any kernel module is imported: numba's cache, keyed by the sources
compilation.install()  # one line on stderr before a kernel compiles (drake_mh._support.compilation)

from drake_mh import errors  # noqa: E402

__version__ = "0.1.0"

# name -> module that defines it; resolved on first attribute access (PEP 562)
_LAZY = {
    "Robot": "drake_mh.robot",
    "load_robot": "drake_mh.robot",
    "available_robots": "drake_mh.robot",
    "register_robot": "drake_mh.robot",
    "BatchKinematics": "drake_mh.kinematics",
    "Scene": "drake_mh.scene",
    "Sphere": "drake_mh.scene",
    "Box": "drake_mh.scene",
    "Cylinder": "drake_mh.scene",
    "Mesh": "drake_mh.scene",
    "PointCloud": "drake_mh.scene",
    "SphereModel": "drake_mh.geometry.spheres",
    "dh_to_urdf": "drake_mh.robot.dh",
    "minimize": "drake_mh.optim",
    "OptimizeResult": "drake_mh.optim",
    "retime": "drake_mh.trajectories",
    "certify": "drake_mh.trajectories",
    "Trajectory": "drake_mh.trajectories",
    "solve_ik": "drake_mh.ik",
    "IKProblem": "drake_mh.ik",
    "IKResult": "drake_mh.ik",
}

__all__ = ["errors", "__version__", *_LAZY]


def __getattr__(name: str):
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'drake_mh' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__():
    return sorted(__all__)
