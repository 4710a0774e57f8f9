"""posekit bench studio's own servers in a real browser: a class of sessions against one server, and the floor
page served beside the studio. Each test starts its own Voila server and Playwright (a module of its own: two
sync Playwright instances cannot run in one thread at once, so these never overlap test_studio_browser's)."""

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

    from posekit.bench.studio import floor_notebook, launch_chromium, open_floor, rapid_updates, serve_voila

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
            page.wait_for_timeout(200)
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
