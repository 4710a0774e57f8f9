"""A hub restart keeps every student's files: a student's server is started, their lesson edited, the hub stopped
(which stops the servers) and started again on the same state folder; the student's next server starts on the
edited lesson. Through the hub's REST API, no browser."""

from __future__ import annotations

import pytest

from tests.hub.hub_helpers import running_hub
from tests.viz.browser_helpers import wait_for

pytestmark = pytest.mark.slow


def _start(hub, user):
    assert hub.api("POST", f"/users/{user}/server")[0] in (201, 202)
    wait_for(lambda: (hub.server(user) or {}).get("ready"), 120, f"{user}'s server to start")


def test_a_hub_restart_keeps_every_students_files(tmp_path):
    with running_hub(tmp_path) as hub:
        hub.api("POST", "/users", {"usernames": ["dana", "eli"]})
        for user in ("dana", "eli"):
            _start(hub, user)
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
