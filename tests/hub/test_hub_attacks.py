"""A class on the hub attacked as one student would attack another (issue 62): each test is an attack that worked on
the hub before its sandbox had a network namespace, private shared places, an exchange made by the instructor and a
collect that refuses forgeries; each must fail now, and the other student's work stay intact.

One hub for the module (``make hub HUB_COURSE=posekit``'s configuration), two students, alice (the attacker) and
bob; code runs in their kernels through their servers' API, as their JupyterLab runs it (no browser needed).
Needs root (the hub keeps students apart only as root) and the proxy from npm (make hub installs it)."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
import textwrap
import time
import uuid
from pathlib import Path

import pytest

from tests.hub.hub_helpers import ROOT, release, run_code, running_hub, start_server

pytestmark = pytest.mark.skipif(os.geteuid() != 0, reason="keeping students apart needs the hub to run as root")

COURSE = "posekit"
ASSIGNMENT = "00_skeletons_and_poses"
SECRET = "bob-secret-7f3a91"


@pytest.fixture(scope="module")
def hub(tmp_path_factory):
    folder = tmp_path_factory.mktemp("hub-attacks")
    exchange = folder / "exchange"
    env = {"POSEKIT_HUB_COURSE": COURSE, "POSEKIT_HUB_EXCHANGE": str(exchange)}
    with running_hub(folder, extra_env=env) as hub:
        hub.exchange = exchange
        for user in ("alice", "bob"):
            start_server(hub, user)
        hub.kernels = {user: run_code(hub, user, "print('ready')")[0] for user in ("alice", "bob")}
        yield hub


def _in(hub, user, code, timeout_s=120.0):
    """What ``code`` printed in ``user``'s kernel (the module's one kernel per student)."""
    return run_code(hub, user, textwrap.dedent(code), timeout_s, kernel=hub.kernels[user])[1]


def _uid(user):
    import pwd

    return pwd.getpwnam(f"posekit-{user}").pw_uid


def test_a_student_cannot_read_another_students_kernel_output(hub):
    # bob's kernel prints a secret every 0.1 s for 20 s, from a thread (on its IOPub socket, like any output)
    _in(hub, "bob", f"""
        import threading, time
        def talk():
            for _ in range(200):
                print({SECRET!r}, flush=True)
                time.sleep(0.1)
        threading.Thread(target=talk, daemon=True).start()
        """)
    # the attack: every listening TCP port of the machine's loopback that is not hers, and bob's kernel's ports as
    # root reads them from his connection file, subscribed to with no key
    runtime = Path(hub.home("bob")) / ".local" / "share" / "jupyter" / "runtime"
    files = sorted(runtime.glob("kernel-*.json"), key=lambda p: p.stat().st_mtime)
    assert files, f"no connection file of bob's kernel in {runtime}"
    bob_ports = sorted({v for k, v in json.loads(files[-1].read_text()).items() if k.endswith("_port")})
    out = _in(hub, "alice", f"""
        import json, os, time, zmq
        mine = os.getuid()
        listening = set()
        for line in open("/proc/net/tcp").readlines()[1:]:
            f = line.split()
            if f[3] == "0A" and int(f[7]) not in (mine, 0):  # root's: the relay to the hub's API
                listening.add(int(f[1].split(":")[1], 16))
        ctx = zmq.Context()
        heard = []
        subs = []
        for port in sorted(listening | set({bob_ports!r})):
            s = ctx.socket(zmq.SUB)
            s.setsockopt(zmq.SUBSCRIBE, b"")
            s.connect(f"tcp://127.0.0.1:{{port}}")
            subs.append(s)
        poller = zmq.Poller()
        for s in subs:
            poller.register(s, zmq.POLLIN)
        end = time.time() + 6
        while time.time() < end:
            for s, _ in poller.poll(200):
                heard.append(b"".join(s.recv_multipart()).decode(errors="replace"))
        print("SNOOP " + json.dumps({{"others' ports": sorted(listening), "heard": heard[:20]}}))
        """)
    seen = json.loads(out.split("SNOOP ", 1)[1])
    assert not seen["others' ports"], f"alice sees other students' listening ports: {seen}"
    assert not any(SECRET in m for m in seen["heard"]), "alice read bob's kernel output"
    assert not seen["heard"], seen["heard"]


def test_shared_places_and_abstract_sockets_are_private(hub):
    planted = f"alice-planted-{uuid.uuid4().hex[:8]}"  # this run's own name: nothing an earlier run left counts
    _in(hub, "alice", """
        import os, socket, threading
        for place in ("/dev/shm", "/var/tmp", "/tmp"):
            with open(os.path.join(place, "PLANTED"), "w") as f:
                f.write("alice")
            os.chmod(os.path.join(place, "PLANTED"), 0o666)
        srv = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        srv.bind("\\0posekit-alice-demo")
        srv.listen()
        threading.Thread(target=lambda: srv.accept()[0].sendall(b"alice's socket"), daemon=True).start()
        print("planted")
        """.replace("PLANTED", planted))
    out = _in(hub, "bob", """
        import os, socket
        seen = {}
        for place in ("/dev/shm", "/var/tmp", "/tmp"):
            seen[place] = os.path.exists(os.path.join(place, "PLANTED"))
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        try:
            s.connect("\\0posekit-alice-demo")
            seen["abstract"] = "connected"
        except OSError as e:
            seen["abstract"] = "refused"
        print("SEEN", seen)
        """.replace("PLANTED", planted))
    assert "SEEN" in out, out
    assert "True" not in out and "'abstract': 'refused'" in out, out
    for place in ("/dev/shm", "/var/tmp"):
        assert not Path(place, planted).exists(), f"alice's file reached the machine's {place}"


def test_a_student_runs_with_limits_and_no_privilege(hub):
    out = _in(hub, "alice", """
        import os, resource
        status = dict(l.split(":", 1) for l in open("/proc/self/status").read().splitlines() if ":" in l)
        sizes = {p: os.statvfs(p).f_blocks * os.statvfs(p).f_frsize for p in ("/tmp", "/dev/shm", "/var/tmp")}
        print("LIMITS", {"nnp": status["NoNewPrivs"].strip(), "bnd": int(status["CapBnd"], 16),
                         "nproc": resource.getrlimit(resource.RLIMIT_NPROC)[0], "sizes": sizes,
                         "cgroup": open("/proc/self/cgroup").read()})
        """)
    import ast

    seen = ast.literal_eval(out.split("LIMITS ", 1)[1].strip())
    assert seen["nnp"] == "1" and seen["bnd"] == 0
    assert seen["nproc"] == 1024
    assert seen["sizes"] == {"/tmp": 1 << 30, "/dev/shm": 256 << 20, "/var/tmp": 256 << 20}
    sys.path.insert(0, str(ROOT / "deploy" / "jupyterhub"))
    import limits

    groups = limits.cgroup_dirs("posekit-alice")
    if groups is not None:
        assert "posekit/posekit-alice" in seen["cgroup"]
        limit = (groups["memory"] / "memory.limit_in_bytes") if "memory" in groups else groups[""] / "memory.max"
        expected = json.loads((ROOT / "deploy" / "jupyterhub" / "class_sizing.json").read_text())["per_student_peak_mb"]
        assert int(limit.read_text()) >= expected * 1024 * 1024  # the measured peak, with headroom


def test_the_hubs_state_is_the_hubs_alone(hub):
    # root follows no link a student plants in a shared sticky folder (machine-wide, set by the hub as root)
    assert Path("/proc/sys/fs/protected_symlinks").read_text().strip() == "1"
    assert stat.S_IMODE(hub.state.stat().st_mode) == 0o700
    assert stat.S_IMODE((hub.state / "jupyterhub.sqlite").stat().st_mode) == 0o600
    out = _in(hub, "alice", f"""
        for path in ({str(hub.state / 'jupyterhub.sqlite')!r}, {str(hub.state / 'jupyterhub_cookie_secret')!r}):
            try:
                open(path, "rb").read(4)
                print("READ", path)
            except OSError:
                print("refused")
        """)
    assert "READ" not in out and out.count("refused") == 2, out


def _fetch_edit_submit(mark: str, *submits) -> str:
    """A student's cell: fetch the assignment, put ``mark`` in its first answer, submit it once per ``submits``
    (each a tuple of extra arguments to ``nbgrader submit``)."""
    return f"""
import os, subprocess, sys
def nbgrader(*args):
    done = subprocess.run([sys.executable, "-m", "nbgrader", *args], capture_output=True, text=True)
    print(done.returncode, done.stdout[-1500:], done.stderr[-1500:])
os.chdir(os.path.expanduser("~"))
nbgrader("fetch_assignment", {ASSIGNMENT!r})
path = os.path.join({ASSIGNMENT!r}, {ASSIGNMENT!r} + ".ipynb")
with open(path) as f:
    text = f.read()
with open(path, "w") as f:
    f.write(text.replace("YOUR CODE HERE", {mark!r}, 1))
""" + "".join(f"nbgrader('submit', {ASSIGNMENT!r}, *{list(extra)!r})\n" for extra in submits)


def test_a_student_cannot_take_over_the_exchange_nor_submit_as_another(hub, tmp_path):
    course_folder = hub.exchange / COURSE
    st = course_folder.stat()
    assert st.st_uid == os.geteuid() and stat.S_IMODE(hub.exchange.stat().st_mode) == 0o1777
    # 1. alice moves the course aside and puts her own in its place (worked when the root was 0777)
    out = _in(hub, "alice", f"""
        import os, shutil
        ex = {str(hub.exchange)!r}
        for what, do in [("move the course", lambda: os.rename(os.path.join(ex, {COURSE!r}), os.path.join(ex, "old"))),
                         ("remove outbound", lambda: shutil.rmtree(os.path.join(ex, {COURSE!r}, "outbound"))),
                         ("plant in outbound", lambda: os.mkdir(os.path.join(ex, {COURSE!r}, "outbound", "trojan"))),
                         ("list inbound", lambda: os.listdir(os.path.join(ex, {COURSE!r}, "inbound")))]:
            try:
                do()
                print("DID", what)
            except OSError as e:
                print("refused", what, type(e).__name__)
        """)
    assert "DID" not in out, out
    assert course_folder.stat().st_uid == os.geteuid() and (course_folder / "outbound").is_dir()
    # 2. the instructor releases; bob fetches the real assignment and submits it
    release(hub.exchange, tmp_path / "course", COURSE, ASSIGNMENT)
    out = _in(hub, "bob", _fetch_edit_submit("bob's own work", ()), timeout_s=300)
    assert "bob's own work" in (hub.home("bob") / ASSIGNMENT / f"{ASSIGNMENT}.ipynb").read_text(), out
    released = (tmp_path / "course" / "release" / ASSIGNMENT / f"{ASSIGNMENT}.ipynb").read_text()
    assert released.replace("YOUR CODE HERE", "bob's own work", 1) == \
        (hub.home("bob") / ASSIGNMENT / f"{ASSIGNMENT}.ipynb").read_text()
    time.sleep(1.1)  # a later timestamp for the forgery: nbgrader's collect would take it
    # 3. alice submits a forged notebook in bob's name
    out = _in(hub, "alice", _fetch_edit_submit("FORGED by alice", ("--student=bob",), ()), timeout_s=300)
    inbound = sorted(p.name for p in (course_folder / "inbound").iterdir())
    assert [n.split("+")[0] for n in inbound].count("bob") == 2, inbound  # bob's and the forgery
    assert any(n.startswith("alice+") for n in inbound), inbound  # her own, under her hub name
    # 4. the instructor collects: bob's own work, and the forgery refused with a sentence
    done = subprocess.run([sys.executable, "-m", "nbgrader", "collect", ASSIGNMENT, f"--Exchange.root={hub.exchange}",
                           f"--CourseDirectory.course_id={COURSE}"], cwd=tmp_path / "course", capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    collected = tmp_path / "course" / "submitted" / "bob" / ASSIGNMENT / f"{ASSIGNMENT}.ipynb"
    assert "bob's own work" in collected.read_text() and "FORGED" not in collected.read_text()
    assert "claims to be bob's but was made by alice" in done.stderr + done.stdout
    assert (tmp_path / "course" / "submitted" / "alice").is_dir()  # nbgrader's ids are the hub's names
    assert not (tmp_path / "course" / "submitted" / "posekit-alice").exists()


def test_the_hub_never_follows_a_students_link_when_copying_the_lessons(hub):
    bob_lessons = hub.home("bob") / "lessons"
    (bob_lessons / "03_autoencoder_solvers.ipynb").unlink()  # a copy into bob's folder would put it back
    before = sorted(p.name for p in bob_lessons.iterdir())
    out = _in(hub, "alice", f"""
        import os, shutil
        shutil.rmtree(os.path.expanduser("~/lessons"))
        os.symlink({str(bob_lessons)!r}, os.path.expanduser("~/lessons"))
        print("linked")
        """)
    assert "linked" in out
    assert hub.api("DELETE", "/users/alice/server")[0] in (202, 204)
    t0 = time.time()
    while hub.server("alice") is not None and time.time() - t0 < 60:
        time.sleep(0.5)
    status, _ = hub.api("POST", "/users/alice/server")
    time.sleep(2)
    assert status >= 400 or not (hub.server("alice") or {}).get("ready"), status
    assert sorted(p.name for p in bob_lessons.iterdir()) == before, "the hub wrote into bob's lessons"
    assert "is a link, expected a folder of your own" in hub.log_text()
