"""The Meshcat server shared by every view: started once, bound to localhost only.

Drake's ``Meshcat`` is a websocket + http server (no browser is needed to use it). Starting one
takes a port, and Drake requires every call on an instance to come from the thread that created
it (a call from another thread ends the process with ``SystemExit``). So drake_mh keeps **one
instance per thread that uses it** — in practice one per process, created on first use in the
main thread — and refuses, with a clear error, an instance used from the wrong thread. Drake
also aborts the process when an instance is *destroyed* by another thread than its creator, and
Python destroys an object in whichever thread drops its last reference (at exit, the main
thread). So every server that a thread other than the main thread starts stays held by that
thread (:class:`_Keeper`) until nothing else refers to it, and is then destroyed there; one that
is still referred to when its thread ends (a :class:`~drake_mh.viz.View` handed to another
thread) is never destroyed: it serves until the process exits.

Unlike ``pydrake.geometry.StartMeshcat()`` (which listens on every interface by default), the
server here listens on ``localhost`` only; to view it from another machine, forward the port
(``ssh -L 7000:localhost:7000 host``).
"""

from __future__ import annotations

import contextlib
import logging
import sys
import threading
import weakref

from drake_mh.errors import InvalidArgument, VisualizationError

logger = logging.getLogger(__name__)

__all__ = ["get_meshcat", "close_meshcat", "meshcat_url", "check_thread", "private_meshcat"]

DEFAULT_HOST = "localhost"
"""Interface the server listens on; never ``*`` (all interfaces)."""

_local = threading.local()  # main thread: .meshcat, its shared server; other threads: .keeper
_owner: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # meshcat -> creating thread id


def get_meshcat(port: int | None = None, *, announce: bool = True):
    """The Meshcat server of the calling thread, started on first use.

    Args:
        port: http port; ``None`` (default) takes the first free port from 7000 to 7999,
            ``0`` an arbitrary free port. Once the server runs, ``None`` or its own port
            returns it; another port raises (call :func:`close_meshcat` first).
        announce: print the URL to stdout when the server starts.

    Returns:
        A ``pydrake.geometry.Meshcat`` listening on ``localhost``.

    Raises:
        InvalidArgument: ``port`` is not ``None``, 0 or 1024-65535, or differs from the
            running server's port.
        VisualizationError: the server cannot start (e.g. the port is taken).
    """
    if port is not None:
        if isinstance(port, bool) or not isinstance(port, int) or not (port == 0 or 1024 <= port <= 65535):
            raise InvalidArgument(f"port must be None (first free from 7000), 0 (any free port) or "
                                  f"1024-65535, got {port!r}")
    keeper = _keeper()
    meshcat = getattr(_local, "meshcat", None) if keeper is None else keeper.shared
    if meshcat is not None:
        if port not in (None, 0) and port != meshcat.port():
            raise InvalidArgument(
                f"a Meshcat server already runs at {meshcat.web_url()} in this thread; use it "
                f"(port=None) or call drake_mh.viz.close_meshcat() before asking for port {port}")
        return meshcat
    from pydrake.geometry import Meshcat, MeshcatParams

    params = MeshcatParams()
    params.host = DEFAULT_HOST
    params.show_stats_plot = False  # the "rtr%" frame-rate box means nothing to a planning user
    params.port = port
    try:
        meshcat = Meshcat(params)
    except (RuntimeError, SystemExit) as exc:  # Drake throws when no port can be bound
        where = f"port {port}" if port else "any port from 7000 to 7999"
        raise VisualizationError(
            f"cannot start Meshcat on localhost ({where}): {exc}; free the port, pass another "
            "port, or reuse the running server with drake_mh.viz.get_meshcat()") from exc
    if keeper is None:
        _local.meshcat = meshcat
    else:
        keeper.shared = meshcat
    _owner[meshcat] = threading.get_ident()
    logger.info("Meshcat listening at %s", meshcat.web_url())
    if announce:
        print(f"drake_mh.viz: Meshcat at {meshcat.web_url()} (open it in a browser)", file=sys.stdout)
    return meshcat


@contextlib.contextmanager
def private_meshcat():
    """A Meshcat of its own for recording a page (``StaticHtml``), closed on exit.

    Drake's ``Meshcat`` always runs a server (there is no offline scene builder), so recording
    an animation for a report needs one; this one is made silent and short-lived: it listens
    on ``localhost`` only, on an arbitrary free port (never 7000-7999, which a user's viewer
    takes), is not announced (Drake's "Meshcat listening" log line is held back and nothing
    is printed), is not this thread's shared server, and is closed when the block ends
    (once the caller has dropped every view drawn on it).

    Yields:
        A ``pydrake.geometry.Meshcat``.

    Raises:
        VisualizationError: no port can be bound.
    """
    from pydrake.geometry import Meshcat, MeshcatParams

    params = MeshcatParams()
    params.host = DEFAULT_HOST
    params.show_stats_plot = False
    params.port = 0
    drake_logger = logging.getLogger("drake")
    level = drake_logger.level
    drake_logger.setLevel(max(logging.WARNING, level))
    try:
        meshcat = Meshcat(params)
    except (RuntimeError, SystemExit) as exc:
        raise VisualizationError(f"cannot start a private Meshcat on localhost: {exc}") from exc
    finally:
        drake_logger.setLevel(level)
    _owner[meshcat] = threading.get_ident()
    logger.debug("private Meshcat for recording on port %d", meshcat.port())
    try:
        yield meshcat
    finally:
        _owner.pop(meshcat, None)
        keeper = _keeper()
        if keeper is not None:
            keeper.release(meshcat)
        del meshcat  # last reference: Drake stops the server and frees the port here


def meshcat_url(meshcat=None) -> str:
    """URL (``http://localhost:PORT``) of ``meshcat`` or of this thread's server (started if needed)."""
    return (meshcat if meshcat is not None else get_meshcat()).web_url()


def close_meshcat() -> None:
    """Forget this thread's server; it stops (freeing its port) once no view refers to it.

    The next :func:`get_meshcat` starts a new server.
    """
    keeper = _keeper()
    if keeper is not None:
        if keeper.shared is not None:
            _owner.pop(keeper.shared, None)
            keeper.release(keeper.shared)
            keeper.shared = None
        return
    meshcat = getattr(_local, "meshcat", None)
    if meshcat is not None:
        _owner.pop(meshcat, None)
        del _local.meshcat


def check_thread(meshcat) -> None:
    """Raise :class:`VisualizationError` if ``meshcat`` was created by another thread.

    Drake would otherwise end the process (``SystemExit``) on the first call.
    """
    owner = _owner.get(meshcat)
    if owner is not None and owner != threading.get_ident():
        raise VisualizationError(
            "this Meshcat server was started by another thread and Drake only accepts calls from "
            "that thread; create the view in the thread that uses it (drake_mh.viz.get_meshcat() "
            "gives each thread its own server) or use a process pool")


class _Keeper:
    """What a thread other than the main thread holds of the servers it started: its shared
    server, and those it released (:func:`close_meshcat`, the end of :func:`private_meshcat`)
    that a caller or a view may still refer to. Each call of this module on the thread drops the
    released ones that nothing else refers to any more: Drake destroys them there, on their own
    thread. When the thread ends, Python clears its locals on that thread, and :meth:`__del__`
    does the same one last time; a server still referred to then would later be destroyed by
    another thread (Drake aborts the process), so it is kept for the life of the process."""

    def __init__(self):
        self.shared = None
        self.released: list = []

    def release(self, meshcat) -> None:
        """Hold ``meshcat`` until nothing else refers to it (:meth:`sweep`)."""
        if not any(m is meshcat for m in self.released):
            self.released.append(meshcat)

    def sweep(self) -> list:
        """Drop the released servers that nothing else refers to (destroyed now, on this thread);
        returns those still referred to."""
        refs = [weakref.ref(meshcat) for meshcat in self.released]
        self.released.clear()
        self.released = [meshcat for meshcat in (ref() for ref in refs) if meshcat is not None]
        return self.released

    def __del__(self):
        if self.shared is not None:
            self.release(self.shared)
            self.shared = None
        for meshcat in self.sweep():
            _keep_forever(meshcat)


def _keeper() -> _Keeper | None:
    """This thread's :class:`_Keeper` (``None`` on the main thread: Python's exit destroys what is
    left there, on the main thread), after a :meth:`~_Keeper.sweep`."""
    if threading.current_thread() is threading.main_thread():
        return None
    keeper = getattr(_local, "keeper", None)
    if keeper is None:
        keeper = _local.keeper = _Keeper()
    keeper.sweep()
    return keeper


def _keep_forever(meshcat) -> None:
    """A reference that is never dropped: ``meshcat`` is never destroyed (so never by a thread
    that did not make it); it serves until the process exits."""
    import ctypes

    ctypes.pythonapi.Py_IncRef(ctypes.py_object(meshcat))
    logger.warning("a Meshcat server (%s) is still in use after the thread that started it ended; Drake can "
                   "only destroy it on that thread, so it serves until the process exits", meshcat.web_url())
