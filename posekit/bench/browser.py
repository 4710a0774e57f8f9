"""The browser plumbing that ``posekit bench studio`` and the browser tests share: notebook servers (Voila, as
``make studio`` runs it; JupyterLab, as ``make lab`` runs it) on a free local port, headless Chromium with the
project's flags, and the kernels a server leaves behind stopped.

Introduced with the posing studio of ``notebooks/06_posing_studio.ipynb`` (``posekit bench studio`` measures it in
the browser). Top-layer tooling beside the benchmarks: it imports the viewer's serving settings
(:mod:`posekit.viz.studio_app`, :mod:`posekit.viz.websocket`) when it starts a server, and nothing imports it but
the benchmark and the tests.

* :func:`free_port` — a TCP port nothing listens on, on 127.0.0.1;
* :func:`serve_voila` — a copy of a notebook served by Voila (the studio app's page template, the kernel's
  websocket without Nagle's delay, idle kernels culled), yielding a :class:`VoilaServer`;
* :func:`serve_lab` — JupyterLab on a folder, with a token, yielding a :class:`LabServer`;
* :meth:`NotebookServer.stop` — stops a server and kills any kernel it left running;
* :func:`launch_chromium` — Debian's ``/usr/bin/chromium`` (or ``$POSEKIT_CHROMIUM``; Playwright cannot download a
  browser here), headless, with :data:`CHROMIUM_FLAGS` (software WebGL, nothing fetched in the background);
  :func:`chromium_missing` says why it cannot start;
* :func:`new_tab`, :func:`blank_tab` — pages with :data:`QUIET_CONSOLE` installed.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from pathlib import Path

from ..paths import notebooks_dir

__all__ = ["CHROMIUM", "CHROMIUM_FLAGS", "QUIET_CONSOLE", "STUDIO_NOTEBOOK", "free_port", "chromium_missing",
           "launch_chromium", "new_tab", "blank_tab", "kernel_processes", "NotebookServer", "VoilaServer", "LabServer",
           "serve_voila", "serve_lab"]

STUDIO_NOTEBOOK = notebooks_dir() / "studio.ipynb"
"""What ``make studio`` serves: the studio alone (:mod:`posekit.viz.studio_app`; lesson 06 builds the same)."""
CHROMIUM = os.environ.get("POSEKIT_CHROMIUM", "/usr/bin/chromium")
"""The Chromium the tests and the benchmark drive: Debian's (``make test`` installs it), or ``$POSEKIT_CHROMIUM``."""
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-quic"]
"""Chromium's command-line flags here: no sandbox (containers, root), WebGL drawn in software (SwiftShader), and no
background requests (updates, sync, QUIC) that a machine without the internet would wait on."""

QUIET_CONSOLE = "console.debug = () => {};"
"""Run in every page the bench opens, before the page's own scripts: pythreejs logs each change of a scene's objects
with ``console.debug`` (several calls per studio update), and with Playwright attached every console call is
serialised and sent to the driving process — about 20 ms of the browser's time per update here (150 updates of
FABRIK + DLS with the renderer's profiler running: key press to update p50 90 ms with the calls, 61 ms without), a
cost a student's browser without a debugger attached does not pay. Other console levels stay as they are."""


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on now (the system picks it), for a server to bind next.

    Returns
    -------
    int
    """
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def chromium_missing() -> str | None:
    """Why :func:`launch_chromium` cannot start a browser (a sentence naming :data:`CHROMIUM` and how to install
    it), or None when it is there."""
    if Path(CHROMIUM).exists():
        return None
    return (f"{CHROMIUM} not found: install Debian's chromium and chromium-driver (make test does), "
            "or set POSEKIT_CHROMIUM")


def launch_chromium(playwright, headless: bool = True):
    """Debian's Chromium through Playwright, with :data:`CHROMIUM_FLAGS` (the flags WebGL needs here: SwiftShader).

    Parameters
    ----------
    playwright : playwright.sync_api.Playwright
        The object ``sync_playwright()`` gives.
    headless : bool

    Returns
    -------
    playwright.sync_api.Browser

    Raises
    ------
    RuntimeError
        When :data:`CHROMIUM` is missing (:func:`chromium_missing`).
    """
    missing = chromium_missing()
    if missing:
        raise RuntimeError(missing)
    return playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_FLAGS, headless=headless)


def new_tab(browser, viewport=(1400, 1600)):
    """A new page of ``viewport`` (width, height) pixels with :data:`QUIET_CONSOLE` installed."""
    page = browser.new_page(viewport={"width": viewport[0], "height": viewport[1]})
    page.add_init_script(QUIET_CONSOLE)
    return page


def blank_tab(browser, viewport=(1400, 1600)):
    """A new tab showing nothing yet (``about:blank``): the browser's own start of a tab (its renderer process, the
    software GL context) done, as in the browser a person already has open when they ask for the studio."""
    page = new_tab(browser, viewport)
    page.goto("about:blank")
    return page


def kernel_processes(server_pid: int) -> list:
    """The kernel processes (``psutil.Process``) a notebook server started: its descendants running ipykernel."""
    import psutil

    try:
        kids = psutil.Process(server_pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []
    out = []
    for p in kids:
        try:
            if "ipykernel" in " ".join(p.cmdline()):
                out.append(p)
        except psutil.Error:
            pass
    return out


class NotebookServer:
    """A running notebook server: ``url``, ``process``, ``folder`` (where it runs), ``log`` (path); :meth:`stop`
    shuts it down and returns the kernel processes still alive afterwards (none, when the server shut its kernels
    down: any left are killed)."""

    def __init__(self, process, url, folder, log):
        self.process, self.url, self.folder, self.log = process, url, Path(folder), Path(log)
        self.kernels_seen = []

    def note_kernels(self) -> list:
        """Remember the kernels now running (call while a page is open); returns every kernel seen so far."""
        for p in kernel_processes(self.process.pid):
            if p.pid not in {k.pid for k in self.kernels_seen}:
                self.kernels_seen.append(p)
        return self.kernels_seen

    def stop(self, timeout: float = 30.0) -> list:
        """Stop the server (SIGTERM: Voila and JupyterLab shut their kernels down), then wait up to ``timeout``
        seconds for its kernels to go and kill those that did not; returns the ones that had to be killed."""
        import psutil

        self.note_kernels()
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait(timeout=10)
        deadline = time.time() + timeout
        alive = [k for k in self.kernels_seen if k.is_running()]
        while alive and time.time() < deadline:
            time.sleep(0.5)
            alive = [k for k in alive if k.is_running() and k.status() != psutil.STATUS_ZOMBIE]
        for k in alive:  # never leave a kernel behind, even when the server did
            with contextlib.suppress(psutil.Error):
                k.kill()
        return alive

    def log_tail(self, n: int = 2000) -> str:
        """The last ``n`` characters of the server's log (its kernels write there too)."""
        return self.log.read_text(errors="replace")[-n:] if self.log.exists() else ""


class VoilaServer(NotebookServer):
    """A running Voila server (:func:`serve_voila`): ``url`` is the served notebook's page, ``base`` the server's
    root URL."""

    base = ""

    def url_of(self, name: str) -> str:
        """The page of another notebook the server was given (``serve_voila(extra=...)``)."""
        return f"{self.base}voila/render/{name}"


class LabServer(NotebookServer):
    """A running JupyterLab (:func:`serve_lab`): ``url`` is the server's root, ``token`` its login token."""

    token = ""


def _wait_until_up(server: NotebookServer, probe: str, startup_s: float, what: str) -> None:
    """Poll ``probe`` until the server answers at all (an HTTP error counts as an answer); RuntimeError with the
    log's tail when the server exits or ``startup_s`` seconds pass first."""
    t0 = time.time()
    while True:
        try:
            urllib.request.urlopen(probe, timeout=2)
            return
        except urllib.error.HTTPError:
            return
        except OSError:
            if server.process.poll() is not None:
                raise RuntimeError(f"{what} exited: {server.log_tail()}") from None
            if time.time() - t0 > startup_s:
                raise RuntimeError(f"{what} did not answer within {startup_s:.0f} s: {server.log_tail()}") from None
            time.sleep(0.5)


@contextlib.contextmanager
def serve_voila(notebook=None, folder=None, cull_idle_s: int = 600, startup_s: float = 120.0,
                preheat: int = 0, cull_interval_s: int = 30, extra=(), env=None):
    """Serve a copy of ``notebook`` with Voila on a free local port, as ``make studio`` does; yields a
    :class:`VoilaServer`.

    Parameters
    ----------
    notebook : str or Path, optional
        Default :data:`STUDIO_NOTEBOOK`, the studio app.
    folder : str or Path, optional
        Where the copy lives and the server runs (default a new temporary folder, removed afterwards): exports and
        autosaves never touch the repository.
    cull_idle_s, cull_interval_s : int
        Kernels idle for ``cull_idle_s`` seconds are culled, looked for every ``cull_interval_s``.
    startup_s : float
        How long the server may take to answer (RuntimeError after, with its log's tail).
    preheat : int
        That many kernels kept with the notebook already run (Voila's kernel pool, what ``make studio`` does),
        0 none.
    extra : sequence of paths
        More notebooks served by the same server (``server.url_of(name)``).
    env : dict, optional
        Environment variables for the server and its kernels over this process's (e.g.
        ``{"POSEKIT_ANTIALIAS": "0"}``).

    Leaving the block stops the server and its kernels (:meth:`NotebookServer.stop`).
    """
    from ..viz.studio_app import VOILA_PATH, VOILA_TEMPLATE
    from ..viz.websocket import server_flags

    notebook = STUDIO_NOTEBOOK if notebook is None else notebook
    own = folder is None
    folder = Path(tempfile.mkdtemp(prefix="posekit-studio-") if own else folder)
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(notebook, folder / Path(notebook).name)
    for nb in extra:
        shutil.copy(nb, folder / Path(nb).name)
    port = free_port()
    log_path = folder / "voila.log"
    served = [] if extra else [Path(notebook).name]  # several notebooks: Voila serves the folder
    cmd = [sys.executable, "-m", "voila", *served, "--no-browser", f"--port={port}", f"--template={VOILA_TEMPLATE}",
           "--Voila.ip=127.0.0.1", f"--MappingKernelManager.cull_idle_timeout={cull_idle_s}",
           f"--MappingKernelManager.cull_interval={cull_interval_s}", "--VoilaConfiguration.show_tracebacks=True"]
    cmd += server_flags("voila")  # each message to the page leaves at once (posekit.viz.websocket), as make studio
    if preheat > 0:
        cmd += ["--preheat_kernel=True", f"--pool_size={int(preheat)}"]
    log = open(log_path, "w")
    paths = os.pathsep.join(filter(None, [str(VOILA_PATH), os.environ.get("JUPYTER_PATH")]))
    proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=folder,
                            env={**os.environ, "JUPYTER_PATH": paths, **(env or {})})
    base = f"http://127.0.0.1:{port}/"
    server = VoilaServer(proc, base + (f"voila/render/{Path(notebook).name}" if extra else ""), folder, log_path)
    server.base = base
    try:
        # any answer means the server is up (a GET of the notebook itself would start a kernel)
        _wait_until_up(server, f"{base}static/", startup_s, "voila")
        yield server
    finally:
        server.stop()
        log.close()
        if own:
            shutil.rmtree(folder, ignore_errors=True)


@contextlib.contextmanager
def serve_lab(folder, token: str = "posekit-test", startup_s: float = 60.0, log_name: str = "lab.log"):
    """JupyterLab on ``folder`` on a free local port, as ``make lab`` runs it (no news, no update check, the kernel's
    websocket without Nagle's delay); yields a :class:`LabServer`.

    Parameters
    ----------
    folder : str or Path
        The server's root and working folder; its workspaces and its log (``log_name``) are written there.
    token : str
        The login token (``server.token``; a page opens ``{server.url}/lab?token=...``).
    startup_s : float
        How long the server may take to answer ``/api/status`` (RuntimeError after, with its log's tail).

    Leaving the block stops the server and its kernels (:meth:`NotebookServer.stop`).
    """
    from ..viz.websocket import server_flags

    folder = Path(folder)
    port = free_port()
    cmd = [sys.executable, "-m", "jupyter", "lab", "--no-browser", f"--port={port}", "--ip=127.0.0.1",
           f"--ServerApp.token={token}", f"--ServerApp.root_dir={folder}", "--ServerApp.open_browser=False",
           "--LabApp.news_url=", "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",
           f"--LabApp.workspaces_dir={folder / 'workspaces'}", *server_flags("lab")]  # as make lab
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        cmd.append("--allow-root")
    log_path = folder / log_name
    log = open(log_path, "w")
    proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=folder)
    server = LabServer(proc, f"http://127.0.0.1:{port}", folder, log_path)
    server.token = token
    try:
        _wait_until_up(server, f"{server.url}/api/status?token={token}", startup_s, "jupyter lab")
        yield server
    finally:
        server.stop(timeout=20.0)
        log.close()
