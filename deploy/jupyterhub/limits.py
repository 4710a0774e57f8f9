"""Limits per student on one machine, enforced by the kernel (called by sandbox.py, as root, inside the sandbox).

``limits`` (a dict in the sandbox's job file, made by the spawner from ``class_sizing.json``; see docs/hub.md):

* ``memory_bytes``: the student's server, kernels, their children and what they write into their private tmpfs
  together (a memory control group: past it the kernel reclaims, then kills the largest process of the group —
  a kernel, not the machine);
* ``cpu``: CPUs at most (a CPU quota: 1.0 is one core's time, whatever the student starts);
* ``pids``: processes and threads at most (a fork bomb stops there).

Where the machine has control groups (v2, or v1's ``memory``, ``cpu`` and ``pids`` hierarchies) that the hub may
write, each student gets one under the hub's own, ``posekit/<user>``. Where it has none, only what rlimits can do
is done: ``pids`` becomes ``RLIMIT_NPROC`` (per system user, so per student) and ``memory_bytes`` ``RLIMIT_DATA``
(per process, not for the student's processes together); a CPU share is not enforced. :func:`join_cgroup` says
which. The private tmpfs sizes (sandbox.py's ``PRIVATE``) bound what a student can hold in memory through files.
"""

from __future__ import annotations

import ctypes
import os
import resource
from pathlib import Path

__all__ = ["join_cgroup", "apply_rlimits", "empty_bounding_set", "no_new_privs", "not_dumpable", "cgroup_dirs"]

_LIBC = ctypes.CDLL(None, use_errno=True)
PR_SET_DUMPABLE, PR_CAPBSET_DROP, PR_SET_NO_NEW_PRIVS = 4, 24, 38
CGROUP = Path("/sys/fs/cgroup")
CPU_PERIOD_US = 100_000


def _prctl(option: int, arg: int) -> None:
    if _LIBC.prctl(option, ctypes.c_ulong(arg), 0, 0, 0) != 0:
        err = ctypes.get_errno()
        raise OSError(err, f"prctl({option}, {arg}): {os.strerror(err)}")


def empty_bounding_set() -> None:
    """Drop every capability from the calling thread's bounding set (needs CAP_SETPCAP: call it as root)."""
    last = int(Path("/proc/sys/kernel/cap_last_cap").read_text())
    for cap in range(last + 1):
        _prctl(PR_CAPBSET_DROP, cap)


def no_new_privs() -> None:
    """No program started from here on gains a privilege (set-uid, set-gid, file capabilities)."""
    _prctl(PR_SET_NO_NEW_PRIVS, 1)


def not_dumpable() -> None:
    """The calling process can be neither traced nor read through /proc by its own (unprivileged) user."""
    _prctl(PR_SET_DUMPABLE, 0)


def _own_path(controller: str) -> str:
    """The calling process's control group in ``controller``'s hierarchy ("" for v2's unified one)."""
    for line in Path("/proc/self/cgroup").read_text().splitlines():
        _, names, path = line.split(":", 2)
        if names.split(",") == [""] and controller == "" or controller in names.split(","):
            return path.lstrip("/")
    raise LookupError(controller)


def cgroup_dirs(user: str, root: Path = CGROUP) -> dict[str, Path] | None:
    """Where ``user``'s control group goes, per controller (``{"": dir}`` on v2; ``{"memory": ..., "cpu": ...,
    "pids": ...}`` on v1), under the calling process's own group; None when the machine has none the hub may use."""
    if (root / "cgroup.controllers").exists():  # v2 alone
        wanted = {"memory", "cpu", "pids"}
        if not wanted <= set((root / "cgroup.controllers").read_text().split()):
            return None
        return {"": root / _own_path("") / "posekit" / user}
    found = {}
    for controller in ("memory", "cpu", "pids"):
        top = root / controller
        if not (top / "cgroup.procs").exists() or not os.access(top, os.W_OK):
            return None
        found[controller] = top / _own_path(controller) / "posekit" / user
    return found


def _write(path: Path, value) -> None:
    path.write_text(f"{value}\n")


def join_cgroup(user: str, limits: dict, root: Path = CGROUP) -> tuple[str, bool]:
    """Put the calling process (and so everything it starts) in ``user``'s control group with ``limits``.

    Returns a sentence saying what is enforced where (the sandbox prints it into the server's log) and whether a
    control group holds them. Raises OSError when a control group exists but a limit cannot be set (fail closed)."""
    if not limits:
        return "no limits asked", False
    dirs = cgroup_dirs(user, root)
    if dirs is None:
        return "no control group the hub may use: rlimits only (processes per user, memory per process)", False
    mem, cpu, pids = limits.get("memory_bytes"), limits.get("cpu"), limits.get("pids")
    if "" in dirs:  # v2: every controller on the way down
        d = dirs[""]
        for parent in [*reversed(d.relative_to(root).parents), d.relative_to(root)]:
            (root / parent).mkdir(exist_ok=True)
            if root / parent != d:
                _write(root / parent / "cgroup.subtree_control", "+memory +cpu +pids")
        if mem:
            _write(d / "memory.max", int(mem))
            if (d / "memory.swap.max").exists():
                _write(d / "memory.swap.max", 0)
        if cpu:
            _write(d / "cpu.max", f"{int(cpu * CPU_PERIOD_US)} {CPU_PERIOD_US}")
        if pids:
            _write(d / "pids.max", int(pids))
        _write(d / "cgroup.procs", 0)
        return f"control group {d} (memory {mem} B, {cpu} CPU, {pids} processes)", True
    for controller, d in dirs.items():
        d.mkdir(parents=True, exist_ok=True)
    if mem:
        swap = dirs["memory"] / "memory.memsw.limit_in_bytes"
        if swap.exists():  # memory and swap together may never be below memory alone: lift it first
            _write(swap, -1)
        _write(dirs["memory"] / "memory.limit_in_bytes", int(mem))
        if swap.exists():
            _write(swap, int(mem))
    if cpu:
        _write(dirs["cpu"] / "cpu.cfs_period_us", CPU_PERIOD_US)
        _write(dirs["cpu"] / "cpu.cfs_quota_us", int(cpu * CPU_PERIOD_US))
    if pids:
        _write(dirs["pids"] / "pids.max", int(pids))
    for d in dirs.values():
        _write(d / "cgroup.procs", 0)
    return (f"control groups {', '.join(str(d) for d in dirs.values())} (memory {mem} B, {cpu} CPU, "
            f"{pids} processes)"), True


def apply_rlimits(limits: dict) -> None:
    """The limits rlimits can set, whatever the control groups did: processes per user (``RLIMIT_NPROC``, counted
    over the student's system user), and with no control group for memory, memory per process (``RLIMIT_DATA``)."""
    if limits.get("pids"):
        n = int(limits["pids"])
        resource.setrlimit(resource.RLIMIT_NPROC, (n, n))
    if limits.get("memory_bytes") and not limits.get("memory_by_cgroup"):
        n = int(limits["memory_bytes"])
        resource.setrlimit(resource.RLIMIT_DATA, (n, n))
    resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
