"""Where the files a robot model refers to are: ``package://``, ``model://``, relative paths.

A model file names its meshes by URI. :class:`UriResolver` turns each into an existing file,
trying, for ``package://NAME/rest`` (and Gazebo's ``model://NAME/rest``), in this order:

1. ``packages={"NAME": "/dir"}`` given by the caller (shell: ``--package NAME=DIR``);
2. ``package.xml`` files found up the tree from the model (each ancestor folder of the model
   and the folders directly inside the nearest ancestors), whose ``<name>`` is ``NAME``;
3. ``ROS_PACKAGE_PATH`` (entries that are, or directly contain, a package ``NAME``),
   ``AMENT_PREFIX_PATH`` (``PREFIX/share/NAME``) and the Python environment's prefixes
   (``sys.prefix/share/NAME``, ``site-packages/cmeel.prefix/share/NAME``: pip wheels that ship
   ROS packages, such as ``example-robot-data``);
4. failing those, the model's own folder and its parents: an ancestor called ``NAME``, or an
   ancestor ``A`` with ``A/NAME/rest`` or ``A/rest`` (models exported from CAD tools and
   simulators often assume that layout).

Relative paths resolve against the model's folder, ``file://`` and absolute paths are taken
as they are. A URI that resolves nowhere raises :class:`~drake_mh.errors.MeshNotFound`
(or :class:`~drake_mh.errors.UnknownPackage`) naming every place searched.
"""

from __future__ import annotations

import logging
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from urllib.parse import unquote, urlparse

from drake_mh.errors import InvalidArgument, MeshNotFound, UnknownPackage

logger = logging.getLogger(__name__)

_NEAR_ANCESTORS = 4
"""How many ancestors of the model also have their sub-folders scanned for ``package.xml``."""


def installed_package_dir(name: str) -> Path | None:
    """Folder of a ROS-style package installed in this Python environment, or ``None``.

    Looks at ``sys.prefix/share/NAME`` and ``<site-packages>/cmeel.prefix/share/NAME`` (the
    layout of cmeel wheels, e.g. ``pip install example-robot-data``).
    """
    import site
    import sys

    bases = [Path(sys.prefix) / "share"]
    try:
        sites = [*site.getsitepackages(), site.getusersitepackages()]
    except AttributeError:  # some virtualenv builds lack getsitepackages
        sites = []
    for entry in [*sites, *sys.path]:
        if entry and "site-packages" in str(entry):
            bases.append(Path(entry) / "cmeel.prefix" / "share")
    for base in bases:
        folder = base / name
        if folder.is_dir():
            return folder
    return None


def parse_package_option(items) -> dict[str, str]:
    """``["NAME=DIR", ...]`` (the shell's ``--package``) → ``{"NAME": "DIR"}``.

    Raises:
        InvalidArgument: an item has no ``=`` or an empty name or folder.
    """
    out: dict[str, str] = {}
    for item in items or ():
        name, sep, folder = str(item).partition("=")
        if not sep or not name.strip() or not folder.strip():
            raise InvalidArgument(
                f"--package expects NAME=DIR (e.g. --package my_robot_description=~/ws/src/"
                f"my_robot_description), got {item!r}")
        out[name.strip()] = folder.strip()
    return out


def check_packages(packages) -> dict[str, Path]:
    """Validate a ``packages`` mapping: names to existing folders (``~`` expanded).

    Raises:
        InvalidArgument: not a mapping of str to path, or a folder does not exist.
    """
    if packages is None:
        return {}
    if not hasattr(packages, "items"):
        raise InvalidArgument(
            f"packages must be a dict {{'NAME': '/path/to/NAME'}}, got {type(packages).__name__}")
    out = {}
    for name, folder in packages.items():
        if not isinstance(name, str) or not name:
            raise InvalidArgument(f"packages: names must be non-empty strings, got {name!r}")
        path = Path(os.fspath(folder)).expanduser().resolve()
        if not path.is_dir():
            raise InvalidArgument(
                f"packages[{name!r}] = {str(folder)!r} is not an existing folder; give the folder "
                f"that 'package://{name}/...' refers to (the one holding package.xml)")
        out[name] = path
    return out


def _package_xml_name(folder: Path) -> str | None:
    try:
        return (ET.parse(folder / "package.xml").getroot().findtext("name") or "").strip() or None
    except (OSError, ET.ParseError):
        return None


class UriResolver:
    """Resolves the file URIs of one model (see the module docstring for the order).

    Args:
        model_dir: folder of the model file (``None`` for a model given as text: only
            absolute paths, ``file://`` and the given/installed packages resolve).
        packages: ``{"NAME": folder}``.
        source: the model's name for messages.
    """

    def __init__(self, model_dir: Path | None, packages=None, source: str = "<string>"):
        self.model_dir = Path(model_dir).resolve() if model_dir is not None else None
        self.packages = check_packages(packages)
        self.source = source
        self.found: dict[str, Path] = {}  # package name -> folder, for Drake's PackageMap
        self._xml_cache: dict[str, list[tuple[str, Path]]] | None = None

    # --- package search -------------------------------------------------------------------

    def _ancestors(self) -> list[Path]:
        if self.model_dir is None:
            return []
        return [self.model_dir, *self.model_dir.parents]

    def _package_xml_candidates(self) -> list[tuple[str, Path]]:
        """(name, folder) of every package.xml up the tree (and beside the nearest ancestors)."""
        if self._xml_cache is None:
            seen, out = set(), []
            for i, folder in enumerate(self._ancestors()):
                dirs = [folder]
                if i < _NEAR_ANCESTORS:
                    try:
                        dirs += sorted(p for p in folder.iterdir() if p.is_dir())
                    except OSError:
                        pass
                for d in dirs:
                    if d in seen or not (d / "package.xml").is_file():
                        continue
                    seen.add(d)
                    name = _package_xml_name(d)
                    if name:
                        out.append((name, d))
            self._xml_cache = out
        return self._xml_cache

    def package_dir(self, name: str, rest: str, searched: list[str]) -> Path | None:
        """The folder of package ``name`` (``rest`` is the path inside it), or ``None``."""
        if name in self.packages:
            return self.packages[name]
        searched.append(f"packages= (given: {sorted(self.packages) or 'none'})")
        for pkg, folder in self._package_xml_candidates():
            if pkg == name:
                return folder
        if self.model_dir is not None:
            searched.append(f"package.xml files up the tree from {self.model_dir} (found: "
                            f"{sorted({n for n, _ in self._package_xml_candidates()}) or 'none'})")
        for entry in filter(None, os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep)):
            base = Path(entry).expanduser()
            for d in (base, base / name):
                if d.is_dir() and (d.name == name or _package_xml_name(d) == name):
                    return d
        searched.append(f"ROS_PACKAGE_PATH ({os.environ.get('ROS_PACKAGE_PATH') or 'not set'})")
        for prefix in filter(None, os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep)):
            d = Path(prefix).expanduser() / "share" / name
            if d.is_dir():
                return d
        searched.append(f"AMENT_PREFIX_PATH/share/{name} "
                        f"({os.environ.get('AMENT_PREFIX_PATH') or 'not set'})")
        folder = installed_package_dir(name)
        if folder is not None:
            return folder
        searched.append(f"this Python's prefixes (share/{name}, site-packages/cmeel.prefix/share/{name})")
        for folder in self._ancestors():
            if folder.name == name:
                return folder
            if (folder / name / rest).exists():
                return folder / name
            if rest and (folder / rest).exists():
                return folder
        if self.model_dir is not None:
            searched.append(f"the model's folder and its parents ({self.model_dir} ... /): a "
                            f"folder named {name!r}, or holding {name}/{rest} or {rest}")
        return None

    # --- files ---------------------------------------------------------------------------

    def resolve(self, uri: str) -> Path:
        """The existing file ``uri`` refers to.

        Raises:
            UnknownPackage: ``package://NAME/...`` and no place provides ``NAME``.
            MeshNotFound: the file does not exist where the URI points.
        """
        uri = uri.strip()
        parsed = urlparse(uri)
        searched: list[str] = []
        if parsed.scheme in ("package", "model"):
            name, rest = parsed.netloc, unquote(parsed.path).lstrip("/")
            folder = self.package_dir(name, rest, searched)
            if folder is None:
                raise UnknownPackage(name, uri, searched, self.source)
            self.found.setdefault(name, folder)
            path = folder / rest
            searched = [f"{path} (package {name!r} at {folder})"]
        elif parsed.scheme == "file":
            path = Path(unquote(parsed.path))
            searched.append(str(path))
        elif parsed.scheme in ("", ) or (len(parsed.scheme) == 1 and os.name == "nt"):
            path = Path(uri).expanduser()
            if not path.is_absolute():
                if self.model_dir is None:
                    raise MeshNotFound(
                        uri, ["(relative path in a model given as text: nothing to resolve it "
                              "against)"], self.source,
                        hint="load the model from its file with load_robot(path), or use absolute "
                             "or package:// URIs with packages={'NAME': DIR}")
                path = self.model_dir / path
            searched.append(str(path))
        else:
            raise MeshNotFound(uri, [f"(scheme {parsed.scheme!r} is not supported: use package://, "
                                     "file://, or a path)"], self.source)
        if not path.is_file():
            raise MeshNotFound(uri, searched, self.source)
        return path.resolve()

    def populate(self, package_map) -> None:
        """Add the packages given or found so far to a Drake ``PackageMap``."""
        for name, folder in {**self.found, **self.packages}.items():
            if not package_map.Contains(name):
                package_map.Add(name, str(folder))
