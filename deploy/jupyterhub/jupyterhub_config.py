# JupyterHub configuration for a posekit class on one machine (`make hub`; docs/hub.md).
#
# Each student who logs in gets a Jupyter server of their own that opens JupyterLab on their own copy of the lessons
# (copied on the first start; a file already there is never overwritten, so their edits stay), with `make lab`'s
# kernel websocket setting and the studio one link away (Voila's server extension). Idle servers are stopped by
# jupyterhub-idle-culler, run by the hub as a service. The proxy is configurable-http-proxy from the npm registry
# (deploy/jupyterhub/package.json, installed by `make hub`).
#
# STUDENTS KEPT APART (posekit_spawner.py, when the hub runs as root): each student's server runs as their own system
# user (posekit-<name>, made on their first start), in a sandbox of its own (sandbox.py: a mount, PID, IPC and
# network namespace): it sees no other process, no other student's home or kernel, not the hub's database or
# secrets, not the instructor's folder (instructor/: the exercises' solutions), private /tmp, /var/tmp, /dev/shm and
# /run/lock, with limits on memory, CPU and processes (limits.py, from class_sizing.json). Not as root, the hub
# cannot: every server then runs as the hub's user, with no isolation, and the log says so.
# TRIAL LOGIN: the authenticator is JupyterHub's SharedPasswordAuthenticator (any user name, one password): whoever
# knows the password can log in under any name, another student's included. A real class uses a real authenticator
# (docs/hub.md).
# NBGRADER: with POSEKIT_HUB_COURSE set, every student's JupyterLab has nbgrader's Assignments panel (fetch, submit,
# validate) on the exchange folder POSEKIT_HUB_EXCHANGE; the instructor releases and collects with nbgrader in the
# course folder (docs/nbgrader.md).
#
# Settings (environment variables, all optional):
#   POSEKIT_HUB_STATE           the hub's state folder: database, secrets, the students' homes (default build/hub)
#   POSEKIT_HUB_PORT            the port the class opens (default 8000), on POSEKIT_HUB_IP (default 127.0.0.1)
#   POSEKIT_HUB_PASSWORD        the trial password every student types (default "posekit-trial")
#   POSEKIT_HUB_CULL_TIMEOUT    seconds without activity before a server is stopped (default 3600)
#   POSEKIT_HUB_CULL_EVERY      seconds between the culler's checks (default 300, at most the timeout / 2)
#   POSEKIT_HUB_ACTIVITY_EVERY  seconds between a server's activity reports to the hub (default 300, the same bound)
#   POSEKIT_HUB_API_PORT, POSEKIT_HUB_PROXY_API_PORT   the hub's and the proxy's internal ports (8081, 8001)
#   POSEKIT_HUB_LESSONS         the folder of lessons each student copies (default notebooks/)
#   POSEKIT_HUB_COURSE          an nbgrader course id: students get nbgrader's Assignments panel (default: none)
#   POSEKIT_HUB_EXCHANGE        nbgrader's exchange folder, shared by the instructor and the students
#                               (default <state>/exchange)
#   POSEKIT_HUB_INSTRUCTOR      the system user who releases and collects (owns the course's exchange folder;
#                               default the hub's own user)

import json
import os
import pwd
import signal
import stat
import sys
from pathlib import Path

from tornado.web import HTTPError

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
STATE = Path(os.environ.get("POSEKIT_HUB_STATE") or ROOT / "build" / "hub").resolve()
LESSONS = Path(os.environ.get("POSEKIT_HUB_LESSONS") or ROOT / "notebooks").resolve()
LESSON_FOLDER = "lessons"
"""The folder, in each student's home, that holds their copy of the lessons (JupyterLab opens on it)."""
NODELAY = "posekit.viz.websocket.NoDelayConnection"
"""make lab's kernel websocket connection class (the Makefile's NODELAY)."""
PROXY = HERE / "node_modules" / ".bin" / "configurable-http-proxy"
CULL_TIMEOUT = int(os.environ.get("POSEKIT_HUB_CULL_TIMEOUT") or 3600)
CULL_EVERY = min(int(os.environ.get("POSEKIT_HUB_CULL_EVERY") or 300), max(1, CULL_TIMEOUT // 2))
ACTIVITY_EVERY = min(int(os.environ.get("POSEKIT_HUB_ACTIVITY_EVERY") or 300), max(1, CULL_TIMEOUT // 2))
COURSE = os.environ.get("POSEKIT_HUB_COURSE") or ""
EXCHANGE = Path(os.environ.get("POSEKIT_HUB_EXCHANGE") or STATE / "exchange").resolve()
INSTRUCTOR = os.environ.get("POSEKIT_HUB_INSTRUCTOR") or ""
SIZING = HERE / "class_sizing.json"
STATE.mkdir(parents=True, exist_ok=True)
STATE.chmod(0o700)  # the hub's alone: its database, secrets, the sandboxes' job files
(STATE / "users").mkdir(exist_ok=True)
(STATE / "users").chmod(0o711)  # each student walks through to their own home; none can list the others
DB = STATE / "jupyterhub.sqlite"
os.close(os.open(DB, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600))  # made by us, so never readable by others
DB.chmod(0o600)
sys.path.insert(0, str(HERE))
from measure_class import z2jh_resources  # noqa: E402 - deploy/jupyterhub/measure_class.py
from posekit_spawner import ClassSpawner  # noqa: E402 - deploy/jupyterhub/posekit_spawner.py

c = get_config()  # noqa: F821 - JupyterHub defines it when it loads this file

# A hub started where Ctrl-C is ignored (a script's background job, `make hub &`, some CI runners) would pass that on
# to every process it starts: the idle culler would outlive the hub's SIGINT, and each stop of the hub wait 30 s for
# it; each student's server, 10 s. The hub handles SIGINT itself once running; what it starts gets the default.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

# -- the hub and its proxy ------------------------------------------------------------------------------------------
c.JupyterHub.bind_url = (f"http://{os.environ.get('POSEKIT_HUB_IP', '127.0.0.1')}:"
                         f"{os.environ.get('POSEKIT_HUB_PORT', '8000')}")
c.JupyterHub.hub_bind_url = f"http://127.0.0.1:{os.environ.get('POSEKIT_HUB_API_PORT', '8081')}"
c.ConfigurableHTTPProxy.api_url = f"http://127.0.0.1:{os.environ.get('POSEKIT_HUB_PROXY_API_PORT', '8001')}"
c.ConfigurableHTTPProxy.command = [str(PROXY)]
c.ConfigurableHTTPProxy.pid_file = str(STATE / "jupyterhub-proxy.pid")
c.JupyterHub.db_url = f"sqlite:///{DB}"
c.JupyterHub.cookie_secret_file = str(STATE / "jupyterhub_cookie_secret")
c.JupyterHub.last_activity_interval = ACTIVITY_EVERY
# a student may retry after a failed start at once; a start slower than this is reported as failed
c.Spawner.start_timeout = 120
c.Spawner.http_timeout = 120

# -- TRIAL authenticator: any name, one password. Not for a class (docs/hub.md names the ones a class uses) ----------
# (JupyterHub's SharedPasswordAuthenticator: whoever knows the password logs in under any name, and as any other
# student too -- it keeps no one out of anyone's account)
c.JupyterHub.authenticator_class = "shared-password"
c.SharedPasswordAuthenticator.user_password = os.environ.get("POSEKIT_HUB_PASSWORD") or "posekit-trial"
c.Authenticator.allow_all = True

# -- the spawner: one system user, one home and one sandbox per student (see the top; posekit_spawner.py) -----------
c.JupyterHub.spawner_class = ClassSpawner
c.ClassSpawner.home_dir_template = str(STATE / "users" / "{username}")
c.Spawner.cmd = [str(Path(sys.executable).parent / "jupyterhub-singleuser")]
c.Spawner.default_url = f"/lab/tree/{LESSON_FOLDER}"
c.Spawner.args = [
    f"--ServerApp.kernel_websocket_connection_class={NODELAY}",  # as make lab
    "--LabApp.news_url=", "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate",  # nothing fetched
    "--VoilaConfiguration.template=posekit",  # the studio's page (make studio's template)
    # a kernel left behind by a closed studio or lesson tab is stopped after 20 minutes without a connection
    "--MappingKernelManager.cull_idle_timeout=1200", "--MappingKernelManager.cull_interval=60",
] + (["--allow-root"] if os.geteuid() == 0 else [])
c.Spawner.environment = {
    # the studio's Voila template (posekit/viz/voila), found by Voila's server extension as make studio finds it
    "JUPYTER_PATH": os.pathsep.join(filter(None, [str(ROOT / "posekit" / "viz" / "voila"),
                                                  os.environ.get("JUPYTER_PATH")])),
    "JUPYTERHUB_ACTIVITY_INTERVAL": str(ACTIVITY_EVERY),
    # one compiled-solver cache for the class: the hub's own (posekit/_jit.py's default place, which `make hub`
    # warms first). Each student's home would otherwise hold a cache of its own, and each student's first lesson
    # compiled every solver again, slower and in more memory
    "POSEKIT_NUMBA_CACHE": os.environ.get("POSEKIT_NUMBA_CACHE") or os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache"), "posekit"),
}
c.Spawner.env_keep = ["PATH", "PYTHONPATH", "VIRTUAL_ENV", "LANG", "LC_ALL", "POSEKIT_DATA_DIR", "NUMBA_CACHE_DIR"]

# what a student's sandbox may read (Python, the environment, the repository, the data), what it may not see
# (the hub's state but their own home, the instructor's folder), the class's compiled-solver cache shared read-only
# with a private writable layer
_needed = [sys.base_prefix, sys.prefix, str(ROOT), os.environ.get("POSEKIT_DATA_DIR"),
           *os.environ.get("PYTHONPATH", "").split(os.pathsep)]
c.ClassSpawner.expose_ro = [p for p in dict.fromkeys(filter(None, _needed)) if os.path.isdir(p)]
c.ClassSpawner.hide = [str(STATE), str(ROOT / "instructor")]
c.ClassSpawner.overlay = c.Spawner.environment["POSEKIT_NUMBA_CACHE"]

# -- limits per student (limits.py): the measured peak of the worst lesson with the studio open, as the
# zero-to-jupyterhub values have it (measure_class.z2jh_resources: twice the peak rounded up to 64 MB, one CPU)
_RESOURCES = z2jh_resources(json.loads(SIZING.read_text()))


def limits_from_sizing(resources=_RESOURCES) -> dict:
    """The spawner's limits from the zero-to-jupyterhub resources: ``mem_limit`` (bytes), ``cpu_limit`` (CPUs)."""
    mb = int(resources["memory"]["limit"].rstrip("M"))
    return {"mem_limit": mb * 1024 * 1024, "cpu_limit": float(resources["cpu"]["limit"])}


for _name, _value in limits_from_sizing().items():
    setattr(c.Spawner, _name, _value)
c.ClassSpawner.pids_limit = 1024  # a choice (not measured): a kernel with torch and numba runs some 40 threads


def harden_links() -> list[str]:
    """Root never follows a link a student planted in a shared sticky folder, nor hands over a hard link: the
    kernel's protected_symlinks / protected_hardlinks / protected_regular on (machine-wide, where the hub may set
    them). Returns what could not be set."""
    missed = []
    for name in ("protected_symlinks", "protected_hardlinks", "protected_regular"):
        path = Path("/proc/sys/fs") / name
        try:
            if path.read_text().strip() in ("", "0"):
                path.write_text("1")
        except OSError:
            missed.append(name)
    return missed


if os.geteuid() == 0:
    _missed = harden_links()
    if _missed:
        print(f"posekit: could not set fs.{', fs.'.join(_missed)} to 1 (docs/hub.md)", file=sys.stderr)

# -- nbgrader for the students (POSEKIT_HUB_COURSE): the Assignments panel, on one exchange folder ------------------
STUDENT_CONFIG = STATE / "student-config"
"""A Jupyter configuration folder put first on every student server's JUPYTER_CONFIG_PATH."""


def student_config(course: str, exchange: Path, folder: Path = STUDENT_CONFIG) -> Path:
    """Write the students' Jupyter configuration: nbgrader's student extensions on (the Assignments panel, fetch,
    submit, validate) and the instructor's off (formgrader, course list, create assignment), for ``course`` on
    ``exchange``. ``make lab``'s environment turns them all off (the Makefile); this folder comes first."""
    (folder / "labconfig").mkdir(parents=True, exist_ok=True)
    student, instructor = ["assignment_list", "validate_assignment"], ["formgrader", "course_list"]
    server = {"ServerApp": {"jpserver_extensions": {
        **{f"nbgrader.server_extensions.{e}": True for e in student},
        **{f"nbgrader.server_extensions.{e}": False for e in instructor}}}}
    (folder / "jupyter_server_config.json").write_text(json.dumps(server, indent=1))
    lab = {"disabledExtensions": {"@jupyter/nbgrader": False, "@jupyter/nbgrader:formgrader": True,
                                  "@jupyter/nbgrader:course-list": True, "@jupyter/nbgrader:create-assignment": True},
           "lockedExtensions": {"@jupyter/nbgrader": True}}
    (folder / "labconfig" / "page_config.json").write_text(json.dumps(lab, indent=1))
    (folder / "nbgrader_config.py").write_text(
        "import os\n"
        "c = get_config()  # noqa: F821 - written by deploy/jupyterhub/jupyterhub_config.py\n"
        f"c.CourseDirectory.course_id = {course!r}\n"
        f"c.Exchange.root = {str(exchange)!r}\n"
        "# the student's id in the course is their hub name (not their system user, posekit-<name>): the class list\n"
        "# is the hub's. nbgrader collect checks it against the submission's owner (posekit.course.exchange)\n"
        "if os.environ.get('JUPYTERHUB_USER'):\n"
        "    c.CourseDirectory.student_id = os.environ['JUPYTERHUB_USER']\n")
    for p in [folder, *folder.rglob("*")]:
        p.chmod(0o755 if p.is_dir() else 0o644)
    return folder


def make_exchange(exchange: Path, course: str, instructor: int | None = None) -> Path:
    """nbgrader's exchange as nbgrader means it on a shared machine, made before any student starts.

    The root is ``1777`` (anyone may make an entry; the sticky bit: no one may move or remove another's), and the
    course's folder is made and owned by the instructor (``instructor``, a uid; default the calling user) before
    the first release: ``outbound`` ``0755`` (students read what is released), ``inbound`` ``3733`` (students submit
    but cannot list, and cannot move or remove another's submission), ``feedback`` ``0711``. A course folder or a
    part of it owned by anyone else (a student who made it first) is refused with a sentence, not used."""
    uid = os.geteuid() if instructor is None else instructor
    gid = pwd.getpwuid(uid).pw_gid
    exchange.mkdir(parents=True, exist_ok=True)
    exchange.chmod(0o1777)
    folder = exchange / course
    for path, mode in ((folder, 0o755), (folder / "outbound", 0o755), (folder / "inbound", 0o3733),
                       (folder / "feedback", 0o711)):
        try:
            os.mkdir(path)
        except FileExistsError:
            pass
        st = os.lstat(path)
        if not stat.S_ISDIR(st.st_mode) or st.st_uid != uid:
            owner = st.st_uid
            raise SystemExit(f"posekit: {path} is not a folder of the instructor's (uid {uid}) but "
                             f"{'a link or file' if not stat.S_ISDIR(st.st_mode) else 'owned by uid %d' % owner}: "
                             f"someone made it before the hub did; move it away and start the hub again")
        os.lchown(path, uid, gid)
        os.chmod(path, mode)
    return folder


if COURSE:
    student_config(COURSE, EXCHANGE)
    make_exchange(EXCHANGE, COURSE, pwd.getpwnam(INSTRUCTOR).pw_uid if INSTRUCTOR else None)
    c.Spawner.environment["JUPYTER_CONFIG_PATH"] = os.pathsep.join(
        filter(None, [str(STUDENT_CONFIG), os.environ.get("JUPYTER_CONFIG_PATH")]))
    c.ClassSpawner.expose_ro = [*c.ClassSpawner.expose_ro, str(STUDENT_CONFIG)]
    c.ClassSpawner.expose = [str(EXCHANGE)]


class LessonCopyError(HTTPError):
    """The lessons could not be copied: the server is not started, and the hub's error page shows the student the
    message (an HTTP error passes through the hub's spawn handler with its message; another exception becomes
    "Unhandled error starting server")."""

    def __init__(self, message):
        super().__init__(500, message)
        self.jupyterhub_message = message


def copy_lessons(home: Path, lessons: Path = LESSONS) -> list[str]:
    """Copy every lesson notebook of ``lessons`` that ``home``/lessons lacks; never overwrite a file there.

    Run as root by the hub, so it never follows a path the student controls: ``lessons`` is opened without
    following a link (a link there, to another student's home or a folder of root's, is refused), and each file is
    made new in that open folder (``O_EXCL | O_NOFOLLOW``: an existing file or link is left alone, never written
    through). Returns the names copied. Raises ``LessonCopyError`` with a sentence naming the path when the copy
    cannot be made (the hub shows it on the student's error page)."""
    dest = home / LESSON_FOLDER
    copied = []
    try:
        home.mkdir(parents=True, exist_ok=True)
        top = os.open(home, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
        try:
            try:
                os.mkdir(LESSON_FOLDER, 0o755, dir_fd=top)
            except FileExistsError:
                pass
            st = os.stat(LESSON_FOLDER, dir_fd=top, follow_symlinks=False)
            if stat.S_ISLNK(st.st_mode):
                raise LessonCopyError(f"posekit: cannot copy the lessons: {dest} is a link, expected a folder of "
                                      f"your own (remove the link and start the server again)")
            if not stat.S_ISDIR(st.st_mode):
                raise LessonCopyError(f"posekit: cannot copy the lessons: {dest} is a file, expected a folder "
                                      f"(move it away and start the server again)")
            folder = os.open(LESSON_FOLDER, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW, dir_fd=top)
        finally:
            os.close(top)
        try:
            for src in sorted(lessons.glob("*.ipynb")):
                if src.name.startswith("_"):  # the lesson template is for authors
                    continue
                try:
                    fd = os.open(src.name, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644, dir_fd=folder)
                except FileExistsError:
                    continue  # the student's own copy, perhaps edited (or a link of theirs): kept as it is
                with os.fdopen(fd, "wb") as out:
                    out.write(src.read_bytes())
                copied.append(src.name)
        finally:
            os.close(folder)
    except LessonCopyError:
        raise
    except OSError as err:
        raise LessonCopyError(f"posekit: cannot copy the lessons into {dest}: {err}") from err
    return copied


def _pre_spawn(spawner):
    home = Path(spawner.home_dir)
    copied = copy_lessons(home)
    if copied:
        spawner.log.info("posekit: copied %d lessons into %s", len(copied), home / LESSON_FOLDER)


c.Spawner.pre_spawn_hook = _pre_spawn

# -- idle servers stopped: jupyterhub-idle-culler as a hub service -------------------------------------------------
c.JupyterHub.services = [{
    "name": "idle-culler",
    "command": [sys.executable, "-m", "jupyterhub_idle_culler", f"--timeout={CULL_TIMEOUT}",
                f"--cull-every={CULL_EVERY}"],
}]
c.JupyterHub.load_roles = [{
    "name": "idle-culler",
    "scopes": ["list:users", "read:users:activity", "read:servers", "delete:servers"],
    "services": ["idle-culler"],
}]
