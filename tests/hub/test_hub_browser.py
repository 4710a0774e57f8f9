"""A class on the hub (`make hub`, deploy/jupyterhub): two students log in through the login page in headless
Chromium, each lands in JupyterLab on their own copy of the lessons and runs lesson 01's solver panel (a target
moved, every solver re-solves); one student's browser is refused the other's server; an edit survives a server
restart; a student whose lessons cannot be copied sees the hub's error page while the others work on; and the culler
stops the server of a student who left, not the one of a student still working.

Run as root, the hub keeps the students apart at the system level too (deploy/jupyterhub/posekit_spawner.py): a
probe run in alice's kernel, from her JupyterLab, finds no file of bob's, no process but her own, not bob's server
token, not the hub's database nor the instructor's solutions; and with a course configured, nbgrader's Assignments
panel lists what the instructor released.

The tests run in order on one hub (module fixture). Needs Debian's chromium and the proxy from npm (make hub installs
it: deploy/jupyterhub/node_modules)."""

from __future__ import annotations

import json
import os
import re
import subprocess
import time
from pathlib import Path

import pytest

from tests.hub.hub_helpers import PASSWORD, ROOT, release, running_hub
from tests.viz.browser_helpers import wait_for
from tests.viz.test_browser import (_RUNNING, CHROMIUM, FLAGS, PANEL_CELLS, PANEL_NOTEBOOK, _drag, _lab_page,
                                    _trimmed, _wait_visible)

pytestmark = pytest.mark.browser

CULL_TIMEOUT = 45
"""Seconds without activity before the test hub's culler stops a server (the hub's default is an hour)."""
STUDENTS = ("alice", "bob")
MARK = "alice-edited-this-cell"


COURSE = "posekit"
ASSIGNMENT = "00_skeletons_and_poses"


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    if not Path(CHROMIUM).exists():
        pytest.fail(f"{CHROMIUM} not found: install Debian's chromium (make test does)")
    folder = tmp_path_factory.mktemp("hub")
    course = {"POSEKIT_HUB_COURSE": COURSE, "POSEKIT_HUB_EXCHANGE": str(folder / "exchange")}
    with running_hub(folder, cull_timeout=CULL_TIMEOUT, cull_every=5, activity_every=5, extra_env=course) as hub:
        hub.exchange = folder / "exchange"
        # each student already has lesson 01 trimmed to its panel (as tests/viz runs it): the hub must keep it
        for user in STUDENTS:
            (hub.home(user) / "lessons").mkdir(parents=True)
            _trimmed(ROOT / "notebooks" / PANEL_NOTEBOOK, hub.home(user) / "lessons" / PANEL_NOTEBOOK, PANEL_CELLS)
        hub.pages = {}
        yield hub


@pytest.fixture(scope="module")
def chromium():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS, headless=True)
        try:
            yield browser
        finally:
            browser.close()


def _log_in(chromium, hub, user):
    """A new browser (its own cookies) logs ``user`` in through the hub's login page and waits for JupyterLab."""
    page = _lab_page(chromium, {"width": 1500, "height": 1100})
    page.goto(f"{hub.url}/hub/login", timeout=60_000)
    page.fill("#username_input", user)
    page.fill("#password_input", PASSWORD)
    page.click("#login_submit")
    page.wait_for_url(f"**/user/{user}/lab/tree/lessons**", timeout=150_000)
    page.wait_for_selector(".jp-DirListing-item", timeout=60_000)
    return page


def _open_and_run_all(page, hub, user):
    """Open lesson 01 from the file browser (as a student does) and Run All once its one kernel is idle."""
    page.locator(".jp-DirListing-item", has_text=PANEL_NOTEBOOK).dblclick()
    page.wait_for_selector(".jp-Notebook:visible .jp-Cell", timeout=60_000)
    page.wait_for_selector("#jp-main-statusbar :text('Idle')", timeout=120_000)
    sessions = f"{hub.url}/user/{user}/api/sessions"
    wait_for(lambda: len(page.request.get(sessions).json()) == 1 or None, 30, f"{user}'s one kernel session")
    for _ in range(9):  # the menu item may still be greyed out: as tests/viz/test_browser.py does
        try:
            page.locator(".jp-Notebook:visible .jp-Cell").first.click(timeout=5_000)
            page.locator(".lm-MenuBar-itemLabel", has_text="Run").first.click(timeout=5_000)
            page.locator(".lm-Menu-item:not(.lm-mod-disabled) .lm-Menu-itemLabel",
                         has_text="Run All Cells").first.click(timeout=5_000)
            page.wait_for_function(_RUNNING, timeout=10_000, polling=100)
            return
        except Exception:  # noqa: BLE001 - playwright's TimeoutError; try the menu again
            page.keyboard.press("Escape")
    pytest.fail(f"{user}: Run All Cells never started the kernel")


def _run_panel_and_move_target(page, hub, user):
    url = f"{hub.url}/user/{user}"
    _open_and_run_all(page, hub, user)
    labels = page.locator(".widget-html-content", has_text="worst effector")
    _wait_visible(page, labels, 300, url, "", hub.state, "lesson 01's solver panel")
    cell = page.locator(".jp-CodeCell", has=labels.first)
    cell.scroll_into_view_if_needed()
    assert labels.count() == 3 and cell.locator("canvas").count() == 3
    texts = [l.inner_text() for l in labels.all()]
    _drag(page, cell.locator(".widget-slider", has_text="target y").locator(".noUi-handle").first, 60)
    wait_for(lambda: all(l.inner_text() != t for l, t in zip(labels.all(), texts)), 60,
             f"{user}'s solvers to re-solve after the target moved")


def test_two_students_log_in_and_run_lesson_01(hub, chromium):
    trimmed = {u: (hub.home(u) / "lessons" / PANEL_NOTEBOOK).read_text() for u in STUDENTS}
    for user in STUDENTS:
        page = hub.pages[user] = _log_in(chromium, hub, user)
        lessons = hub.home(user) / "lessons"
        # the first start copied every lesson and the studio, and kept the student's own lesson 01
        for name in ("00_skeletons_and_poses.ipynb", "06_posing_studio.ipynb", "studio.ipynb"):
            assert (lessons / name).read_bytes() == (ROOT / "notebooks" / name).read_bytes(), name
        assert not (lessons / "_template.ipynb").exists()
        assert (lessons / PANEL_NOTEBOOK).read_text() == trimmed[user], "the hub overwrote a student's lesson"
        _run_panel_and_move_target(page, hub, user)
    # make lab's websocket setting reached each student's server: its kernel socket reads back TCP_NODELAY=1
    assert hub.log_text().count("websocket TCP_NODELAY=1") >= len(STUDENTS)


PROBE = r"""
import glob, json, os
bob, state, root = {bob!r}, {state!r}, {root!r}
seen = {{"uid": os.getuid()}}
def attempt(key, do):
    try:
        seen[key] = repr(do())[:300]
    except Exception as e:
        seen[key] = "refused: " + type(e).__name__
attempt("list bob's home", lambda: os.listdir(bob))
attempt("read bob's lesson", lambda: open(os.path.join(bob, "lessons", {lesson!r})).read(20))
attempt("write into bob's home", lambda: open(os.path.join(bob, "planted.txt"), "w").write("x"))
attempt("read the hub's database", lambda: open(os.path.join(state, "jupyterhub.sqlite"), "rb").read(16))
attempt("list the instructor's folder", lambda: os.listdir(os.path.join(root, "instructor")))
attempt("import the solutions", lambda: __import__("posekit.exercises.solutions"))
environs = []
for path in glob.glob("/proc/[0-9]*/environ"):
    try:
        environs.append(open(path, "rb").read().decode(errors="replace"))
    except OSError:
        pass
seen["processes"] = sorted(int(p.split("/")[2]) for p in glob.glob("/proc/[0-9]*/environ"))
seen["process owners"] = sorted({{os.stat(p).st_uid for p in glob.glob("/proc/[0-9]*")}})
seen["environ text"] = "\n".join(environs)
print("PROBE " + json.dumps(seen))
"""


def _contents_put(page, url, path, model):
    """PUT a file through a student's server's contents API, with the page's cookies (and its XSRF token)."""
    xsrf = next((c["value"] for c in page.context.cookies() if c["name"] == "_xsrf"), "")
    response = page.request.put(f"{url}/api/contents/{path}", data=json.dumps(model),
                                headers={"X-XSRFToken": xsrf, "Content-Type": "application/json"})
    assert response.status in (200, 201), f"{path}: {response.status} {response.text()[:300]}"


def _server_pid(user) -> int:
    """The pid of ``user``'s jupyterhub-singleuser (as root sees it)."""
    out = subprocess.run(["ps", "-ww", "-eo", "pid,user:32,args"], capture_output=True, text=True).stdout
    pids = [int(line.split()[0]) for line in out.splitlines()
            if f"posekit-{user}" in line.split()[1:2] and "jupyterhub-singleuser" in line and "sandbox.py" not in line]
    assert pids, out
    return pids[0]


@pytest.mark.skipif(os.geteuid() != 0, reason="keeping students apart needs the hub to run as root (docs/hub.md)")
def test_a_students_kernel_sees_no_other_student_nor_the_hub_nor_the_solutions(hub):
    page = hub.pages["alice"]
    url = f"{hub.url}/user/alice"
    # what the probe must not find: bob's server token, as root reads it from his server's environment
    bob_env = Path(f"/proc/{_server_pid('bob')}/environ").read_bytes().decode(errors="replace").split("\0")
    bob_token = next(v.split("=", 1)[1] for v in bob_env if v.startswith("JUPYTERHUB_API_TOKEN="))
    assert len(bob_token) >= 16
    source = PROBE.format(bob=str(hub.home("bob")), state=str(hub.state), root=str(ROOT), lesson=PANEL_NOTEBOOK)
    nb = {"cells": [{"cell_type": "code", "metadata": {}, "source": source, "outputs": [], "execution_count": None}],
          "metadata": {"kernelspec": {"name": "python3", "display_name": "Python 3", "language": "python"}},
          "nbformat": 4, "nbformat_minor": 5}
    _contents_put(page, url, "probe.ipynb", {"type": "notebook", "format": "json", "content": nb})
    page.goto(f"{url}/lab/tree/probe.ipynb", timeout=60_000)
    page.wait_for_selector("#jp-main-statusbar :text('Idle')", timeout=120_000)
    out = page.locator(".jp-OutputArea-output", has_text="PROBE ")
    for _ in range(8):  # a key press can arrive before the kernel is connected: press again until it runs
        # the probe's own cell (lesson 01's tab, restored behind it, holds editors too)
        page.locator(".jp-Cell .jp-InputArea-editor", has_text="PROBE ").first.click()
        page.keyboard.press("Control+Enter")
        try:
            out.first.wait_for(timeout=15_000)
            break
        except Exception:  # noqa: BLE001 - playwright's TimeoutError
            continue
    out.first.wait_for(timeout=60_000)
    seen = json.loads(re.search(r"PROBE (\{.*\})", out.first.inner_text(), re.S).group(1))
    alice_uid, bob_uid = hub.home("alice").stat().st_uid, hub.home("bob").stat().st_uid
    assert seen["uid"] == alice_uid and alice_uid not in (0, bob_uid, os.getuid())
    for what in ("list bob's home", "read bob's lesson", "write into bob's home", "read the hub's database",
                 "list the instructor's folder", "import the solutions"):
        assert seen[what].startswith("refused"), f"alice could {what}: {seen[what]}"
    assert not (hub.home("bob") / "planted.txt").exists()
    assert seen["process owners"] == [alice_uid], seen["process owners"]  # her own processes only
    assert len(seen["processes"]) < 10, seen["processes"]
    assert bob_token not in seen["environ text"] and "JUPYTERHUB_USER=bob" not in seen["environ text"]
    assert (hub.home("alice").stat().st_mode & 0o777) == 0o700


def test_the_studio_is_served_from_each_server(hub):
    # Voila's server extension answers on each student's server; on alice's it renders her copy of the studio
    # with the studio's page (make studio's template: no stylesheet from a CDN); driving the studio in a browser is
    # tests/viz/test_studio_browser.py's part
    for user in STUDENTS:
        response = hub.pages[user].request.get(f"{hub.url}/user/{user}/voila/tree/lessons")
        assert response.status == 200 and "Voil" in response.text(), f"{user}: no Voila at /voila/tree"
    studio = hub.pages["alice"].request.get(f"{hub.url}/user/alice/voila/render/lessons/studio.ipynb",
                                            timeout=180_000)
    page = studio.text()
    assert studio.status == 200 and "application/vnd.jupyter.widget-view+json" in page, page[-2000:]
    assert "cdn.jsdelivr.net" not in page, "the studio was not served with its own template (posekit/viz/voila)"


def test_a_student_cannot_reach_another_students_server(hub):
    bob = hub.pages["bob"]
    for path in ("lab/tree/lessons", f"api/contents/lessons/{PANEL_NOTEBOOK}", "voila/tree/lessons"):
        response = bob.request.get(f"{hub.url}/user/alice/{path}", max_redirects=10)
        assert response.status == 403, f"bob got {response.status} for alice's {path}"
        assert "worst effector" not in response.text() and PANEL_CELLS[0] not in response.text()
    # bob's own server answers the same request
    assert bob.request.get(f"{hub.url}/user/bob/api/contents/lessons/{PANEL_NOTEBOOK}").status == 200
    bob.close()  # bob leaves: his server is idle from now on (the culler's wait runs while the next tests do)


def test_the_assignments_panel_lists_what_the_instructor_released(hub, tmp_path):
    release(hub.exchange, tmp_path / "course", COURSE, ASSIGNMENT)
    page = hub.pages["alice"]
    listed = page.request.get(f"{hub.url}/user/alice/assignments?course_id={COURSE}")
    assert listed.status == 200, listed.text()[:500]
    names = {a["assignment_id"]: a["status"] for a in listed.json()["value"]}
    assert names.get(ASSIGNMENT) == "released", names
    # and in her JupyterLab: the Assignments panel, from nbgrader's menu
    page.goto(f"{hub.url}/user/alice/lab", timeout=60_000)
    page.wait_for_selector(".jp-DirListing-item", timeout=60_000)
    page.locator(".lm-MenuBar-itemLabel", has_text="Nbgrader").first.click(timeout=30_000)
    page.locator(".lm-Menu-itemLabel", has_text="Assignment List").first.click(timeout=30_000)
    wait_for(lambda: page.locator(f"text={ASSIGNMENT}").count() or None, 60, "the released assignment in the panel")
    page.screenshot(path=str(tmp_path / "assignments.png"))
    assert page.locator(".lm-Menu-itemLabel", has_text="Formgrader").count() == 0


def test_an_edit_survives_a_server_restart(hub):
    page = hub.pages["alice"]
    notebook = hub.home("alice") / "lessons" / PANEL_NOTEBOOK
    page.goto(f"{hub.url}/user/alice/lab/tree/lessons/{PANEL_NOTEBOOK}", timeout=60_000)
    page.wait_for_selector("#jp-main-statusbar :text('Idle')", timeout=120_000)
    # JupyterLab reopens alice's other tabs (the probe notebook) as it opens this one, and may leave one of them in
    # front (it did when this test ran right after the Assignments panel's): she chooses the lesson's tab
    page.locator(".lm-DockPanel-tabBar .lm-TabBar-tab", has_text=PANEL_NOTEBOOK).first.click()
    wait_for(lambda: page.locator(".jp-Notebook:visible .jp-Cell", has_text=PANEL_CELLS[0]).count() or None, 30,
             f"{PANEL_NOTEBOOK} in front")
    page.locator(".jp-Notebook:visible .jp-Cell").first.click()
    page.keyboard.press("Escape")
    page.keyboard.press("a")  # a new cell above, as a student adds one
    page.keyboard.press("Enter")
    page.keyboard.type(f"# {MARK}")
    page.keyboard.press("Escape")
    page.keyboard.press("Control+s")
    wait_for(lambda: MARK in notebook.read_text(), 30, "the edited notebook to be saved")
    assert hub.api("DELETE", "/users/alice/server")[0] in (202, 204)
    wait_for(lambda: hub.server("alice") is None, 60, "alice's server to stop")
    assert hub.api("POST", "/users/alice/server")[0] in (201, 202)
    wait_for(lambda: (hub.server("alice") or {}).get("ready"), 120, "alice's server to start again")
    cells = json.loads(notebook.read_text())["cells"]
    assert MARK in "".join(cells[0]["source"]), "the restart replaced alice's edited lesson"
    page.goto(f"{hub.url}/user/alice/lab/tree/lessons/{PANEL_NOTEBOOK}", timeout=60_000)
    wait_for(lambda: page.locator(".jp-Notebook:visible .jp-Cell", has_text=MARK).count() or None, 60,
             "alice's edit in the reopened notebook")


def test_a_student_whose_server_cannot_start_sees_the_error_page(hub, chromium):
    home = hub.home("carol")
    home.mkdir(parents=True)
    (home / "lessons").write_text("not a folder")  # the lessons cannot be copied
    page = _lab_page(chromium, {"width": 1200, "height": 900})
    try:
        page.goto(f"{hub.url}/hub/login", timeout=60_000)
        page.fill("#username_input", "carol")
        page.fill("#password_input", PASSWORD)
        page.click("#login_submit")
        page.wait_for_selector("text=expected a folder", timeout=120_000)  # the hub's error page says why
        assert hub.server("carol") is None
    finally:
        page.close()
    # alice works on: her server is up and her notebook still answers
    assert (hub.server("alice") or {}).get("ready")
    alice = hub.pages["alice"]
    assert alice.request.get(f"{hub.url}/user/alice/api/contents/lessons/{PANEL_NOTEBOOK}").status == 200


def test_the_culler_stops_the_server_of_a_student_who_left(hub):
    # bob closed his page before alice's restart; alice's JupyterLab is still open (it polls her server)
    t0 = time.time()
    wait_for(lambda: hub.server("bob") is None, CULL_TIMEOUT + 60, "the culler to stop bob's idle server")
    assert "Culling server bob" in hub.log_text() or "culling server bob" in hub.log_text().lower()
    assert (hub.server("alice") or {}).get("ready"), (
        f"alice's server, in use, was stopped too ({time.time() - t0:.0f} s after bob's)")
    assert (hub.home("bob") / "lessons" / PANEL_NOTEBOOK).exists()  # culling keeps a student's files
