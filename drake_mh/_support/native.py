"""The compiled core ``drake_mh._native`` (C++ in ``cpp/``, built by ``pip install``:
docs/native.md), found in one place for every package.

Where it is built, the scene's collision check, the planners' motion checks, the verification's
clearances, inverse dynamics and the trajectory bounds run in it, with nothing compiled at call
time; where it is not, or the environment sets ``DRAKE_MH_COMPILED_CORE=0``, the numba kernels
answer the same questions.
"""

from __future__ import annotations

import importlib
import os
import sys

__all__ = ["ENVIRONMENT", "compiled_core"]

ENVIRONMENT = "DRAKE_MH_COMPILED_CORE"
"""``0`` in the environment: the numba kernels answer even where the compiled core is built (read
at each call of :func:`compiled_core`; a scene reads it when it binds its check)."""


def compiled_core():
    """The module ``drake_mh._native``, or None where it is not built or :data:`ENVIRONMENT` is
    ``0``. A module that is there but does not load (built for another Python) raises its
    ``ImportError``."""
    if os.environ.get(ENVIRONMENT, "1").strip() == "0":
        return None
    loaded = sys.modules.get("drake_mh._native")
    if loaded is not None:  # imported already (every call after the first)
        return loaded
    try:
        return importlib.import_module("drake_mh._native")
    except ModuleNotFoundError as error:
        if error.name != "drake_mh._native":
            raise
        return None  # not built: the kernels answer
