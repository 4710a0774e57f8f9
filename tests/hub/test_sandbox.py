"""One student's sandbox without a hub (deploy/jupyterhub/sandbox.py, as the class spawner starts it): a probe runs
in it as a student's user, with the repository and the hub's state laid out under /tmp, under /root and under a
home of 0750 (Ubuntu's default), and finds the hub's database, the other students' homes, the solutions and the
machine's shared places hidden, the other students' network out of reach, and its limits set; a cover that cannot
be made stops the start (fail closed).

Needs root and ``unshare`` (the hub's own conditions for keeping students apart)."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import socket
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import pytest

from tests.hub.hub_helpers import ROOT, free_port

pytestmark = pytest.mark.skipif(os.geteuid() != 0 or shutil.which("unshare") is None,
                                reason="the sandbox needs root and unshare (docs/hub.md)")

SANDBOX = ROOT / "deploy" / "jupyterhub" / "sandbox.py"
sys.path.insert(0, str(SANDBOX.parent))
import limits  # noqa: E402 - deploy/jupyterhub/limits.py
UID = GID = 64_123
"""The student's uid and gid (no user needs to exist for them)."""
USER = f"posekit-sandboxtest-{os.getpid()}"
"""The student's name, which names their control group: this run's own. A hub's student ``alice`` is the system
user ``posekit-alice``, whose group the hub tests' servers share: a job here under that name once set that group's
memory to this test's 512 MB while another worker's hub served alice, and her server was killed for memory."""


@pytest.fixture(scope="module", autouse=True)
def _own_control_group():
    """This module's control group goes with it (empty by then: each sandbox has ended)."""
    yield
    for d in (limits.cgroup_dirs(USER) or {}).values():
        with contextlib.suppress(OSError):
            d.rmdir()

PROBE = r"""
import json, os, socket, sys
seen = {"uid": os.getuid()}
def attempt(key, do):
    try:
        seen[key] = repr(do())[:300]
    except Exception as e:
        seen[key] = "refused: " + type(e).__name__
state, instructor, host_port, abstract, marker = sys.argv[1:6]
attempt("read the hub's database", lambda: open(os.path.join(state, "jupyterhub.sqlite"), "rb").read(16))
attempt("list the state folder", lambda: sorted(os.listdir(state)))
attempt("list the homes", lambda: sorted(os.listdir(os.path.join(state, "users"))))
attempt("read bob's file", lambda: open(os.path.join(state, "users", "bob", "secret.txt")).read())
attempt("list the instructor's folder", lambda: os.listdir(instructor))
attempt("write my home", lambda: open(os.path.join(state, "users", "alice", "mine.txt"), "w").write("x"))
for place in ("/tmp", "/var/tmp", "/dev/shm"):
    attempt("see the machine's " + place, lambda p=place: open(os.path.join(p, marker)).read())
    attempt("write " + place, lambda p=place: open(os.path.join(p, marker + "-sandbox"), "w").write("x"))
def tcp():
    with socket.create_connection(("127.0.0.1", int(host_port)), timeout=2) as s:
        return s.recv(64)
attempt("reach the machine's port", tcp)
def unix():
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.connect("\0" + abstract)
        return s.recv(64)
attempt("reach the machine's abstract socket", unix)
seen["listening ports"] = sorted({int(l.split()[1].split(":")[1], 16) for l in open("/proc/net/tcp").readlines()[1:]})
status = dict(l.split(":", 1) for l in open("/proc/self/status").read().splitlines() if ":" in l)
seen["NoNewPrivs"] = status["NoNewPrivs"].strip()
seen["CapBnd"] = status["CapBnd"].strip()
seen["CapEff"] = status["CapEff"].strip()
seen["cgroup"] = open("/proc/self/cgroup").read()
import resource
seen["nproc"] = resource.getrlimit(resource.RLIMIT_NPROC)[0]
print("PROBE " + json.dumps(seen))
"""


def _layout(parent: Path):
    """A repository with the hub's state under ``parent``: ``(repo, state)``; alice's and bob's homes in it."""
    repo = parent / "repo"
    state = repo / "build" / "hub"
    for user in ("alice", "bob"):
        (state / "users" / user).mkdir(parents=True)
    (state / "jupyterhub.sqlite").write_bytes(b"SQLite format 3\0")
    (state / "users" / "bob" / "secret.txt").write_text("bob's secret")
    os.chown(state / "users" / "alice", UID, GID)
    (state / "users").chmod(0o711)
    for home in ("alice", "bob"):
        (state / "users" / home).chmod(0o700)
    (repo / "instructor").mkdir()
    (repo / "instructor" / "solutions.py").write_text("ANSWER = 42")
    return repo, state


def _job(tmp_path, repo, state, hide_extra=(), relay=None):
    job = {"user": USER, "uid": UID, "gid": GID, "home": str(state / "users" / "alice"),
           "expose": [str(state / "users" / "alice")],
           "expose_ro": list(dict.fromkeys([sys.base_prefix, sys.prefix, str(repo)])),
           "overlay": "", "hide": [str(state), str(repo / "instructor"), *map(str, hide_extra)],
           "private": {"/tmp": "64m", "/var/tmp": "16m", "/dev/shm": "16m", "/run/lock": "1m"},
           "limits": {"memory_bytes": 512 * 1024 * 1024, "cpu": 1.0, "pids": 256}}
    if relay:
        job["relay"] = relay
    path = tmp_path / f"job-{uuid.uuid4().hex[:6]}.json"
    path.write_text(json.dumps(job))
    return path


def _sandbox(job, *cmd, timeout=60):
    return subprocess.run(["unshare", "--mount", "--pid", "--ipc", "--fork", "--mount-proc", "--propagation",
                           "private", sys.executable, str(SANDBOX), str(job), "--", *cmd],
                          capture_output=True, text=True, timeout=timeout)


@pytest.fixture
def machine():
    """What the machine has that a student's sandbox must not reach: a marker file in each shared place, a TCP
    port and an abstract unix socket answering on its loopback."""
    marker = f"posekit-marker-{uuid.uuid4().hex[:8]}"
    for place in ("/tmp", "/var/tmp", "/dev/shm"):
        Path(place, marker).write_text("the machine's")
        os.chmod(Path(place, marker), 0o644)
    tcp = socket.create_server(("127.0.0.1", 0))
    unix = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    unix.bind("\0" + marker)
    unix.listen()

    def answer(server):
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            conn.sendall(b"the machine's")
            conn.close()

    for server in (tcp, unix):
        threading.Thread(target=answer, args=(server,), daemon=True).start()
    yield {"marker": marker, "port": tcp.getsockname()[1]}
    tcp.close()
    unix.close()
    for place in ("/tmp", "/var/tmp", "/dev/shm"):
        for suffix in ("", "-sandbox"):
            Path(place, marker + suffix).unlink(missing_ok=True)


def _parent(where, tmp_path):
    """A folder to lay the repository out in: under /tmp, under /root, or a home of 0750."""
    if where == "tmp":
        parent = Path("/tmp") / f"posekit-sandbox-{uuid.uuid4().hex[:8]}"
    elif where == "root":
        parent = Path("/root") / f"posekit-sandbox-{uuid.uuid4().hex[:8]}"
    else:
        parent = Path("/home") / f"teacher-{uuid.uuid4().hex[:8]}"
    parent.mkdir(mode=0o750)
    parent.chmod(0o750)
    return parent


def test_a_shared_folder_others_cannot_walk_through_is_named_and_nothing_starts(tmp_path):
    """A repository the students' servers run from, but of mode 0700 (a checkout in ``mktemp -d``): the sandbox says
    which folder and what to do, and starts nothing (it used to start the server, which failed with a bare
    "Permission denied")."""
    parent = _parent("tmp", tmp_path)
    try:
        repo, state = _layout(parent)
        parent.chmod(0o755)
        repo.chmod(0o700)
        done = _sandbox(_job(tmp_path, repo, state), sys.executable, "-c", "print('STARTED')")
        assert done.returncode == 3 and "STARTED" not in done.stdout, done.stdout + done.stderr
        assert f"{repo} is shared read-only with the students" in done.stderr and f"chmod o+x {repo}" in done.stderr, \
            done.stderr
    finally:
        shutil.rmtree(parent, ignore_errors=True)


@pytest.mark.parametrize("where", ["tmp", "root", "home0750"])
def test_a_students_sandbox_hides_the_hub_the_others_and_the_machine(where, tmp_path, machine):
    parent = _parent(where, tmp_path)
    try:
        repo, state = _layout(parent)
        hub_port = free_port()
        relay = {"server": ["127.0.0.1", free_port()], "hub": ["127.0.0.1", hub_port]}
        job = _job(tmp_path, repo, state, relay=relay)
        done = _sandbox(job, sys.executable, "-I", "-c", PROBE, str(state), str(repo / "instructor"),
                        str(machine["port"]), machine["marker"], machine["marker"])
        assert done.returncode == 0, done.stderr[-3000:]
        line = next(l for l in done.stdout.splitlines() if l.startswith("PROBE "))
        seen = json.loads(line[len("PROBE "):])
        assert seen["uid"] == UID
        for what in ("read the hub's database", "list the state folder", "list the homes", "read bob's file",
                     "list the instructor's folder", "see the machine's /tmp", "see the machine's /var/tmp",
                     "see the machine's /dev/shm", "reach the machine's port", "reach the machine's abstract socket"):
            assert seen[what].startswith("refused"), f"{where}: the student could {what}: {seen[what]}"
        for what in ("write my home", "write /tmp", "write /var/tmp", "write /dev/shm"):
            assert not seen[what].startswith("refused"), f"{where}: the student could not {what}: {seen[what]}"
        for place in ("/tmp", "/var/tmp", "/dev/shm"):  # what the student wrote stayed in their sandbox
            assert not Path(place, machine["marker"] + "-sandbox").exists(), place
        assert machine["port"] not in seen["listening ports"]
        assert seen["NoNewPrivs"] == "1" and int(seen["CapBnd"], 16) == 0 and int(seen["CapEff"], 16) == 0
        assert seen["nproc"] == 256
        assert (state / "users" / "alice" / "mine.txt").exists()
        groups = limits.cgroup_dirs(USER)
        if groups is not None:  # the machine has control groups the hub may use: the student's held the probe
            assert f"/posekit/{USER}" in seen["cgroup"], seen["cgroup"]
            if "memory" in groups:
                assert int((groups["memory"] / "memory.limit_in_bytes").read_text()) == 512 * 1024 * 1024
                assert int((groups["cpu"] / "cpu.cfs_quota_us").read_text()) == 100_000
                assert (groups["pids"] / "pids.max").read_text().strip() == "256"
            else:
                assert int((groups[""] / "memory.max").read_text()) == 512 * 1024 * 1024
                assert (groups[""] / "pids.max").read_text().strip() == "256"
    finally:
        shutil.rmtree(parent, ignore_errors=True)


def test_a_cover_that_cannot_be_made_stops_the_start(tmp_path):
    parent = _parent("tmp", tmp_path)
    try:
        repo, state = _layout(parent)
        secret = repo / "secret-token.txt"  # a file to hide: no folder to cover it with
        secret.write_text("token")
        job = _job(tmp_path, repo, state, hide_extra=[secret])
        done = _sandbox(job, sys.executable, "-I", "-c", "print('STARTED')")
        assert done.returncode != 0 and "STARTED" not in done.stdout
        assert f"{secret} should be hidden" in done.stderr, done.stderr[-2000:]
    finally:
        shutil.rmtree(parent, ignore_errors=True)


def test_the_relay_joins_the_server_and_the_hub_and_nothing_else(tmp_path):
    """The server in its own network namespace is reached on its port from the machine, and reaches the hub's
    API port on the machine: the two connections a server needs."""
    parent = _parent("tmp", tmp_path)
    hub = socket.create_server(("127.0.0.1", 0))
    hub_port = hub.getsockname()[1]
    threading.Thread(target=lambda: [c.sendall(b"hub here") or c.close() for c in iter(lambda: hub.accept()[0], None)],
                     daemon=True).start()
    try:
        repo, state = _layout(parent)
        server_port = free_port()
        job = _job(tmp_path, repo, state, relay={"server": ["127.0.0.1", server_port], "hub": ["127.0.0.1", hub_port]})
        server = (f"import socket\n"
                  f"s = socket.create_connection(('127.0.0.1', {hub_port}), timeout=5)\n"
                  f"print('FROM HUB', s.recv(64).decode())\n"
                  f"srv = socket.create_server(('127.0.0.1', {server_port}))\n"
                  f"c, _ = srv.accept(); c.sendall(b'server here'); c.close()\n")
        proc = subprocess.Popen(["unshare", "--mount", "--pid", "--ipc", "--fork", "--mount-proc", "--propagation",
                                 "private", sys.executable, str(SANDBOX), str(job), "--", sys.executable, "-I", "-c",
                                 server], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        reply = b""
        deadline = time.monotonic() + 90  # by the clock, not by tries: 200 tries refused at once last 20 s, and a
        while time.monotonic() < deadline:  # loaded machine can take longer to make the sandbox
            # the relay listens once the sandbox is made; until the server inside listens too, it closes what it
            # accepts unanswered (a hub polls a starting server the same way)
            try:
                with socket.create_connection(("127.0.0.1", server_port), timeout=20) as s:
                    s.settimeout(20)
                    while chunk := s.recv(64):
                        reply += chunk
            except ConnectionError:
                pass
            if reply:
                break
            time.sleep(0.1)
        out, err = proc.communicate(timeout=30)
        assert "FROM HUB hub here" in out, err[-2000:]
        assert reply == b"server here"
    finally:
        hub.close()
        shutil.rmtree(parent, ignore_errors=True)
