"""Finding and loading study scripts (``studies/NAME.py`` or any path to a ``.py`` file).

Study modules are loaded from their file under a private module name, so the same file
loads identically in the main process and in worker processes (local or Dask).
"""

from __future__ import annotations

import hashlib
import logging
import os
import sys
import threading
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from drake_mh.errors import InvalidStudy, UnknownStudy
from drake_mh.study.spec import Study

logger = logging.getLogger(__name__)

#: environment variable with extra study folders (``os.pathsep`` separated), searched first
STUDIES_ENV = "DRAKE_MH_STUDIES"

_lock = threading.Lock()
_modules: dict[str, ModuleType] = {}


@dataclass(frozen=True)
class StudySource:
    """Everything a worker needs to load a study: its path and its source text.

    The text travels with each task, so a worker on another machine (Dask) that lacks the
    file can still load the study, provided drake_mh is installed there.
    """

    path: str
    text: str
    name: str

    @classmethod
    def from_path(cls, path: str | os.PathLike, name: str) -> StudySource:
        """Reads the study file."""
        path = Path(path).resolve()
        return cls(path=str(path), text=path.read_text(encoding="utf-8"), name=name)

    @property
    def digest(self) -> str:
        """Short hash of the source text."""
        return hashlib.sha256(self.text.encode("utf-8")).hexdigest()[:12]


def studies_dirs() -> list[Path]:
    """Returns the folders searched for study names, in order.

    ``$DRAKE_MH_STUDIES`` entries, then ``./studies`` of the working directory, then the
    ``studies/`` folder of the repository this package lives in (editable installs).
    """
    dirs: list[Path] = []
    for entry in os.environ.get(STUDIES_ENV, "").split(os.pathsep):
        if entry:
            dirs.append(Path(entry))
    dirs.append(Path.cwd() / "studies")
    dirs.append(Path(__file__).resolve().parents[2] / "studies")
    unique: list[Path] = []
    for d in dirs:
        d = d.resolve()
        if d not in unique and d.is_dir():
            unique.append(d)
    return unique


def available_studies() -> list[str]:
    """Returns the names of the study scripts in :func:`studies_dirs` (sorted)."""
    names = set()
    for folder in studies_dirs():
        for path in folder.glob("*.py"):
            if not path.name.startswith("_"):
                names.add(path.stem)
    return sorted(names)


def find_study_file(name_or_path: str | os.PathLike) -> Path:
    """Resolves a study name or path to a file.

    Raises:
        UnknownStudy: neither an existing ``.py`` path nor a name in the studies folders.
    """
    text = os.fspath(name_or_path)
    candidate = Path(text)
    looks_like_path = text.endswith(".py") or os.sep in text or "/" in text
    if looks_like_path:
        if candidate.is_file():
            return candidate.resolve()
        raise UnknownStudy(text, available_studies(), folder=_folders_text())
    for folder in studies_dirs():
        path = folder / f"{text}.py"
        if path.is_file():
            return path.resolve()
    raise UnknownStudy(text, available_studies(), folder=_folders_text())


def _folders_text() -> str:
    return ", ".join(str(d) for d in studies_dirs()) or "studies/ (none found)"


def _load_module(source: StudySource) -> ModuleType:
    cache_key = f"{source.path}:{source.digest}"
    with _lock:
        module = _modules.get(cache_key)
        if module is not None:
            return module
        stem = "".join(c if c.isalnum() else "_" for c in Path(source.path).stem)
        module_name = f"drake_mh_studies.{stem}_{source.digest}"
        module = ModuleType(module_name)
        module.__file__ = source.path
        folder = str(Path(source.path).parent)
        if Path(folder).is_dir() and folder not in sys.path:
            sys.path.append(folder)  # lets a study import helpers living beside it
        if "drake_mh_studies" not in sys.modules:
            sys.modules["drake_mh_studies"] = ModuleType("drake_mh_studies")
        sys.modules[module_name] = module
        try:
            code = compile(source.text, source.path, "exec")
            exec(code, module.__dict__)  # noqa: S102 - running the user's study script is the point
        except Exception as exc:  # the file's own error (or not a study file at all): the user's to fix
            del sys.modules[module_name]
            where = getattr(exc, "lineno", None) or _line_of(exc, source.path)
            raise InvalidStudy(f"{source.path}{f':{where}' if where else ''} is not a study file that runs: "
                               f"{type(exc).__name__}: {exc} (--verbose shows the traceback)") from exc
        _modules[cache_key] = module
        return module


def _line_of(exc: BaseException, path: str) -> int | None:
    """The line of ``path`` where ``exc`` was raised, from its traceback (None if not there)."""
    import traceback

    lines = [frame.lineno for frame in traceback.extract_tb(exc.__traceback__) if frame.filename == path]
    return lines[-1] if lines else None


def study_from_module(module: ModuleType, where: str) -> Study:
    """Returns the module's single module-level :class:`Study` (preferring ``study``).

    Raises:
        InvalidStudy: none or several.
    """
    found = getattr(module, "study", None)
    if isinstance(found, Study):
        return found
    studies = [v for v in vars(module).values() if isinstance(v, Study)]
    if len(studies) == 1:
        return studies[0]
    if not studies:
        raise InvalidStudy(f"{where} defines no Study; add `study = drake_mh.study.Study(...)` at module level")
    raise InvalidStudy(f"{where} defines {len(studies)} Study objects; name the one to run `study`")


def load_source(source: StudySource) -> Study:
    """Loads (once per process) the study described by ``source``."""
    return study_from_module(_load_module(source), source.path)


def load_study(name_or_path: str | os.PathLike) -> tuple[Study, StudySource]:
    """Loads a study by name (``studies/NAME.py``) or path.

    Returns:
        ``(study, source)``; pass ``source`` to workers.

    Raises:
        UnknownStudy: no such study.
        InvalidStudy: the file defines no usable Study.
    """
    path = find_study_file(name_or_path)
    source = StudySource.from_path(path, name=path.stem)
    return load_source(source), source
