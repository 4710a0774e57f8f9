"""A hub restart keeps every student's files: a student's server is started, their lesson edited, the hub stopped
(which stops the servers) and started again on the same state folder; the student's next server starts on the
edited lesson. Through the hub's REST API, no browser. The first hub starts where Ctrl-C is ignored, as a script's
background job starts it: what the hub starts must still end on its SIGINT."""

from __future__ import annotations

import signal

import psutil
import pytest

from tests.hub.hub_helpers import running_hub
from tests.viz.browser_helpers import wait_for

pytestmark = pytest.mark.slow


def _start(hub, user):
    assert hub.api("POST", f"/users/{user}/server")[0] in (201, 202)
    wait_for(lambda: (hub.server(user) or {}).get("ready"), 120, f"{user}'s server to start")


def _ignores_sigint(proc: psutil.Process) -> bool:
    with open(f"/proc/{proc.pid}/status") as fh:
        mask = next(int(line.split()[1], 16) for line in fh if line.startswith("SigIgn:"))
    return bool(mask & (1 << (signal.SIGINT - 1)))


def _started(hub, marker: str) -> list[psutil.Process]:
    return [p for p in psutil.Process(hub.proc.pid).children(recursive=True) if marker in " ".join(p.cmdline())]


def test_a_hub_restart_keeps_every_students_files(tmp_path):
    with running_hub(tmp_path, sigint_ignored=True) as hub:
        hub.api("POST", "/users", {"usernames": ["dana", "eli"]})
        for user in ("dana", "eli"):
            _start(hub, user)
        # the culler and the students' servers end on the hub's SIGINT (ignoring it, each stop of the hub waited
        # 30 s for the culler, and each server's stop 10 s)
        culler, servers = _started(hub, "jupyterhub_idle_culler"), _started(hub, "jupyterhub-singleuser")
        assert len(culler) == 1 and len(servers) >= 2
        assert [p.pid for p in culler + servers if _ignores_sigint(p)] == []
        lesson = hub.home("dana") / "lessons" / "00_skeletons_and_poses.ipynb"
        lesson.write_text(lesson.read_text().replace('"cells": [', '"cells": [{"cell_type": "markdown", '
                                                     '"id": "dana", "metadata": {}, "source": "dana was here"},', 1))
        assert "dana was here" in lesson.read_text()
        copies = sorted(p.name for p in (hub.home("eli") / "lessons").iterdir())
    with running_hub(tmp_path) as hub:  # the same state folder: database, secrets, homes
        assert hub.server("dana") is None  # the servers stopped with the hub
        _start(hub, "dana")
        assert "dana was here" in lesson.read_text()
        assert sorted(p.name for p in (hub.home("eli") / "lessons").iterdir()) == copies
