"""The app's own page: its controls and status on the left, Meshcat's 3-D view beside them.

Why a page of our own: Meshcat's control panel (dat.GUI) lists Drake's buttons and sliders
*after* its own "Scene", "Save / Load / Capture" and "Animations" folders, behind "Open
Controls"; in a 1400×900 window the status line and the obstacle sliders were below the fold.
Drake's ``Meshcat`` (pydrake 1.51) can neither reorder nor collapse those folders, nor run
JavaScript in its page (``SetProperty`` reaches scene objects only). So:

* a small HTTP server (standard library, ``localhost`` only, one daemon thread) serves one
  page: a panel with the status box first, then the controls in Table 1's order, and
  Meshcat's own page in an ``<iframe>`` beside it (its controls stay closed);
* the panel is a second client of Meshcat's websocket: it receives Drake's ``set_control`` /
  ``set_control_value`` / ``delete_control`` messages and draws them (the inert "Setup: ..." /
  "Status: ..." buttons become the status box); a click or a slider move calls the callback
  Drake attached to that control — the very code Meshcat's page runs (it sends a ``button`` or
  ``slider`` message), so Drake's click counts and slider values do not know the difference.

The server thread only returns the page's bytes: every Meshcat call stays in the thread that
created Meshcat (a Drake requirement). The page needs ``msgpack``, which Drake's
``meshcat.js`` carries: the server hands out pydrake's own copy (Drake's server names it by a
content hash only).
"""

from __future__ import annotations

import json
import logging
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

from drake_mh.errors import VisualizationError

logger = logging.getLogger(__name__)

__all__ = ["AppPage", "page_html"]

_PAGE = r"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>drake-mh app</title>
<style>
  html, body { margin: 0; height: 100%; font: 14px/1.35 system-ui, sans-serif; background: #1e1f24; color: #eee; }
  #wrap { display: flex; height: 100vh; }
  #panel { width: 360px; min-width: 360px; height: 100vh; overflow-y: auto; overflow-x: hidden; box-sizing: border-box;
           padding: 10px 12px; background: #1e1f24; border-right: 1px solid #444; }
  #view { flex: 1; border: 0; height: 100vh; }
  h1 { font-size: 16px; margin: 0 0 8px; font-weight: 600; }
  h1 small { display: block; font-size: 12px; font-weight: 400; color: #aaa; }
  #status { background: #fff8d6; color: #222; border-left: 5px solid #e0a000; padding: 6px 8px;
            margin-bottom: 8px; min-height: 58px; position: sticky; top: 0; z-index: 1; }
  #status .setup { font-size: 12px; color: #444; }
  #status .message { font-weight: 600; margin-top: 3px; }
  #status.down { background: #ffd9d6; border-left-color: #c0392b; }
  h2 { font-size: 12px; text-transform: uppercase; letter-spacing: .04em; color: #9ab;
       margin: 9px 0 4px; font-weight: 600; }
  /* minmax(0, 1fr): a grid column may shrink below its content's natural width (a range input's
     is about 130 px), so that every control stays inside the panel beside its scrollbar */
  .buttons { display: grid; grid-template-columns: minmax(0, 1fr) minmax(0, 1fr); gap: 5px; }
  .buttons > div { display: flex; }
  .buttons > div > button { flex: 1; }
  .buttons > .wide { grid-column: span 2; }
  button { font: inherit; padding: 5px 6px; border: 1px solid #556; border-radius: 4px; background: #2e3440;
           color: #eee; cursor: pointer; min-width: 0; overflow-wrap: anywhere; }
  button:hover { background: #3b4252; }
  button.primary { background: #2d6cdf; border-color: #2d6cdf; }
  button.stop { background: #8c2f2f; border-color: #8c2f2f; }
  .slider { display: grid; grid-template-columns: 132px minmax(0, 1fr) 62px; gap: 6px; align-items: center;
            margin: 2px 0; font-size: 13px; }
  .slider > * { min-width: 0; margin: 0; }
  .slider input[type=range] { width: 100%; }
  .slider input[type=number] { width: 100%; box-sizing: border-box; font: inherit; background: #2e3440; color: #eee;
                               border: 1px solid #556; border-radius: 3px; }
  .hint { font-size: 12px; color: #999; margin-top: 10px; }
  .hint a { color: #9cf; }
</style>
</head>
<body>
<div id="wrap">
  <div id="panel">
    <h1>drake-mh app <small>path planner, obstacle moves live</small></h1>
    <div id="status"><div class="setup">connecting to the app...</div><div class="message"></div></div>
    <div id="sections"></div>
    <div class="hint">3-D view: drag to orbit, scroll to zoom; its "Open Controls" is Meshcat's own panel
      (scene tree, recording). <a id="meshcat-link" target="_blank">Meshcat alone</a></div>
  </div>
  <iframe id="view" title="Meshcat 3-D view"></iframe>
</div>
<script>
const CONFIG = __CONFIG__;
const MESHCAT = location.protocol + "//" + location.hostname + ":" + CONFIG.meshcat_port;
document.getElementById("view").src = MESHCAT + "/";
document.getElementById("meshcat-link").href = MESHCAT + "/";
const script = document.createElement("script");
script.src = "meshcat.js";              // pydrake's, served beside this page
script.onload = start;
script.onerror = () => down("cannot load the 3-D viewer: is drake-mh app running?");
document.head.appendChild(script);

const panel = {connection: null};   // `this` of Drake's callbacks (they call this.connection.send)
const controls = {};                // name -> {callback, element, input?, number?}
const rows = {};                    // name -> the element reserved for it in its section
let msgpack = null;                 // Drake's callbacks call msgpack.encode

function down(text) {
  const box = document.getElementById("status");
  box.classList.add("down");
  box.querySelector(".setup").textContent = "";
  box.querySelector(".message").textContent = text;
}

function build() {
  const root = document.getElementById("sections");
  for (const section of CONFIG.sections) {
    const h = document.createElement("h2");
    h.textContent = section.title;
    root.appendChild(h);
    let grid = null;
    for (const name of section.controls) {
      const slot = document.createElement("div");
      slot.style.display = "none";
      if (CONFIG.sliders.includes(name)) {
        grid = null;
        root.appendChild(slot);
      } else {
        if (!grid) { grid = document.createElement("div"); grid.className = "buttons"; root.appendChild(grid); }
        if (CONFIG.wide.includes(name)) slot.className = "wide";
        grid.appendChild(slot);
      }
      rows[name] = slot;
    }
  }
  const other = document.createElement("div");
  other.className = "buttons";
  root.appendChild(other);
  rows[""] = other;
}

function isStatus(name) { return name.startsWith("Setup: ") || name.startsWith("Status: "); }

function showStatus() {
  const names = Object.keys(controls).filter(isStatus);
  const box = document.getElementById("status");
  box.classList.remove("down");
  const setup = names.find(n => n.startsWith("Setup: "));
  const message = names.find(n => n.startsWith("Status: "));
  box.querySelector(".setup").textContent = setup ? setup.trim() : "";
  box.querySelector(".message").textContent = message ? message.slice(8).trim() : "";
}

// Drake's own callback source, evaluated as Meshcat's page does; `this` in it is `panel`
function drakeCallback(source) { return eval(source); }

function addControl(cmd) {
  removeControl(cmd.name);
  const callback = drakeCallback.call(panel, cmd.callback);
  const entry = {callback: callback};
  controls[cmd.name] = entry;
  if (isStatus(cmd.name)) { showStatus(); return; }
  const slot = rows[cmd.name];
  if (cmd.value === undefined || cmd.value === null) {
    const b = document.createElement("button");
    b.textContent = cmd.name;
    b.dataset.name = cmd.name;
    if (CONFIG.primary.includes(cmd.name)) b.className = "primary";
    if (cmd.name === "Stop") b.className = "stop";
    b.onclick = () => entry.callback();
    entry.element = b;
  } else {
    const row = document.createElement("div");
    row.className = "slider";
    row.dataset.name = cmd.name;
    const label = document.createElement("span");
    label.textContent = cmd.name;
    const range = document.createElement("input");
    const number = document.createElement("input");
    range.type = "range"; number.type = "number";
    for (const input of [range, number]) {
      input.min = cmd.min; input.max = cmd.max; input.step = cmd.step; input.value = cmd.value;
    }
    range.oninput = () => { number.value = range.value; entry.callback(parseFloat(range.value)); };
    number.onchange = () => {
      const v = Math.min(Math.max(parseFloat(number.value), cmd.min), cmd.max);
      if (!isNaN(v)) { range.value = v; number.value = v; entry.callback(v); }
    };
    row.append(label, range, number);
    entry.element = row; entry.input = range; entry.number = number;
  }
  if (slot) { slot.replaceChildren(entry.element); slot.style.display = ""; }
  else rows[""].appendChild(entry.element);
}

function removeControl(name) {
  const entry = controls[name];
  if (!entry) return;
  delete controls[name];
  if (isStatus(name)) { showStatus(); return; }
  if (rows[name]) { rows[name].replaceChildren(); rows[name].style.display = "none"; }
  else if (entry.element) entry.element.remove();
}

function handle(cmd) {
  if (cmd.type === "set_control") addControl(cmd);
  else if (cmd.type === "delete_control") removeControl(cmd.name);
  else if (cmd.type === "set_control_value") {
    const entry = controls[cmd.name];
    if (entry && entry.input) { entry.input.value = cmd.value; entry.number.value = cmd.value; }
  }
}

function connect() {
  const ws = new WebSocket(MESHCAT.replace(/^http/, "ws") + "/");
  ws.binaryType = "arraybuffer";
  ws.onmessage = (m) => {
    let cmd = null;
    try { cmd = msgpack.decode(new Uint8Array(m.data)); } catch (e) { return; }  // scene data: not ours
    if (cmd && typeof cmd.type === "string" && cmd.type.indexOf("control") >= 0) handle(cmd);
  };
  ws.onclose = () => {
    for (const name of Object.keys(controls)) removeControl(name);
    down("app stopped (or not reachable): start drake-mh app again and reload this page");
    setTimeout(connect, 2000);
  };
  panel.connection = ws;
}

function start() {
  msgpack = MeshCat.msgpack;
  build();
  connect();
}
</script>
</body>
</html>
"""


def page_html(meshcat_port: int, sections, sliders, primary=(), wide=()) -> str:
    """The page's HTML.

    Args:
        meshcat_port: port of the Meshcat server (same host as the page).
        sections: ``[(title, [control names in order])]``: the panel's sections.
        sliders: names of the slider controls (the others are buttons).
        primary: buttons drawn highlighted; wide: buttons spanning the panel's width.
    """
    config = {"meshcat_port": int(meshcat_port), "sections": [{"title": t, "controls": list(c)} for t, c in sections],
              "sliders": list(sliders), "primary": list(primary), "wide": list(wide)}
    # "</" cannot end the script element early: names are plain text
    return _PAGE.replace("__CONFIG__", json.dumps(config).replace("</", "<\\/"))


def _meshcat_js() -> bytes:
    from pydrake.common import FindResourceOrThrow

    with open(FindResourceOrThrow("drake/geometry/meshcat.js"), "rb") as f:
        return f.read()


class AppPage:
    """Serves :func:`page_html` at ``/`` and pydrake's ``meshcat.js`` on ``localhost`` from a
    daemon thread until :meth:`close`.

    Args:
        html: the page.
        port: http port; ``None`` takes the first free port from ``first`` on (up to 65535),
            ``0`` any.
        first: where the search for a free port starts (the app passes Meshcat's port + 1).

    Raises:
        VisualizationError: no port could be bound.
    """

    def __init__(self, html: str, port: int | None = None, first: int = 7001):
        files = {"/": (html.encode(), "text/html; charset=utf-8"),
                 "/meshcat.js": (_meshcat_js(), "text/javascript; charset=utf-8")}

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self):  # noqa: N802 - http.server's name
                path = self.path.split("?")[0]
                if path not in files:
                    self.send_error(404, "only / is served here; the 3-D view is Meshcat's own server")
                    return
                body, kind = files[path]
                self.send_response(200)
                self.send_header("Content-Type", kind)
                self.send_header("Content-Length", str(len(body)))
                self.send_header("Cache-Control", "no-store")
                self.end_headers()
                self.wfile.write(body)

            def log_message(self, fmt, *args):  # requests go to the debug log, not stderr
                logger.debug("app page: " + fmt, *args)

        candidates = [port] if port is not None else range(max(int(first), 1024), 65536)
        self._server, last = None, OSError("no port left to try")
        for candidate in candidates:
            try:
                self._server = ThreadingHTTPServer(("localhost", candidate), Handler)
                break
            except OSError as exc:
                last = exc
        if self._server is None:
            raise VisualizationError(f"cannot serve the app's page on localhost (port {port or 'from ' + str(first)}): "
                                     f"{last}; pass another port or free one")
        self._server.daemon_threads = True
        self._port = int(self._server.server_address[1])
        self._thread = threading.Thread(target=self._server.serve_forever, name="drake-mh app page", daemon=True)
        self._thread.start()

    @property
    def port(self) -> int:
        """The port the page is served on."""
        return self._port

    @property
    def url(self) -> str:
        """``http://localhost:PORT``."""
        return f"http://localhost:{self.port}"

    def close(self) -> None:
        """Stops serving (idempotent)."""
        if self._server is not None:
            self._server.shutdown()
            self._server.server_close()
            self._server = None
