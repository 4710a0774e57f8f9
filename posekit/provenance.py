"""Where a measured figure comes from: the machine, the command and the date a results file carries.

Every results file a ``posekit bench ...`` or ``posekit train ...-studies`` command writes under
``data_samples/results`` holds its own provenance (``command``, ``date``, ``machine``), so a page that shows
the figures (``docs/benchmarks.md``, written by ``posekit docs build``: :mod:`posekit.docs`) takes them from
the file, never from prose.

The machine is described by what bears on a timing — operating system, architecture, CPU model, CPU count,
Python — and not by the kernel's build string (``platform.platform()``), which names a host, not a
machine class.
"""

from __future__ import annotations

import datetime
import os
import platform

__all__ = ["machine", "today", "stamp"]


def _cpu_model() -> str:
    """The CPU's model name (``/proc/cpuinfo`` on Linux, ``platform.processor()`` elsewhere), else the
    architecture."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.lower().startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> dict:
    """The machine a measurement ran on, without the kernel's build string.

    Returns
    -------
    dict
        ``platform`` (operating system and architecture, e.g. ``"Linux x86_64"``), ``processor`` (the CPU
        model), ``cpu_count`` and ``python`` (its version).
    """
    return {"platform": f"{platform.system()} {platform.machine()}".strip(), "processor": _cpu_model(),
            "cpu_count": os.cpu_count(), "python": platform.python_version()}


def today() -> str:
    """The date of a run, ``YYYY-MM-DD`` (UTC)."""
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d")


def stamp(command: str) -> dict:
    """``{"command": command, "date": today(), "machine": machine()}``: the provenance a results file carries."""
    return {"command": command, "date": today(), "machine": machine()}
