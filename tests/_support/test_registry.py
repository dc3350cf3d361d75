"""The method registry (drake_mh._support.registry) and the three tables that use it: IK,
planning and the optimizers list the same names through it as through their entry points."""

from __future__ import annotations

import subprocess
import sys

import pytest

from drake_mh._support.registry import Registry
from drake_mh.errors import UnknownMethod


def _table():
    loaded = []

    def load():
        loaded.append(1)
        return "built"

    table = Registry("toy method", case_sensitive=False)
    table.add("direct", 42, description="the value itself")
    table.add("by_string", load="math:sqrt", description="imported on first use")
    table.add("by_call", load=load, description="built on first use")
    table.add("by_factory", load="operator:mul", args=(6, 7), description="a factory's answer")
    table.add("peer", load="no_such_module_xyz:f", requires=("no_such_module_xyz",), description="optional")
    return table, loaded


def test_lookups_load_once_and_an_absent_peer_is_unknown():
    import math

    table, loaded = _table()
    assert table.names() == ["direct", "by_string", "by_call", "by_factory"]  # the peer cannot import
    assert table.available()["by_string"] == "imported on first use"
    assert table.get("DIRECT") == 42 and table["by_string"] is math.sqrt and table.get("by_factory") == 42
    assert loaded == []  # listing and other lookups build nothing
    assert table.get("by_call") == "built" and table.get("by_call") == "built" and loaded == [1]
    assert "by_call" in table and "peer" not in table and 3 not in table and len(table) == 4
    with pytest.raises(UnknownMethod, match=r"unknown toy method 'peer'; available: by_call, by_factory"):
        table.get("peer")
    with pytest.raises(UnknownMethod):
        table.get(None)


def test_a_method_is_the_value_or_where_to_load_it_not_both():
    table = Registry("toy method")
    with pytest.raises(TypeError):
        table.add("both", 1, load="math:pi")
    with pytest.raises(TypeError):
        table.add("neither")


def test_register_adds_the_decorated_function_and_extend_runs_once_before_the_first_read():
    calls = []

    def extend(registry):
        calls.append(1)
        registry.add("late", 1, description="added on first read")

    table = Registry("toy method", extend=extend)

    @table.register("early", "a decorated function")
    def early():
        return "early"

    assert calls == []
    assert table.names() == ["early", "late"] and table.names() == ["early", "late"] and calls == [1]
    assert table.get("early") is early
    with pytest.raises(UnknownMethod):
        table.get("EARLY")  # case-sensitive by default
    table.remove("early")
    assert table.names() == ["late"]


def test_the_three_tables_agree_with_their_entry_points():
    from drake_mh.ik import GRADIENT_METHODS, available_ik_methods
    from drake_mh.ik.solve import METHODS as IK
    from drake_mh.optim import METHODS as OPTIM
    from drake_mh.optim import available_methods, get_method
    from drake_mh.planning import available_motion_methods, get_motion_method
    from drake_mh.planning.methods import METHODS as PLANNING

    optimizers = available_methods()
    assert optimizers == OPTIM.names() and get_method("PSO") is OPTIM.get("pso")
    assert available_ik_methods() == optimizers + list(GRADIENT_METHODS) == IK.names()
    planners = available_motion_methods()
    assert list(planners) == PLANNING.names()
    assert {f"mh_{name}" for name in optimizers} <= set(planners)
    assert {"straight", "rrt_connect", "rrt_connect_smooth", "lazy_prm_star", "drake_kto",
            "drake_kto_warm"} <= set(planners)
    assert callable(get_motion_method("rrt_connect").prepare) and callable(get_motion_method("mh_de").prepare)


def test_importing_the_planning_table_imports_no_planner():
    code = ("import sys, drake_mh.planning\n"
            "planners = ('rrt_connect', 'lazy_prm_star', 'drake_kto', 'viapoint_mh', 'ompl_peer')\n"
            "loaded = [m for m in sys.modules if m.startswith('drake_mh.planning.') and m.split('.')[2] in planners]\n"
            "assert not loaded, loaded\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=1800)
    assert done.returncode == 0, done.stderr[-2000:]
