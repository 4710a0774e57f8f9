"""The hub's configuration without a hub (deploy/jupyterhub/jupyterhub_config.py): each student's lessons copied
without overwriting, make lab's settings passed to each server, the culler as a service; and the pages and files
built from the measured class (docs/hub.md's tables, the zero-to-jupyterhub values, the image's settings)."""

from __future__ import annotations

import json
import re
import runpy

import pytest
import yaml
from traitlets.config import Config

from posekit.viz.websocket import server_flags
from tests.hub.hub_helpers import CONFIG, ROOT

HUB = ROOT / "deploy" / "jupyterhub"
RESULTS = HUB / "class_sizing.json"
VALUES = HUB / "z2jh-values.yaml"


@pytest.fixture
def config(tmp_path, monkeypatch):
    """The configuration file run as JupyterHub runs it, its state in a temporary folder: (namespace, config)."""
    monkeypatch.setenv("POSEKIT_HUB_STATE", str(tmp_path / "state"))
    monkeypatch.setenv("POSEKIT_HUB_CULL_TIMEOUT", "600")
    c = Config()
    return runpy.run_path(str(CONFIG), init_globals={"get_config": lambda: c}), c


def test_lessons_are_copied_once_and_edits_are_kept(config, tmp_path):
    ns, _ = config
    home = tmp_path / "alice"
    first = ns["copy_lessons"](home)
    lessons = sorted(p.name for p in (ROOT / "notebooks").glob("*.ipynb") if not p.name.startswith("_"))
    assert first == lessons and "studio.ipynb" in first and "01_fabrik.ipynb" in first
    edited = home / "lessons" / "01_fabrik.ipynb"
    edited.write_text("my own work")
    (home / "lessons" / "00_skeletons_and_poses.ipynb").unlink()  # deleted by the student: copied back
    assert ns["copy_lessons"](home) == ["00_skeletons_and_poses.ipynb"]
    assert edited.read_text() == "my own work"


def test_a_lessons_copy_that_cannot_be_made_says_why(config, tmp_path):
    ns, _ = config
    home = tmp_path / "carol"
    home.mkdir()
    (home / "lessons").write_text("")
    with pytest.raises(ns["LessonCopyError"], match="is a file, expected a folder") as err:
        ns["copy_lessons"](home)
    assert "expected a folder" in err.value.jupyterhub_message  # what the hub's error page shows


def test_each_server_gets_make_labs_settings_and_the_culler_runs(config):
    _, c = config
    assert server_flags("lab")[0] in c.Spawner.args
    assert "--VoilaConfiguration.template=posekit" in c.Spawner.args
    assert c.Spawner.default_url == "/lab/tree/lessons"
    assert str(ROOT / "posekit" / "viz" / "voila") in c.Spawner.environment["JUPYTER_PATH"]
    assert c.Spawner.environment["POSEKIT_NUMBA_CACHE"]  # one compiled-solver cache, not one per student's home
    culler = next(s for s in c.JupyterHub.services if s["name"] == "idle-culler")
    assert culler["command"][1:3] == ["-m", "jupyterhub_idle_culler"] and "--timeout=600" in culler["command"]
    role = next(r for r in c.JupyterHub.load_roles if "idle-culler" in r.get("services", []))
    assert "delete:servers" in role["scopes"]
    assert c.JupyterHub.authenticator_class == "shared-password"  # the trial login, labelled so in the file
    assert c.JupyterHub.bind_url.startswith("http://127.0.0.1:")  # a trial is not served to the network


def _measure_module():
    return runpy.run_path(str(HUB / "measure_class.py"), run_name="posekit_measure_class")


def test_the_sizing_table_is_the_measured_one():
    table = _measure_module()["table"](json.loads(RESULTS.read_text()))
    page = (ROOT / "docs" / "hub.md").read_text()
    found = re.search(r"<!-- class-sizing: begin[^>]*-->\n(.*?)\n<!-- class-sizing: end -->", page, re.S)
    assert found, "docs/hub.md lacks the class-sizing block"
    assert found.group(1).strip() == table.strip(), (
        "docs/hub.md's class-sizing table differs from python deploy/jupyterhub/measure_class.py --table "
        f"{RESULTS.relative_to(ROOT)}")


def test_the_kubernetes_resources_follow_the_measured_peak():
    results = json.loads(RESULTS.read_text())
    values = yaml.safe_load(VALUES.read_text())
    single = values["singleuser"]
    want = _measure_module()["z2jh_resources"](results)
    assert single["memory"] == want["memory"] and single["cpu"] == want["cpu"]
    guarantee = int(single["memory"]["guarantee"].rstrip("M"))
    assert guarantee >= results["per_student_peak_mb"]  # every student is sure to have their measured peak
    said = VALUES.read_text()  # the comment names the lesson the figures come from and their file
    assert f"worst lesson, {results['worst_lesson']}" in said and "deploy/jupyterhub/class_sizing.json" in said
    assert single["defaultUrl"] == "/lab/tree/lessons"
    assert values["cull"]["enabled"] and values["cull"]["timeout"] == 3600  # as make hub's default


def test_the_image_carries_make_hubs_server_settings():
    post = (ROOT / "deploy" / "image" / "postBuild").read_text()
    settings = json.loads(re.search(r"<<JSON\n(.*?)\nJSON", post, re.S).group(1))
    assert settings["ServerApp"]["kernel_websocket_connection_class"] == server_flags("lab")[0].split("=", 1)[1]
    assert settings["VoilaConfiguration"]["template"] == "posekit"
    requirements = (ROOT / "deploy" / "image" / "requirements.txt").read_text()
    assert "download.pytorch.org/whl/cpu" in requirements and "+cpu" in requirements  # never the CUDA build


def test_each_student_gets_a_system_user_name_of_their_own():
    import sys

    sys.path.insert(0, str(HUB))
    from posekit_spawner import unix_name

    assert unix_name("alice") == "posekit-alice"
    names = {unix_name(n) for n in ("Alice", "alice", "a.lice", "a_lice", "élise", "x" * 60)}
    assert len(names) == 6  # a name that had to change carries a hash of the original: no two share a user
    assert all(re.fullmatch(r"posekit-[a-z0-9-]{1,24}", n) for n in names)


def test_the_sandbox_hides_the_state_and_solutions_and_exposes_what_a_server_needs(config, tmp_path):
    import sys

    _, c = config
    spawner = c.ClassSpawner
    assert c.JupyterHub.spawner_class.__name__ == "ClassSpawner"
    assert str(tmp_path / "state") in spawner.hide and str(ROOT / "instructor") in spawner.hide
    assert sys.base_prefix in spawner.expose_ro and str(ROOT) in spawner.expose_ro
    assert spawner.overlay == c.Spawner.environment["POSEKIT_NUMBA_CACHE"]
    sys.path.insert(0, str(HUB))
    import sandbox

    locked = tmp_path / "locked"
    (locked / "inside").mkdir(parents=True)
    locked.chmod(0o700)
    block = sandbox._blocking(locked / "inside")  # covered, its needed part bound back (pytest's own tmp may block first)
    assert block in (locked, *locked.parents) and not block.stat().st_mode & 0o001
    assert sandbox._blocking(ROOT) is None


def test_a_course_gives_students_the_assignments_panel_and_not_the_instructors_tools(tmp_path, monkeypatch):
    monkeypatch.setenv("POSEKIT_HUB_STATE", str(tmp_path / "state"))
    monkeypatch.setenv("POSEKIT_HUB_COURSE", "posekit")
    c = Config()
    runpy.run_path(str(CONFIG), init_globals={"get_config": lambda: c})
    folder = tmp_path / "state" / "student-config"
    assert c.Spawner.environment["JUPYTER_CONFIG_PATH"].split(":")[0] == str(folder)
    server = json.loads((folder / "jupyter_server_config.json").read_text())["ServerApp"]["jpserver_extensions"]
    assert server["nbgrader.server_extensions.assignment_list"] and not server["nbgrader.server_extensions.formgrader"]
    lab = json.loads((folder / "labconfig" / "page_config.json").read_text())["disabledExtensions"]
    assert lab["@jupyter/nbgrader"] is False and lab["@jupyter/nbgrader:formgrader"] is True
    said = (folder / "nbgrader_config.py").read_text()
    assert "course_id = 'posekit'" in said and str(tmp_path / "state" / "exchange") in said
    assert c.ClassSpawner.expose == [str(tmp_path / "state" / "exchange")]


def _row(peak, rss=500.0, studio=800.0, start=4.0, lesson=10.0, page=3.0):
    return {"student": "student1", "server_start_s": start, "lesson_s": lesson, "studio_s": page,
            "server_rss_mb": 250.0, "kernel_rss_mb": rss - 250.0, "rss_mb": rss, "lesson_peak_mb": rss + 40.0,
            "studio_rss_mb": studio,
            "peak_mb": peak}


def test_the_sizing_table_has_a_row_per_lesson_and_sizes_by_the_worst_one():
    m = _measure_module()
    runs = [{"lesson": "00_skeletons_and_poses.ipynb", "students": 1, "per_student": [_row(700.4)]},
            {"lesson": "05_protores.ipynb", "students": 2,
             "per_student": [_row(1046.2, rss=760.0, lesson=30.0), _row(1001.0, rss=740.0, lesson=20.0)]},
            {"lesson": "06_posing_studio.ipynb", "students": 1, "per_student": [_row(990.0)]}]
    result = {"runs": runs, **m["worst"](runs)}
    assert result == {"runs": runs, "per_student_peak_mb": 1046.2, "worst_lesson": "05_protores.ipynb"}
    lines = m["table"](result).splitlines()
    assert lines[2].startswith("| 00_skeletons_and_poses | 1 | 4.0 / 4.0 | 10.0 / 10.0 | 3.0 / 3.0 | 500 | 540 | 800 | 700 |")
    assert lines[3] == "| 05_protores | 2 | 4.0 / 4.0 | 25.0 / 30.0 | 3.0 / 3.0 | 760 | 800 | 800 | 1046 |"
    tljh = next(line for line in lines if line.startswith("Memory a machine needs"))
    assert "1046 MB, the peak of 05_protores" in tljh
    assert lines[-1] == "| memory, GB | " + " | ".join(f"{(n * 1046.2 + 128) / 1024:.1f}" for n in (10, 20, 30, 50)) + " |"
    assert m["z2jh_resources"](result)["memory"] == {"guarantee": "1088M", "limit": "2176M"}  # 1046.2 -> 17 x 64


def test_the_lessons_to_measure_are_read_from_their_numbers(tmp_path):
    m = _measure_module()
    assert m["lesson_names"]("05,0") == ["05_protores.ipynb", "00_skeletons_and_poses.ipynb"]
    assert len(m["lesson_names"]("00,01,02,03,04,05,06")) == 7
    for bad in ("07", "", "1,x"):
        with pytest.raises(SystemExit, match="expected lesson numbers from 00, 01"):
            m["lesson_names"](bad)
    code = m["lesson_code"](ROOT / "notebooks" / "01_fabrik.ipynb")
    assert any("SolverPanel(" in src for src in code) and all(src.strip() for src in code)
    broken = tmp_path / "broken.ipynb"
    broken.write_text('{"cells": [')
    with pytest.raises(SystemExit, match="broken.ipynb: expected a Jupyter notebook"):
        m["lesson_code"](broken)
    empty = tmp_path / "empty.ipynb"
    empty.write_text('{"cells": [{"cell_type": "markdown", "source": ["# only prose"]}]}')
    with pytest.raises(SystemExit, match="empty.ipynb: expected a notebook with code cells"):
        m["lesson_code"](empty)


def test_a_lessons_link_is_refused_and_nothing_is_written_through_it(config, tmp_path):
    ns, _ = config
    elsewhere = tmp_path / "bob" / "lessons"
    elsewhere.mkdir(parents=True)
    home = tmp_path / "alice"
    home.mkdir()
    (home / "lessons").symlink_to(elsewhere)
    with pytest.raises(ns["LessonCopyError"], match="is a link, expected a folder of your own"):
        ns["copy_lessons"](home)
    assert list(elsewhere.iterdir()) == []
    # a link in place of one lesson is the student's: left alone, never written through
    (home / "lessons").unlink()
    (home / "lessons").mkdir()
    target = tmp_path / "root-only.txt"
    target.write_text("root's")
    (home / "lessons" / "01_fabrik.ipynb").symlink_to(target)
    copied = ns["copy_lessons"](home)
    assert "01_fabrik.ipynb" not in copied and "00_skeletons_and_poses.ipynb" in copied
    assert target.read_text() == "root's"


def test_the_exchange_is_made_by_the_instructor_and_refuses_a_squatter(config, tmp_path):
    import os
    import stat

    ns, _ = config
    exchange = tmp_path / "exchange"
    folder = ns["make_exchange"](exchange, "posekit")
    assert stat.S_IMODE(exchange.stat().st_mode) == 0o1777
    modes = {p.name: stat.S_IMODE(p.stat().st_mode) for p in [folder, *folder.iterdir()]}
    assert modes == {"posekit": 0o755, "outbound": 0o755, "inbound": 0o3733, "feedback": 0o711}
    assert all(p.stat().st_uid == os.geteuid() for p in [folder, *folder.iterdir()])
    assert ns["make_exchange"](exchange, "posekit") == folder  # a second start keeps it
    if os.geteuid() == 0:  # a folder a student made first is refused, not used
        squat = exchange / "other"
        squat.mkdir()
        os.chown(squat, 64_123, 64_123)
        with pytest.raises(SystemExit, match="someone made it before the hub did"):
            ns["make_exchange"](exchange, "other")


def test_the_limits_per_student_come_from_the_measured_class(config):
    import math

    ns, c = config
    peak = json.loads(RESULTS.read_text())["per_student_peak_mb"]
    assert c.Spawner.mem_limit == 2 * math.ceil(peak / 64) * 64 * 1024 * 1024  # twice the peak, as z2jh's limit
    assert c.Spawner.cpu_limit == 1.0 and c.ClassSpawner.pids_limit == 1024


def test_students_submit_under_their_hub_name(tmp_path, monkeypatch):
    monkeypatch.setenv("POSEKIT_HUB_STATE", str(tmp_path / "state"))
    monkeypatch.setenv("POSEKIT_HUB_COURSE", "posekit")
    runpy.run_path(str(CONFIG), init_globals={"get_config": Config})
    said = (tmp_path / "state" / "student-config" / "nbgrader_config.py").read_text()
    c = Config()
    monkeypatch.setenv("JUPYTERHUB_USER", "bob")
    exec(compile(said, "nbgrader_config.py", "exec"), {"get_config": lambda: c})
    assert c.CourseDirectory.student_id == "bob"


def test_the_hub_user_marker_is_the_one_collect_reads():
    import sys

    sys.path.insert(0, str(HUB))
    import posekit_spawner

    from posekit.course import exchange

    assert posekit_spawner.HUB_USER_COMMENT == exchange.HUB_USER_COMMENT
