"""Starting and stopping a JupyterHub with the repository's configuration (deploy/jupyterhub/jupyterhub_config.py)
for a test: its own state folder and free ports, a test service with an admin token layered on top, and every
process it started (proxy, culler, students' servers, their kernels) stopped at the end, whatever happened."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

from posekit.bench.browser import free_port

ROOT = Path(__file__).resolve().parents[2]
CONFIG = ROOT / "deploy" / "jupyterhub" / "jupyterhub_config.py"
PROXY = ROOT / "deploy" / "jupyterhub" / "node_modules" / ".bin" / "configurable-http-proxy"
PASSWORD = "posekit-trial"
ADMIN_TOKEN = "posekit-hub-test-admin-token-0123456789"

OVERLAY = """\
# the repository's configuration, and a service whose token the test uses to stop and start servers
load_subconfig({config!r})
c.JupyterHub.services.append({{"name": "posekit-test", "api_token": {token!r}}})
c.JupyterHub.load_roles.append({{"name": "posekit-test", "services": ["posekit-test"],
                                 "scopes": ["admin:users", "admin:servers", "list:users", "read:users",
                                            "access:servers"]}})
"""


class Hub:
    """A running hub: ``url`` (what a browser opens), ``state`` (its folder; students' homes in ``state/users``),
    ``log`` (the hub's, its proxy's and the servers' output)."""

    def __init__(self, url, state, log, proc):
        self.url, self.state, self.log, self.proc = url, state, log, proc

    def home(self, user) -> Path:
        return self.state / "users" / user

    def api(self, method, path, body=None, timeout=30):
        """The hub's REST API as the test service (admin): (status, decoded JSON or None)."""
        req = urllib.request.Request(f"{self.url}/hub/api{path}", method=method,
                                     data=None if body is None else json.dumps(body).encode(),
                                     headers={"Authorization": f"token {ADMIN_TOKEN}"})
        try:
            with urllib.request.urlopen(req, timeout=timeout) as r:
                raw = r.read()
                return r.status, (json.loads(raw) if raw else None)
        except urllib.error.HTTPError as err:
            return err.code, None

    def server(self, user):
        """The user's default server as the hub reports it (``ready``, ``pending``, ``last_activity``), or None."""
        status, info = self.api("GET", f"/users/{user}")
        return (info or {}).get("servers", {}).get("") if status == 200 else None

    def log_text(self) -> str:
        return self.log.read_text(errors="replace")


@contextlib.contextmanager
def running_hub(folder: Path, cull_timeout: int = 3600, cull_every: int = 300, activity_every: int = 300,
                extra_env=None, startup_s: float = 90.0, sigint_ignored: bool = False):
    """Serve a hub from ``folder`` (its state and log there) until the block ends; then stop it and everything
    it started, even when the block failed. ``sigint_ignored``: the hub starts with Ctrl-C ignored, as a script's
    background job starts it."""
    import psutil

    hub_cmd = Path(sys.executable).parent / "jupyterhub"
    if not hub_cmd.exists():
        raise RuntimeError(f"{hub_cmd} is missing: pip install -e '.[hub]' (make hub and the dev extra install it)")
    if not PROXY.exists():  # the proxy from the npm registry, as make hub installs it
        if shutil.which("npm") is None:
            raise RuntimeError(f"{PROXY} is missing and npm is not installed: install Node.js and npm, then make hub")
        subprocess.run(["npm", "ci", "--no-audit", "--no-fund", "--loglevel=error"], cwd=PROXY.parents[2], check=True)
    state, log = folder / "state", folder / "hub.log"
    overlay = folder / "jupyterhub_test_config.py"
    overlay.write_text(OVERLAY.format(config=str(CONFIG), token=ADMIN_TOKEN))
    port = free_port()
    env = dict(os.environ, POSEKIT_HUB_STATE=str(state), POSEKIT_HUB_PORT=str(port),
               POSEKIT_HUB_API_PORT=str(free_port()), POSEKIT_HUB_PROXY_API_PORT=str(free_port()),
               POSEKIT_HUB_CULL_TIMEOUT=str(cull_timeout), POSEKIT_HUB_CULL_EVERY=str(cull_every),
               POSEKIT_HUB_ACTIVITY_EVERY=str(activity_every), POSEKIT_HUB_PASSWORD=PASSWORD,
               PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}", **(extra_env or {}))
    out = open(log, "w")
    proc = subprocess.Popen([str(hub_cmd), "-f", str(overlay)], cwd=folder, env=env, stdout=out,
                            stderr=subprocess.STDOUT,
                            preexec_fn=(lambda: signal.signal(signal.SIGINT, signal.SIG_IGN)) if sigint_ignored else None)
    hub = Hub(f"http://127.0.0.1:{port}", state, log, proc)
    try:
        t0 = time.time()
        while True:
            if proc.poll() is not None:
                raise RuntimeError(f"the hub exited ({proc.returncode}):\n{hub.log_text()[-3000:]}")
            with contextlib.suppress(OSError):
                if hub.api("GET", "/", timeout=2)[0] == 200 and "JupyterHub is now running" in hub.log_text():
                    break
            if time.time() - t0 > startup_s:
                raise RuntimeError(f"the hub did not start within {startup_s:.0f} s:\n{hub.log_text()[-3000:]}")
            time.sleep(0.5)
        yield hub
    finally:
        try:
            started = psutil.Process(proc.pid).children(recursive=True)
        except psutil.Error:
            started = []
        proc.terminate()  # the hub stops the students' servers, its services and its proxy
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        for child in started:  # whatever the hub left behind
            with contextlib.suppress(psutil.Error):
                child.kill()
        out.close()


def start_server(hub: Hub, user: str, timeout_s: float = 120.0):
    """Make ``user`` (when new) and start their server through the hub's API; wait until it is ready."""
    hub.api("POST", f"/users/{user}")
    status, _ = hub.api("POST", f"/users/{user}/server")
    if status not in (201, 202, 400):  # 400: already running
        raise RuntimeError(f"{user}'s server did not start: {status}\n{hub.log_text()[-3000:]}")
    t0 = time.time()
    while not (hub.server(user) or {}).get("ready"):
        if time.time() - t0 > timeout_s:
            raise RuntimeError(f"{user}'s server was not ready within {timeout_s:.0f} s:\n{hub.log_text()[-3000:]}")
        time.sleep(0.5)


def run_code(hub: Hub, user: str, code: str, timeout_s: float = 120.0, kernel: str | None = None) -> tuple[str, str]:
    """Run ``code`` in a kernel of ``user``'s server, as their JupyterLab would (the server's REST API and kernel
    websocket, through the hub's proxy, with the test service's token): ``(kernel id, what it printed)``. A new
    kernel unless ``kernel`` names one; an error in the code is part of what it printed."""
    import asyncio
    import uuid

    from tornado.httpclient import HTTPRequest
    from tornado.websocket import websocket_connect

    headers = {"Authorization": f"token {ADMIN_TOKEN}"}
    base = f"{hub.url}/user/{user}/api"
    if kernel is None:
        req = urllib.request.Request(f"{base}/kernels", method="POST", data=b"{}", headers=headers)
        with urllib.request.urlopen(req, timeout=60) as r:
            kernel = json.loads(r.read())["id"]

    async def go():
        url = f"{base.replace('http', 'ws', 1)}/kernels/{kernel}/channels"
        ws = await websocket_connect(HTTPRequest(url, headers=headers, connect_timeout=60))
        msg_id = uuid.uuid4().hex
        ws.write_message(json.dumps({
            "header": {"msg_id": msg_id, "msg_type": "execute_request", "username": "test", "session": msg_id,
                       "version": "5.3", "date": ""},
            "parent_header": {}, "metadata": {}, "channel": "shell", "buffers": [],
            "content": {"code": code, "silent": False, "store_history": False, "user_expressions": {},
                        "allow_stdin": False, "stop_on_error": True}}))
        out = []
        while True:
            raw = await asyncio.wait_for(ws.read_message(), timeout_s)
            if raw is None:
                raise RuntimeError(f"{user}'s kernel closed the connection; printed so far: {''.join(out)}")
            msg = json.loads(raw)
            if msg.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            kind, content = msg["header"]["msg_type"], msg["content"]
            if kind == "stream":
                out.append(content["text"])
            elif kind == "error":
                out.append(f"{content['ename']}: {content['evalue']}\n")
            elif kind == "status" and content["execution_state"] == "idle":
                ws.close()
                return "".join(out)

    return kernel, asyncio.run(go())


def release(exchange: Path, course_folder: Path, course_id: str, assignment: str) -> None:
    """The instructor's side, as docs/nbgrader.md has it: a course folder with one lesson (``assignment``),
    generated and released to ``exchange``."""
    from posekit.course.nbgrader import scripts_on_path

    scripts_on_path()  # nbgrader's grade book runs alembic by name
    subprocess.run([sys.executable, "-m", "posekit", "course", "nbgrader", "--out", str(course_folder), "--lesson",
                    assignment[:2]], check=True, capture_output=True, text=True, cwd=ROOT)
    for step in (["generate_assignment", assignment], ["release_assignment", assignment]):
        subprocess.run([sys.executable, "-m", "nbgrader", *step, f"--Exchange.root={exchange}",
                        f"--CourseDirectory.course_id={course_id}"], cwd=course_folder, check=True,
                       capture_output=True, text=True)
