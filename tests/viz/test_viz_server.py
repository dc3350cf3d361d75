"""The shared Meshcat server: localhost only, reused, clear errors, thread ownership."""

from __future__ import annotations

import threading
import urllib.request
from pathlib import Path

import pytest

from drake_mh.errors import InvalidArgument, VisualizationError
from drake_mh.viz import View, close_meshcat, get_meshcat, meshcat_url


def test_server_is_reused_and_on_localhost(meshcat):
    assert get_meshcat() is meshcat
    assert get_meshcat(port=meshcat.port()) is meshcat
    assert meshcat_url() == meshcat.web_url() == f"http://localhost:{meshcat.port()}"


def test_server_serves_the_viewer_offline(meshcat):
    with urllib.request.urlopen(meshcat.web_url(), timeout=10) as response:
        page = response.read()
    assert response.status == 200
    assert b"meshcat" in page.lower()


def _listening_addresses(port: int) -> list[str]:
    """Local addresses (hex, as in /proc/net/tcp*) of the sockets listening on ``port``."""
    out = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        path = Path(table)
        if not path.exists():
            continue
        for line in path.read_text().splitlines()[1:]:
            fields = line.split()
            address, state = fields[1], fields[3]
            host, hex_port = address.rsplit(":", 1)
            if state == "0A" and int(hex_port, 16) == port:  # 0A = LISTEN
                out.append(host)
    return out


@pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux /proc/net/tcp to list listening sockets")
def test_server_listens_on_loopback_only(meshcat):
    hosts = _listening_addresses(meshcat.port())
    assert hosts, "the Meshcat port is not listening"
    loopback = {"0100007F", "00000000000000000000000001000000"}  # 127.0.0.1, ::1
    assert set(hosts) <= loopback, f"Meshcat listens on {hosts}, not only on loopback"


@pytest.mark.parametrize("port", [-1, 80, 70000, 1.5, "7000", True])
def test_bad_port_is_refused(meshcat, port):
    with pytest.raises(InvalidArgument, match="port"):
        get_meshcat(port=port)


def test_other_port_than_the_running_server_is_refused(meshcat):
    other = 65000 if meshcat.port() != 65000 else 65001
    with pytest.raises(InvalidArgument, match="already runs"):
        get_meshcat(port=other)


def test_use_from_another_thread_raises_instead_of_exiting(meshcat, planar2r):
    found = {}

    def worker():
        # Drake also aborts if a server is destroyed by another thread than its creator, so
        # nothing created here may outlive the thread: keep only plain values.
        try:
            View(planar2r, meshcat=meshcat)
        except VisualizationError as exc:
            found["error"] = str(exc)
        own = get_meshcat(port=0, announce=False)  # the thread's own server works
        view = View(planar2r, meshcat=own)
        found["own_is_shared"] = own is meshcat
        found["drawn"] = own.HasPath(view.link_paths()["link1"])
        del view, own
        close_meshcat()

    thread = threading.Thread(target=worker)
    thread.start()
    thread.join(timeout=60)
    assert "another thread" in found["error"]
    assert found["own_is_shared"] is False and found["drawn"] is True


def test_every_drawing_method_checks_the_thread(meshcat, planar2r):
    """A view made here and drawn from another thread: each call raises (Drake would abort)."""
    view = View(planar2r, meshcat=meshcat)
    calls = {
        "set_q": lambda: view.set_q(planar2r.home),
        "add_ghost": lambda: view.add_ghost(planar2r.home),
        "add_path": lambda: view.add_path([[0, 0, 0], [0.1, 0, 0]]),
        "add_target": lambda: view.add_target([0.3, 0, 0]),
        "clear": view.clear,
    }
    errors = {}

    def worker():
        for name, call in calls.items():
            try:
                call()
            except VisualizationError:
                errors[name] = True

    thread = threading.Thread(target=worker)
    thread.start()
    thread.join(timeout=60)
    assert errors == {name: True for name in calls}
    view.set_q(planar2r.home)                    # the owner thread still draws


_HANDED_OVER = """
import threading
import drake_mh
from drake_mh.errors import VisualizationError
from drake_mh.viz import View, get_meshcat, close_meshcat
robot = drake_mh.load_robot("panda")
made = {}

def worker():
    made["view"] = View(robot, meshcat=get_meshcat(port=0, announce=False))  # handed to the main thread

def tidy_worker():  # everything it makes dies with it: destroyed on its own thread, port freed
    meshcat = get_meshcat(port=0, announce=False)
    made["port"] = meshcat.port()
    View(robot, meshcat=meshcat)
    del meshcat
    close_meshcat()

for target in (worker, tidy_worker):
    thread = threading.Thread(target=target)
    thread.start()
    thread.join()
try:
    made["view"].set_q(robot.home)
except VisualizationError as exc:
    print("refused:", exc)
import socket
with socket.socket() as s:
    s.bind(("localhost", made["port"]))  # the tidy worker's server is gone
print("port free")
"""


def test_a_view_handed_from_a_worker_thread_does_not_abort_the_process(tmp_path):
    """Drake's Meshcat asserts in its destructor that its creating thread destroys it: a view made
    in a worker and kept by the main thread ended the process with SIGABRT (rc -6) at exit."""
    import subprocess
    import sys

    script = tmp_path / "handed_over.py"
    script.write_text(_HANDED_OVER)
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "refused: this Meshcat server was started by another thread" in out.stdout
    assert "port free" in out.stdout
    assert "serves until the process exits" in out.stderr  # the handed-over server, said once
    assert out.stderr.count("serves until the process exits") == 1
