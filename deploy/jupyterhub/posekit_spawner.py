"""The class spawner of ``make hub``: every student's server as their own system user, in a sandbox of its own.

JupyterHub's ``SimpleLocalProcessSpawner`` (the trial's spawner until now) runs every student's server as the hub's
own user: one student's kernel could read and write every other student's files, and read another's server token
from ``/proc/<pid>/environ``. :class:`ClassSpawner` instead, when the hub runs as root:

* gives each student a system user of their own, ``posekit-<name>`` (made on their first start with ``useradd``:
  no password, no login shell, the hub name in its comment field, so that tools that see only the system user, such
  as nbgrader's ``collect``, can name the student as the hub does), and a home only they can open (``0700``,
  theirs), under the hub's state folder;
* starts their server under ``unshare`` in a mount, PID and IPC namespace of its own, through ``sandbox.py``: no
  other process is visible, only their own home of all the homes, no hub database or secret, no ``instructor/``
  folder (the exercises' solutions), a private ``/tmp``, ``/var/tmp``, ``/dev/shm`` and ``/run/lock``; Python, the
  repository and the data readable; the class's compiled-solver cache shared read-only with a private writable
  layer; a network namespace of its own (``relay.py``); memory, CPU and process limits (``limits.py``); then it
  drops to their user with no capability and ``no_new_privs``.

When the hub does not run as root it cannot do any of this: it falls back to the trial's behaviour
(``SimpleLocalProcessSpawner``: every server as the hub's user) and says so in its log, once per start.
"""

from __future__ import annotations

import hashlib
import json
import os
import pwd
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path

from urllib.parse import urlparse

from jupyterhub.spawner import SimpleLocalProcessSpawner
from jupyterhub.utils import random_port
from traitlets import Bool, Dict, Integer, List, Unicode

HERE = Path(__file__).resolve().parent
SANDBOX = HERE / "sandbox.py"


def unix_name(hub_name: str, prefix: str = "posekit-") -> str:
    """The system user of hub user ``hub_name``: ``prefix`` + the name in lower-case letters, digits and ``-``
    (32 characters at most); a short hash of the hub name is added when anything had to change, so two hub
    names never share a system user."""
    clean = re.sub(r"[^a-z0-9-]", "-", hub_name.lower()).strip("-") or "user"
    if clean != hub_name:
        clean = f"{clean[:16]}-{hashlib.sha256(hub_name.encode()).hexdigest()[:8]}"
    return (prefix + clean)[:32]


HUB_USER_COMMENT = "posekit hub user "
"""The start of a student's system user's comment field; the rest is their hub name (read back by
``posekit.course.exchange.student_of_uid``, which nbgrader's collect uses)."""


def ensure_user(name: str, home: Path, hub_name: str | None = None) -> pwd.struct_passwd:
    """The system user ``name``, made (no password, no login shell, a group of its own, ``hub_name`` in its comment
    field) when missing; an existing one gets the comment when it lacks it."""
    comment = HUB_USER_COMMENT + (hub_name or name)
    try:
        pw = pwd.getpwnam(name)
    except KeyError:
        useradd = shutil.which("useradd") or "/usr/sbin/useradd"
        subprocess.run([useradd, "--system", "--user-group", "--no-create-home", "--home-dir", str(home),
                        "--shell", "/usr/sbin/nologin", "--comment", comment, name],
                       check=True, capture_output=True, text=True)
        return pwd.getpwnam(name)
    if hub_name is not None and pw.pw_gecos != comment:
        usermod = shutil.which("usermod") or "/usr/sbin/usermod"
        subprocess.run([usermod, "--comment", comment, name], check=True, capture_output=True, text=True)
        pw = pwd.getpwnam(name)
    return pw


def own_home(home: Path, uid: int, gid: int) -> None:
    """``home`` and what root made in it (the lessons the hub just copied) belong to the student; ``home`` is ``0700``.

    Never follows a link, and never hands over a file with a second hard link (one the student may have made to a
    file of someone else's): only entries owned by root with one link change hands."""
    home.mkdir(parents=True, exist_ok=True)
    os.lchown(home, uid, gid)
    for dirpath, dirnames, filenames in os.walk(home):
        for name in [*(os.path.join(dirpath, n) for n in dirnames + filenames)]:
            st = os.lstat(name)
            if st.st_uid == 0 and (os.path.isdir(name) and not os.path.islink(name) or st.st_nlink == 1):
                os.lchown(name, uid, gid)
    home.chmod(0o700)


class ClassSpawner(SimpleLocalProcessSpawner):
    """One system user and one sandbox per student (see the module docstring)."""

    user_prefix = Unicode("posekit-", config=True, help="Prefix of the students' system user names.")
    expose = List(Unicode(), config=True, help="Folders every server reads and writes besides the home "
                                                "(none by default).")
    expose_ro = List(Unicode(), config=True, help="Folders every server needs read-only: Python, the virtual "
                                                   "environment, the repository, the data.")
    overlay = Unicode("", config=True, help="The class's compiled-solver cache: shared read-only, each server's "
                                            "writes in a private layer.")
    hide = List(Unicode(), config=True, help="Folders no server may see (covered by an empty folder): the hub's "
                                             "state, the instructor's folder.")
    private = Dict(config=True, help="The places every user may write, made private per student: {path: tmpfs "
                                     "size} (sandbox.PRIVATE by default).")
    pids_limit = Integer(1024, config=True, help="Processes and threads per student at most.")
    network_namespace = Bool(True, config=True, help="Each server in a network namespace of its own, joined to the "
                                                     "machine's loopback by a relay (relay.py).")

    @property
    def isolated(self) -> bool:
        return os.geteuid() == 0 and shutil.which("unshare") is not None

    def job(self, pw) -> dict:
        import sandbox

        job = {"user": pw.pw_name, "uid": pw.pw_uid, "gid": pw.pw_gid, "home": self.home_dir,
               "expose": [self.home_dir, *self.expose], "expose_ro": list(self.expose_ro),
               "overlay": self.overlay, "hide": list(self.hide),
               "private": dict(self.private or sandbox.PRIVATE),
               "limits": {"memory_bytes": self.mem_limit or None, "cpu": self.cpu_limit or None,
                          "pids": self.pids_limit or None}}
        if self.network_namespace:
            hub = urlparse(self.get_env()["JUPYTERHUB_API_URL"])
            ip = self.ip or "127.0.0.1"
            for what, host in (("the hub's API", hub.hostname), ("the server", ip)):
                if host not in ("127.0.0.1", "localhost"):
                    raise RuntimeError(f"posekit: {what} is on {host}, not the loopback: a server in a network "
                                       f"namespace of its own cannot reach it (ClassSpawner.network_namespace)")
            job["relay"] = {"server": ["127.0.0.1", self.port], "hub": ["127.0.0.1", hub.port or 80]}
        return job

    def make_preexec_fn(self, name):
        if not self.isolated:
            return super().make_preexec_fn(name)
        return lambda: None  # root until sandbox.py has built the student's view; it drops to their user itself

    def user_env(self, env):
        env = super().user_env(env)
        if self.isolated:
            env["USER"] = env["LOGNAME"] = unix_name(self.user.name, self.user_prefix)
        return env

    async def start(self):
        if not self.isolated:
            self.log.warning("posekit: the hub does not run as root (or unshare is missing): %s's server runs as "
                             "the hub's own user, NOT kept apart from the other students (docs/hub.md)",
                             self.user.name)
            return await super().start()
        home = Path(self.home_dir)
        pw = ensure_user(unix_name(self.user.name, self.user_prefix), home, self.user.name)
        own_home(home, pw.pw_uid, pw.pw_gid)
        if self.port == 0:
            self.port = random_port()
        jobs = home.parent.parent / "sandbox-jobs"
        jobs.mkdir(mode=0o700, exist_ok=True)
        job = jobs / f"{pw.pw_name}.json"
        fd = os.open(job, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o600)
        with os.fdopen(fd, "w") as f:
            f.write(json.dumps(self.job(pw)))
        saved = self.cmd
        self.cmd = ["unshare", "--mount", "--pid", "--ipc", "--fork", "--mount-proc", "--propagation", "private",
                    sys.executable, str(SANDBOX), str(job), "--", *saved]
        try:
            return await super().start()
        finally:
            self.cmd = saved

    async def _signal(self, sig):
        """The hub's stop signals go to the sandbox's init (unshare itself ignores SIGINT and SIGTERM)."""
        if not self.isolated or sig == signal.SIGKILL:
            return await super()._signal(sig)
        try:
            children = Path(f"/proc/{self.pid}/task/{self.pid}/children").read_text().split()
        except OSError:
            children = []
        if not children:
            return await super()._signal(sig)
        for child in children:
            try:
                os.kill(int(child), sig)
            except ProcessLookupError:
                pass
        return True
