"""What a failed browser test leaves to read: each page's screenshot, the page's console, and the servers' logs.

A headless-Chromium test that fails on a busy machine (CI, a class server) is hard to read from its assertion
alone. The hooks here (imported by ``tests/conftest.py``) make every Playwright page that a test process opens
record its console and uncaught errors; when a test marked ``browser`` fails, they write into
``build/test-artifacts/<test>/`` (``$POSEKIT_TEST_ARTIFACTS`` moves it):

- ``page-N.png`` and ``page-N.html``: every page still open when the test failed, and every page the test closed
  while its failure was on the way out (a ``finally:`` or ``with`` block: the picture is taken before the close);
- ``page-N-console.txt``: what that page wrote to its console, and its uncaught errors;
- the logs of the servers the test used (JupyterLab's ``lab.log``, Voila's ``voila.log``: the kernels write
  there too), copied from the fixtures' folders.

The failure's report names the folder, and ``make test``'s closing summary lists every such folder; ``.ci/run``
prints the text files' tails when a test failed, so a failed landing can be read in its log.
"""

from __future__ import annotations

import os
import re
import shutil
import sys
import time
from collections import deque
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
ARTIFACTS = Path(os.environ.get("POSEKIT_TEST_ARTIFACTS", ROOT / "build" / "test-artifacts"))

_LOGS: dict = {}  # id(page) -> (page, deque of console lines)
_CLOSED: list = []  # (console lines, png bytes or None, html or None) of pages closed while a failure was raised
_SESSION_START = time.time()
_patched = False


def _record(page) -> None:
    if id(page) in _LOGS:
        return
    lines: deque = deque(maxlen=2000)
    _LOGS[id(page)] = (page, lines)
    t0 = time.monotonic()

    def on_console(msg):
        try:
            lines.append(f"{time.monotonic() - t0:8.3f} s  {msg.type}: {msg.text}")
        except Exception:  # a message from a page being torn down
            pass

    page.on("console", on_console)
    page.on("pageerror", lambda err: lines.append(f"{time.monotonic() - t0:8.3f} s  uncaught: {err}"))


def _keep_before_close(page) -> None:
    """A page closed while an exception is on its way out (the test is failing): keep its picture first."""
    if sys.exc_info()[0] is None or page.is_closed():
        return
    png = html = None
    try:
        png = page.screenshot(timeout=10_000)
        html = page.content()
    except Exception:
        pass
    lines = _LOGS.get(id(page), (None, []))[1]
    _CLOSED.append((list(lines), png, html))


def install() -> None:
    """Make every Playwright page this process opens record its console (once per process)."""
    global _patched
    if _patched:
        return
    try:
        from playwright.sync_api import Browser, BrowserContext, Page
    except ImportError:  # pragma: no cover - the browser tests need playwright anyway
        return
    _patched = True

    def wrap_new_page(cls):
        original = cls.new_page

        def new_page(self, *args, **kwargs):
            page = original(self, *args, **kwargs)
            _record(page)
            return page

        cls.new_page = new_page

    wrap_new_page(Browser)
    wrap_new_page(BrowserContext)

    original_page_close = Page.close

    def page_close(self, *args, **kwargs):
        _keep_before_close(self)
        return original_page_close(self, *args, **kwargs)

    Page.close = page_close

    original_context_close = BrowserContext.close

    def context_close(self, *args, **kwargs):
        for page in list(self.pages):
            _keep_before_close(page)
        return original_context_close(self, *args, **kwargs)

    BrowserContext.close = context_close

    original_browser_close = Browser.close

    def browser_close(self, *args, **kwargs):
        for context in list(self.contexts):
            for page in list(context.pages):
                _keep_before_close(page)
        return original_browser_close(self, *args, **kwargs)

    Browser.close = browser_close


def _server_logs(item) -> list[Path]:
    """The log files of the servers the test's fixtures started (JupyterLab's, Voila's)."""
    found = []

    def visit(value, depth=0):
        if depth > 2:
            return
        if isinstance(value, Path):
            if value.is_dir():
                found.extend(sorted(value.glob("*.log")))
            elif value.suffix == ".log" and value.is_file():
                found.append(value)
        elif isinstance(value, (tuple, list)):
            for v in value:
                visit(v, depth + 1)
        else:
            for attr in ("log_path", "folder"):
                v = getattr(value, attr, None)
                if isinstance(v, Path):
                    visit(v, depth + 1)

    for value in getattr(item, "funcargs", {}).values():
        visit(value)
    return list(dict.fromkeys(found))


def write(item) -> Path | None:
    """Write what the failed test ``item`` leaves to read; returns the folder (None when there was nothing)."""
    folder = ARTIFACTS / re.sub(r"[^\w.-]+", "_", item.nodeid)[-150:]
    n = 0
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True, exist_ok=True)

    def save(lines, png, html):
        nonlocal n
        n += 1
        if png:
            (folder / f"page-{n}.png").write_bytes(png)
        if html:
            (folder / f"page-{n}.html").write_text(html, encoding="utf-8")
        (folder / f"page-{n}-console.txt").write_text("\n".join(lines) + "\n", encoding="utf-8")

    for lines, png, html in _CLOSED:
        save(lines, png, html)
    for page, lines in list(_LOGS.values()):
        if page.is_closed():
            continue
        png = html = None
        try:
            png = page.screenshot(timeout=10_000)
            html = page.content()
        except Exception as e:  # a crashed page still leaves its console
            lines.append(f"(no screenshot: {e})")
        save(list(lines), png, html)
    for log in _server_logs(item):
        shutil.copy(log, folder / f"server-{log.parent.name}-{log.name}")
    if not any(folder.iterdir()):
        folder.rmdir()
        return None
    return folder


def runtest_makereport(item, call, report) -> None:
    """Write the artifacts of a failed browser test and name their folder in its report."""
    if report.when == "setup":
        _CLOSED.clear()
        for key, (page, _) in list(_LOGS.items()):  # pages of earlier tests that are gone
            if page.is_closed():
                del _LOGS[key]
    if report.when != "call" or not report.failed or item.get_closest_marker("browser") is None:
        if report.when == "teardown":
            _CLOSED.clear()
        return
    try:
        folder = write(item)
    except Exception as e:  # never hide the test's own failure behind ours
        report.sections.append(("browser artifacts", f"could not write them: {e!r}"))
        return
    if folder is not None:
        shown = folder.relative_to(ROOT) if folder.is_relative_to(ROOT) else folder
        files = ", ".join(sorted(p.name for p in folder.iterdir()))
        report.sections.append(("browser artifacts", f"screenshots, page consoles and server logs in {shown}/: "
                                                     f"{files}"))


def terminal_summary(terminalreporter) -> None:
    """List the artifact folders this run wrote (on the controller too, with pytest-xdist)."""
    if not ARTIFACTS.is_dir():
        return
    fresh = sorted(p for p in ARTIFACTS.iterdir() if p.is_dir() and p.stat().st_mtime >= _SESSION_START)
    if fresh:
        terminalreporter.write_sep("-", "browser artifacts of failed tests (screenshots, consoles, server logs)")
        for p in fresh:
            terminalreporter.write_line(str(p.relative_to(ROOT) if p.is_relative_to(ROOT) else p))

