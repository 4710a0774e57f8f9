"""A failed browser test leaves what it saw: the page's screenshot and console, and the report says where."""

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from posekit.bench.browser import chromium_missing

pytestmark = pytest.mark.browser
ROOT = Path(__file__).resolve().parent.parent


def test_a_failed_browser_test_leaves_its_screenshot_console_and_logs(tmp_path):
    missing = chromium_missing()
    if missing:
        pytest.fail(missing)
    work = tmp_path / "suite"
    work.mkdir()
    (work / "conftest.py").write_text(textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(ROOT)!r})
        from tests.conftest import pytest_configure, pytest_runtest_makereport, pytest_terminal_summary
    """))
    server = work / "server"
    server.mkdir()
    (server / "lab.log").write_text("a kernel said: posekit-kernel-line\\n")
    (work / "test_page.py").write_text(textwrap.dedent(f"""
        from pathlib import Path
        import pytest
        pytestmark = pytest.mark.browser

        @pytest.fixture
        def lab():
            return ("http://127.0.0.1:1", "token", Path({str(server)!r}))

        def test_a_page_that_fails(lab):
            from playwright.sync_api import sync_playwright
            from posekit.bench.browser import launch_chromium
            with sync_playwright() as p:
                browser = launch_chromium(p)
                try:
                    page = browser.new_page()
                    page.set_content("<h1 style='font-size:80px'>posekit</h1>"
                                     "<script>console.log('posekit-console-line')</script>")
                    page.wait_for_function("() => document.querySelector('h1')")
                    try:
                        assert False, "failing on purpose"
                    finally:
                        page.close()
                finally:
                    browser.close()
    """))
    art = tmp_path / "artifacts"
    env = dict(os.environ, POSEKIT_TEST_ARTIFACTS=str(art))
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-p", "no:xdist",
                        "--rootdir", str(work), "-c", os.devnull, str(work / "test_page.py")],
                       cwd=work, env=env, capture_output=True, text=True, timeout=300)
    out = r.stdout + r.stderr
    assert r.returncode == 1, out
    folders = list(art.iterdir()) if art.is_dir() else []
    assert len(folders) == 1, out
    folder = folders[0]
    names = sorted(p.name for p in folder.iterdir())
    assert "page-1.png" in names and "page-1-console.txt" in names, names
    assert (folder / "page-1.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "posekit-console-line" in (folder / "page-1-console.txt").read_text()
    assert "posekit-kernel-line" in (folder / "server-server-lab.log").read_text()
    assert "browser artifacts" in out and str(folder.name) in out, out
