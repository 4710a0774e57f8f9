"""``make test-latest``'s parts that run without installing anything: the requirements it lifts the bounds of,
and the page rendered from its record."""

import importlib.util
import json
from pathlib import Path

from posekit.docs import versions_page

ROOT = Path(__file__).resolve().parent.parent


def _tool():
    spec = importlib.util.spec_from_file_location("test_latest", ROOT / "tools" / "test_latest.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_newest_stack_lifts_every_bound_but_torchs(tmp_path):
    tool = _tool()
    py = tmp_path / "pyproject.toml"
    py.write_text('[project]\nname = "x"\ndependencies = ["numpy>=1.26,<3", "torch>=2.2,<=2.13.0", '
                  '"pythreejs>=2.4.2,<2.5"]\n[project.optional-dependencies]\ndev = ["nbval>=0.11,<0.12", '
                  '"numpy"]\n')
    assert tool._requirement_names(py) == ["numpy", "pythreejs", "nbval"]  # no bound, no torch, no repeat
    assert tool.TORCH_CPU == "torch==2.13.0"
    names = tool._requirement_names(ROOT / "pyproject.toml")
    assert {"jupyterlab", "ipywidgets", "pythreejs", "voila", "nbval", "playwright", "numpy"} <= set(names)
    assert all("<" not in n and ">" not in n and "=" not in n for n in names)


def test_the_page_shows_the_recorded_run_and_says_when_none_was(tmp_path):
    record = {"command": "python tools/test_latest.py --pre", "date": "2027-01-02", "machine": "x86_64, 2 cores",
              "result": "failed (pytest exit 1)", "seconds": 10, "stack": {"jupyterlab": "4.7.0a2", "voila": "0.6.0"}}
    path = tmp_path / "tested-versions.json"
    path.write_text(json.dumps(record))
    page = versions_page.markdown(path)
    for text in ("`python tools/test_latest.py --pre`", "2027-01-02", "failed (pytest exit 1)",
                 "| jupyterlab | 4.7.0a2 |", "| voila | 0.6.0 |"):
        assert text in page
    assert "No run has been recorded" in versions_page.markdown(tmp_path / "missing.json")
