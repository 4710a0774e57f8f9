# JupyterHub configuration for a posekit class on one machine (`make hub`; docs/hub.md).
#
# Each student who logs in gets a Jupyter server of their own that opens JupyterLab on their own copy of the lessons
# (copied on the first start; a file already there is never overwritten, so their edits stay), with `make lab`'s
# kernel websocket setting and the studio one link away (Voila's server extension). Idle servers are stopped by
# jupyterhub-idle-culler, run by the hub as a service. The proxy is configurable-http-proxy from the npm registry
# (deploy/jupyterhub/package.json, installed by `make hub`).
#
# TRIAL SET-UP: the authenticator is JupyterHub's SharedPasswordAuthenticator (any user name, one password) and the
# spawner is SimpleLocalProcessSpawner (every student's server runs as the hub's own system user, with its own home
# folder under the state folder). The hub keeps students apart at the web level only: a student's browser cannot
# open or drive another student's server. Their processes are NOT kept apart: code in one student's kernel can read
# and write every other student's files. A real class uses a real authenticator and one system user (or container)
# per student: The Littlest JupyterHub (SystemdSpawner) or zero-to-jupyterhub (KubeSpawner) -- docs/hub.md.
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

import os
import shutil
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
STATE.mkdir(parents=True, exist_ok=True)
(STATE / "users").mkdir(exist_ok=True)

c = get_config()  # noqa: F821 - JupyterHub defines it when it loads this file

# -- the hub and its proxy ------------------------------------------------------------------------------------------
c.JupyterHub.bind_url = (f"http://{os.environ.get('POSEKIT_HUB_IP', '127.0.0.1')}:"
                         f"{os.environ.get('POSEKIT_HUB_PORT', '8000')}")
c.JupyterHub.hub_bind_url = f"http://127.0.0.1:{os.environ.get('POSEKIT_HUB_API_PORT', '8081')}"
c.ConfigurableHTTPProxy.api_url = f"http://127.0.0.1:{os.environ.get('POSEKIT_HUB_PROXY_API_PORT', '8001')}"
c.ConfigurableHTTPProxy.command = [str(PROXY)]
c.ConfigurableHTTPProxy.pid_file = str(STATE / "jupyterhub-proxy.pid")
c.JupyterHub.db_url = f"sqlite:///{STATE / 'jupyterhub.sqlite'}"
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

# -- TRIAL spawner: one home folder per student, every server as the hub's own system user (see the top) ------------
c.JupyterHub.spawner_class = "simple"
c.SimpleLocalProcessSpawner.home_dir_template = str(STATE / "users" / "{username}")
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


class LessonCopyError(HTTPError):
    """The lessons could not be copied: the server is not started, and the hub's error page shows the student the
    message (an HTTP error passes through the hub's spawn handler with its message; another exception becomes
    "Unhandled error starting server")."""

    def __init__(self, message):
        super().__init__(500, message)
        self.jupyterhub_message = message


def copy_lessons(home: Path, lessons: Path = LESSONS) -> list[str]:
    """Copy every lesson notebook of ``lessons`` that ``home``/lessons lacks; never overwrite a file there.

    Returns the names copied. Raises ``LessonCopyError`` with a sentence naming the path when the copy cannot be made
    (the hub shows it on the student's error page)."""
    dest = home / LESSON_FOLDER
    if dest.exists() and not dest.is_dir():
        raise LessonCopyError(f"posekit: cannot copy the lessons: {dest} is a file, expected a folder "
                           f"(move it away and start the server again)")
    copied = []
    try:
        dest.mkdir(parents=True, exist_ok=True)
        for src in sorted(lessons.glob("*.ipynb")):
            if src.name.startswith("_"):  # the lesson template is for authors
                continue
            target = dest / src.name
            if target.exists() or target.is_symlink():
                continue  # the student's own copy, perhaps edited: kept as it is
            shutil.copyfile(src, target)
            copied.append(src.name)
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
