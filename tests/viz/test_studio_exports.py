"""The tests leave a student's ``notebooks/studio_exports/`` alone: every studio a test makes, every notebook nbval
runs and every server a browser test starts writes its exports under a temporary folder (``$POSEKIT_EXPORTS_DIR``,
set by ``tests/conftest.py``; :func:`posekit.paths.exports_dir`)."""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

from posekit.paths import EXPORTS, exports_dir, notebooks_dir
from tests.conftest import EXPORTS_VAR


def _inside(path: Path, folder: Path) -> bool:
    return Path(path).resolve().is_relative_to(Path(folder).resolve())


def test_the_export_folder_of_the_tests_is_a_temporary_one():
    folder = exports_dir()
    assert folder.is_absolute() and folder.name == EXPORTS  # the lesson's printed paths compare (nbval_sanitize.cfg)
    assert _inside(folder, tempfile.gettempdir()), folder
    assert not _inside(folder, notebooks_dir()) and not _inside(folder, notebooks_dir().parent), folder


def test_a_studio_without_a_folder_and_the_apps_pages_write_there(sample):
    from posekit.data.cases import build_cases
    from posekit.viz import PosingStudio
    from posekit.viz.studio_app import session_folder

    studio = PosingStudio(sample.skeleton, build_cases(sample, 1, seed=0).pose(0), ["fabrik", "dls"])
    assert studio.export_dir == exports_dir()
    assert session_folder().parent == exports_dir()


def test_without_the_variable_the_studio_writes_beside_the_notebook(monkeypatch):
    monkeypatch.delenv(EXPORTS_VAR)
    assert exports_dir() == Path(EXPORTS)  # relative: the working folder, which is the notebook's in a kernel


def test_a_kernel_started_in_notebooks_as_nbval_starts_one_writes_outside_them():
    """nbval runs each lesson in a kernel whose working folder is ``notebooks/``: that kernel's export folder is the
    temporary one (it inherits the variable), so lesson 06's saves and exports never land in the repository."""
    from jupyter_client.manager import start_new_kernel

    km, kc = start_new_kernel(kernel_name="python3", cwd=str(notebooks_dir()))
    out = []
    try:
        reply = kc.execute_interactive(
            "from posekit.paths import exports_dir; print(exports_dir().resolve())", timeout=120,
            output_hook=lambda msg: out.append(msg["content"].get("text", "")) if msg["msg_type"] == "stream" else None)
    finally:
        kc.stop_channels()
        km.shutdown_kernel(now=True)
    assert reply["content"]["status"] == "ok", reply["content"]
    printed = Path("".join(out).strip())
    assert printed == exports_dir().resolve(), printed
    assert not _inside(printed, notebooks_dir()), printed


def test_a_printed_export_path_compares_whatever_the_temporary_folders_name():
    """nbval applies tests/nbval_sanitize.cfg's rules in order: a temporary folder whose random name ends like a rate
    (``..._h68z3s`` + ``/studio_exports``) must still compare as ``studio_exports/`` (a CI run failed on lesson 06)."""
    from nbval.plugin import get_sanitize_patterns

    rules = get_sanitize_patterns((Path(__file__).resolve().parents[1] / "nbval_sanitize.cfg").read_text())
    for name in ("posekit-test-exports-_h68z3s", "posekit-test-exports-abc12it", "posekit-test-exports-q0.5s"):
        text = f"loaded /tmp/{name}/{EXPORTS}/raise_hand.json: 7 effectors"
        for regex, replace in rules:
            text = re.sub(regex, replace, text)
        assert text == f"loaded {EXPORTS}/raise_hand.json: 7 effectors", (name, text)
