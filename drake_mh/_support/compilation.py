"""Numba compilation made visible and shorter: the notice before a kernel compiles, the seconds
spent compiling, and one specialization per kernel.

Every numba kernel of the package is compiled on its first call on a machine and kept in
numba's disk cache (:mod:`drake_mh._support.numba_cache`); from an empty cache a first plan compiles for
minutes. So:

* :func:`install` (called when :mod:`drake_mh` is imported) listens to numba's compile events
  once numba is imported: before a kernel of the package compiles at the top level (called from
  Python, not from another kernel), one line goes to the ``drake_mh.compile`` logger at WARNING,
  which Python prints on stderr when the user configured no logging; it names the kernel, about
  how long it takes here from an empty cache (:data:`KERNELS`) and where it is cached.
  :func:`compile_seconds` counts the seconds spent compiling, for callers that report them.
* :func:`stable_calls` makes a kernel that other kernels call compile once per argument *types*,
  not once per constant *value* a caller passes (numba compiles a separate copy of a kernel for
  ``f(0)`` and for ``f(i)``; for some kernels each copy took 5-20 s).
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import inspect
import logging
import os
import sys
import threading
import time

logger = logging.getLogger("drake_mh.compile")

KERNELS = {
    "collision_free_one": ("the scene's collision check of one configuration", 21),
    "collision_free_packed": ("the scene's batched collision check", 28),
    "obstacle_clearances_packed": ("the scene's batched clearances", 25),
    "certify_segments": ("the certified motion check", 57),
    "plan_kernel": ("rrt_connect's planner", 110),
    "certify_motions": ("rrt_connect's motion check", 95),
    "prm_kernel": ("lazy_prm_star's planner", 200),
}
"""What the kernels a user's first calls compile do, and the CPU seconds each takes from an empty
cache on the reference machine (2-core AMD EPYC; ``drake-mh study first_call``). Others take a
few seconds to a minute."""

_STATE = {"depth": 0, "seconds": 0.0, "started": 0.0, "first": True, "installed": False}
_LOCK = threading.Lock()


def compile_seconds() -> float:
    """Seconds this process has spent compiling the package's kernels (top-level compiles, their
    callees included); read it before and after a call to get that call's share."""
    with _LOCK:
        running = time.perf_counter() - _STATE["started"] if _STATE["depth"] and _STATE.get("ours") else 0.0
        return _STATE["seconds"] + running


def _cache_folder() -> str:
    return os.environ.get("NUMBA_CACHE_DIR") or "numba's default folder next to the sources"


def _announce(name: str) -> None:
    what, seconds = KERNELS.get(name, (None, None))
    about = f"{what}, about {seconds} s" if what else "seconds to a minute"
    if _STATE["first"]:
        _STATE["first"] = False
        logger.warning("drake_mh: compiling %s (%s, once per machine: cached in %s; `drake-mh warmup` compiles "
                       "every kernel ahead)", name, about, _cache_folder())
    else:
        logger.warning("drake_mh: compiling %s (%s, once per machine)", name, about)


def _listener():
    from numba.core import event

    class CompileListener(event.Listener):
        """Announces and times the top-level compiles of the package's kernels."""

        def on_start(self, ev):
            dispatcher = ev.data.get("dispatcher")
            module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
            with _LOCK:
                _STATE["depth"] += 1
                if _STATE["depth"] != 1:
                    return
                _STATE["started"] = time.perf_counter()
                _STATE["ours"] = module.startswith("drake_mh.")
            if _STATE["ours"]:
                _announce(dispatcher.py_func.__name__)

        def on_end(self, ev):
            with _LOCK:
                _STATE["depth"] -= 1
                if _STATE["depth"] == 0 and _STATE.get("ours"):
                    _STATE["seconds"] += time.perf_counter() - _STATE["started"]

    event.register("numba:compile", CompileListener())


class _AfterNumbaImport(importlib.abc.MetaPathFinder):
    """Registers the listener right after ``numba`` is imported (importing numba here would add a
    second to every ``import drake_mh``)."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname != "numba":
            return None
        sys.meta_path.remove(self)
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is None or spec.loader is None:
            return spec
        exec_module = spec.loader.exec_module

        def exec_then_listen(module):
            exec_module(module)
            _register()

        spec.loader.exec_module = exec_then_listen
        return spec


class _SharedBlockCopies:
    """Stands for the ``copy`` module in numba's ``inline_closurecall``, whose ``inline_ir`` copies
    an inlined function's IR block by block, each with its own ``copy.deepcopy`` memo: every block's
    copy then copies the function's whole variable scope again (blocks x variables). Here the
    blocks of one copy share one memo, as a ``deepcopy`` of all of them at once would: the same
    copied IR, made once (inlining measured 25 % of a kernel's compile time). A copy starts anew
    at a block of another scope or at a block it copied already (the next copy of that IR)."""

    def __init__(self, copy_module, block_type):
        self._copy, self._block = copy_module, block_type
        self._scope, self._memo, self._seen = None, None, set()

    def deepcopy(self, x, memo=None):
        if memo is not None or not isinstance(x, self._block):
            return self._copy.deepcopy(x, memo)
        if x.scope is not self._scope or id(x) in self._seen:
            self._scope, self._memo, self._seen = x.scope, {}, set()
        self._seen.add(id(x))
        return self._copy.deepcopy(x, self._memo)

    def __getattr__(self, name):
        return getattr(self._copy, name)


def _share_inline_copies() -> None:
    """Install :class:`_SharedBlockCopies` where numba's inliner reads ``copy`` (nothing if its
    code is not the one this was written for, or with ``DRAKE_MH_SHARED_INLINE_COPIES=0``)."""
    import copy

    from numba.core import inline_closurecall, ir

    source = inspect.getsource(inline_closurecall.InlineWorker.inline_ir)
    if os.environ.get("DRAKE_MH_SHARED_INLINE_COPIES", "1") == "0" or inline_closurecall.copy is not copy \
            or "copy.deepcopy(the_ir.blocks[block_label])" not in source:
        return
    inline_closurecall.copy = _SharedBlockCopies(copy, ir.Block)


def _register() -> None:
    if not _STATE["installed"]:
        _STATE["installed"] = True
        try:
            _listener()
            _share_inline_copies()
        except Exception:  # noqa: BLE001 - another numba: no notice or shorter inlining, kernels still work
            logger.debug("numba's compile events or inliner are not those expected", exc_info=True)


def install() -> None:
    """Announce and time the package's compiles (module docstring): now if numba is imported,
    else right after it is."""
    if "numba" in sys.modules:
        _register()
    elif not any(isinstance(f, _AfterNumbaImport) for f in sys.meta_path):
        sys.meta_path.insert(0, _AfterNumbaImport())


def stable_calls(*literal: str):
    """Decorator over ``numba.njit(...)``: a call from another kernel compiles this one for the
    argument types with their constant values dropped (``f(0)`` and ``f(i)`` share one compiled
    copy), except for the parameters named in ``literal``, whose constant values choose code at
    compile time (numba prunes the branches they decide).

    Calls from Python never pass constant values, so they are unchanged.
    """

    def wrap(dispatcher):
        from numba.core import types

        names = list(inspect.signature(dispatcher.py_func).parameters)
        unknown = set(literal) - set(names)
        if unknown:
            raise ValueError(f"stable_calls: {dispatcher.py_func.__name__} has no parameter {sorted(unknown)}")
        kept = {names.index(name) for name in literal}
        get_call_template = dispatcher.get_call_template

        def call_template(args, kws):
            args = tuple(a if i in kept else types.unliteral(a) for i, a in enumerate(args))
            kws = {k: v if k in literal else types.unliteral(v) for k, v in kws.items()}
            return get_call_template(args, kws)

        dispatcher.get_call_template = call_template
        return dispatcher

    return wrap
