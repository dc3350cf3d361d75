"""Study runner: grids of cases run on any executor, stored loss-free, turned into reports.

See ``docs/studies.md``. The public API::

    from drake_mh.study import Case, Fields, Study, load_study, run_study, write_report
"""

from __future__ import annotations

from drake_mh.study.case import Case, CaseSpec
from drake_mh.study.loader import available_studies, load_study, studies_dirs
from drake_mh.study.runner import StudyResult, default_folder, run_study
from drake_mh.study.seeding import case_key, derive_seed
from drake_mh.study.spec import Fields, Study


def write_report(folder):
    """Writes ``report.md`` and ``index.html`` for a results folder; returns the html path.

    Thin wrapper that imports the report machinery lazily (see
    :func:`drake_mh.study.report.write_report`).
    """
    from drake_mh.study.report import write_report as _write

    return _write(folder)


__all__ = [
    "Case",
    "CaseSpec",
    "Fields",
    "Study",
    "StudyResult",
    "available_studies",
    "case_key",
    "default_folder",
    "derive_seed",
    "load_study",
    "run_study",
    "studies_dirs",
    "write_report",
]
