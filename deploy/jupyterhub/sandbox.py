"""Start one student's Jupyter server in a sandbox of its own (run as root by the class spawner, posekit_spawner.py).

    unshare --mount --pid --ipc --fork --mount-proc -- python sandbox.py JOB.json -- jupyterhub-singleuser ...

``unshare`` gives the server a mount, PID and System V IPC namespace of its own (its own /proc: no other process on
the machine is visible from it; no other student's shared-memory segment or message queue). This script then, still
as root and inside them:

1. puts itself and everything it will start in the student's control group (memory, CPU share, process count; see
   :mod:`limits`), where the machine lets it;
2. covers the *hidden* folders with empty tmpfs: the hub's state folder (its database, secrets and every other
   student's home), the instructor's folder (``instructor/``: the exercises' solutions), the places every user may
   write (``/tmp``, ``/var/tmp``, ``/dev/shm``, ``/run/lock``: private and sized, each its own tmpfs), and any folder
   the student could not walk through on the way to what the server needs (``/root`` when Python lives under it);
3. binds back, at their own paths, only what the server needs from inside a covered folder: the student's home
   (read-write), Python and the virtual environment, the repository, the data folder (read-only where bound back;
   elsewhere their own permissions apply: root's files, which a student cannot change), and the class's
   compiled-solver cache as an overlay (the shared cache below, the student's writes in a private layer above, so
   no student can change what another loads). Covers and binds are made shallowest first, so a hidden folder inside
   a folder bound back (the state folder inside a repository under ``/tmp``) is covered again after the bind; then
   every hidden path is checked: one still visible stops the start (**fail closed**);
4. gives the server a network namespace of its own (only its own loopback: no other student's kernel ports,
   no abstract unix socket of theirs, nothing outside), joined to the machine's loopback by a relay
   (:mod:`relay`) for the two connections a server needs: the proxy's and the hub's to the server's port, and the
   server's to the hub's API;
5. drops to the student's own system user (uid, gid, no other groups) with no capability left in its bounding set
   and ``no_new_privs`` set (no set-uid program gives any back), and runs the server as the child of a small init
   that passes on the hub's stop signals, reaps orphans and runs the relay; that init cannot be traced or read by
   the student (not dumpable).

The job file (JSON, written by the spawner, readable by root only) holds ``user``, ``uid``, ``gid``, ``home``,
``expose`` (paths, read-write), ``expose_ro``, ``overlay`` (the cache), ``hide``, ``private`` (``{path: size}``:
the shared writable places made private), ``limits`` (:func:`limits.apply`) and ``relay`` (``{"server": [host,
port], "hub": [host, port]}``, or absent: no network namespace).
"""

from __future__ import annotations

import ctypes
import json
import os
import signal
import stat
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import limits  # noqa: E402 - deploy/jupyterhub/limits.py
import relay  # noqa: E402 - deploy/jupyterhub/relay.py

_LIBC = ctypes.CDLL(None, use_errno=True)
MS_RDONLY, MS_NOSUID, MS_NODEV, MS_REMOUNT, MS_BIND = 1, 2, 4, 32, 4096
PRIVATE = {"/tmp": "1g", "/var/tmp": "256m", "/dev/shm": "256m", "/run/lock": "8m"}
"""The places every user may write on a Debian machine, made private per student (tmpfs, mode 1777) and sized."""


class SandboxError(RuntimeError):
    """The sandbox could not be made as meant: the server is not started."""


def _mount(source: str, target, fstype: str | None = None, flags: int = 0, data: str | None = None) -> None:
    """mount(2) itself: a bind source given as ``/proc/self/fd/N`` is followed as the kernel sees it (the mount
    command would first turn it back into a path, which by then leads into the cover)."""
    enc = (lambda v: None if v is None else str(v).encode())
    if _LIBC.mount(enc(source), enc(target), enc(fstype), ctypes.c_ulong(flags), enc(data)) != 0:
        err = ctypes.get_errno()
        raise SandboxError(f"mount {source} on {target}: {os.strerror(err)}")


def _under(path: Path, top: Path) -> bool:
    return path == top or top in path.parents


def _blocking(path: Path):
    """The first folder on the way to ``path`` that other users cannot walk through (no o+x), or None."""
    for parent in [*reversed(path.parents), path]:
        try:
            mode = parent.stat().st_mode
        except OSError:
            return None
        if stat.S_ISDIR(mode) and not mode & stat.S_IXOTH:
            return parent if parent != path else None
    return None


def _makedirs(path: Path) -> None:
    """Make ``path`` and the folders on the way inside a cover, each ``0711`` (walked through, never listed)."""
    for p in [*reversed(path.parents), path]:
        if not p.exists():
            os.mkdir(p, 0o711)
            os.chmod(p, 0o711)


def plan(job) -> list[tuple[str, Path]]:
    """The mounts of steps 2 and 3, in the order they are made: ``("cover", path)`` and ``("bind", path)``.

    Shallowest first; at one depth a cover before a bind. A cover of a private place (``/tmp``) is a cover like the
    others. The cache (an overlay) is mounted last, apart."""
    rw = [Path(p) for p in job["expose"]]
    ro = [Path(p) for p in job["expose_ro"]]
    cache = Path(job["overlay"]) if job.get("overlay") else None
    hide = [Path(p) for p in job["hide"]] + [Path(p) for p in job.get("private", {})]
    every = [p for p in rw + ro + ([cache] if cache else []) if p.exists()]
    for p in every:  # a folder on the way that a student cannot walk through is covered too, its needed parts bound
        block = _blocking(p)
        if block is not None and not any(_under(p, h) for h in hide):
            hide.append(block)
    steps = [(len(h.parts), 0, "cover", h) for h in set(hide)]
    steps += [(len(p.parts), 1, "bind", p) for p in set(every) if p != cache]
    return [(kind, path) for _, _, kind, path in sorted(steps, key=lambda s: (s[0], s[1], str(s[3])))]


def build(job) -> None:
    """Steps 2 and 3 of the module docstring; raises :class:`SandboxError` when a hidden path stays visible."""
    ro = {Path(p) for p in job["expose_ro"]}
    for p in sorted(ro):  # a folder on the way is covered (plan), but a shared folder's own mode is its owner's word
        if p.is_dir() and not p.stat().st_mode & stat.S_IXOTH:
            raise SandboxError(f"{p} is shared read-only with the students (Python, the virtual environment or the "
                               f"repository) but other users cannot walk through it (mode "
                               f"{stat.S_IMODE(p.stat().st_mode):04o}); the server is not started: chmod o+x {p}")
    cache = Path(job["overlay"]) if job.get("overlay") else None
    private = {Path(p): size for p, size in job.get("private", {}).items()}
    steps = plan(job)
    # every path to bind back, opened before anything is covered (bound from /proc/self/fd/N afterwards)
    fds = {p: os.open(p, os.O_PATH) for kind, p in steps if kind == "bind"}
    if cache is not None and cache.exists():
        fds[cache] = os.open(cache, os.O_PATH)
    ours: set[int] = set()  # the devices of the tmpfs covers made here
    covered: list[Path] = []
    for kind, path in steps:
        if kind == "cover":
            if not path.is_dir() or path.is_symlink():
                continue  # not there (or hidden by a cover above it): checked below
            if path in private:
                opts, flags = f"mode=1777,size={private[path]}", MS_NOSUID | MS_NODEV
            else:
                opts, flags = "mode=0711,size=16m", MS_NOSUID | MS_NODEV
            _mount("tmpfs", path, "tmpfs", flags, opts)
            ours.add(path.stat().st_dev)
            covered.append(path)
        else:
            if not any(_under(path, h) for h in covered):
                continue  # reachable as it is, with its own permissions
            if Path(f"/proc/self/fd/{fds[path]}").is_dir():
                _makedirs(path)
            else:
                _makedirs(path.parent)
                path.touch()
            _mount(f"/proc/self/fd/{fds[path]}", path, None, MS_BIND)
            if path in ro:
                _mount("none", path, None, MS_REMOUNT | MS_BIND | MS_RDONLY)
    if cache is not None and cache in fds:
        layer = Path("/tmp/.posekit-cache")  # in the private /tmp: the student's own compiled kernels
        for d in ("upper", "work"):
            (layer / d).mkdir(parents=True, exist_ok=True)
        os.chown(layer / "upper", job["uid"], job["gid"])
        cache.mkdir(parents=True, exist_ok=True)
        _mount("overlay", cache, "overlay", 0, f"lowerdir=/proc/self/fd/{fds[cache]},upperdir={layer / 'upper'},"
               f"workdir={layer / 'work'}")
        # the student's copy of the cache is theirs to update (a few MB, copied up into the private layer): numba
        # rewrites an index when it adds a kernel, posekit marks the folder in use
        for dirpath, dirnames, filenames in os.walk(cache):
            for name in [dirpath, *(os.path.join(dirpath, n) for n in dirnames + filenames)]:
                os.lchown(name, job["uid"], job["gid"])
    for fd in fds.values():
        os.close(fd)
    check(job, ours)


def check(job, ours: set[int]) -> None:
    """Fail closed: every hidden path and private place is either gone from the student's view or one of the covers
    made here (``ours``: their devices). Raises :class:`SandboxError` naming the first that is not."""
    for h in [*job["hide"], *job.get("private", {})]:
        p = Path(h)
        if not os.path.lexists(p):
            continue  # not visible at all
        st = os.lstat(p)
        if not stat.S_ISDIR(st.st_mode) or st.st_dev not in ours:
            raise SandboxError(f"{p} should be hidden from the student but is still visible (the sandbox's cover "
                               f"could not be made); the server is not started")


def drop_privileges(job) -> None:
    """Step 5 for the calling process: no capability in the bounding set, ``no_new_privs``, the student's user."""
    limits.empty_bounding_set()
    os.setgroups([])
    os.setgid(job["gid"])
    os.setuid(job["uid"])
    limits.no_new_privs()
    if os.getuid() == 0 or os.geteuid() == 0:
        raise SandboxError("could not drop root")


def run(job, cmd) -> int:
    """Steps 4 and 5: the relay, then the student's user, then a child running ``cmd``; this process waits as the
    namespace's init (and keeps the relay's threads)."""
    pipes = relay.start(job["relay"]) if job.get("relay") else None
    child = os.fork()
    if child == 0:
        try:
            os.setsid()
            limits.apply_rlimits(job.get("limits") or {})
            drop_privileges(job)
            os.chdir(job["home"])
            os.execvp(cmd[0], cmd)
        except BaseException as err:  # noqa: BLE001 - report and leave; never return into the init's code
            print(f"sandbox.py: cannot start the server: {err}", file=sys.stderr)
        finally:
            os._exit(127)
    drop_privileges(job)
    limits.not_dumpable()
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, lambda s, _f: os.kill(child, s))
    status = 0
    while True:
        try:
            pid, code = os.wait()
        except ChildProcessError:
            return status
        except InterruptedError:
            continue
        if pid == child:
            status = os.waitstatus_to_exitcode(code)
            if pipes is not None:
                pipes.stop()


def _where(err: BaseException) -> str:
    """The file and line an error came from, for the hub's log."""
    tb = err.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    return f"{Path(tb.tb_frame.f_code.co_filename).name}:{tb.tb_lineno}" if tb else "?"


def main(argv) -> int:
    if "--" not in argv or len(argv) < 4:
        print("usage: sandbox.py JOB.json -- COMMAND ...", file=sys.stderr)
        return 2
    job = json.loads(Path(argv[1]).read_text())
    cmd = argv[argv.index("--") + 1:]
    if os.getpid() != 1:
        print("sandbox.py: expected to run as PID 1 of a new PID namespace (under unshare --pid --fork)",
              file=sys.stderr)
        return 2
    try:
        said, held = limits.join_cgroup(job["user"], job.get("limits") or {})
        job.setdefault("limits", {})["memory_by_cgroup"] = held
        print(f"sandbox.py: {job['user']}: {said}", file=sys.stderr)
        build(job)
    except (SandboxError, OSError) as err:
        where = "" if isinstance(err, SandboxError) else f" ({type(err).__name__} in {_where(err)})"
        print(f"sandbox.py: {job['user']}'s server is not started: {err}{where}", file=sys.stderr)
        return 3
    return run(job, cmd)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
