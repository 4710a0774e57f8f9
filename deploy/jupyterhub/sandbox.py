"""Start one student's Jupyter server in a sandbox of its own (run as root by the class spawner, posekit_spawner.py).

    unshare --mount --pid --fork --mount-proc -- python sandbox.py JOB.json -- jupyterhub-singleuser ...

``unshare`` gives the server a mount namespace and a PID namespace of its own (with its own /proc: no other
process on the machine is visible from it). This script then, still as root and inside them:

1. covers the *hidden* folders with empty tmpfs: the hub's state folder (its database, secrets and every other
   student's home), the instructor's folder (``instructor/``: the exercises' solutions), a private ``/tmp``, and
   any folder the student could not walk through on the way to what the server needs (``/root`` when Python lives
   under it);
2. binds back, at their own paths, only what the server needs from inside a covered folder: the student's home
   (read-write), Python and the virtual environment, the repository, the data folder (read-only where bound back;
   elsewhere their own permissions apply: root's files, which a student cannot change), and the class's
   compiled-solver cache as an overlay (the shared cache below, the student's writes in a private layer above, so
   no student can change what another loads);
3. drops to the student's own system user (uid, gid, no other groups) and runs the server as the child of a small
   init that passes on the hub's stop signals and reaps orphans.

The job file (JSON, written by the spawner, readable by root only) holds ``user``, ``uid``, ``gid``, ``home``,
``expose`` (paths, read-write), ``expose_ro``, ``overlay`` (the cache), ``hide``.
"""

from __future__ import annotations

import ctypes
import json
import os
import signal
import stat
import sys
from pathlib import Path


_LIBC = ctypes.CDLL(None, use_errno=True)
MS_RDONLY, MS_REMOUNT, MS_BIND = 1, 32, 4096


def _mount(source: str, target, fstype: str | None = None, flags: int = 0, data: str | None = None) -> None:
    """mount(2) itself: a bind source given as ``/proc/self/fd/N`` is followed as the kernel sees it (the mount
    command would first turn it back into a path, which by then leads into the cover)."""
    enc = (lambda v: None if v is None else str(v).encode())
    if _LIBC.mount(enc(source), enc(target), enc(fstype), ctypes.c_ulong(flags), enc(data)) != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"mount {source} on {target}: {os.strerror(err)}")


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


def build(job) -> None:
    """Steps 1 and 2 of the module docstring."""
    rw = [Path(p) for p in job["expose"]]
    ro = [Path(p) for p in job["expose_ro"]]
    cache = Path(job["overlay"]) if job.get("overlay") else None
    hide = [Path(p) for p in job["hide"]] + [Path("/tmp")]
    every = [p for p in rw + ro + ([cache] if cache else []) if p.exists()]
    for p in every:  # a folder on the way that a student cannot walk through is covered too, its needed parts bound
        block = _blocking(p)
        if block is not None and not any(_under(p, h) for h in hide):
            hide.append(block)
    hide = sorted(set(hide), key=lambda h: len(h.parts))
    covering = [h for h in hide if any(_under(p, h) for p in every)]  # what must be covered before binding back
    leaves = [h for h in hide if h not in covering]
    # every path to bind back, opened before anything is covered (bound from /proc/self/fd/N afterwards)
    fds = {p: os.open(p, os.O_PATH) for p in every}

    def cover(h):
        if h.is_dir():
            _mount("tmpfs", h, "tmpfs", 0, f"mode={'1777' if h == Path('/tmp') else '0711'},size=1g")

    for h in covering:
        cover(h)
    for p in sorted(fds, key=lambda p: len(p.parts)):
        if p == cache:
            continue
        if not any(_under(p, h) for h in covering):
            continue  # reachable as it is, with its own permissions (binding it again would hide the covers below it)
        if Path(f"/proc/self/fd/{fds[p]}").is_dir():
            p.mkdir(parents=True, exist_ok=True)
        else:
            p.parent.mkdir(parents=True, exist_ok=True)
            p.touch()
        _mount(f"/proc/self/fd/{fds[p]}", p, None, MS_BIND)
        if p in ro:
            _mount("none", p, None, MS_REMOUNT | MS_BIND | MS_RDONLY)
    for h in leaves:
        cover(h)
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


def run(job, cmd) -> int:
    """Step 3: the student's user, then a child running ``cmd``; this process waits as the namespace's init."""
    os.setgroups([])
    os.setgid(job["gid"])
    os.setuid(job["uid"])
    os.chdir(job["home"])
    child = os.fork()
    if child == 0:
        os.setsid()
        os.execvp(cmd[0], cmd)
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
    build(job)
    return run(job, cmd)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
