"""posekit bench studio's own servers in a real browser: a class of sessions against one server, a page closed in
the middle of a drag, and the floor page served beside the studio. Each test starts its own Voila server and
Playwright (a module of its own: two sync Playwright instances cannot run in one thread at once, so these never
overlap test_studio_browser's)."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.browser


def test_a_class_of_two_loses_no_update_and_the_cull_frees_every_kernel():
    """posekit bench studio --sessions: two sessions on one server moving their targets at once, each with its own
    kernel; no update lost; after the pages close the cull (5 s idle) leaves no kernel behind."""
    from posekit.bench.studio import class_sessions

    rows = class_sessions(2, 10, cull_idle_s=5, cull_interval_s=1, progress=False)
    each = [r for r in rows if "session" in r]
    whole = rows[-1]
    assert [r["session"] for r in each] == [1, 2] and all(r["lost"] == 0 and r["p95_ms"] > 0 for r in each)
    assert whole["kernels"] == 2 and whole["lost"] == 0 and whole["rss_mb_total"] > 100
    assert whole["kernels_after_cull"] == 0 and whole["cull_s"] < 60


def test_the_floor_page_answers_every_key_press(tmp_path):
    """posekit bench studio's floor: served beside the studio by the same server, a bare slider whose label counts
    its changes answers every key press (the latency every studio update is compared with)."""
    from playwright.sync_api import sync_playwright

    from posekit.bench.browser import launch_chromium, serve_voila
    from posekit.bench.studio import floor_notebook, open_floor, rapid_updates
    from tests.viz.browser_helpers import wait_for

    with serve_voila(extra=[floor_notebook(tmp_path)], cull_idle_s=60) as server, sync_playwright() as p:
        assert server.url.endswith("voila/render/studio.ipynb")
        browser = launch_chromium(p)
        try:
            page = open_floor(browser, server.url_of("floor.ipynb"))
            r = rapid_updates(page, 20)
            # the bench's pages drop console.debug (pythreejs's log, serialised to Playwright), nothing else
            logs = []
            page.on("console", lambda m: logs.append(m.type))
            page.evaluate("() => { console.debug('posekit'); console.log('posekit'); }")
            wait_for(lambda: "log" in logs, 10, "the page's console.log")  # it follows the debug line, if any
        finally:
            browser.close()
    assert r["updates"] == 20 and len(r["latency_ms"]) == 20 and (r["latency_ms"] > 0).all()
    assert "debug" not in logs and "log" in logs, logs


def test_the_first_view_is_timed_in_the_page_from_a_preheated_kernel():
    """posekit bench studio's preheated first view (here of the floor page, the cheapest to serve): the page's own
    clock sees the first frame drawn with the page's elements, no later than Playwright sees them; two pages, the
    second served from the kernel the pool preheated after the first was taken."""
    from posekit.bench.studio import preheated_first_views

    views = preheated_first_views(2, floor=True)
    assert len(views["page_s"]) == len(views["wall_s"]) == 2
    for page_s, wall_s in zip(views["page_s"], views["wall_s"]):
        assert 0 < page_s <= wall_s + 0.05 and wall_s < 60, views


def test_a_page_closed_mid_drag_leaves_no_kernel_and_another_session_goes_on(tmp_path):
    """Bad input: a student closes the tab in the middle of a 3D drag (the mouse still pressed, the drag's updates
    in flight). The cull frees that page's kernel; another student's session on the same server goes on answering."""
    import psutil
    from playwright.sync_api import sync_playwright

    from posekit.bench.browser import launch_chromium, serve_voila
    from posekit.bench.studio import open_studio, rapid_updates, update_number
    from tests.viz.browser_helpers import pixels, press_in_3d, selected_joint, wait_for

    def gone(kernel):
        try:
            return not kernel.is_running() or kernel.status() == psutil.STATUS_ZOMBIE
        except psutil.NoSuchProcess:
            return True

    with serve_voila(folder=tmp_path / "served", cull_idle_s=5, cull_interval_s=1) as server, sync_playwright() as p:
        browser = launch_chromium(p)
        try:
            a = open_studio(browser, server.url)
            kernel_a = server.note_kernels()[0]
            b = open_studio(browser, server.url)
            kernels = server.note_kernels()
            assert len(kernels) == 2
            canvas = a.locator(".posekit-views canvas").first
            canvas.scroll_into_view_if_needed()
            n0 = update_number(a)
            x, y = press_in_3d(a, canvas, selected_joint(pixels(canvas)))  # on the selected joint; the mouse stays down
            for k in range(1, 11):
                a.mouse.move(x, y - 4 * k)
            wait_for(lambda: update_number(a) > n0, 30, "a solve from the drag", every=0.2)
            for k in range(11, 31):  # more of the drag in flight as the tab goes
                a.mouse.move(x, y - 4 * k)
            a.close()
            assert rapid_updates(b, 20)["updates"] == 20  # the other student goes on meanwhile
            wait_for(lambda: gone(kernel_a), 60, "the closed page's kernel to be culled")
            other = next(k for k in kernels if k.pid != kernel_a.pid)
            assert not gone(other)  # a connected page's kernel is never culled
            n1 = update_number(b)
            b.keyboard.press("ArrowRight")
            wait_for(lambda: update_number(b) > n1, 30, "an update after the other page's kernel went", every=0.2)
        finally:
            browser.close()
