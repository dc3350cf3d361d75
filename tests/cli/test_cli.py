"""The drake-mh command line: subcommands, exit codes, one-line errors."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from drake_mh.cli import COMMAND_MODULES, build_parser, main

REPO = Path(__file__).resolve().parents[2]
TOY = '''
from drake_mh.study import Study

def run(case):
    if case["i"] == 2:
        raise RuntimeError("case two fails")
    return {"success": True, "error": 0.1 * case["i"], "method": "m"}

study = Study(name="clitoy", run=run, grid={"i": [0, 1, 2, 3]}, quick_grid={"i": [0, 1]})
'''


def _run_cli(*args, cwd=None, timeout=1800):  # a hang guard: from an empty cache commands compile for minutes
    env = {**os.environ, "DRAKE_MH_NO_PROGRESS": "1"}
    return subprocess.run(
        [sys.executable, "-m", "drake_mh", *args], capture_output=True, text=True, cwd=cwd, env=env, timeout=timeout
    )


@pytest.fixture
def toy(tmp_path):
    path = tmp_path / "clitoy.py"
    path.write_text(TOY)
    return path


def test_help_lists_subcommands(capsys):
    assert main(["--help"]) == 0
    text = capsys.readouterr().out
    for name in ("robots", "study", "report", "demo"):
        assert name in text


def test_subcommand_modules_plug_in():
    assert "drake_mh.cli.ik" in COMMAND_MODULES and "drake_mh.cli.app" in COMMAND_MODULES
    parser = build_parser()
    assert parser.prog == "drake-mh"


@pytest.mark.parametrize(
    "argv, words",
    [
        (["frobnicate"], "invalid choice: 'frobnicate'"),
        (["study"], "required: name"),
        (["study", "no_such_study"], "unknown study 'no_such_study'; studies in"),
        (["study", "x", "--workers", "two"], "--workers"),
        (["study", "x", "--bogus"], "unrecognized arguments: --bogus"),
        (["robots", "no_such_robot"], "unknown robot 'no_such_robot'"),
        (["report", "/no/such/folder"], "/no/such/folder does not exist"),
        (["report", __file__], "is a file, not a results folder"),
        (["study", __file__.replace("test_cli.py", "no_study.txt")], "unknown study"),
        (["app", "--max-seconds", "1", "--status-file", "/no/such/dir/s.json"], "--status-file"),
        (["study", "bench_kinematics", "--quick", "--out", "/proc/no_such"], "results folder /proc/no_such"),
    ],
)
def test_bad_input_exits_2_with_one_line(argv, words, capsys):
    assert main(argv) == 2
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("drake-mh: error: ") and words in lines[0]
    assert "Traceback" not in captured.err


def test_a_file_that_is_not_a_study_exits_2_with_one_line(tmp_path, capsys):
    """A path to any file was run as a study: its own error was 'internal error: NameError'."""
    for text, words in (("x\n", "NameError: name 'x' is not defined"), ("def (:\n", "SyntaxError"),
                        ("import drake_mh\n", "defines no Study")):
        path = tmp_path / "not_a_study"
        path.write_text(text)
        assert main(["study", str(path)]) == 2
        lines = capsys.readouterr().err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("drake-mh: error: ") and words in lines[0], lines
        assert f"{path}" in lines[0]


def test_unknown_names_list_valid_ones(capsys):
    assert main(["study", "no_such_study"]) == 2
    assert "fk_accuracy" in capsys.readouterr().err
    assert main(["robots", "no_such_robot"]) == 2
    assert "panda" in capsys.readouterr().err


def test_verbose_shows_the_traceback(capsys):
    assert main(["study", "no_such_study", "--verbose"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" in err and "UnknownStudy" in err


def test_robots_lists_bundled_models(capsys):
    import drake_mh

    assert main(["robots"]) == 0
    out = capsys.readouterr().out
    for name in drake_mh.available_robots():
        assert name in out
    assert "Smoke test" in out and "max|ΔFK|" in out  # the catalogue and the smoke test


def test_study_runs_records_errors_and_reports(toy, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["study", str(toy), "--workers", "0", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "4/4 cases" in text and "1 raised" in text and f"report: {out / 'index.html'}" in text
    assert main(["study", str(toy), "--workers", "0", "--out", str(out), "--strict"]) == 1
    assert "0 run now, 4 already done" in capsys.readouterr().out
    assert main(["report", str(out)]) == 0
    assert "index.html" in capsys.readouterr().out


def test_study_quick_seed_and_mismatch(toy, tmp_path, capsys):
    out = tmp_path / "q"
    assert main(["study", str(toy), "--quick", "--workers", "0", "--out", str(out), "--seed", "5", "--quiet"]) == 0
    assert capsys.readouterr().out.strip() == f"report: {out / 'index.html'}"
    assert main(["study", str(toy), "--workers", "0", "--out", str(out)]) == 2
    assert "another --out" in capsys.readouterr().err


def test_study_script_runs_like_the_cli(toy, tmp_path):
    script = toy.read_text() + "\nif __name__ == '__main__':\n    from drake_mh.cli import run_script\n    run_script(study)\n"
    toy.write_text(script)
    result = subprocess.run(
        [sys.executable, str(toy), "--quick", "--workers", "0", "--out", str(tmp_path / "s")],
        capture_output=True, text=True, timeout=120, env={**os.environ, "DRAKE_MH_NO_PROGRESS": "1"},
    )
    assert result.returncode == 0, result.stderr
    assert "2/2 cases" in result.stdout
    bad = subprocess.run([sys.executable, str(toy), "--workers", "-3"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "Traceback" not in bad.stderr


def test_python_m_drake_mh_and_console_script(tmp_path):
    result = _run_cli(cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "panda" in result.stdout and "demo" in result.stdout
    assert "Smoke test" in result.stdout and "usage:" not in result.stdout  # no usage dump
    script = Path(sys.executable).with_name("drake-mh")
    if script.exists():
        bad = subprocess.run([str(script), "study", "nope"], capture_output=True, text=True, timeout=120)
        assert bad.returncode == 2 and bad.stderr.startswith("drake-mh: error: unknown study")


def _records(folder: Path) -> list[dict]:
    import json

    return [json.loads(line) for line in (folder / "records.jsonl").read_text().splitlines() if line.strip()]


def _section(markdown: str, name: str) -> str:
    """The demo report's section of study ``name`` (from its heading to the next one)."""
    return markdown.split(f"\n## {name}\n", 1)[1].split("\n## ", 1)[0]


def check_demo_report(out: Path, took: float) -> None:
    """The demo's report in ``out`` holds what it claims, read back from the files it wrote: a
    section per demo study, in order, saying that all its cases ran and none raised (the counts
    are those of the study's own records); fk_accuracy's table passes every bundled robot with
    the largest differences its records hold, all below its tolerance; retime_benchmark reports
    no limit violation; the wall time it prints is positive and at most ``took`` [s]; and every
    file the report links to or shows exists."""
    import re

    import drake_mh
    from drake_mh.study.demo import DEMO_STUDIES, demo_studies

    markdown = (out / "report.md").read_text()
    studies = demo_studies()
    assert set(DEMO_STUDIES) <= set(studies)
    assert [h for h in re.findall(r"^## (\S+)$", markdown, re.M) if h in studies] == studies
    for name in studies:
        section = _section(markdown, name)
        line = re.search(r"^(\d+)/(\d+) cases.*$", section, re.M)
        done, total = int(line.group(1)), int(line.group(2))
        records = _records(out / name)
        assert done == total == len(records) > 0 and all(r["status"] == "ok" for r in records), name
        assert "raised" not in line.group(0), line.group(0)
        assert f"]({name}/index.html)" in section and (out / name / "index.html").is_file()
    rows = re.findall(r"^\| (\w+) \| (\d+) \| (\d+) \| (\S+) \| (\S+) \| (\S+) \| (\w+) \|$",
                      _section(markdown, "fk_accuracy"), re.M)
    assert sorted(r[0] for r in rows) == sorted(drake_mh.available_robots())
    records = _records(out / "fk_accuracy")
    for robot, nq, configurations, position, rotation, jacobian, passed in rows:
        mine = [r for r in records if r["robot"] == robot]
        assert int(nq) == drake_mh.load_robot(robot).nq
        assert int(configurations) == sum(r["configurations"] for r in mine)
        for text, field in ((position, "position_error"), (rotation, "rotation_error"), (jacobian, "jacobian_error")):
            assert float(text) == pytest.approx(max(r[field] for r in mine), rel=1e-2)
            assert 0.0 <= float(text) < 1e-9
        assert passed == "yes"
    assert re.search(r"violations \(> 1 \+ 1e-06\): 0\.", _section(markdown, "retime_benchmark"))
    wall = float(re.search(r"^Demo wall time ([0-9.]+) s\.$", markdown, re.M).group(1))
    assert 0.0 < wall <= took
    targets = re.findall(r"\]\(([^)]+)\)", markdown)
    assert any(t.startswith("figures/") for t in targets)
    for target in targets:
        assert (out / target).is_file(), target
    for target in re.findall(r'(?:href|src)="([^"]+)"', (out / "index.html").read_text()):
        if ":" not in target and not target.startswith("#"):
            assert (out / target).is_file(), target


@pytest.mark.slow
def test_demo_runs_end_to_end(tmp_path):
    """``drake-mh demo`` exits 0, names its report, and the report holds what it claims
    (:func:`check_demo_report`)."""
    import time

    out = tmp_path / "demo"
    start = time.monotonic()
    result = _run_cli("demo", "--workers", "2", "--out", str(out), cwd=tmp_path, timeout=1800)
    took = time.monotonic() - start
    assert result.returncode == 0, result.stderr
    assert f"demo report: {(out / 'index.html').resolve()}" in result.stdout
    check_demo_report(out, took)


def test_progress_only_on_an_interactive_terminal(monkeypatch):
    import argparse

    from drake_mh.cli import wants_progress

    class TTY:
        def isatty(self):
            return True

    monkeypatch.delenv("CI", raising=False)
    monkeypatch.delenv("DRAKE_MH_NO_PROGRESS", raising=False)
    monkeypatch.setattr(sys, "stderr", TTY())
    assert wants_progress(argparse.Namespace(quiet=False))
    assert not wants_progress(argparse.Namespace(quiet=True))
    monkeypatch.setenv("CI", "true")
    assert not wants_progress(argparse.Namespace(quiet=False))
    monkeypatch.delenv("CI")
    monkeypatch.setattr(sys, "stderr", open(os.devnull, "w"))
    assert not wants_progress(argparse.Namespace(quiet=False))


@pytest.mark.parametrize("command, resumable", [("ik", False), ("study", True)])
def test_ctrl_c_says_resume_only_where_results_are_kept(monkeypatch, capsys, command, resumable):
    import argparse

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args",
                        lambda self, argv=None: argparse.Namespace(command=command, func=interrupted))
    assert main([command]) == 130
    err = capsys.readouterr().err
    assert f"drake-mh {command}: interrupted" in err
    assert ("run the same command again" in err) == resumable


def test_log_handler_follows_the_current_stderr(monkeypatch, capsys):
    """The CLI's log handler writes to sys.stderr as it is at each record (a stream swapped in
    and closed since, as test runners and notebooks do, must not break logging)."""
    import io
    import logging

    from drake_mh.cli.main import _configure_logging

    _configure_logging(verbose=False, quiet=False)
    old = io.StringIO()
    monkeypatch.setattr("sys.stderr", old)
    old.close()  # the stream the handler saw first is gone
    current = io.StringIO()
    monkeypatch.setattr("sys.stderr", current)
    logging.getLogger("drake_mh.test").warning("still heard")
    assert "still heard" in current.getvalue()
