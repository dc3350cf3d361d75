"""Compilation made visible and shorter (drake_mh/_support/compilation.py): the notice before a kernel
compiles, the seconds counted, one specialization per kernel, the inliner's shared copies."""

from __future__ import annotations

import copy
import logging
import os
import subprocess
import sys
import textwrap
import threading

import numba
import numpy as np
import pytest

import drake_mh  # noqa: F401 - installs the compile listener
from drake_mh._support import compilation as _compile
from drake_mh._support.native import ENVIRONMENT, compiled_core


def _kernel_in(module: str, source: str, name: str):
    """A fresh numba kernel whose function belongs to ``module`` (compiled on its first call)."""
    namespace = {"np": np, "numba": numba}
    exec(textwrap.dedent(source), namespace)  # noqa: S102 - test source
    function = namespace[name]
    function.__module__ = module
    return numba.njit(cache=False)(function)


def test_a_package_kernel_is_announced_and_timed(caplog):
    kernel = _kernel_in("drake_mh.fake_kernels", """
        def summed(x):
            s = 0.0
            for v in x:
                s += v
            return s
    """, "summed")
    before = _compile.compile_seconds()
    with caplog.at_level(logging.WARNING, logger="drake_mh.compile"):
        assert kernel(np.arange(4.0)) == 6.0
        kernel(np.arange(3.0))  # compiled already: no second notice
    notices = [r.getMessage() for r in caplog.records if r.name == "drake_mh.compile"]
    assert len(notices) == 1 and "compiling summed" in notices[0]
    assert _compile.compile_seconds() > before


def test_other_kernels_are_neither_announced_nor_counted(caplog):
    kernel = _kernel_in("user_code", "def twice(x):\n    return 2 * x\n", "twice")
    before = _compile.compile_seconds()
    with caplog.at_level(logging.WARNING, logger="drake_mh.compile"):
        assert kernel(2.0) == 4.0
    assert not [r for r in caplog.records if r.name == "drake_mh.compile"]
    assert _compile.compile_seconds() == before


def _callers(callee):
    @numba.njit(cache=False)
    def with_constant(x):
        return callee(x, 0)

    @numba.njit(cache=False)
    def with_variable(x, i):
        return callee(x, i)

    return with_constant, with_variable


def _offset(x, i):
    return x + i


def test_stable_calls_compiles_one_copy_for_constants_and_variables():
    plain = numba.njit(cache=False)(_offset)
    stable = _compile.stable_calls()(numba.njit(cache=False)(_offset))
    for callee, copies in ((plain, 2), (stable, 1)):
        with_constant, with_variable = _callers(callee)
        assert with_constant(1.0) == 1.0 and with_variable(1.0, 2) == 3.0
        assert len(callee.signatures) == copies  # numba's own: one copy for f(x, 0), one for f(x, i)


def test_stable_calls_keeps_the_constants_it_is_told_to():
    stable = _compile.stable_calls("i")(numba.njit(cache=False)(_offset))
    with_constant, with_variable = _callers(stable)
    assert with_constant(1.0) == 1.0 and with_variable(1.0, 2) == 3.0
    assert len(stable.signatures) == 2
    with pytest.raises(ValueError, match="no parameter"):
        _compile.stable_calls("j")(numba.njit(cache=False)(_offset))


def _branchy(x):
    s = 0.0
    for i in range(x.shape[0]):
        if x[i] > 0:
            s += x[i]
        else:
            s -= 2 * x[i]
    return s


def test_shared_block_copies_equal_numba_s_own_copies():
    """The inliner's copy of a function's IR, block by block: the same blocks as numba's own
    (a fresh deepcopy per block), sharing one scope as the original blocks do."""
    from numba.core import ir
    from numba.core.compiler import run_frontend

    blocks = run_frontend(_branchy).blocks
    shared = _compile._SharedBlockCopies(copy, ir.Block)
    for _ in range(2):  # a second copy of the same IR starts anew
        ours = {label: shared.deepcopy(block) for label, block in blocks.items()}
        numbas = {label: copy.deepcopy(block) for label, block in blocks.items()}
        assert ours.keys() == numbas.keys()
        for label in blocks:
            assert [str(s) for s in ours[label].body] == [str(s) for s in numbas[label].body]
            assert ours[label] is not blocks[label] and ours[label].scope is not blocks[label].scope
        assert len({id(b.scope) for b in ours.values()}) == len({id(b.scope) for b in blocks.values()})


FIRST_PLAN = """
    import sys
    import numpy as np
    import drake_mh
    from drake_mh.planning import MotionProblem, solve_motion
    from drake_mh.scene import Box, Scene, Sphere
    panda = drake_mh.load_robot("panda")
    scene = Scene(panda)
    scene.add("ball", Sphere(0.1), [0.5, 0.0, 0.5])
    scene.add("table", Box(1.0, 1.0, 0.05), [0.5, 0.0, -0.05])
    print("MARK before", file=sys.stderr, flush=True)
    problem = MotionProblem(panda, scene, panda.home.copy(), np.array([1.0, 0.3, 0.0, -1.5, 0.0, 1.8, 0.7]),
                            clearance=0.01)
    print("MARK problem built", file=sys.stderr, flush=True)
    result = solve_motion(problem, "rrt_connect", seed=0)
    print("MARK planned", result.success, result.info["compile_time"], file=sys.stderr, flush=True)
"""


def _first_plan_lines(tmp_path, core: str) -> list[str]:
    """stderr of the first-plan script in a new process with an empty kernel cache, up to the
    first compile notice or the end of the plan (the process is then stopped)."""
    script = tmp_path / "first_plan.py"
    script.write_text(textwrap.dedent(FIRST_PLAN))
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "DRAKE_MH_NUMBA_CACHE_DIR")}
    env["DRAKE_MH_CACHE"] = str(tmp_path / "cache")
    env[ENVIRONMENT] = core
    process = subprocess.Popen([sys.executable, str(script)], env=env, stderr=subprocess.PIPE, text=True)
    watchdog = threading.Timer(1800, process.kill)
    watchdog.start()
    lines = []
    try:
        for line in process.stderr:
            lines.append(line.rstrip("\n"))
            if line.startswith(("drake_mh: compiling", "MARK planned")):
                break
    finally:
        process.kill()
        process.communicate()
        watchdog.cancel()
    return lines


@pytest.mark.slow
def test_a_first_plan_compiles_nothing_with_the_compiled_core(tmp_path):
    """The first-plan script from an empty cache, in a new process, with the compiled core (what
    the install line builds): it plans, retimes and verifies without compiling any kernel."""
    if compiled_core() is None:
        pytest.skip("the compiled core drake_mh._native is not built (pip install . builds it)")
    lines = _first_plan_lines(tmp_path, "1")
    assert lines and lines[-1].startswith("MARK planned"), "\n".join(lines[-40:])
    assert not any(line.startswith("drake_mh: compiling") for line in lines)
    assert lines[-1].split()[2:] == ["True", "0.0"]  # success, and no compile time inside the call


@pytest.mark.slow
def test_a_first_plan_says_what_compiles_before_it_compiles(tmp_path):
    """The same script on the numba kernels (``DRAKE_MH_COMPILED_CORE=0``): the notice is on
    stderr after the script started and while a call is still compiling (the marker that follows
    the plan not yet written), naming where it is cached; the process is then stopped, so the
    test does not wait for the compilation."""
    lines = _first_plan_lines(tmp_path, "0")
    assert lines and lines[-1].startswith("drake_mh: compiling"), "\n".join(lines[-40:])
    assert "MARK before" in lines  # announced after the script started, while the call still runs
    assert str(tmp_path / "cache") in lines[-1]  # says where it is cached
