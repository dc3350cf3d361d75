"""What a reader sees in a report: grouped rows, units, reasons for failures, readable figures,
and the demo page's reuse notice and fresh runs."""

import dataclasses
import datetime

import numpy as np
import pytest

from drake_mh.errors import InvalidArgument
from drake_mh.study import Fields, write_report
from drake_mh.study.report import ReportData, method_table
from drake_mh.study.report import plots
from drake_mh.study.report.document import Document, Paragraph, Table, to_html
from drake_mh.study.report.units import time_unit, with_unit
from drake_mh.study.store import RecordStore


def _results(folder, fields: Fields, records: list[dict]):
    """A results folder with ``study.json`` declaring ``fields`` and the given records."""
    store = RecordStore(folder)
    store.prepare({"name": "layout", "seed": 0, "quick": True, "fields": fields.to_dict(),
                   "grid_keys": ["case", "method", "rep"], "n_cases": len(records)})
    for i, record in enumerate(records):
        store.append({"key": f"case={record['case']}/method={record['method']}/rep={record['rep']}",
                      "case_id": f"c{i}", "status": "ok", **record})
    return folder


def _two_kinds(n_reps=6):
    """Two instances of a different scale (fitness about 15 and 21), two methods; pso fails at 'big'."""
    records = []
    for case, level in (("small", 15.0), ("big", 21.0)):
        for method in ("ga", "pso"):
            for rep in range(n_reps):
                ok = not (method == "pso" and case == "big")
                records.append({"case": case, "method": method, "rep": rep, "fitness": level + 0.01 * rep,
                                "time": 0.002 + 0.0001 * rep, "nfe": 2000 if not ok else 900 + rep,
                                "success": ok, "message": "" if ok else "budget exhausted"})
    return records


def _filled(rows):
    """``(group of the row, row)``: the group name carried down to the rows that leave it blank."""
    group = None
    for row in rows:
        group = row[0] or group
        yield group, row


FIELDS = Fields(error="fitness", group_by=("case",), error_unit="rad",
                conditions="2000 evaluations; success = fitness below the reference + 1e-6")


def test_report_fields_round_trip():
    assert Fields.from_dict(FIELDS.to_dict()) == FIELDS
    assert Fields.from_dict({"method": "m"}).group_by is None  # results written before group_by


def test_rows_per_group_do_not_pool_instances(tmp_path):
    data = ReportData.load(_results(tmp_path, FIELDS, _two_kinds()))
    table = method_table(data)
    assert table.headers[:2] == ["case", "method"]
    assert [r[0] for r in table.rows] == ["big", "", "small", ""]  # a group's name on its first row
    rows = {(r[0] or prev, r[1]): dict(zip(table.headers, r)) for prev, r in _filled(table.rows)}
    assert list(rows) == [("big", "ga"), ("big", "pso"), ("small", "ga"), ("small", "pso")]
    # medians per instance (15.025 and 21.025), never the pooled 18 of both
    assert rows[("small", "ga")]["fitness median [rad]"] == "15"
    assert rows[("big", "ga")]["fitness median [rad]"] == "21"
    assert "One row per case and method" in table.caption


def test_every_header_states_its_unit_and_times_are_scaled(tmp_path):
    data = ReportData.load(_results(tmp_path, FIELDS, _two_kinds()))
    table = method_table(data)
    assert "time median [ms]" in table.headers and "success [%]" in table.headers
    assert "nfe median [count]" in table.headers
    row = dict(zip(table.headers, table.rows[0]))
    assert row["time median [ms]"] == "2.25"  # 2.25e-3 s shown in ms
    assert time_unit([2e-6, 3e-6]) == ("µs", 1e6) and time_unit([0.5]) == ("ms", 1e3) and time_unit([12.0]) == ("s", 1.0)
    assert with_unit("error", "") == "error [-]" and with_unit("error", None) == "error"


def test_a_failing_row_says_why(tmp_path):
    data = ReportData.load(_results(tmp_path, FIELDS, _two_kinds()))
    table = method_table(data)
    assert table.headers[-1] == "why not 100 %"
    rows = {(r[0] or prev, r[1]): r[-1] for prev, r in _filled(table.rows)}
    note = rows[("big", "pso")]
    assert note.startswith("6/6 failed: budget spent (2,000 evaluations each); fitness 21 rad (median)")
    assert note.endswith('6x "budget exhausted"')
    assert rows[("small", "ga")] == ""
    assert "2000 evaluations; success = fitness below" in table.caption


def test_html_renders_inline_code_and_keeps_numbers_whole():
    doc = Document("t")
    doc.add(Paragraph("`vs SNOPT` = **mean** time"))
    doc.add(Table(["time median [ms]", "note"], [["12,345.678", "ga"], ["1.5e-05", "x" * 60]]))
    page = to_html(doc)
    assert "<code>vs SNOPT</code>" in page and "<strong>mean</strong>" in page and "`" not in page.split("<body>")[1]
    assert "<th>time median [ms]</th>" in page
    assert "<td>12,345.678</td>" in page and "<td>1.5e-05</td>" in page  # numbers: nowrap (CSS td)
    assert "td{white-space:nowrap}" in page
    assert '<td class="name">ga</td>' in page and '<td class="text">' in page
    assert '<th class="text">note</th>' in page  # a column of long text is left-aligned, header included


def test_units_in_headers_do_not_break():
    doc = Document("t")
    doc.add(Table(["error median [m + rad]"], [["1"]]))
    assert "[m\u00a0+\u00a0rad]" in to_html(doc)


def _captured(monkeypatch):
    figures = []
    render = plots._render

    def capture(fig):
        figures.append(fig)
        return render(fig)

    monkeypatch.setattr(plots, "_render", capture)
    return figures


def test_small_samples_are_points_large_ones_boxes(tmp_path, monkeypatch):
    figures = _captured(monkeypatch)
    few = ReportData.load(_results(tmp_path / "few", FIELDS, _two_kinds(n_reps=3)))
    assert plots.box_figure(few) is not None
    axes = [ax for ax in figures[-1].axes if ax.get_visible()]
    assert len(axes) == 4  # time and fitness, per case: instances are not pooled
    assert sorted({ax.get_title() for ax in axes}) == ["case = big", "case = small"]
    for ax in axes:
        assert len(ax.collections) == 2 and all(len(c.get_offsets()) == 3 for c in ax.collections)
    many = ReportData.load(_results(tmp_path / "many", FIELDS, _two_kinds(n_reps=8)))
    plots.box_figure(many)
    for ax in (a for a in figures[-1].axes if a.get_visible()):
        assert len(ax.collections) == 0 and len(ax.lines) >= 2 * 5  # box, whiskers, caps, median


def test_one_method_per_group_shares_a_panel(tmp_path, monkeypatch):
    figures = _captured(monkeypatch)
    records = [{"case": n, "method": "panda", "rep": 0, "time": 1e-6 * n ** 0.5, "success": True} for n in (1, 128, 1024)]
    data = ReportData.load(_results(tmp_path, Fields(group_by=("case",), rank=False), records))
    plots.box_figure(data)
    (ax,) = [a for a in figures[-1].axes if a.get_visible()]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["case = 1", "case = 128", "case = 1024"]
    assert ax.get_ylabel() == "time [µs]"


def test_tick_labels_are_plain_numbers(tmp_path, monkeypatch):
    assert plots.linear_tick_labels([21.10128, 21.1013, 21.10132]) == ["21.10128", "21.10130", "21.10132"]
    assert plots.linear_tick_labels([0.1, 0.2, 0.30000000000000004]) == ["0.1", "0.2", "0.3"]
    assert plots.linear_tick_labels([2e-16, 4e-16]) == ["2e-16", "4e-16"]
    figures = _captured(monkeypatch)
    records = [{"case": "a", "method": m, "rep": r, "time": 0.001, "fitness": v, "success": True}
               for m, base in (("x", 1e-4), ("y", 1.0)) for r, v in enumerate(base * np.linspace(1, 3, 6))]
    data = ReportData.load(_results(tmp_path, dataclasses.replace(FIELDS, group_by=None), records))
    plots.box_figure(data)
    fig = figures[-1]
    fig.canvas.draw()
    error_ax = [a for a in fig.axes if a.get_visible()][1]
    assert error_ax.get_yscale() == "log"
    labels = [t.get_text() for t in error_ax.get_yticklabels() if t.get_text()]
    assert labels and "0.001" in labels and "1" in labels
    assert not any("\\times" in s or "$" in s or "×" in s for s in labels)


def test_report_of_grouped_study_is_written(tmp_path):
    index = write_report(_results(tmp_path, FIELDS, _two_kinds()))
    md = (tmp_path / "report.md").read_text()
    assert "| case | method |" in md and "why not 100 %" in md
    assert index.is_file()


# --- demo: reuse notice and fresh runs --------------------------------------------------------


def test_demo_move_aside_keeps_earlier_results(tmp_path):
    from drake_mh.study.demo import earlier_results, move_aside, reuse_message

    out = tmp_path / "demo"
    _results(out / "ik_comparison", FIELDS, _two_kinds(n_reps=1))
    earlier = earlier_results(out, ["bench_kinematics", "ik_comparison"])
    assert earlier.total == 4 and earlier.cases == {"ik_comparison": 4}
    message = reuse_message(out, earlier)
    assert "Reusing 4 finished cases" in message and str(out) in message and "--fresh" in message
    moved = move_aside(out, ["ik_comparison"], now=datetime.datetime(2026, 1, 2, 3, 4, 5))
    assert moved == tmp_path / "demo-20260102-030405"
    assert not out.exists() and len(RecordStore(moved / "ik_comparison").records()) == 4
    assert move_aside(out, ["ik_comparison"]) is None  # nothing there any more
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "thesis.tex").write_text("x")
    with pytest.raises(InvalidArgument, match="not a demo results folder"):
        move_aside(tmp_path / "mine", ["ik_comparison"])
    assert (tmp_path / "mine" / "thesis.tex").is_file()


def test_demo_key_figures_come_from_the_study_report(tmp_path):
    from drake_mh.study.demo import key_figures
    from drake_mh.study.report.plots import FigureFile

    blocks = key_figures(_results(tmp_path / "s", FIELDS, _two_kinds()), "s")
    why, figure = blocks
    assert isinstance(why, Table) and why.headers == ["case", "method", "success [%]", "why not 100 %"]
    assert why.rows == [["big", "pso", "0.0", why.rows[0][-1]]] and "budget spent" in why.rows[0][-1]
    assert "2000 evaluations" in why.caption
    assert isinstance(figure, FigureFile) and figure.name == "s-boxplots"
    assert figure.png.startswith(b"\x89PNG") and "case" in figure.caption


def test_examples_show_an_animation_per_group_and_method(tmp_path):
    from drake_mh.study.report import _attachment_blocks
    from drake_mh.study.report.document import Animation
    from drake_mh.study.report.plots import FigureFile

    store = RecordStore(tmp_path)
    store.prepare({"name": "ex", "fields": FIELDS.to_dict(), "grid_keys": ["case", "method", "rep"]})
    png = b"\x89PNG\r\n\x1a\n" + b"0" * 16
    for case in ("small", "big"):
        for rep in range(2):
            store.append({"key": f"case={case}/method=woa/rep={rep}", "case_id": f"{case}{rep}", "case": case,
                          "method": "woa", "rep": rep, "status": "ok"},
                         attachments={"a.png": png, "b.png": png, "c.png": png, "motion.html": "<html>m</html>"})
    blocks = _attachment_blocks(ReportData.load(tmp_path))
    animations = [b for b in blocks if isinstance(b, Animation)]
    figures = [b for b in blocks if isinstance(b, FigureFile)]
    assert sorted(a.title.split(" ")[1] for a in animations) == ["case=big/method=woa/rep=0", "case=small/method=woa/rep=0"]
    assert len(figures) == 4  # two per case: the animation does not crowd out the figures or the other case


def test_report_of_earlier_results_takes_the_layout_from_the_study_file(tmp_path):
    study_file = tmp_path / "grouped.py"
    study_file.write_text(
        "from drake_mh.study import Fields, Study\n"
        "study = Study(name='grouped', run=lambda case: {}, grid={'case': ['a'], 'method': ['m'], 'rep': [0]},\n"
        "              fields=Fields(error='fitness', group_by=('case',), error_unit='rad', conditions='c'))\n")
    old = Fields(error="fitness").to_dict()
    for key in ("group_by", "error_unit", "conditions", "message"):
        old.pop(key)  # a study.json written before these existed
    store = RecordStore(tmp_path / "out")
    store.prepare({"name": "grouped", "fields": old, "source": str(study_file)})
    for case in ("a", "b"):
        store.append({"key": f"case={case}/method=m/rep=0", "case_id": case, "case": case, "method": "m", "rep": 0,
                      "status": "ok", "fitness": 1.0})
    data = ReportData.load(tmp_path / "out")
    assert data.fields.group_by == ("case",) and data.fields.error_unit == "rad"
    assert method_table(data).headers[:2] == ["case", "method"]
    (tmp_path / "grouped.py").unlink()  # the study file gone: the report still works, ungrouped
    assert ReportData.load(tmp_path / "out").fields.group_by is None
