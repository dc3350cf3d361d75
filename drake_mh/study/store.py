"""Loss-free, resumable storage of a study's results folder.

Layout (see ``docs/studies.md``)::

    study.json  records.jsonl  arrays/<case_id>.npz  artifacts/<case_id>/<name>

Every finished case becomes exactly one line of ``records.jsonl``. Its arrays and
attachments are written first (temporary file + ``os.replace``), then the line is appended
with a single ``os.write`` on an ``O_APPEND`` descriptor followed by ``fsync``. A process
killed at any instant therefore leaves either the whole line or a torn last line without
newline, which :meth:`RecordStore.load` drops (the case then simply runs again).

Damage from outside (a block of NUL bytes after a power loss, a truncated ``.npz``) costs only
the damaged cases: :meth:`RecordStore.load` skips unreadable lines and records whose arrays
cannot be opened, lists them in :attr:`RecordStore.damaged`, and those cases run again.

One writer at a time: :meth:`RecordStore.prepare` takes an exclusive lock (``flock`` on
``.lock`` in the folder, released when the store is closed or its process ends, even by
``kill -9``); a second run into the same folder gets :class:`ResultsLocked`.
"""

from __future__ import annotations

import fcntl
import io
import json
import logging
import os
import zipfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from drake_mh.errors import NoResults, ResultsFolderError, ResultsLocked, ResultsMismatch

logger = logging.getLogger(__name__)

RECORDS = "records.jsonl"
META = "study.json"
LOCK = ".lock"
#: settings of study.json that must match to resume into a folder
_RESUME_KEYS = ("name", "seed", "quick", "cases_digest")


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:  # pragma: no cover - e.g. Windows
        return
    try:
        os.fsync(fd)
    except OSError:  # pragma: no cover
        pass
    finally:
        os.close(fd)


def write_atomic(path: Path, data: bytes) -> None:
    """Writes ``data`` to ``path`` through a temporary file and ``os.replace`` (with fsync)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "wb") as handle:
        handle.write(data)
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(tmp, path)
    _fsync_dir(path.parent)


def _json_default(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"{type(value).__name__} is not JSON serializable")


class RecordStore:
    """A results folder: metadata, records, arrays and attachments.

    Args:
        folder: the results folder (created on :meth:`prepare`).
    """

    def __init__(self, folder: str | os.PathLike):
        self.folder = Path(folder)
        #: ``(where, why)`` of every damaged line or arrays file the last :meth:`load` skipped
        self.damaged: list[tuple[str, str]] = []
        self._lock = None

    @property
    def records_path(self) -> Path:
        """``records.jsonl``."""
        return self.folder / RECORDS

    @property
    def meta_path(self) -> Path:
        """``study.json``."""
        return self.folder / META

    # --- metadata -----------------------------------------------------------------------

    def read_meta(self) -> dict[str, Any] | None:
        """Returns ``study.json`` or ``None`` when absent.

        Raises:
            ResultsFolderError: ``study.json`` exists but cannot be read (truncated, not JSON).
        """
        if not self.meta_path.is_file():
            return None
        try:
            meta = json.loads(self.meta_path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ResultsFolderError(
                f"{self.meta_path} is damaged ({type(exc).__name__}: {exc}); the records are safe in "
                f"{RECORDS}: delete or fix {META} (it is rewritten on the next run) or use another --out"
            ) from None
        if not isinstance(meta, dict):
            raise ResultsFolderError(f"{self.meta_path} does not hold a JSON object; delete it or use another --out")
        return meta

    def prepare(self, meta: Mapping[str, Any]) -> None:
        """Creates the folder and ``study.json``, or checks that an existing one matches.

        Raises:
            ResultsMismatch: the folder was made by another study / seed / quick flag / grid.
            ResultsLocked: another process is writing into the folder.
        """
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            if not os.access(self.folder, os.W_OK | os.X_OK):
                raise PermissionError(f"no write permission on {self.folder}")
        except OSError as exc:
            what = "is a file, not a folder" if self.folder.is_file() else f"cannot be created or written ({exc})"
            raise ResultsFolderError(f"results folder {self.folder} {what}; pass another --out DIR") from None
        self.lock()
        old = self.read_meta()
        if old is not None:
            diff = {k: (old.get(k), meta.get(k)) for k in _RESUME_KEYS if old.get(k) != meta.get(k)}
            if diff:
                raise ResultsMismatch(str(self.folder), diff)
            merged = {**old, **meta, "created": old.get("created", meta.get("created"))}
        else:
            merged = dict(meta)
        write_atomic(self.meta_path, json.dumps(merged, indent=2, default=_json_default).encode())

    def lock(self) -> None:
        """Takes the folder's writer lock (idempotent).

        Raises:
            ResultsLocked: another process holds it.
        """
        if self._lock is not None:
            return
        try:
            handle = open(self.folder / LOCK, "a+")  # noqa: SIM115 - held until close()
        except OSError as exc:
            raise ResultsFolderError(f"cannot write into results folder {self.folder} ({exc}); "
                                     "pass another --out DIR") from None
        try:
            fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            raise ResultsLocked(
                f"{self.folder} is being written by another run (lock {self.folder / LOCK}); wait for "
                "it to finish, or give this run another folder with --out DIR") from None
        self._lock = handle

    def close(self) -> None:
        """Releases the writer lock (also released when the process ends)."""
        if self._lock is not None:
            self._lock.close()
            self._lock = None

    # --- records ------------------------------------------------------------------------

    def _repair_tail(self) -> None:
        """Drops a torn last line (no trailing newline) left by a killed writer."""
        path = self.records_path
        if not path.is_file():
            return
        with open(path, "rb+") as handle:
            handle.seek(0, io.SEEK_END)
            size = handle.tell()
            if size == 0:
                return
            handle.seek(size - 1)
            if handle.read(1) == b"\n":
                return
            # find the last newline
            block = 1 << 16
            position = size
            keep = 0
            while position > 0:
                start = max(0, position - block)
                handle.seek(start)
                chunk = handle.read(position - start)
                index = chunk.rfind(b"\n")
                if index >= 0:
                    keep = start + index + 1
                    break
                position = start
            logger.warning("dropping a torn last record in %s (%d bytes)", path, size - keep)
            handle.truncate(keep)
            handle.flush()
            os.fsync(handle.fileno())

    def load(self) -> dict[str, dict[str, Any]]:
        """Returns ``{key: record}`` of every complete, readable record (first one wins on duplicates).

        Unreadable lines (NUL blocks, garbage) and records whose arrays file cannot be opened
        are skipped, logged and listed in :attr:`damaged`; their cases count as not run.
        """
        records: dict[str, dict[str, Any]] = {}
        self.damaged = []
        if not self.records_path.is_file():
            return records
        with open(self.records_path, "rb") as handle:
            for number, line in enumerate(handle, start=1):
                if not line.endswith(b"\n"):
                    logger.warning("ignoring torn last line %d of %s", number, self.records_path)
                    break
                where = f"{RECORDS} line {number}"
                text = line.lstrip(b"\x00")  # a zero-filled block may precede a good record
                if not text.strip():
                    if len(text) < len(line):
                        self._damage(where, "NUL bytes")
                    continue
                try:
                    record = json.loads(text.decode("utf-8"))
                except ValueError as exc:  # JSONDecodeError and UnicodeDecodeError
                    self._damage(where, f"unreadable ({type(exc).__name__})")
                    continue
                key = record.get("key") if isinstance(record, dict) else None
                if key is None or key in records:
                    continue
                why = self._arrays_damage(record)
                if why:
                    self._damage(f"{record.get('arrays')} of case {key}", why)
                    continue
                records[key] = record
        return records

    def _damage(self, where: str, why: str) -> None:
        self.damaged.append((where, why))
        logger.warning("%s: skipping %s (%s); the case runs again", self.folder, where, why)

    def _arrays_damage(self, record: Mapping[str, Any]) -> str:
        """Why a record's arrays file cannot be used ('' when it can): missing or not a whole zip."""
        relative = record.get("arrays")
        if not relative:
            return ""
        path = self.folder / relative
        try:
            with zipfile.ZipFile(path) as archive:  # reads the central directory at the end
                archive.namelist()
        except FileNotFoundError:
            return "missing"
        except (OSError, zipfile.BadZipFile, ValueError) as exc:
            return f"damaged ({exc})"
        return ""

    def records(self) -> list[dict[str, Any]]:
        """Returns all complete records.

        Raises:
            NoResults: the folder has no ``records.jsonl``.
        """
        if not self.records_path.is_file():
            what = ("is a file, not a results folder" if self.folder.is_file() else
                    "does not exist" if not self.folder.exists() else f"holds no study results ({RECORDS} missing)")
            raise NoResults(f"{self.folder} {what}; give the --out folder of a `drake-mh study NAME --out DIR` run")
        return list(self.load().values())

    def append(
        self,
        record: Mapping[str, Any],
        arrays: Mapping[str, np.ndarray] | None = None,
        attachments: Mapping[str, str | bytes] | None = None,
    ) -> dict[str, Any]:
        """Stores one finished case: arrays, attachments, then the record line.

        Args:
            record: flat record with at least ``key`` and ``case_id``.
            arrays: saved as ``arrays/<case_id>.npz``.
            attachments: saved as ``artifacts/<case_id>/<name>``.

        Returns:
            The record as written (with ``arrays`` / ``attachments`` paths).
        """
        record = dict(record)
        case_id = record["case_id"]
        if arrays:
            buffer = io.BytesIO()
            np.savez_compressed(buffer, **{name: np.asarray(a) for name, a in arrays.items()})
            relative = f"arrays/{case_id}.npz"
            write_atomic(self.folder / relative, buffer.getvalue())
            record["arrays"] = relative
        if attachments:
            paths = []
            for name, data in attachments.items():
                relative = f"artifacts/{case_id}/{name}"
                write_atomic(self.folder / relative, data.encode("utf-8") if isinstance(data, str) else data)
                paths.append(relative)
            record["attachments"] = paths
        line = (json.dumps(record, default=_json_default, separators=(",", ":")) + "\n").encode("utf-8")
        self._repair_tail()
        fd = os.open(self.records_path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
        try:
            view = memoryview(line)
            while view:
                written = os.write(fd, view)
                view = view[written:]
            os.fsync(fd)
        finally:
            os.close(fd)
        return record

    def load_arrays(self, record: Mapping[str, Any]) -> dict[str, np.ndarray]:
        """Returns the arrays saved for a record (empty dict if none or unreadable)."""
        relative = record.get("arrays")
        if not relative:
            return {}
        path = self.folder / relative
        try:
            with np.load(path, allow_pickle=False) as data:
                return {name: data[name] for name in data.files}
        except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
            logger.warning("cannot read arrays %s: %s", path, exc)
            return {}
