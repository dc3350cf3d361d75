"""optimizer_peers' statistics: rank-sum tests per cell, Holm per function and D, mealpy's run length."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from drake_mh.study.report.stats import holm

PATH = Path(__file__).resolve().parents[2] / "studies" / "optimizer_peers.py"


@pytest.fixture(scope="module")
def peers():
    spec = importlib.util.spec_from_file_location("optimizer_peers_under_test", PATH)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_rank_sum_is_mann_whitney_with_direction(peers):
    rng = np.random.default_rng(0)
    low, high = rng.random(10), 5.0 + rng.random(10)
    p, effect = peers.rank_sum(low, high)
    assert p == pytest.approx(stats.mannwhitneyu(low, high, alternative="two-sided").pvalue)
    assert effect == 1.0 and p < 1e-3                       # ours lower on every pair
    assert peers.rank_sum(high, low)[1] == 0.0
    assert peers.rank_sum(np.zeros(10), np.zeros(10)) == (1.0, 0.5)   # both solved every run
    p, effect = peers.rank_sum([], low)
    assert np.isnan(p) and np.isnan(effect)


def test_significance_pairs_each_of_our_entries_with_each_peer_and_holm_corrects(peers):
    rng = np.random.default_rng(1)
    records = []
    for rep in range(10):
        for function in (1, 3):
            for library, method, shift in (("drake_mh", "woa", 10.0), ("drake_mh", "woa_greedy", 0.0),
                                           ("mealpy", "mealpy_woa", 1.0)):
                records.append({"algorithm": "woa", "library": library, "method": method, "dim": 10,
                                "function": function, "rep": rep, "error": shift + rng.random()})
    tests = peers.significance(records)
    assert [(t["ours"], t["peer"], t["function"]) for t in tests] == [
        ("woa", "mealpy", 1), ("woa", "mealpy", 3), ("woa_greedy", "mealpy", 1), ("woa_greedy", "mealpy", 3)]
    assert all(t["n_ours"] == t["n_peer"] == 10 for t in tests)
    np.testing.assert_allclose([t["p_holm_all"] for t in tests], holm(np.array([t["p"] for t in tests])))
    for function in (1, 3):                                  # one family per function and D
        family = [t for t in tests if t["function"] == function]
        np.testing.assert_allclose([t["p_holm"] for t in family], holm(np.array([t["p"] for t in family])))
    verdicts = [peers._verdict(t).split()[0] for t in tests]
    assert verdicts == ["worse", "worse", "**better**", "**better**"]


def test_mealpy_run_length_follows_the_budget(peers):
    assert peers.mealpy_epochs(100_000, 30) == 3333          # 30 initial + 3333 x 30 >= 100,000
    assert peers.mealpy_epochs(10, 30) == 1
    assert peers.mealpy_epochs(10**9, 5) == 100_000          # mealpy's own upper limit


def test_variants_run_with_the_peers_population(peers):
    assert peers.OURS["woa_greedy"] == ("woa", "woa_greedy", {})
    assert peers.OURS["de_F1"] == ("de", "de", {"F": 1.0})
    assert [m for _, m in peers._entries("woa")][:2] == ["woa", "woa_greedy"]


def test_summary_keeps_complete_replicates_only(peers):
    records = []
    for rep in range(3):
        for library, method in (("drake_mh", "woa"), ("mealpy", "mealpy_woa")):
            if rep == 2 and library == "mealpy":
                continue                                     # the run was stopped in replicate 2
            records.append({"status": "ok", "algorithm": "woa", "library": library, "method": method, "dim": 10,
                            "function": 5, "rep": rep, "error": 1.0 + rep, "time": 1.0, "cpu_time": 1.0,
                            "nfe": 10, "budget": 10, "load": 1.0})
    text = peers.summarize(records)
    assert "2 replicate(s)" in text and "Left out: replicate(s) 2" in text
