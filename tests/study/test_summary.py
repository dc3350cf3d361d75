"""The study-summary helpers: statistics against numpy, NaN and missing values skipped, tables and ranks."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_mh.study.report.summary import (cell, cpu_and_load, finished, group_by, load_range, markdown_table, mean,
                                           median, median_iqr, p95, quartiles, rank_lines, ratio, share, values)


def test_statistics_equal_numpy_and_skip_nan():
    rng = np.random.default_rng(0)
    x = rng.normal(size=101)
    with_nan = list(x) + [math.nan, float("nan")]
    assert median(with_nan) == pytest.approx(np.median(x))
    assert p95(with_nan) == pytest.approx(np.percentile(x, 95))
    assert mean(with_nan) == pytest.approx(np.mean(x))
    q25, q50, q75 = quartiles(with_nan)
    assert (q25, q50, q75) == pytest.approx(tuple(np.percentile(x, [25, 50, 75])))
    assert math.isnan(median([])) and math.isnan(p95([math.nan])) and math.isnan(mean([]))


def test_values_keep_finite_numbers_of_the_field_only():
    records = [{"t": 1.0}, {"t": None}, {"t": "x"}, {}, {"t": math.inf}, {"t": 2}, {"t": True}]
    assert values(records, "t", 1e3).tolist() == [1000.0, 2000.0, 1000.0]


def test_finished_share_ratio_and_cells():
    records = [{"status": "ok", "success": True}, {"status": "error"}, {"status": "ok", "success": False}]
    assert finished(records) == [records[0], records[2]]
    assert share(records) == pytest.approx(1 / 3) and math.isnan(share([]))
    assert ratio(6.0, 3.0) == 2.0 and math.isnan(ratio(1.0, 0.0)) and math.isnan(ratio(None, 1.0))
    assert cell(1.23456, ".2f") == "1.23" and cell(None) == "-" and cell(math.nan, ".1f", "n/a") == "n/a"
    assert median_iqr([1.0, 2.0, 3.0, 4.0, 5.0], ".1f") == "3.0 [2.0, 4.0]" and median_iqr([]) == "-"


def test_group_by_keeps_first_appearance_order():
    records = [{"m": "b", "s": 1}, {"m": "a", "s": 1}, {"m": "b", "s": 2}]
    assert list(group_by(records, "m")) == ["b", "a"]
    assert group_by(records, "m", "s")[("b", 2)] == [records[2]]


def test_markdown_table_lines():
    assert markdown_table(["a", "b"], [[1, "x"]]) == ["| a | b |", "|---|---|", "| 1 | x |"]


def test_machine_line_names_cpu_and_load_range():
    records = [{"cpu": "CPU X", "load_average": 1.0, "load_max": 3.0}, {"load_average": 2.0}]
    assert load_range(records, "load_average", "load_max") == (1.0, 3.0)
    line = cpu_and_load(records, loads=("load_average", "load_max"))
    assert line.startswith("CPU: CPU X (") and "1.0-3.0" in line


def test_rank_lines_order_the_methods_by_their_paired_ranks():
    rng = np.random.default_rng(1)
    records = []
    for block in range(12):
        for method, offset in (("fast", 0.0), ("mid", 1.0), ("slow", 2.0)):
            records.append({"status": "ok", "method": method, "block": block, "time": offset + 0.1 * rng.random()})
    records.append({"status": "error", "method": "fast", "block": 12})   # a failure ranks last in its block
    records += [{"status": "ok", "method": m, "block": 12, "time": 1.0} for m in ("mid", "slow")]
    lines = rank_lines(records, ["slow", "mid", "fast"], "time", ("block",), "Time")
    rows = [line.split(" | ")[0].strip("| ") for line in lines[4:]]
    assert rows == ["fast", "mid", "slow"]
    assert "13 blocks" in lines[0] and "fast wins/losses/ties" in lines[2]
    assert lines[5].split(" | ")[2] == "12/1/0"                          # fast against mid: lost the failed block
