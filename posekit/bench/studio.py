"""``posekit bench studio``: what a student feels in the browser — the posing studio's update latency, end to end.

Introduced in ``notebooks/06_posing_studio.ipynb``. One run:

1. serves a copy of the notebook with **Voila** (in a temporary folder, so exports never touch the
   repository; idle kernels are culled) and opens it in headless **Chromium** through Playwright
   (Debian's ``/usr/bin/chromium``, or ``$POSEKIT_CHROMIUM``; Playwright cannot download a browser here);
2. for each configuration (``--configs``, e.g. ``fabrik,dls`` and ``protores,neural``) chooses those solvers
   with the studio's own list and *compare* button;
3. moves the first view's *target x* slider by one 1 mm step per key press, ``--updates`` times, each press
   as soon as the previous update has arrived. The **latency** of an update runs from the key press in the
   page to the moment the studio's summary shows the next update number: the value has crossed the
   websocket, the kernel has solved with every solver and redrawn every view, and the browser has applied
   the new poses and labels (times taken in the page with ``performance.now()``);
4. records the kernel's resident memory (RSS) after the first tenth of the updates and at the end, and
   whether the kernel process survived.

Goals (issue: the posing studio): p95 <= 100 ms with FABRIK, <= 150 ms with the learned solvers. These are
measured and printed, never asserted: ``tests/viz/test_studio_browser.py`` asserts only that 1,000 rapid
updates all arrive, the kernel survives and its memory does not grow.
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

import numpy as np

from ..ik.registry import solver_info
from ..paths import notebooks_dir
from .plugin import arg, register_benchmark

__all__ = ["serve_voila", "launch_chromium", "update_number", "open_studio", "choose_solvers", "rapid_updates", "kernel_processes", "run", "GOALS",
           "CHROMIUM", "CHROMIUM_FLAGS", "NOTEBOOK"]

NOTEBOOK = notebooks_dir() / "studio.ipynb"
"""What ``make studio`` serves: the studio alone (:mod:`posekit.viz.studio_app`; lesson 06 builds the same)."""
CHROMIUM = os.environ.get("POSEKIT_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-quic"]
GOALS = {"fabrik": 100.0, "learned": 150.0}
"""p95 goals, milliseconds: a configuration with a learned solver gets the learned goal."""
def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def kernel_processes(server_pid: int) -> list:
    """The kernel processes (psutil.Process) a Voila server started."""
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


class VoilaServer:
    """A running Voila server: ``url``, ``process``, ``folder`` (its working copy), ``log`` (path) and
    :meth:`stop`, which shuts it down and returns the kernel processes still alive afterwards (none, when
    Voila shut its kernels down)."""

    def __init__(self, process, url, folder, log):
        self.process, self.url, self.folder, self.log = process, url, Path(folder), Path(log)
        self.kernels_seen = []

    def note_kernels(self):
        """Remember the kernels now running (call while a page is open)."""
        for p in kernel_processes(self.process.pid):
            if p.pid not in {k.pid for k in self.kernels_seen}:
                self.kernels_seen.append(p)
        return self.kernels_seen

    def stop(self, timeout: float = 30.0) -> list:
        import psutil

        self.note_kernels()
        if self.process.poll() is None:
            self.process.terminate()  # Voila shuts its kernels down on SIGTERM
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
        for k in alive:  # never leave a kernel behind, even when Voila did
            with contextlib.suppress(psutil.Error):
                k.kill()
        return alive

    def log_tail(self, n: int = 2000) -> str:
        return self.log.read_text(errors="replace")[-n:] if self.log.exists() else ""


@contextlib.contextmanager
def serve_voila(notebook=NOTEBOOK, folder=None, cull_idle_s: int = 600, startup_s: float = 120.0,
                preheat: int = 0):
    """Serve a copy of ``notebook`` with Voila on a free local port; yields a :class:`VoilaServer`.

    The copy lives in ``folder`` (default a new temporary folder); kernels idle for ``cull_idle_s`` seconds
    are culled, and leaving the block stops the server and its kernels. ``preheat``: that many kernels kept
    with the notebook already run (Voila's kernel pool, what ``make studio`` does), 0 none.
    """
    own = folder is None
    folder = Path(tempfile.mkdtemp(prefix="posekit-studio-") if own else folder)
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(notebook, folder / Path(notebook).name)
    port = _free_port()
    log_path = folder / "voila.log"
    cmd = [sys.executable, "-m", "voila", Path(notebook).name, "--no-browser", f"--port={port}",
           "--Voila.ip=127.0.0.1", f"--MappingKernelManager.cull_idle_timeout={cull_idle_s}",
           "--MappingKernelManager.cull_interval=30", "--VoilaConfiguration.show_tracebacks=True"]
    if preheat > 0:
        cmd += ["--preheat_kernel=True", f"--pool_size={int(preheat)}"]
    log = open(log_path, "w")
    proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=folder)
    server = VoilaServer(proc, f"http://127.0.0.1:{port}/", folder, log_path)
    try:
        t0 = time.time()
        while True:
            try:  # any answer means the server is up (a GET of the notebook itself would start a kernel)
                urllib.request.urlopen(f"http://127.0.0.1:{port}/static/", timeout=2)
                break
            except urllib.error.HTTPError:
                break
            except OSError:
                if proc.poll() is not None:
                    raise RuntimeError(f"voila exited: {server.log_tail()}") from None
                if time.time() - t0 > startup_s:
                    raise RuntimeError(f"voila did not answer within {startup_s:.0f} s: {server.log_tail()}") from None
                time.sleep(0.5)
        yield server
    finally:
        server.stop()
        log.close()
        if own:
            shutil.rmtree(folder, ignore_errors=True)


def launch_chromium(playwright):
    """Debian's Chromium, headless, with the flags WebGL needs here (SwiftShader)."""
    if not Path(CHROMIUM).exists():
        raise RuntimeError(f"{CHROMIUM} not found: install Debian's chromium (make test does), or set POSEKIT_CHROMIUM")
    return playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_FLAGS, headless=True)


SUMMARY = ".posekit-summary"
"""The studio's summary table (its text starts with ``update N``)."""

_UPDATE = f"""() => {{ const e = document.querySelector('{SUMMARY}');
  const m = e && e.textContent.match(/update (\\d+)/); return m ? parseInt(m[1]) : -1; }}"""


def update_number(page) -> int:
    """The studio's update counter as the page shows it (-1 before the studio is drawn)."""
    return page.evaluate(_UPDATE)


def open_studio(browser, url: str, timeout_s: float = 300.0, viewport=(1400, 1600)):
    """Open the served studio; returns the page once its summary and every view's canvas are drawn."""
    page = browser.new_page(viewport={"width": viewport[0], "height": viewport[1]})
    page.goto(url, timeout=timeout_s * 1000, wait_until="commit")  # Voila streams the page as cells run
    page.wait_for_selector(f"{SUMMARY}:has-text('update')", timeout=timeout_s * 1000)
    page.wait_for_selector(".posekit-views canvas", timeout=timeout_s * 1000)
    return page


def choose_solvers(page, names, timeout_s: float = 120.0):
    """Tick exactly ``names`` in the studio's solver check boxes, press *compare*, wait for one canvas per solver."""
    n0 = update_number(page)
    for box in page.locator(".posekit-solver-choice .widget-checkbox").all():
        tick = box.locator("input")
        if (box.inner_text().strip() in names) != tick.is_checked():
            tick.click()
    page.locator(".posekit-compare").click()
    page.wait_for_function(f"() => document.querySelectorAll('.posekit-views canvas').length === {len(names)}",
                           timeout=timeout_s * 1000)
    page.wait_for_function(f"() => ({_UPDATE})() > {n0}", timeout=timeout_s * 1000)
    for name in names:
        page.locator(".posekit-views").get_by_text(name, exact=True).first.wait_for(timeout=timeout_s * 1000)


_RECORD = f"""() => {{
  window.__posekit = {{keys: [], updates: []}};
  const handle = document.querySelector('.posekit-target-x .noUi-handle');
  handle.addEventListener('keydown', () => window.__posekit.keys.push(performance.now()), true);
  const summary = document.querySelector('{SUMMARY}');
  new MutationObserver(() => {{
    const m = summary.textContent.match(/update (\\d+)/);
    if (m) window.__posekit.updates.push([parseInt(m[1]), performance.now()]);
  }}).observe(summary, {{subtree: true, childList: true, characterData: true}});
}}"""


def _settle(page, quiet_s: float = 1.5, timeout_s: float = 60.0) -> None:
    """Wait until the studio's update counter has stood still for ``quiet_s`` seconds (at most ``timeout_s``)."""
    last, since, t0 = update_number(page), time.monotonic(), time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        page.wait_for_timeout(100)
        now = update_number(page)
        if now != last:
            last, since = now, time.monotonic()
        elif time.monotonic() - since >= quiet_s:
            return


def rapid_updates(page, n: int, kernel=None, timeout_s: float = 30.0, progress: bool = False) -> dict:
    """Move the first view's target-x slider one step per key press, ``n`` times, each as soon as the last
    update has arrived; returns the latencies (ms, key press -> summary shows the next update) and the
    kernel's memory.

    Parameters
    ----------
    page : playwright Page with the studio open
    n : int
    kernel : psutil.Process, optional
        The kernel, for its resident memory after the first tenth of the updates and at the end.

    Returns
    -------
    dict
        ``latency_ms`` (n,), ``rss_mb_early``, ``rss_mb_end``, ``kernel_alive``, ``updates`` (how many arrived).
    """
    if n < 1:
        raise ValueError(f"--updates must be at least 1, got {n}")
    if page.locator(".posekit-target-x .noUi-target[disabled], .posekit-target-x [disabled]").count():
        raise RuntimeError("the target sliders are disabled: select a joint in the first view first")
    _settle(page)  # a joint just selected re-draws its sliders: a key press must not land on the old ones
    page.evaluate(_RECORD)
    handle = page.locator(".posekit-target-x .noUi-handle").first
    handle.scroll_into_view_if_needed()
    handle.focus()
    rss_early = None
    it = range(n)
    if progress:
        from tqdm.auto import tqdm

        it = tqdm(it, desc="updates", unit="update")
    arrived = 0
    for i in it:
        before = update_number(page)
        page.keyboard.press("ArrowRight" if i % 2 == 0 else "ArrowLeft")  # 1 mm right, then back
        try:
            page.wait_for_function(f"() => ({_UPDATE})() > {before}", timeout=timeout_s * 1000, polling=5)
        except Exception as err:  # noqa: BLE001 - playwright's TimeoutError: the update never came
            on_slider = page.evaluate("() => !!document.activeElement && "
                                      "document.activeElement.classList.contains('noUi-handle')")
            raise RuntimeError(f"update {i + 1} of {n} did not arrive within {timeout_s:.0f} s (the key press "
                               f"{'reached' if on_slider else 'did not reach'} the slider)") from err
        arrived += 1
        if kernel is not None and i == max(n // 10 - 1, 0):
            rss_early = kernel.memory_info().rss / 2 ** 20
    rec = page.evaluate("() => window.__posekit")
    keys = np.asarray(rec["keys"], float)
    ups = np.sort(np.asarray([u[1] for u in rec["updates"]], float))
    # each key press's latency: the first summary change after it
    first = np.searchsorted(ups, keys)  # the first change at or after each press
    answered = first < len(ups)
    lat = ups[first[answered]] - keys[answered]
    alive = kernel.is_running() if kernel is not None else None
    rss_end = kernel.memory_info().rss / 2 ** 20 if alive else None
    return {"latency_ms": lat, "rss_mb_early": rss_early, "rss_mb_end": rss_end, "kernel_alive": alive,
            "updates": arrived}


def run(updates: int = 1000, configs=("fabrik,dls", "protores,neural"), progress: bool = True) -> list[dict]:
    """Serve the studio, measure every configuration (see the module docstring); one row per configuration."""
    from playwright.sync_api import sync_playwright

    configs = [tuple(n.strip() for n in c.split(",") if n.strip()) if isinstance(c, str) else tuple(c) for c in configs]
    from ..ik.registry import solver_names

    known = solver_names()
    for c in configs:
        bad = [n for n in c if n not in known]
        if bad or not 2 <= len(c) <= 4:
            raise ValueError(f"configuration {','.join(c)!r}: give 2-4 registered solvers"
                             + (f" (unknown: {', '.join(bad)})" if bad else ""))
    rows = []
    with serve_voila() as server, sync_playwright() as p:
        browser = launch_chromium(p)
        try:
            page = open_studio(browser, server.url)
            kernels = server.note_kernels()
            kernel = kernels[0] if kernels else None
            for c in configs:
                choose_solvers(page, c)
                r = rapid_updates(page, updates, kernel, progress=progress)
                lat = r["latency_ms"]
                learned = any(solver_info(n).data for n in c)  # a learned solver names the data it was trained on
                rows.append({
                    "solvers": ",".join(c), "updates": r["updates"], "p50_ms": round(float(np.percentile(lat, 50)), 1),
                    "p95_ms": round(float(np.percentile(lat, 95)), 1), "max_ms": round(float(lat.max()), 1),
                    "goal_p95_ms": GOALS["learned" if learned else "fabrik"],
                    "met": bool(np.percentile(lat, 95) <= GOALS["learned" if learned else "fabrik"]),
                    "rss_mb_early": None if r["rss_mb_early"] is None else round(r["rss_mb_early"], 1),
                    "rss_mb_end": None if r["rss_mb_end"] is None else round(r["rss_mb_end"], 1),
                    "kernel_alive": r["kernel_alive"]})
            page.close()
        finally:
            browser.close()
    return rows


register_benchmark(
    "studio", lambda args: run(updates=args.updates, configs=args.configs.split(";"), progress=not args.json),
    help="the posing studio in Voila + headless Chromium: p50/p95 latency of rapid target updates, kernel memory",
    args=[arg("--updates", type=int, default=1000, help="target updates per configuration"),
          arg("--configs", default="fabrik,dls;protores,neural",
              help="semicolon-separated configurations, each 2-4 comma-separated registered solvers")],
    tables=[("End-to-end update latency in the browser (key press -> every view solved and drawn)",
             ["solvers", "updates", "p50_ms", "p95_ms", "max_ms", "goal_p95_ms", "met"]),
            ("Kernel", ["solvers", "rss_mb_early", "rss_mb_end", "kernel_alive"])],
    labels={"p50_ms": "p50 ms", "p95_ms": "p95 ms", "max_ms": "max ms", "goal_p95_ms": "goal p95 ms",
            "rss_mb_early": "RSS MB at 10%", "rss_mb_end": "RSS MB at end", "kernel_alive": "kernel alive"},
    lesson="notebooks/06_posing_studio.ipynb")
