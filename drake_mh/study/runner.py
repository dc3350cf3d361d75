"""Running a study: expand the grid, skip finished cases, execute the rest, store, report."""

from __future__ import annotations

import dataclasses
import datetime
import hashlib
import logging
import os
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, Executor, Future, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from drake_mh.errors import InvalidArgument
from drake_mh.study.case import CaseSpec
from drake_mh.study.executors import default_workers, open_executor
from drake_mh.study.loader import StudySource, load_study
from drake_mh.study.spec import Study
from drake_mh.study.store import RecordStore, write_atomic
from drake_mh.study.worker import run_case_task

logger = logging.getLogger(__name__)

#: cases submitted ahead of the running ones, per unit of parallelism
_WINDOW_FACTOR = 2


@dataclass(frozen=True)
class StudyResult:
    """What a run produced.

    Attributes:
        study: study name.
        folder: results folder.
        records: every finished record, in grid order.
        n_cases: cases in the grid.
        n_new: cases run by this call (the others were already finished).
        n_errors: records whose case raised.
        summary: the study's summary markdown ('' if none).
        report: path of ``index.html`` or ``None`` if no report was written.
    """

    study: str
    folder: Path
    records: list[dict[str, Any]]
    n_cases: int
    n_new: int
    n_errors: int
    summary: str
    report: Path | None

    @property
    def complete(self) -> bool:
        """All cases of the grid have a record."""
        return len(self.records) == self.n_cases


def default_folder(name: str, quick: bool) -> Path:
    """``results/<name>`` (``results/<name>-quick`` for the quick grid), relative to the cwd."""
    return Path("results") / (f"{name}-quick" if quick else name)


def _resolve(study: Study | str | os.PathLike, source: StudySource | None) -> tuple[Study, StudySource | Study]:
    if not isinstance(study, Study):
        return load_study(study)
    if source is not None:
        return study, source
    module = getattr(study.run, "__module__", "") or ""
    path = study.source_file
    if (module.startswith("drake_mh_studies.") or module == "__main__") and path and Path(path).is_file():
        return study, StudySource.from_path(path, name=study.name)
    return study, study  # importable module: the Study pickles by reference


def build_specs(study: Study, quick: bool, seed: int) -> list[CaseSpec]:
    """Returns the case specs of the (quick) grid with seeds derived from ``seed``."""
    return [
        CaseSpec.build(params, seed, study.fields.method, quick, index)
        for index, params in enumerate(study.cases(quick))
    ]


def _meta(study: Study, specs: list[CaseSpec], quick: bool, seed: int, source: Any) -> dict[str, Any]:
    digest = hashlib.sha256("\n".join(s.key for s in specs).encode()).hexdigest()[:16]
    return {
        "name": study.name,
        "description": study.description,
        "seed": seed,
        "quick": quick,
        "grid_keys": list(specs[0].params),
        "instance_keys": list(study.instance_keys(quick)),
        "n_cases": len(specs),
        "methods": list(dict.fromkeys(str(s.params.get(study.fields.method, "(all)")) for s in specs)),
        "cases_digest": digest,
        "case_keys": [s.key for s in specs],  # the report counts only these (a folder may hold others)
        "fields": study.fields.to_dict(),
        "source": getattr(source, "path", None) or study.source_file,
        "created": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
    }


def _crash_record(spec: CaseSpec, exc: BaseException) -> dict[str, Any]:
    return {
        **spec.params,
        "status": "error",
        "exception_type": type(exc).__name__,
        "exception": (str(exc) or "the worker running this case failed")[:2000],
        "key": spec.key,
        "case_id": spec.case_id,
        "seed": spec.seed,
        "wall_time": float("nan"),
    }


def run_study(
    study: Study | str | os.PathLike,
    *,
    quick: bool = False,
    out: str | os.PathLike | None = None,
    executor: Executor | str | None = None,
    workers: int | None = None,
    seed: int | None = None,
    progress: bool = False,
    report: bool = True,
    source: StudySource | None = None,
    on_record: Callable[[dict[str, Any]], None] | None = None,
    first_by: tuple[str, ...] | str | None = None,
) -> StudyResult:
    """Runs (or resumes) a study and writes its records, summary and report.

    Args:
        study: a :class:`Study`, a study name in ``studies/`` or a path to a study file.
        quick: run the quick grid.
        out: results folder; default :func:`default_folder`.
        executor: a ``concurrent.futures.Executor`` (used as is, not shut down), or a
            specification ``"local"`` / ``"serial"`` / ``"dask://HOST:PORT"``.
        workers: local worker processes (``0`` = in this process); default CPU count.
        seed: overrides the study seed.
        progress: show a tqdm progress bar (count, rate, ETA) on stderr.
        report: write ``report.md`` and ``index.html`` at the end.
        source: the study file, when ``study`` is a Study object loaded from a file.
        on_record: called in this process with each newly stored record.
        first_by: grid keys that order the cases to run (then grid order), e.g. ``"rep"``:
            every cell's first replicate before any second one, so that a run stopped early
            leaves a balanced partial result. Results do not depend on the order.

    Returns:
        The :class:`StudyResult`.

    Raises:
        UnknownStudy, InvalidStudy: bad study. ResultsMismatch: ``out`` holds another run.
        InvalidArgument: bad executor / workers / seed.
    """
    study, task_source = _resolve(study, source)
    if seed is not None:
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise InvalidArgument(f"--seed must be a non-negative integer, got {seed!r}")
        study = dataclasses.replace(study, seed=seed)
    specs = build_specs(study, quick, study.seed)
    folder = Path(out) if out is not None else default_folder(study.name, quick)
    store = RecordStore(folder)
    store.prepare(_meta(study, specs, quick, study.seed, task_source))
    done = store.load()
    pending = [s for s in specs if s.key not in done]
    if first_by:
        keys = (first_by,) if isinstance(first_by, str) else tuple(first_by)
        unknown = [k for k in keys if specs and k not in specs[0].params]
        if unknown:
            raise InvalidArgument(f"first_by: {unknown} not in the grid keys {list(specs[0].params)}")
        pending.sort(key=lambda s: (tuple(str(s.params[k]).zfill(12) for k in keys), s.index))
    logger.info("study %s: %d cases, %d finished, %d to run -> %s", study.name, len(specs), len(done), len(pending), folder)

    n_new = 0
    n_errors_new = 0
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=len(specs), initial=len(specs) - len(pending), unit="case", desc=study.name, dynamic_ncols=True)

    def store_record(record: dict[str, Any], arrays=None, attachments=None) -> None:
        nonlocal n_new, n_errors_new
        stored = store.append(record, arrays, attachments)
        n_new += 1
        if stored.get("status") == "error":
            n_errors_new += 1
            logger.warning("case %s raised %s: %s", stored["key"], stored.get("exception_type"), stored.get("exception"))
        if bar is not None:
            bar.update(1)
            if n_errors_new:
                bar.set_postfix(errors=n_errors_new, refresh=False)
        if on_record is not None:
            on_record(stored)

    try:
        if pending:
            _execute(pending, task_source, study, executor, workers, store_record)
    finally:
        if bar is not None:
            bar.close()

    by_key = store.load()
    records = [by_key[s.key] for s in specs if s.key in by_key]
    summary = ""
    if study.summarize is not None:
        try:
            summary = study.summarize(records) or ""
        except Exception as exc:  # noqa: BLE001 - a broken summary must not lose the results
            logger.warning("summarize of study %s raised %s: %s", study.name, type(exc).__name__, exc)
            summary = f"*summarize() raised {type(exc).__name__}: {exc}*"
        write_atomic(folder / "summary.md", summary.encode("utf-8"))
    report_path = None
    if report:
        from drake_mh.study.report import write_report

        report_path = write_report(folder)
    store.close()  # the folder's writer lock (also released if this process dies)
    return StudyResult(
        study=study.name,
        folder=folder,
        records=records,
        n_cases=len(specs),
        n_new=n_new,
        n_errors=sum(1 for r in records if r.get("status") == "error"),
        summary=summary,
        report=report_path,
    )


def _isolate(
    suspects: list[CaseSpec],
    task_source: StudySource | Study,
    executor: str | None,
    store_record: Callable[..., None],
) -> None:
    """Re-runs the cases that were in flight when a worker died, each alone in a fresh
    one-worker pool, so that only the case that kills its worker is recorded as a crash."""
    for spec in sorted(suspects, key=lambda s: s.index):
        with open_executor(executor, 1) as (pool, _):
            future = pool.submit(run_case_task, task_source, spec)
            try:
                outcome = future.result()
            except BrokenProcessPool:
                store_record(_crash_record(spec, WorkerDied(
                    "the worker process died while running this case (a crash or abort in native "
                    "code, e.g. Drake, or os._exit); run it with --workers 0 --verbose to see where"
                )))
                continue
            except Exception as exc:  # noqa: BLE001
                store_record(_crash_record(spec, exc))
                continue
        store_record(outcome.record, outcome.arrays, outcome.attachments)


class WorkerDied(RuntimeError):
    """Recorded (not raised) for a case whose worker process died."""


def _execute(
    pending: list[CaseSpec],
    task_source: StudySource | Study,
    study: Study,
    executor: Executor | str | None,
    workers: int | None,
    store_record: Callable[..., None],
) -> None:
    queue = list(reversed(pending))  # pop() from the end keeps grid order
    while queue:
        suspects: list[CaseSpec] = []
        with ExitStack() as stack:
            if isinstance(executor, Executor):
                pool, parallel = executor, (workers or default_workers())
            else:
                count = workers
                if study.max_workers is not None and count != 0:
                    count = min(count or default_workers(), study.max_workers)
                pool, parallel = stack.enter_context(open_executor(executor, count))
            if study.max_workers is not None:
                parallel = min(parallel, study.max_workers)
                window = parallel  # timing studies: never queue cases behind running ones
            else:
                window = parallel * _WINDOW_FACTOR
            running: dict[Future, CaseSpec] = {}
            broken = False  # the pool broke before we saw which future it took down
            try:
                while queue or running:
                    while queue and len(running) < window and not suspects and not broken:
                        spec = queue.pop()
                        try:
                            running[pool.submit(run_case_task, task_source, spec)] = spec
                        except BrokenProcessPool:
                            queue.append(spec)  # never started: runs again in a fresh pool
                            broken = True
                    if not running:
                        break
                    finished, _ = wait(running, return_when=FIRST_COMPLETED)
                    for future in sorted(finished, key=lambda f: running[f].index):
                        spec = running.pop(future)
                        try:
                            outcome = future.result()
                        except BrokenProcessPool:
                            suspects.append(spec)  # this case or a neighbour killed the worker
                            continue
                        except Exception as exc:  # noqa: BLE001 - e.g. unpicklable result, lost Dask worker
                            store_record(_crash_record(spec, exc))
                            continue
                        store_record(outcome.record, outcome.arrays, outcome.attachments)
                    if suspects and not running:
                        break
            except BaseException:
                for future in running:
                    future.cancel()
                raise
        if isinstance(executor, Executor) and (suspects or broken):
            raise RuntimeError("the executor passed to run_study broke (a worker died); pass a fresh one")
        if not suspects:
            if broken and queue:
                continue  # a fresh pool for the cases that could not be submitted
            return
        logger.warning("a worker process died; re-running the %d case(s) it was running one by one", len(suspects))
        _isolate(suspects, task_source, executor, store_record)
