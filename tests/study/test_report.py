import re

import numpy as np
import pytest
from scipy import stats

from study_toys import external_resources

from drake_mh.errors import NoResults
from drake_mh.study import run_study, write_report
from drake_mh.study.report import ReportData, method_table, rank_stats
from drake_mh.study.report.plots import best_so_far_on_grid
from drake_mh.study.report.stats import holm
from drake_mh.study.store import RecordStore

EXTERNAL = re.compile(r"""(?:src|href|action|poster|data)\s*=\s*["']?\s*(?:https?:)?//|url\(\s*["']?\s*(?:https?:)?//|@import""", re.I)


@pytest.fixture(scope="module")
def toy_results(tmp_path_factory):
    from study_toys import write_toy

    folder = tmp_path_factory.mktemp("report")
    path = write_toy(folder)
    run_study(path, out=folder / "out", workers=0)
    return folder / "out"


def test_report_files_and_sections(toy_results):
    md = (toy_results / "report.md").read_text()
    for section in ("## Summary", "## Methods", "## Statistics", "## Figures", "## Examples", "## Cases that raised"):
        assert section in md
    assert "toy summary: 24 records" in md
    assert "boom on purpose" in md
    for name in ("convergence", "boxplots", "trajectories"):
        assert (toy_results / "figures" / f"{name}.png").read_bytes().startswith(b"\x89PNG")
        assert f"figures/{name}.png" in md


def test_html_is_self_contained(toy_results):
    page = (toy_results / "index.html").read_text()
    assert page.count("data:image/png;base64,") >= 3
    assert "<iframe" in page and "srcdoc=" in page  # the attached animation, embedded
    assert not EXTERNAL.search(page), EXTERNAL.search(page)
    assert external_resources(page) == []
    assert "http://" not in page and "https://" not in page


def test_method_table_numbers(toy_results):
    data = ReportData.load(toy_results)
    table = method_table(data)
    rows = {row[0]: dict(zip(table.headers, row)) for row in table.rows}
    assert set(rows) == {"a", "b", "bad"}
    assert rows["bad"]["raised"] == "2" and rows["a"]["raised"] == "0"
    errors_a = np.array([r["error"] for r in data.records if r["method"] == "a"])
    assert float(rows["a"]["error median"]) == pytest.approx(np.median(errors_a), rel=5e-3)  # 3 digits shown
    q25, q75 = np.percentile(errors_a, [25, 75])
    assert float(rows["a"]["error IQR"]) == pytest.approx(q75 - q25, rel=5e-3)


def test_rank_statistics_match_scipy(toy_results):
    data = ReportData.load(toy_results)
    result = rank_stats(data)
    # b has half the scale of a on the same instances: best in every block
    assert result.best == "b"
    assert result.n_blocks == 8
    assert result.average_ranks[0] == pytest.approx(1.0)
    by_method = {t.method: t for t in result.pairwise}
    assert by_method["a"].wins == 8 and by_method["a"].losses == 0
    b = sorted((r for r in data.records if r["method"] == "b"), key=lambda r: (r["inst"], r["rep"]))
    a = sorted((r for r in data.records if r["method"] == "a"), key=lambda r: (r["inst"], r["rep"]))
    expected = stats.wilcoxon([r["error"] for r in b], [r["error"] for r in a]).pvalue
    assert by_method["a"].p_value == pytest.approx(expected)
    # the cases of "bad" that raised rank last in their blocks
    assert result.methods[-1] == "bad"


def test_holm_adjustment():
    adjusted = holm(np.array([0.01, 0.04, 0.03, np.nan]))
    np.testing.assert_allclose(adjusted[:3], [0.03, 0.06, 0.06])
    assert np.isnan(adjusted[3])
    np.testing.assert_allclose(holm(np.array([0.5, 0.6])), [1.0, 1.0])


def test_best_so_far_sampling():
    grid = np.array([0.0, 10.0, 15.0, 30.0, 100.0])
    out = best_so_far_on_grid(np.array([10, 20, 30]), np.array([5.0, 7.0, 1.0]), grid, True)
    np.testing.assert_array_equal(out[1:], [5.0, 5.0, 1.0, 1.0])
    assert np.isnan(out[0])


def test_partial_results_and_missing_folder(tmp_path):
    store = RecordStore(tmp_path)
    store.append({"key": "m=x/r=0", "case_id": "c0", "method": "x", "r": 0, "status": "ok", "error": 1.0})
    path = write_report(tmp_path)  # no study.json, one method: still a report
    assert path.is_file() and "Statistics need" in (tmp_path / "report.md").read_text()
    with pytest.raises(NoResults):
        write_report(tmp_path / "nothing")


def test_matplotlib_is_not_imported_by_the_runner():
    import subprocess
    import sys

    code = "import sys, drake_mh.study, drake_mh.cli; print('matplotlib' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "False"


def test_resource_audit_catches_remote_references():
    page = (
        '<img src="https://x/y.png"><link href="//cdn/z.css">'
        '<iframe srcdoc="&lt;script src=&quot;http://a/b.js&quot;&gt;&lt;/script&gt;"></iframe>'
        "<style>body{background:url('https://q/r.png')}</style><script>var u='https://in-js'</script>"
    )
    assert external_resources(page) == ["https://x/y.png", "//cdn/z.css", "http://a/b.js", "https://q/r.png"]


@pytest.mark.slow
def test_meshcat_static_html_is_embedded_offline(tmp_path):
    geometry = pytest.importorskip("pydrake.geometry")
    meshcat = geometry.Meshcat()
    meshcat.SetObject("/sphere", geometry.Sphere(0.1), geometry.Rgba(0.2, 0.4, 0.8, 1.0))
    page = meshcat.StaticHtml()
    store = RecordStore(tmp_path)
    for method in ("x", "y"):
        store.append(
            {"key": f"method={method}/r=0", "case_id": f"c{method}", "method": method, "r": 0, "status": "ok", "error": 1.0},
            attachments={"scene.html": page},
        )
    index = write_report(tmp_path).read_text()
    assert index.count("<iframe") == 2
    assert external_resources(index) == []


def test_study_markdown_summary_renders_as_html_tables():
    from drake_mh.study.report.document import Document, Heading, Markdown, Paragraph, Preformatted, Table, markdown_blocks, to_html

    text = "### Ranks\n\nsome words\nmore words\n\n| a | b |\n|---|---|\n| 1 | x \\| y |\n\n```\ncode | here\n```\n"
    blocks = markdown_blocks(text)
    assert blocks[0] == Heading("Ranks", 3)
    assert blocks[1] == Paragraph("some words more words")
    assert blocks[2] == Table(["a", "b"], [["1", "x | y"]])
    assert blocks[3] == Preformatted("code | here")
    doc = Document("t")
    doc.add(Markdown(text))
    page = to_html(doc)
    assert "<table>" in page and ">x | y</td>" in page and "<h3>Ranks</h3>" in page


def test_convergence_panels_per_field_combination(toy_results, monkeypatch):
    import dataclasses

    from drake_mh.study import Fields
    from drake_mh.study.report import plots

    fields = Fields(instance=("inst", "rep"), panels=("inst", "rep"))
    assert Fields.from_dict(fields.to_dict()) == fields
    data = ReportData.load(toy_results)
    data = dataclasses.replace(data, fields=dataclasses.replace(data.fields, panels=("inst", "rep")))
    titles = []
    render = plots._render

    def capture(fig):
        titles.extend(ax.get_title() for ax in fig.axes if ax.get_visible())
        return render(fig)

    monkeypatch.setattr(plots, "_render", capture)
    assert plots.convergence_figure(data) is not None
    assert sorted(titles) == sorted(f"inst = {i}, rep = {r}" for i in "pq" for r in range(4))   # 8 panels, 2 rows


def test_records_outside_the_grid_are_left_out_and_said(tmp_path):
    """A folder holding a case of another grid reported '7 of 6 cases'."""
    import shutil
    from study_toys import write_toy

    path = write_toy(tmp_path, reps=1)
    out = tmp_path / "out"
    run_study(path, out=out, workers=0, report=False)
    store = RecordStore(out)
    stray = dict(store.records()[0], key="inst=z|method=a|rep=9", case_id="stray")
    store.append(stray)
    with open(store.records_path, "ab") as handle:
        handle.write(b"\x00" * 64 + b"\n")                 # and a damaged line
    data = ReportData.load(out)
    assert len(data.records) == 6 and data.outside_grid == 1
    md = (write_report(out).parent / "report.md").read_text()
    assert "6 of 6 cases finished (1 records of cases not in this grid left out)" in md
    assert "1 damaged records skipped" in md
    shutil.rmtree(out)
